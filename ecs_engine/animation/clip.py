"""Clips as the world plays them: each channel a target (the id of a path of names below a
character's root, `target_id`), a property (translation, rotation or scale of its Transform)
and a Curve. Held by the AnimationClips resource, whose handles AnimationPlayer.clip names.
Binding by names, not entity ids, is what lets one clip play on many characters."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ecs_engine.components.animation import EVENT_NAME_LENGTH

from ..errors import UsageError
from .sampling import Curve

PROPERTIES = ("translation", "rotation", "scale", "weights")  # weights: MorphWeights' (morph targets)
_FNV_OFFSET, _FNV_PRIME, _MASK = 0xCBF29CE484222325, 0x100000001B3, (1 << 64) - 1


def target_id(path: str) -> int:
    """A stable 64-bit id of a path of names ("Armature/Hips/Spine"): FNV-1a of its UTF-8 bytes
    (the same in every run and process, unlike Python's hash)."""
    h = _FNV_OFFSET
    for byte in path.encode("utf-8"):
        h = ((h ^ byte) * _FNV_PRIME) & _MASK
    return h


@dataclass(frozen=True)
class ClipChannel:
    target: int  # target_id of the path it animates
    property: str  # translation, rotation or scale
    curve: Curve


@dataclass(frozen=True)
class ClipEvent:
    time: float  # seconds into the clip
    name: str


@dataclass(frozen=True)
class AnimationClip:
    name: str
    channels: tuple[ClipChannel, ...]
    events: tuple[ClipEvent, ...] = ()  # marks a player passing them sends as AnimationEvents, by time

    @property
    def duration(self) -> float:
        return max((c.curve.duration for c in self.channels), default=0.0)


class AnimationClips:
    """The world's clips (a resource): `add` gives the handle AnimationPlayer.clip takes."""

    def __init__(self) -> None:
        self.clips: list[AnimationClip] = []

    def add(self, clip: AnimationClip) -> int:
        for channel in clip.channels:
            if channel.property not in PROPERTIES:
                raise ValueError(
                    f"clip {clip.name!r}: a channel animates {channel.property!r}, not one of {PROPERTIES}"
                )
        self.clips.append(clip)
        return len(self.clips) - 1

    def mark(self, handle: int, time: float, name: str) -> None:
        """Mark clip `handle` at `time` seconds: a player passing that time sends an
        AnimationEvent named `name` (at most EVENT_NAME_LENGTH characters)."""
        clip = self[handle]
        if not (isinstance(time, int | float) and 0.0 <= time <= clip.duration):
            raise UsageError(f"clip {clip.name!r}: a mark's time must be within 0 to {clip.duration:g} s, not {time!r}")
        if not isinstance(name, str) or not 0 < len(name) <= EVENT_NAME_LENGTH:
            raise UsageError(f"clip {clip.name!r}: a mark's name must be 1 to {EVENT_NAME_LENGTH} characters: {name!r}")
        events = tuple(sorted((*clip.events, ClipEvent(float(time), name)), key=lambda e: e.time))
        self.clips[handle] = replace(clip, events=events)

    def __getitem__(self, handle: int) -> AnimationClip:
        return self.clips[handle]

    def __len__(self) -> int:
        return len(self.clips)

    def durations(self) -> np.ndarray:
        return np.array([c.duration for c in self.clips], np.float64)
