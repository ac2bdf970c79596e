"""`--culling temporal` as a culling method: the frustum test, decided while extracting by
temporal_culling.py's `TemporalCuller` (a row tested again only when it could have changed
side), which reads the rows' ModelMatrix and Mesh columns: this method is part of the extract
stage (tests/test_extract_stage.py), called by FrameExtractor alone."""

from __future__ import annotations

from typing import Any

import numpy as np

from ...ecs.world import World
from ..config import Culling
from ..extract.chunks import Chunk
from .method import CullingMethod
from .temporal_culling import TemporalCuller


class TemporalCulling(CullingMethod):
    name = Culling.TEMPORAL
    decides_ahead = True

    def __init__(self, min_interval: float = 0.0) -> None:
        self.culler = TemporalCuller(min_interval)  # per row: its side, until when, its sphere

    def masks(
        self, world: World, cam: Any, origin: np.ndarray, planes: np.ndarray | None, dt: float | None, bounds: Any
    ) -> dict[int, np.ndarray] | None:
        if planes is None:  # (not from this method's planes: a caller's own)
            return None
        return self.culler.masks(world, cam, origin, planes, dt, bounds)

    def reset(self) -> None:
        self.culler.reset()

    def kept(self, data: Any, chunk: Chunk) -> np.ndarray | None:
        visible: np.ndarray | None = data.visible(chunk)  # FrameData.visible: its masks' slice
        return visible
