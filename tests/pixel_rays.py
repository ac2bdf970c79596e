"""The ray through each pixel's centre, in NumPy: what tests compare rendered pixels with (a
shadow's ray cast, the sky's cube face, a mirror's Fresnel)."""

from __future__ import annotations

import numpy as np

from ecs_engine import World
from ecs_engine.render.frame.camera import camera_matrices


def pixel_rays(world: World, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """(height, width, 3) unit directions in the world of the rays through the pixel centres of
    the world's camera, and the eye (float64)."""
    cam = camera_matrices(world, width / height)
    inv_p = np.linalg.inv(cam.projection.astype(np.float64))
    rot = cam.inverse_view[:3, :3].astype(np.float64)
    ys, xs = np.mgrid[0:height, 0:width]
    ndc = np.stack(
        [(xs + 0.5) / width * 2 - 1, (ys + 0.5) / height * 2 - 1, np.full(xs.shape, 0.5), np.ones(xs.shape)], -1
    )
    p = ndc @ inv_p.T
    d = (p[..., :3] / p[..., 3:]) @ rot.T
    return d / np.linalg.norm(d, axis=-1, keepdims=True), np.asarray(cam.position, np.float64)
