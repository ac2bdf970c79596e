"""The engine's rays on numba's own threads (native.parallel): they start together, without the
GIL, where the JobPool's threads start one after another, each taking the GIL in turn to call
its kernel (about 50 us each on the GPU host).

Where the grid is to be brought up to the step first (ray_refresh.py), one kernel does both:
the threads share the look at every shape, wait for the blocks still being looked at, one of
them moves the shapes that escaped while the others wait, then they share the rays. A thread
only ever waits for work another thread has taken and is doing, so the kernel finishes however
many threads the threading layer runs it on, even one after another."""

from __future__ import annotations

from .. import native
from ..native import fetch_add
from .ray_refresh import look, settle
from .ray_walk import cast_rays

# the fused kernel's counters after _look's three (ray_refresh.counters)
_MOVER, _MOVED = 3, 4  # threads past the look (the first moves the shapes); 1: moved, 2: the spill is full


def _refresh_and_cast_kernel(counters, shapes, move, rays):  # pragma: no cover
    """One thread's part: the look, the move (the first thread here) and the rays; none are
    cast where the spill is full (counters[_MOVED] 2: the grid is to be made again)."""
    look(counters, *shapes)
    while fetch_add(counters, 2, 0) < len(shapes[3]):  # (blocks that other threads look at)
        pass
    if fetch_add(counters, _MOVER, 1) == 0:
        fetch_add(counters, _MOVED, 1 if settle(counters, shapes[3], shapes[-1], *move) else 2)
    while fetch_add(counters, _MOVED, 0) == 0:
        pass
    if counters[_MOVED] == 1:
        cast_rays(*rays)  # type: ignore[misc]


_refresh_and_cast = native.inner(_refresh_and_cast_kernel)


# (the parallel kernel takes the rays' arguments one by one and packs them inside the loop: numba
# hands its threads the loop's variables, and refuses a tuple that holds a tuple, the layout)
def _refresh_and_spread_kernel(  # pragma: no cover
    jobs, counters, shapes, o, d, reach, claims, p, r, rows, shape, size, large, layout, bounds, spill, answer, *out
):
    """The refresh (look's `shapes`, the rest as the rays have them) and the rays on `jobs` of
    numba's threads at once: whether the rays were cast (False: the grid is to be made again).
    With no shape to look at, the rays alone: one parallel kernel to compile, not two (each
    takes seconds)."""
    for _ in native.prange(jobs):
        margin, centre, turn = shapes[5], shapes[6], shapes[7]
        move = (p, r, rows, shape, size, margin, centre, turn, bounds, layout, spill)
        rays = (o, d, reach, claims, p, r, rows, shape, size, large, layout, bounds, spill, answer, *out)
        _refresh_and_cast(counters, shapes, move, rays)
    return counters[_MOVED] == 1


refresh_and_spread = native.parallel(_refresh_and_spread_kernel)
