"""Animation: keyframe curves sampled as glTF defines them (sampling.py), clips bound to
entities by their names (clip.py), played by AnimationPlayer components (player.py)."""

from .clip import AnimationClip, AnimationClips, ClipChannel, ClipEvent, target_id
from .sampling import CUBICSPLINE, INTERPOLATIONS, LINEAR, STEP, Curve

__all__ = [
    "CUBICSPLINE",
    "INTERPOLATIONS",
    "LINEAR",
    "STEP",
    "AnimationClip",
    "AnimationClips",
    "ClipChannel",
    "ClipEvent",
    "Curve",
    "target_id",
]
