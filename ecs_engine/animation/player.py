"""AnimationSystem: each frame every AnimationPlayer's time moves on (looping or stopping at the
clip's end), then every AnimationTarget's Transform takes its clip's curves at its player's
time. In bulk: per table of targets and per clip, the rows are sorted by target id once and each
channel finds its rows by binary search and samples all of them in one call."""

from __future__ import annotations

from typing import Any

import numpy as np

from ecs_engine.components import Transform
from ecs_engine.components.animation import AnimationPlayer, AnimationTarget
from ecs_engine.ecs.schedule import System, any_with

from ..errors import UsageError
from .clip import AnimationClips

_COLUMNS = {"translation": "position", "rotation": "rotation", "scale": "scale"}


class AnimationSystem(System):
    def __init__(self) -> None:
        super().__init__(
            reads=[AnimationClips, AnimationTarget],
            writes=[AnimationPlayer, Transform],
            name="animation",
            run_if=any_with(AnimationPlayer),
        )

    def run(self, world: Any, dt: float) -> None:
        clips = world.resources.get(AnimationClips)
        if clips is None:
            return
        players, clip_of, time_of = advance(world, clips, dt)
        if not len(players):
            return
        order = np.argsort(players)
        players, clip_of, time_of = players[order], clip_of[order], time_of[order]
        for batch in world.query(AnimationTarget, Transform):
            target = batch[AnimationTarget]
            at = np.minimum(np.searchsorted(players, target.player), len(players) - 1)
            found = players[at] == target.player
            row_clip = np.where(found, clip_of[at], -1)
            if (row_clip < 0).all():
                continue
            transform = batch[Transform]
            for c in np.unique(row_clip[row_clip >= 0]).tolist():
                rows = np.flatnonzero(row_clip == c)
                ids = target.id[rows]
                by_id = np.argsort(ids, kind="stable")
                rows, ids = rows[by_id], ids[by_id]
                times = time_of[at[rows]]
                for channel in clips[c].channels:
                    key = np.uint64(channel.target)
                    lo, hi = int(np.searchsorted(ids, key, "left")), int(np.searchsorted(ids, key, "right"))
                    if hi > lo:
                        column = getattr(transform, _COLUMNS[channel.property])
                        column[rows[lo:hi]] = channel.curve.sample(times[lo:hi])


def advance(world: Any, clips: AnimationClips, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every player's time moved on by `dt` x speed while playing: wrapped into the clip when
    looping, else held at its end (or start, played backwards), where it stops. The players'
    entities, clips and times (those with a clip)."""
    durations = clips.durations()
    entities, clip_of, time_of = [], [], []
    for batch in world.query(AnimationPlayer):
        p = batch[AnimationPlayer]
        clip = p.clip.astype(np.int64)
        if len(clips) <= clip.max(initial=-1):
            row = int(np.argmax(clip >= len(clips)))
            raise UsageError(
                f"entity {int(batch.entities[row])}: AnimationPlayer.clip is {int(clip[row])}, "
                f"but the world's AnimationClips holds {len(clips)} clips"
            )
        valid = clip >= 0
        length = np.where(valid, durations[np.maximum(clip, 0)] if len(durations) else 0.0, 0.0)
        moving = valid & p.playing
        t = p.time + np.where(moving, p.speed * dt, 0.0)
        wrap = moving & p.looping & (length > 0.0)
        t = np.where(wrap, np.mod(t, np.where(length > 0.0, length, 1.0)), t)
        hold = valid & ~p.looping
        ended = moving & hold & (((p.speed > 0) & (t >= length)) | ((p.speed < 0) & (t <= 0.0)))
        t = np.where(hold, np.clip(t, 0.0, length), t)
        p.time = t
        if ended.any():
            p.playing = p.playing & ~ended
        entities.append(batch.entities[valid])
        clip_of.append(clip[valid])
        time_of.append(t[valid])
    if not entities:
        return np.empty(0, np.int64), np.empty(0, np.int64), np.empty(0)
    return np.concatenate(entities), np.concatenate(clip_of), np.concatenate(time_of)
