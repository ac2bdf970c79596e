"""A glTF file's animations as clips: each channel a node's translation, rotation, scale or
morph weights over time, its sampler read into a Curve (animation/sampling.py). Everything
the specification requires of a sampler is checked here, so a clip that loads samples
cleanly: times finite, at least 0 and strictly increasing; as many values as keys (three a key
for CUBICSPLINE: in-tangent, value, out-tangent; times the morph targets for weights); the
value type of the path; a node that exists."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ....animation.clip import AnimationClip, ClipChannel, target_id
from ....animation.sampling import CUBICSPLINE, INTERPOLATIONS, LINEAR, Curve

__all__ = ["Channel", "Clip", "read_clips"]

PATHS = {"translation": (3,), "rotation": (4,), "scale": (3,), "weights": ()}


@dataclass(frozen=True)
class Channel:
    node: int  # the glTF node it animates
    path: str  # translation, rotation, scale or weights
    curve: Curve


@dataclass(frozen=True)
class Clip:
    name: str
    channels: tuple[Channel, ...]

    @property
    def duration(self) -> float:
        """The last key of any channel (seconds)."""
        return max((c.curve.duration for c in self.channels), default=0.0)


def read_clips(document: Any) -> list[Clip]:
    """Every animation of the document (a GltfDocument), in file order."""
    return [_clip(document, i, a) for i, a in enumerate(document.items("animations"))]


def _clip(document: Any, index: int, animation: Any) -> Clip:
    here = f"animations[{index}]"
    if not isinstance(animation, dict):
        raise document.error(here, "is not an object")
    samplers, channels = animation.get("samplers"), animation.get("channels")
    if not isinstance(samplers, list) or not isinstance(channels, list) or not channels:
        raise document.error(here, "needs arrays of samplers and channels (at least one channel)")
    curves: dict[tuple[int, str, int], Curve] = {}
    out = []
    for c, channel in enumerate(channels):
        at = f"{here}.channels[{c}]"
        if not isinstance(channel, dict) or not isinstance(channel.get("target"), dict):
            raise document.error(at, "is not an object with a target")
        target = channel["target"]
        if "node" not in target:  # (the specification lets an extension name the target instead)
            continue
        node = document.number(target, "node", f"{at}.target")
        document.item("nodes", node, f"{at}.target.node")
        path = target.get("path")
        if path not in PATHS:
            raise document.error(f"{at}.target.path", f"is {path!r}, not one of {', '.join(PATHS)}")
        sampler = document.number(channel, "sampler", at)
        if sampler >= len(samplers):
            raise document.error(f"{at}.sampler", f"is {sampler}, not one of the animation's {len(samplers)} samplers")
        key = (sampler, path, _targets(document, node) if path == "weights" else 0)
        if key not in curves:
            curves[key] = _curve(document, samplers[sampler], f"{here}.samplers[{sampler}]", path, key[2])
        out.append(Channel(node, path, curves[key]))
    return Clip(str(animation.get("name", f"animation{index}")), tuple(out))


def _targets(document: Any, node: int) -> int:
    """How many morph targets node `node`'s mesh has (its weights' count)."""
    entry = document.item("nodes", node, "node")
    if "mesh" not in entry:
        raise document.error(f"nodes[{node}]", "has morph weights animated but no mesh")
    primitives = document.item("meshes", entry["mesh"], f"nodes[{node}].mesh").get("primitives", [])
    targets = primitives[0].get("targets", []) if primitives and isinstance(primitives[0], dict) else []
    if not targets:
        raise document.error(f"nodes[{node}]", "has morph weights animated but its mesh has no morph targets")
    return len(targets)


def _curve(document: Any, sampler: Any, here: str, path: str, targets: int) -> Curve:
    if not isinstance(sampler, dict):
        raise document.error(here, "is not an object")
    interpolation = sampler.get("interpolation", LINEAR)
    if interpolation not in INTERPOLATIONS:
        raise document.error(f"{here}.interpolation", f"is {interpolation!r}, not one of {', '.join(INTERPOLATIONS)}")
    times = document.accessor(document.number(sampler, "input", here), f"{here}.input")
    if times.ndim != 1 or times.dtype.kind != "f":
        raise document.error(f"{here}.input", "is not an accessor of float scalars (times in seconds)")
    times = times.astype(np.float64)
    if times[0] < 0.0:
        raise document.error(f"{here}.input", f"starts at {times[0]}, before 0 s")
    steps = np.diff(times)
    if (steps <= 0.0).any():
        k = int(np.flatnonzero(steps <= 0.0)[0]) + 1
        raise document.error(f"{here}.input", f"times do not increase at key {k} ({times[k]} after {times[k - 1]})")
    values = document.accessor(document.number(sampler, "output", here), f"{here}.output")
    shape = PATHS[path] if path != "weights" else (targets,)
    per_key = 3 if interpolation == CUBICSPLINE else 1
    element = int(np.prod(shape))
    if values.dtype.kind != "f" or values.size != len(times) * per_key * element:
        raise document.error(
            f"{here}.output",
            f"holds {values.size} {values.dtype} numbers; {path} with {len(times)} {interpolation} keys needs "
            f"{len(times) * per_key * element} floats",
        )
    values = values.astype(np.float64).reshape(len(times), per_key, *shape)
    rotation = path == "rotation"
    if rotation:
        length = np.linalg.norm(values[:, per_key // 2], axis=-1)
        if (length < 1e-6).any():
            raise document.error(f"{here}.output", "has a rotation key of length 0 (not a quaternion)")
        values[:, per_key // 2] /= length[:, None]
    if per_key == 1:
        return Curve(times, values[:, 0], interpolation, rotation)
    return Curve(times, values[:, 1], interpolation, rotation, values[:, 0], values[:, 2])


def animation_clip(clip: Clip, paths: dict[int, str]) -> AnimationClip:
    """A file's clip bound by names (`paths`: glTF node index -> its path of names in the scene),
    as AnimationClips holds it; channels of nodes outside the scene are left out."""
    channels = tuple(ClipChannel(target_id(paths[c.node]), c.path, c.curve) for c in clip.channels if c.node in paths)
    return AnimationClip(clip.name, channels)
