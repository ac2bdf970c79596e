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


def _atomics() -> tuple[Callable[..., Any], Callable[..., Any]]:
    """`fetch_add(counters, i, n)`: adds n to counters[i] (an int64 array) at once for every
    thread and answers the value before; `load(counters, i)`: reads counters[i] as another
    thread's fetch_add left it. For kernels whose jobs share work through counters (a job
    claims the next block of rows, so a thread that starts late takes fewer). Without numba,
    plain functions (nothing compiled calls them then)."""
    if not AVAILABLE:

        def plain_add(counters: Any, i: int, n: int) -> int:
            before = int(counters[i])
            counters[i] += n
            return before

        return plain_add, lambda counters, i: int(counters[i])
    from numba import types
    from numba.core import cgutils
    from numba.extending import intrinsic

    def pointer(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        kind = signature.args[0]
        array = context.make_array(kind)(context, builder, args[0])
        return cgutils.get_item_pointer(context, builder, kind, array, [args[1]])

    @intrinsic
    def fetch_add(typingctx: Any, counters: Any, i: Any, n: Any) -> Any:
        def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
            return builder.atomic_rmw("add", pointer(context, builder, signature, args), args[2], "seq_cst")

        return types.int64(types.Array(types.int64, 1, "C"), types.intp, types.int64), codegen

    @intrinsic
    def load(typingctx: Any, counters: Any, i: Any) -> Any:
        def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
            return builder.load_atomic(pointer(context, builder, signature, args), "seq_cst", 8)

        return types.int64(types.Array(types.int64, 1, "C"), types.intp), codegen

    return fetch_add, load


fetch_add, load = _atomics()
