"""Animation: keyframe curves sampled as glTF defines them (sampling.py)."""

from .sampling import CUBICSPLINE, INTERPOLATIONS, LINEAR, STEP, Curve

__all__ = ["CUBICSPLINE", "INTERPOLATIONS", "LINEAR", "STEP", "Curve"]
