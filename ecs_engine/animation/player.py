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
from ecs_engine.components.animation import AnimationEvent, AnimationPlayer, AnimationTarget, MorphWeights
from ecs_engine.components.hierarchy import Parent
from ecs_engine.ecs.gather import gather
from ecs_engine.ecs.schedule import System, any_with
from ecs_engine.jobs import JobPool

from ..errors import UsageError
from .clip import AnimationClip, AnimationClips, ClipChannel
from .sampling import slerp
from .write_linear import Write, write_all

_COLUMNS = {"translation": "position", "rotation": "rotation", "scale": "scale"}  # Transform's, by property
_TARGET_PLAYER, _TARGET_ID = (AnimationTarget, "player"), (AnimationTarget, "id")
_FULL = np.ones(0)  # the weights of rows none of whose players fades: each is 1 (no blend)


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


# per clip a group: (the rows that play it sorted by target id, per channel of the clip the
# (channel, first, end) of its rows among them)
_Group = tuple[np.ndarray, list[tuple[ClipChannel, int, int]]]


@dataclass
class _Binding:
    """Which Transform rows of a table each clip moves, channel by channel: kept while the table's
    rows, its AnimationTarget column, the players and what they play stay the same (a frame then
    only samples and writes)."""

    key: tuple[Any, ...]
    at: np.ndarray  # per row, its player's place in _Players (rows without one: any)
    faded: list[_Group]  # the clips faded from
    playing: list[_Group]
    # per group of `playing`, its rows' players' places (at[rows], gathered once)
    players_of: list[np.ndarray]


class AnimationSystem(System):
    def __init__(self) -> None:
        super().__init__(
            reads=[AnimationClips, AnimationTarget, Parent, JobPool],
            writes=[AnimationPlayer, Transform, AnimationEvent, MorphWeights],
            name="animation",
            run_if=any_with(AnimationPlayer),
        )
        self._bindings: dict[int, _Binding] = {}  # by table id

    def run(self, world: Any, dt: float) -> None:
        clips = world.resources.get(AnimationClips)
        if clips is None:
            return
        players = advance(world, clips, dt)
        pool = world.resources.get(JobPool)
        if not len(players.entity):
            return
        seen = set()
        for batch in world.query(AnimationTarget, Transform):
            table = batch.table
            seen.add(table.id)
            binding = self._binding(world, table, batch[AnimationTarget], players, clips)
            transform = batch[Transform]
            columns = {prop: getattr(transform, name) for prop, name in _COLUMNS.items()}
            self._play(binding, players, columns, len(batch), pool)
        if any(c.property == "weights" for clip in clips.clips for c in clip.channels):
            for batch in world.query(AnimationTarget, MorphWeights):  # the morph targets' weights
                kept = self._bindings.get(batch.table.id)
                if kept is not None:
                    self._play(kept, players, {"weights": batch[MorphWeights].weights}, len(batch), pool)
        weights_to_parts(world)
        for gone in set(self._bindings) - seen:
            del self._bindings[gone]

    @staticmethod
    def _play(binding: _Binding, players: _Players, columns: dict[str, np.ndarray], rows: int, pool: Any) -> None:
        """The binding's clips into `columns` (by channel property; channels of others wait for
        their own pass): the clips faded from, then those playing, blended over them. The
        writes at full weight (most of them) go last, together, over `pool`'s threads: each row
        plays one clip, so they touch rows no blend reads."""
        # per property, the rows the clips faded from wrote this frame (the new clip blends over those)
        written = {prop: np.zeros(rows, bool) for prop in columns} if binding.faded else {}
        writes: list[Write] = []
        for at, spans in binding.faded:  # at full weight
            _apply(columns, at, spans, players.from_time[binding.at[at]], None, written, writes)
        fading = bool((players.weight < 1.0).any())  # else no row blends: its weight is not gathered
        for (at, spans), of in zip(binding.playing, binding.players_of, strict=True):
            weight = players.weight[of] if fading else _FULL
            _apply(columns, at, spans, players.time[of], weight, written, writes)
        write_all(writes, pool)

    def _binding(self, world: Any, table: Any, target: Any, players: _Players, clips: AnimationClips) -> _Binding:
        key = (
            world.storage.structure_version,
            table.column_ticks[_TARGET_PLAYER],
            table.column_ticks[_TARGET_ID],
            players.entity.tobytes(),
            players.clip.tobytes(),
            players.from_clip.tobytes(),
            len(clips),
        )
        kept = self._bindings.get(table.id)
        if kept is not None and kept.key == key:
            return kept
        at = np.minimum(np.searchsorted(players.entity, target.player), len(players.entity) - 1)
        found = players.entity[at] == target.player
        groups = []
        for clip_of in (players.from_clip, players.clip):
            clip = np.where(found, clip_of[at], -1)
            handles = np.unique(clip[clip >= 0]).tolist()
            groups.append([_group(np.flatnonzero(clip == c), target.id, clips[c]) for c in handles])
        players_of = [at[rows] for rows, _ in groups[1]]
        made = self._bindings[table.id] = _Binding(key, at, groups[0], groups[1], players_of)
        return made


