"""Stock systems: the fixed step's snapshot for interpolation, motion, springs, orbits, the fly
camera, the render origin and the transform (matrices)."""

from .camera_control import FlyCameraSystem, InputState
from .interpolation import SnapshotSystem
from .motion import MotionSystem
from .orbit import OrbitSystem
from .spring import SpringSystem
from .transform import RenderOriginSystem, TransformSystem

__all__ = [
    "FlyCameraSystem",
    "InputState",
    "MotionSystem",
    "OrbitSystem",
    "RenderOriginSystem",
    "SnapshotSystem",
    "SpringSystem",
    "TransformSystem",
]
