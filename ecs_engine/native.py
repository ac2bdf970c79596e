"""Optional numba: native loops that release the GIL. Everything has a NumPy fallback.

Set ECS_ENGINE_NO_NUMBA=1 to force the fallbacks (tests compare both paths).
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable
from typing import Any

_numba: Any
try:
    import numba as _numba
except ImportError:  # pragma: no cover - exercised only where numba is not installed
    _numba = None

AVAILABLE: bool = _numba is not None and os.environ.get("ECS_ENGINE_NO_NUMBA", "") != "1"


# Reassociation, contraction, reciprocals and signed zeros only: no "no NaN/Inf" assumptions,
# so non-finite input still propagates instead of being optimised into garbage. Measured on
# the angular kernel: 2.1 -> 1.2 ms per 100k rows. numba's on-disk cache is keyed on the
# kernel's own source file, not on these flags: after changing them, delete the *.nbi/*.nbc
# files under ecs_engine/__pycache__.
FASTMATH = {"contract", "arcp", "nsz", "reassoc"}


def njit(fn: Callable[..., Any]) -> Callable[..., Any] | None:
    """Compile `fn` with nogil (so worker threads run it in parallel), or None without numba."""
    if not AVAILABLE:
        return None
    return _numba.njit(nogil=True, cache=True, error_model="numpy", fastmath=FASTMATH)(fn)


def parallel(fn: Callable[..., Any]) -> Callable[..., Any] | None:
    """Like `njit`, for a kernel whose `prange` loop runs on numba's own threads (its threading
    layer: OpenMP, TBB or its workqueue). Native threads start together; the JobPool's wake
    one after another, each taking the GIL in turn to call its kernel (about 50 us each on the
    GPU host). Launch it under LAUNCH, after `spread`."""
    if not AVAILABLE:
        return None
    return _numba.njit(parallel=True, nogil=True, cache=True, error_model="numpy", fastmath=FASTMATH)(fn)


# numba's workqueue threading layer (where neither OpenMP nor TBB is found) aborts the process
# when two threads launch parallel kernels at once
LAUNCH = threading.Lock()


def spread(threads: int) -> int:
    """Run the calling thread's next parallel kernels on at most `threads` of numba's threads
    (no more than it started: NUMBA_NUM_THREADS, one per core by default); the count.

    OpenMP's threads (numba's omp threading layer) otherwise spin for milliseconds after each
    kernel, taking the cores from whatever runs next: on the GPU host 10,000 rays cast on 16
    of them slowed the library's ray batch run after them from 4.2-4.5 ms to 8.3-9.0. Asleep at
    once they start the next kernel as soon. libgomp reads OMP_WAIT_POLICY when it loads, at
    the first parallel kernel: set here (unless set before) so that a program that never runs
    one keeps its own OpenMP's default."""
    os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")
    count = max(1, min(int(threads), _numba.config.NUMBA_NUM_THREADS))
    _numba.set_num_threads(count)
    return count


prange: Callable[..., Any] = _numba.prange if AVAILABLE else range


def inner(fn: Callable[..., Any]) -> Callable[..., Any]:
    """Like `njit`, for a kernel that only other compiled kernels call: without numba it stays
    the plain function (nothing calls it then), so it is never None."""
    return njit(fn) or fn


def _fetch_add() -> Callable[..., Any]:
    """`fetch_add(counters, i, n)`, for compiled kernels: adds n to counters[i] (an int64
    array) at once for every thread and answers the value before. For jobs that share work
    through a counter (a job claims the next block of rows, so a thread that starts late takes
    fewer). Without numba, a plain function (nothing compiled calls it then)."""
    if not AVAILABLE:

        def plain_add(counters: Any, i: int, n: int) -> int:
            before = int(counters[i])
            counters[i] += n
            return before

        return plain_add
    from numba import types
    from numba.core import cgutils
    from numba.extending import intrinsic

    @intrinsic
    def fetch_add(typingctx: Any, counters: Any, i: Any, n: Any) -> Any:
        def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
            kind = signature.args[0]
            array = context.make_array(kind)(context, builder, args[0])
            at = cgutils.get_item_pointer(context, builder, kind, array, [args[1]])
            return builder.atomic_rmw("add", at, args[2], "seq_cst")

        return types.int64(types.Array(types.int64, 1, "C"), types.intp, types.int64), codegen

    return fetch_add


fetch_add = _fetch_add()
