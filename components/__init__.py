"""Stock component schemas. Declare your own the same way: subclass Component, add Fields."""

from .animation import AnimationPlayer, AnimationTarget
from .camera import (
    ORTHOGRAPHIC,
    PERSPECTIVE,
    ActiveCamera,
    Camera,
    RenderLayers,
    RenderOrigin,
    RenderTexture,
    Viewport,
    active_camera,
    render_origin,
)
from .camera_control import FlyCamera
from .camera_views import CameraView, camera_views
from .environment import Environment
from .hierarchy import Parent, WorldMatrix
from .light import DirectionalLight, PointLight, SpotLight
from .mesh import Mesh
from .motion import AngularVelocity, Spring, Velocity
from .name import Name
from .orbit import Orbit
from .shadow import NotShadowCaster, NotShadowReceiver, Shadow
from .transform import ModelMatrix, NormalMatrix, PreviousTransform, Transform

__all__ = [
    "ORTHOGRAPHIC",
    "PERSPECTIVE",
    "ActiveCamera",
    "AngularVelocity",
    "AnimationPlayer",
    "AnimationTarget",
    "Camera",
    "CameraView",
    "DirectionalLight",
    "Environment",
    "FlyCamera",
    "Mesh",
    "ModelMatrix",
    "Name",
    "NormalMatrix",
    "NotShadowCaster",
    "NotShadowReceiver",
    "Orbit",
    "Parent",
    "PointLight",
    "PreviousTransform",
    "RenderLayers",
    "RenderOrigin",
    "RenderTexture",
    "Shadow",
    "SpotLight",
    "Spring",
    "Transform",
    "Velocity",
    "Viewport",
    "WorldMatrix",
    "active_camera",
    "camera_views",
    "render_origin",
]
