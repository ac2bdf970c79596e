"""Stock systems: motion, springs, transform (matrices), fly camera, orbits."""

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
