"""The active camera's matrices as a frame uses them. They are made by the extract stage
(extract/camera.py, the only reader of the camera's components); this module keeps what the
passes do with them, and the names older code imports from here."""

from __future__ import annotations

import numpy as np

from ..extract.camera import CameraMatrices, camera_matrices

__all__ = ["CameraMatrices", "camera_matrices", "view_from_origin"]


def view_from_origin(cam: CameraMatrices, origin: np.ndarray) -> np.ndarray:
    """The view matrix (4, 4) float32 for model matrices made relative to `origin`: the camera's
    rotation, and the translation from origin to camera (made in float64, cast once). With the
    origin at the camera (camera-relative rendering) the translation is exactly zero."""
    view = cam.view.astype(np.float64)
    view[:3, 3] = view[:3, :3] @ (np.asarray(origin, dtype=np.float64) - cam.position)
    return view.astype(np.float32)
