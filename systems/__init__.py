"""Stock systems: motion, springs, transform (matrices), fly camera, orbits."""

from .camera_control import FlyCameraSystem, InputState
from .interpolation import SnapshotSystem
from .motion import MotionSystem
from .orbit import OrbitSystem
from .spring import SpringSystem
from .transform import RenderOrigin, RenderOriginSystem, TransformSystem, render_origin

__all__ = ["FlyCameraSystem", "InputState", "MotionSystem", "OrbitSystem", "RenderOrigin", "RenderOriginSystem", "SnapshotSystem", "SpringSystem",
           "TransformSystem",
           "render_origin"]
