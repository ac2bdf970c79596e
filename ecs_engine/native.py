"""Optional numba: native loops that release the GIL. Everything has a NumPy fallback.

Set ECS_ENGINE_NO_NUMBA=1 to force the fallbacks (tests compare both paths).
"""

from __future__ import annotations

import os
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
