"""The culling interface: `CullingMethod`, one object per method config.Culling names, asked by
each stage that culls instead of that stage comparing names or flags.

A method answers, per stage of a frame:
- the config table (config.RULES): `supports(mode)` / `refusal(mode)`, whether a render mode
  culls with it and why not;
- the extract stage (frame_data.FrameExtractor): `planes(frustum)`, the planes the camera's rows
  are tested against (None: none are), and `masks(...)`, the rows decided while extracting
  (temporal culling's; None: the chunk jobs cull);
- the CPU chunk jobs (chunk_paths.py): `kept(data, chunk)`, the rows of a chunk decided ahead,
  and `decides_ahead`, whether any are (the jobs then keep no written rows between frames);
- the indirect path's compute (indirect_path.py): `gpu(host, width, height, rows)`, the GPU
  passes beyond the frustum test (occlusion culling's depth pyramid; None: the frustum alone).

The methods with state (temporal) keep it between frames: the renderer holds one method
(Renderer.culling_method), made again only when the culling changes.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from ..config import Culling, Mode, RenderConfig, validate

if TYPE_CHECKING:
    from ..extract.chunks import Chunk
    from .occlusion_passes import OcclusionPasses


class CullingMethod:
    """Frustum culling's answers; the other methods change what differs."""

    name: ClassVar[Culling]
    decides_ahead: ClassVar[bool] = False  # the extract stage decides the camera's rows (masks)
    # why the method cannot cull the frames of several camera views (None: it can)
    views_refusal: ClassVar[str | None] = None

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"

    # ------------------------------------------------------------ the config table
    def refusal(self, mode: str | Mode) -> str | None:
        """Why `mode` cannot cull with this method (config.RULES' words), or None."""
        return "; ".join(validate(RenderConfig.from_strings(mode=mode, culling=self.name), only=("culling",))) or None

    def supports(self, mode: str | Mode) -> bool:
        return self.refusal(mode) is None

    # ----------------------------------------------------------- the extract stage
    def planes(self, frustum: Callable[[], np.ndarray]) -> np.ndarray | None:
        """The planes (k, 4) float64 the camera's rows are tested against: `frustum()`, the
        view's (kept by the extractor while the view stays); None: no row is tested."""
        return frustum()

    def masks(
        self, world: Any, cam: Any, origin: np.ndarray, planes: np.ndarray | None, dt: float | None, bounds: Any
    ) -> dict[int, np.ndarray] | None:
        """Per table id, the rows to draw, decided while extracting (`world` is read only by
        the methods that decide ahead: they are part of the extract stage); None: the chunk
        jobs cull against `planes`."""
        return None

    def reset(self) -> None:
        """Forget what was kept between frames (a new world, a switch)."""

    # -------------------------------------------------------------- the chunk jobs
    def kept(self, data: Any, chunk: Chunk) -> np.ndarray | None:
        """The rows of `chunk` to draw as decided ahead (from `data`, the frame's FrameData);
        None: the job culls them against the frame's planes."""
        return None

    # ------------------------------------------------- the indirect path's compute
    def gpu(self, host: Any, width: int, height: int, rows: int) -> OcclusionPasses | None:
        """The passes the indirect path runs besides the frustum test, ready for a `width` x
        `height` target and `rows` rows (`host`: the path, which owns them: they are made
        against its layouts); None: the frustum test alone."""
        return None


class FrustumCulling(CullingMethod):
    """Every row tested against the view's frustum each frame (the CPU jobs or cull.comp)."""

    name = Culling.FRUSTUM


class NoCulling(CullingMethod):
    """Every row drawn: no planes, so the jobs and cull.comp keep every row."""

    name = Culling.NONE

    def planes(self, frustum: Callable[[], np.ndarray]) -> np.ndarray | None:
        return None
