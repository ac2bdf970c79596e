"""Stock component schemas. Declare your own the same way: subclass Component, add Fields."""

from .camera import ORTHOGRAPHIC, PERSPECTIVE, Camera
from .light import PointLight
from .mesh import Mesh
from .motion import AngularVelocity, Velocity
from .transform import ModelMatrix, Transform

__all__ = [
    "ORTHOGRAPHIC",
    "PERSPECTIVE",
    "AngularVelocity",
    "Camera",
    "Mesh",
    "ModelMatrix",
    "PointLight",
    "Transform",
    "Velocity",
]
