"""AnimationSystem: each frame every AnimationPlayer's time moves on (looping or stopping at the
clip's end), then every AnimationTarget's Transform takes its clip's curves at its player's
time. In bulk: per table of targets and per clip, the rows are sorted by target id once and each
channel finds its rows by binary search and samples all of them in one call.

A cross-fade (`crossfade`) plays the clip it left too, at full weight first, then blends the new
clip over it by the fade's progress (positions and scales linearly, rotations by slerp). As in
Bevy's blending, a value only one of the two clips animates is that clip's alone: a target only
the old clip moves keeps its last pose when the fade ends, one only the new clip moves takes its
pose at once."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ecs_engine.components import Transform
from ecs_engine.components.animation import AnimationPlayer, AnimationTarget
from ecs_engine.ecs.schedule import System, any_with

from ..errors import UsageError
from .clip import AnimationClip, AnimationClips
from .sampling import slerp

_COLUMNS = {"translation": "position", "rotation": "rotation", "scale": "scale"}


@dataclass
class _Players:
    """The players that play something, sorted by entity: their clip and time, the clip they
    fade from (-1: none) and its time, and the new clip's weight."""

    entity: np.ndarray
    clip: np.ndarray
    time: np.ndarray
    from_clip: np.ndarray
    from_time: np.ndarray
    weight: np.ndarray


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
        players = advance(world, clips, dt)
        if not len(players.entity):
            return
        for batch in world.query(AnimationTarget, Transform):
            target = batch[AnimationTarget]
            at = np.minimum(np.searchsorted(players.entity, target.player), len(players.entity) - 1)
            found = players.entity[at] == target.player
            if not found.any():
                continue
            transform = batch[Transform]
            # per column, the rows the clips faded from wrote this frame (the new clip blends over those)
            written = {name: np.zeros(len(found), bool) for name in _COLUMNS.values()}
            from_clip = np.where(found, players.from_clip[at], -1)
            for c in np.unique(from_clip[from_clip >= 0]).tolist():  # the clips faded from, at full weight
                rows = np.flatnonzero(from_clip == c)
                _apply(transform, rows, target.id[rows], players.from_time[at[rows]], clips[c], None, written)
            clip = np.where(found, players.clip[at], -1)
            for c in np.unique(clip[clip >= 0]).tolist():
                rows = np.flatnonzero(clip == c)
                weight = players.weight[at[rows]]
                _apply(transform, rows, target.id[rows], players.time[at[rows]], clips[c], weight, written)


def _apply(
    transform: Any,
    rows: np.ndarray,
    ids: np.ndarray,
    times: np.ndarray,
    clip: AnimationClip,
    weight: Any,
    written: dict[str, np.ndarray],
) -> None:
    """`clip` at `times` into the Transform rows `rows` (whose target ids are `ids`). With
    `weight` (None: a clip faded from, which marks what it writes in `written`), blended by it
    over what a clip faded from wrote this frame, and written outright where none did."""
    order = np.argsort(ids, kind="stable")
    rows, ids, times = rows[order], ids[order], times[order]
    faded_from = weight is None
    blend = not faded_from and bool((weight < 1.0).any())
    if blend:
        weight = weight[order]
    for channel in clip.channels:
        key = np.uint64(channel.target)
        lo, hi = int(np.searchsorted(ids, key, "left")), int(np.searchsorted(ids, key, "right"))
        if hi == lo:
            continue
        name = _COLUMNS[channel.property]
        column, here = getattr(transform, name), rows[lo:hi]
        value = channel.curve.sample(times[lo:hi])
        if faded_from:
            written[name][here] = True
        elif blend:
            w = np.where(written[name][here], weight[lo:hi], 1.0)  # a target the old clip left alone: the new one's
            now = column[here]
            value = slerp(now, value, w) if name == "rotation" else now + (value - now) * w[:, None]
        column[here] = value


def crossfade(world: Any, player: int, clip: int, seconds: float, time: float = 0.0) -> None:
    """Make `player` (an entity with AnimationPlayer) play `clip` from `time`, blending from what
    it plays now over `seconds` (0: at once). A fade begun during another starts from the clip
    it was fading to."""
    if not (np.isfinite(seconds) and seconds >= 0.0):
        raise UsageError(f"crossfade: seconds must be a finite number of at least 0, got {seconds!r}")
    now = world.get(player, AnimationPlayer)
    fading = seconds > 0.0 and int(now.clip) >= 0
    world.set(
        player,
        AnimationPlayer,
        clip=clip,
        time=time,
        playing=True,
        from_clip=int(now.clip) if fading else -1,
        from_time=float(now.time) if fading else 0.0,
        fade=seconds if fading else 0.0,
        faded=0.0,
    )


def advance(world: Any, clips: AnimationClips, dt: float) -> _Players:
    """Every player's times moved on by `dt` x speed while playing (the clip faded from as well):
    wrapped into the clip when looping, else held at its end (or start, played backwards), where
    it stops; a fade's progress moved on, and ended when complete."""
    durations = clips.durations()
    parts: list[tuple[np.ndarray, ...]] = []
    for batch in world.query(AnimationPlayer):
        p = batch[AnimationPlayer]
        clip, from_clip = p.clip.astype(np.int64), p.from_clip.astype(np.int64)
        for name, handles in (("clip", clip), ("from_clip", from_clip)):
            if len(clips) <= handles.max(initial=-1):
                row = int(np.argmax(handles >= len(clips)))
                raise UsageError(
                    f"entity {int(batch.entities[row])}: AnimationPlayer.{name} is {int(handles[row])}, "
                    f"but the world's AnimationClips holds {len(clips)} clips"
                )
        t, ended = _moved(p.time, clip, p, durations, dt)
        p.time = t
        fading = from_clip >= 0
        weight = np.ones(len(clip))
        if fading.any():
            before, _ = _moved(p.from_time, from_clip, p, durations, dt)
            faded = np.where(fading, p.faded + np.where(p.playing, dt, 0.0), 0.0)
            done = fading & (faded >= p.fade)
            weight = np.where(fading & ~done, faded / np.where(p.fade > 0.0, p.fade, 1.0), 1.0)
            p.from_time, p.faded = before, faded
            from_clip = np.where(done, -1, from_clip)
            if done.any():
                p.from_clip = from_clip
        if ended.any():
            p.playing = p.playing & ~ended
        valid = clip >= 0
        here = (batch.entities, clip, t, from_clip, p.from_time, weight)
        parts.append(tuple(c[valid] for c in here))
    if not parts:
        empty = np.empty(0, np.int64)
        return _Players(empty, empty, np.empty(0), empty, np.empty(0), np.empty(0))
    columns = [np.concatenate(c) for c in zip(*parts)]
    order = np.argsort(columns[0])
    return _Players(*(c[order] for c in columns))


def _moved(time: np.ndarray, clip: np.ndarray, p: Any, durations: np.ndarray, dt: float) -> tuple[np.ndarray, ...]:
    """Times of `clip` moved on by dt x speed while playing, and which of them ended (not looping)."""
    valid = clip >= 0
    length = np.where(valid, durations[np.maximum(clip, 0)] if len(durations) else 0.0, 0.0)
    moving = valid & p.playing
    t = time + np.where(moving, p.speed * dt, 0.0)
    wrap = moving & p.looping & (length > 0.0)
    t = np.where(wrap, np.mod(t, np.where(length > 0.0, length, 1.0)), t)
    hold = valid & ~p.looping
    ended = moving & hold & (((p.speed > 0) & (t >= length)) | ((p.speed < 0) & (t <= 0.0)))
    return np.where(hold, np.clip(t, 0.0, length), t), ended
