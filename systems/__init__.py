"""Stock systems: the fixed step's snapshot for interpolation, motion, springs, orbits, the fly
camera, the render origin, the transform (matrices) and the hierarchy (parents' transforms); the
input resources they and games read (InputState, ActionMap)."""

from .action_map import ActionMap, InputConfigError
from .camera_control import FlyCameraSystem
from .hierarchy import HierarchySystem
from .input_state import InputState
from .interpolation import SnapshotSystem
from .motion import MotionSystem
from .orbit import OrbitSystem
from .spring import SpringSystem
from .transform import RenderOriginSystem, TransformSystem

__all__ = [
    "ActionMap",
    "FlyCameraSystem",
    "HierarchySystem",
    "InputConfigError",
    "InputState",
    "MotionSystem",
    "OrbitSystem",
    "RenderOriginSystem",
    "SnapshotSystem",
    "SpringSystem",
    "TransformSystem",
]
