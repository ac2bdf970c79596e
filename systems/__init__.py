"""Stock systems: motion, transform (matrices), fly camera, orbits."""

from .camera_control import FlyCameraSystem, InputState
from .motion import MotionSystem
from .orbit import OrbitSystem
from .transform import RenderOrigin, RenderOriginSystem, TransformSystem, render_origin

__all__ = ["FlyCameraSystem", "InputState", "MotionSystem", "OrbitSystem", "RenderOrigin", "RenderOriginSystem", "TransformSystem",
           "render_origin"]
