"""`--culling occlusion` as a culling method: the frustum test, then, in the indirect mode's
compute, what is hidden behind last frame's visible rows (render/culling/occlusion_passes.py's two-phase
`OcclusionPasses`: early depth, depth pyramid, late cull)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Protocol

from ..config import Culling, Fill
from .method import CullingMethod

if TYPE_CHECKING:
    from .occlusion_passes import OcclusionPasses


class OcclusionHost(Protocol):
    """The indirect path, as this method asks it for the passes (made on first use, against
    its descriptor set and pipeline layouts; destroyed with it)."""

    ctx: Any  # its PathContext

    def occlusion_passes(self) -> OcclusionPasses: ...


def can_cull(ctx: Any) -> bool:
    """Whether the path's triangles are filled (wireframe and points show what is behind them:
    those frames cull the frustum alone)."""
    return bool(ctx.fill == Fill.SOLID)


class OcclusionCulling(CullingMethod):
    name = Culling.OCCLUSION
    views_refusal = (
        "occlusion culling with several camera views: it culls by the last frame's depth, "
        "which is another view's; use frustum or temporal culling"
    )

    def gpu(self, host: OcclusionHost, width: int, height: int, rows: int) -> OcclusionPasses | None:
        if rows == 0 or not can_cull(host.ctx):
            return None
        passes = host.occlusion_passes()
        passes.ensure(width, height, rows)
        return passes
