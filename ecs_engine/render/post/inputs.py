"""What the hdr stage's post effects get from a frame (render/frame/output_passes.py's seam):

    effect.key(inputs)      # what a recorded frame depends on (frame replay), before recording
    effect(cb, inputs)      # records the effect, after the scene's render pass, before the tone map

`inputs` is one frame's `PostInputs`, made by `OutputPasses.begin_post(camera)` before the
frame's replay key is taken. Its images are gpu/memory.py Images (handle, view, format, width,
height), both in SHADER_READ_ONLY_OPTIMAL with the scene's writes visible to fragment and compute
shaders; an effect leaves them so (the HDR colour may be written in between: its writes visible
to the tone map's fragment shader). The depth is reverse-Z D32_SFLOAT, single-sample: None with
MSAA (config.py refuses the effects that read it there).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np


@dataclass(frozen=True, eq=False)
class PostInputs:
    hdr: Any  # the single-sample HDR colour (the MSAA resolve with --msaa)
    depth: Any  # the scene's single-sample depth, or None (MSAA)
    extent: tuple[int, int]  # the images' size
    projection: np.ndarray  # the camera's (FrameData.camera.projection, read-only float32/64 4 x 4)

    def projection_key(self) -> bytes:
        """The projection as bytes (float64): a frame-replay key's part."""
        return np.asarray(self.projection, dtype=np.float64).tobytes()
