"""A LINEAR curve sampled straight into a component column: what AnimationSystem does for most
channels (a clip at full weight), without the temporaries of Curve.sample: per row a binary
search for its key, then lerp or the specification's slerp (sampling.py's), written in place.
A numba kernel (without the GIL: `write_all` spreads a frame's writes over the job pool's
threads in pieces of rows), and Curve.sample where numba is missing."""

from __future__ import annotations

from typing import Any

import numpy as np

from .. import native
from .sampling import LINEAR, Curve

PIECE_ROWS = 4096  # rows a job of write_all samples: a crowd's channel of 10k characters is a few jobs


def _write_kernel(times, values, rotation, t, rows, column):  # pragma: no cover - compiled
    keys = times.shape[0]
    width = values.shape[1]
    for i in range(rows.shape[0]):
        r = rows[i]
        if keys == 1:
            for c in range(width):
                column[r, c] = values[0, c]
            continue
        x = min(max(t[i], times[0]), times[keys - 1])
        lo, hi = 0, keys - 1  # the last key at or before x, at most the one before the last
        while hi - lo > 1:
            mid = (lo + hi) // 2
            if times[mid] <= x:
                lo = mid
            else:
                hi = mid
        k = lo
        s = (x - times[k]) / (times[k + 1] - times[k])
        if not rotation:
            for c in range(width):
                column[r, c] = (1.0 - s) * values[k, c] + s * values[k + 1, c]
            continue
        dot = 0.0
        for c in range(4):
            dot += values[k, c] * values[k + 1, c]
        sign = -1.0 if dot < 0.0 else 1.0
        angle = np.arccos(min(abs(dot), 1.0))
        sin = np.sin(angle)
        if sin < 1e-6:
            wa, wb = 1.0 - s, sign * s
        else:
            wa, wb = np.sin(angle * (1.0 - s)) / sin, sign * np.sin(angle * s) / sin
        norm = 0.0
        for c in range(4):
            v = wa * values[k, c] + wb * values[k + 1, c]
            column[r, c] = v
            norm += v * v
        inv = 1.0 / np.sqrt(norm)
        for c in range(4):
            column[r, c] *= inv


_write_native = native.njit(_write_kernel)


def _kernel_args(curve: Curve, column: np.ndarray) -> tuple[np.ndarray, np.ndarray, bool] | None:
    """The kernel's view of `curve` (key times and values as float64, rotation or not) when it
    can write into `column`; None where Curve.sample must (no numba, not LINEAR, a flat column)."""
    if _write_native is None or curve.interpolation != LINEAR or column.ndim != 2:
        return None
    keys = np.ascontiguousarray(curve.times, np.float64)
    return keys, np.ascontiguousarray(curve.values, np.float64).reshape(len(keys), -1), curve.rotation


def write_sampled(curve: Curve, times: np.ndarray, rows: np.ndarray, column: np.ndarray) -> None:
    """column[rows] = curve.sample(times), in place (LINEAR curves through the kernel)."""
    args, native_write = _kernel_args(curve, column), _write_native
    if args is None or native_write is None:
        column[rows] = curve.sample(times)
        return
    native_write(*args, times, rows, column)


Write = tuple[Curve, np.ndarray, np.ndarray, np.ndarray]  # write_sampled's arguments


def write_all(writes: list[Write], pool: Any = None) -> None:
    """write_sampled for each of `writes`, which touch distinct rows, in pieces of PIECE_ROWS rows
    over `pool`'s threads (a JobPool; None or one thread: in turn, here)."""
    if pool is None or pool.threads == 1 or _write_native is None or sum(len(w[2]) for w in writes) < 2 * PIECE_ROWS:
        for curve, times, rows, column in writes:
            write_sampled(curve, times, rows, column)
        return
    pieces = []
    for curve, times, rows, column in writes:
        args = _kernel_args(curve, column)
        if args is None:
            write_sampled(curve, times, rows, column)
            continue
        for at in range(0, len(rows), PIECE_ROWS):
            piece = slice(at, at + PIECE_ROWS)
            pieces.append((*args, times[piece], rows[piece], column))
    native_write = _write_native
    pool.map(lambda piece: native_write(*piece), pieces)