def _group(rows: np.ndarray, ids: np.ndarray, of: AnimationClip) -> _Group:
    """`rows` sorted by target id, and each channel of `of` with the span of those it targets."""
    order = np.argsort(ids[rows], kind="stable")
    rows = rows[order]
    sorted_ids = ids[rows]
    spans = []
    for channel in of.channels:
        key = np.uint64(channel.target)
        lo, hi = int(np.searchsorted(sorted_ids, key, "left")), int(np.searchsorted(sorted_ids, key, "right"))
        if hi > lo:
            spans.append((channel, lo, hi))
    return rows, spans


def _apply(
    columns: dict[str, np.ndarray],
    rows: np.ndarray,
    spans: list[tuple[ClipChannel, int, int]],
    times: np.ndarray,
    weight: Any,
    written: dict[str, np.ndarray],
    writes: list[Write],
) -> None:
    """A clip's channels (`spans` of `rows`) at `times` (per row) into `columns` (by property;
    a channel of another property is left). With `weight` (None: a clip faded from, which marks
    what it writes in `written`), blended by it over what a clip faded from wrote this frame, and
    written outright where none did. A clip at full weight over nothing faded leaves its
    writes in `writes` (write_all's), for the caller to make."""
    faded_from = weight is None
    blend = not faded_from and bool((weight < 1.0).any())
    for channel, lo, hi in spans:
        name = channel.property
        column = columns.get(name)
        if column is None:
            continue
        here = rows[lo:hi]
        if name == "weights":  # as many of the eight as the mesh has targets
            column = column[:, : channel.curve.values.shape[1]]
        if not faded_from and not blend:  # the usual case: sampled straight into the column
            writes.append((channel.curve, times[lo:hi], here, column))
            continue
        value = channel.curve.sample(times[lo:hi])
        if faded_from:
            written[name][here] = True
        elif blend:
            w = np.where(written[name][here], weight[lo:hi], 1.0)  # a target the old clip left alone: the new one's
            now = column[here]
            value = slerp(now, value, w) if name == "rotation" else now + (value - now) * w[:, None]
        column[here] = value


def weights_to_parts(world: Any) -> None:
    """A node of several primitives: its parts (children with MorphWeights and no target of
    their own) take the node's weights, as its channel (and layers) wrote them or a system set them."""
    for batch in world.query(Parent, MorphWeights, without=(AnimationTarget,)):
        weights, found = gather(world, batch[Parent].entity, MorphWeights, "weights")
        column = batch[MorphWeights].weights
        column[found] = weights[found]


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
    marked = any(clip.events for clip in clips.clips)  # else no player can pass a mark
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
        if marked:
            _send_events(world, clips, batch.entities, clip, p.time, t, p.speed * np.where(p.playing, dt, 0.0))
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


def _send_events(
    world: Any, clips: AnimationClips, players: np.ndarray, clip: np.ndarray, before: np.ndarray, after: np.ndarray,
    moved: np.ndarray,
) -> None:  # fmt: skip
    """An AnimationEvent for each mark a player's time passed this frame: within (before, after]
    going forwards, [after, before) backwards, round the end when the clip looped (`moved`: the
    time the player moved, signed)."""
    for c in np.unique(clip[(clip >= 0) & (moved != 0.0)]).tolist():
        events = clips[c].events
        if not events:
            continue
        rows = np.flatnonzero((clip == c) & (moved != 0.0))
        t0, t1, forward = before[rows], after[rows], moved[rows] > 0.0
        wrapped = np.where(forward, t1 < t0, t1 > t0)
        for event in events:
            e = event.time
            inside = np.where(forward, (t0 < e) & (e <= t1), (t1 <= e) & (e < t0))
            around = np.where(forward, (e > t0) | (e <= t1), (e < t0) | (e >= t1))
            passed = rows[np.where(wrapped, around, inside)]
            if len(passed):
                sent = AnimationEvent(player=players[passed], clip=c, name=event.name, time=e)
                world.events(AnimationEvent).send(sent)


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
