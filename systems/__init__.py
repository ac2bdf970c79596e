"""Stock systems: motion integration and the transform (matrix) system."""

from .motion import MotionSystem
from .transform import RenderOrigin, TransformSystem

__all__ = ["MotionSystem", "RenderOrigin", "TransformSystem"]
