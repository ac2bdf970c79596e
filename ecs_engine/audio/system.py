"""AudioSystem: once a frame, after the hierarchy, every AudioSource's sound brought up to date.

In bulk, per table of sources (NumPy over the columns; Python per source only where one starts,
stops or pauses):
- the voices the mixer finished are given back, and their sources' `playing` cleared;
- a source playing without a voice starts one (a new source with `autoplay`, or one a system set
  `playing` on); a voice whose source stopped `playing`, changed its clip, or is gone (destroyed,
  or its AudioSource removed) is stopped;
- the listener is found (AudioListener, else the active camera, else the origin);
- every source's gains and pitch are worked out from the world poses (WorldMatrix for children,
  else Transform) and Velocity (spatial.py) and handed to the mixer in one command, with the
  spatial one-shots' (audio.play(at=...));
- a captured output mixes the frame's sound (outputs.py)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..components import Transform, Velocity
from ..components.audio import AudioListener, AudioSource
from ..components.camera import Camera
from ..components.hierarchy import WorldMatrix
from ..ecs.entities import INDEX_MASK
from ..ecs.errors import describe_entity
from ..ecs.schedule import System
from ..maths.transform import quat_to_mat3
from .audio import Audio
from .spatial import Listener, SourceColumns, heard_points, spatialize


class AudioSystem(System):
    """See the module."""

    def __init__(self) -> None:
        super().__init__(
            reads=[AudioSource, AudioListener, Transform, WorldMatrix, Velocity, Camera],
            writes=[AudioSource],
            name="audio",
        )
        self._voice = np.full(0, -1, np.int64)  # by entity index: its source's voice
        self._owner = np.full(0, -1, np.int64)  # by entity index: the entity that voice was started for
        self._clip = np.full(0, -1, np.int64)  # by entity index: the clip its voice plays
        self._paused = np.zeros(0, bool)
        self._seen = np.full(0, -1, np.int64)  # by entity index: the source already looked at (autoplay once)
        self._structure = -1  # the world's structure version when orphaned voices were last looked for

    def _fit(self, top: int) -> None:
        size = len(self._voice)
        if top < size:
            return
        grown = max(top + 1, 2 * size, 64)
        for name, fill in (("_voice", -1), ("_owner", -1), ("_clip", -1), ("_seen", -1), ("_paused", False)):
            column = getattr(self, name)
            wider = np.full(grown, fill, column.dtype)
            wider[:size] = column
            setattr(self, name, wider)

    def run(self, world: Any, dt: float) -> None:
        audio = world.resources.get(Audio)
        if audio is None:
            return
        if audio.notice is not None:
            print(audio.notice)
            audio.notice = None
        ended = audio.collect()
        mixer = audio.mixer
        listener = _listener(world)
        audio.listener = listener
        live_voices: list[np.ndarray] = []
        gains: list[np.ndarray] = []
        pitches: list[np.ndarray] = []
        clear: list[int] = []  # entities whose sound ended: playing cleared
        set_on: list[int] = []  # new autoplay sources: playing set
        ended_set = set(ended)
        for batch, place in _sources(world):
            ids = batch.entities
            if not len(ids):
                continue
            index = ids & INDEX_MASK
            self._fit(int(index.max()))
            src = batch[AudioSource]
            mine = self._owner[index] == ids
            voice = np.where(mine, self._voice[index], -1)
            if ended_set:  # voices the mixer finished: their sources stop playing
                done = np.isin(voice, list(ended_set))
                for row in np.flatnonzero(done):
                    self._voice[index[row]] = -1
                    if src.playing[row] and not src.loop[row]:
                        clear.append(int(ids[row]))
                voice = np.where(done, -1, voice)
            fresh = self._seen[index] != ids
            self._seen[index] = ids
            playing = np.where(fresh, src.autoplay | src.playing, src.playing)
            if clear:
                playing = playing & ~np.isin(ids, clear)
            changed = (voice >= 0) & (self._clip[index] != src.clip)
            for row in np.flatnonzero(((voice >= 0) & ~playing) | changed):  # stopped, or another clip
                mixer.stop(int(voice[row]))
                self._voice[index[row]] = voice[row] = -1
            for row in np.flatnonzero(fresh & playing & ~src.playing):
                set_on.append(int(ids[row]))
            starts = np.flatnonzero(playing & (voice < 0))
            left, right, factor = _gains(src, place, listener, audio.doppler_factor)
            for row in starts:
                clip = int(src.clip[row])
                if clip < 0:
                    continue
                problem = _unplayable(audio, clip, int(src.bus[row]))
                if problem:  # said once; the source stays silent, the game goes on
                    audio.say(f"{describe_entity(int(ids[row]))} AudioSource.{problem}")
                    continue
                bus = int(src.bus[row])
                v = audio.voice(int(ids[row]))
                gain = (float(left[row]), float(right[row]))
                mono = bool(src.spatial[row])
                mixer.start(v, clip, gain, float(src.pitch[row] * factor[row]), bool(src.loop[row]), mono, bus)
                voice[row] = self._voice[index[row]] = v
                self._owner[index[row]], self._clip[index[row]], self._paused[index[row]] = ids[row], clip, False
            rows = np.flatnonzero(voice >= 0)
            flips = rows[self._paused[index[rows]] != src.paused[rows]]
            for row in flips:
                mixer.pause(int(voice[row]), bool(src.paused[row]))
                self._paused[index[row]] = src.paused[row]
            live_voices.append(voice[rows])
            gains.append(np.c_[left[rows], right[rows]])
            pitches.append(src.pitch[rows] * factor[rows])
        if world.storage.structure_version != self._structure:  # a source destroyed, or its AudioSource gone?
            self._structure = world.storage.structure_version
            self._stop_orphans(audio, np.concatenate(live_voices) if live_voices else np.zeros(0, np.int64))
        shots = [(v, *audio.one_shots[v]) for v in audio.one_shots if audio.one_shots[v][0] is not None]
        if shots:
            voices, points, volume, pitch, near, far = (np.array(column) for column in zip(*shots))
            at = np.asarray(points, np.float64).reshape(-1, 3)
            left, right, factor = heard_points(listener, at, volume, near, far, audio.doppler_factor)
            live_voices.append(voices)
            gains.append(np.c_[left, right])
            pitches.append(pitch * factor)
        if live_voices:
            mixer.set(np.concatenate(live_voices), np.concatenate(gains), np.concatenate(pitches))
        if clear or set_on:
            _write_playing(world, clear, set_on)
        audio.advance(dt)

    def _stop_orphans(self, audio: Audio, kept: np.ndarray) -> None:
        """Stop the voices of sources that are gone (destroyed, or their AudioSource removed)."""
        owned = [v for v, owner in audio.owner.items() if owner >= 0]
        if not owned:
            return
        for v in np.setdiff1d(np.array(owned, np.int64), kept):
            owner = audio.owner[int(v)]
            if self._voice[owner & INDEX_MASK] == v and self._owner[owner & INDEX_MASK] == owner:
                self._voice[owner & INDEX_MASK] = -1
                audio.mixer.stop(int(v))
                audio.owner[int(v)] = -2  # stopping: given back when the mixer says so


def _unplayable(audio: Audio, clip: int, bus: int) -> str | None:
    """Why a source's clip or bus cannot play (the field and the reason), or None."""
    if clip >= audio.clip_count:
        return f"clip: {clip} is not a clip of the Audio resource (it has {audio.clip_count}): it stays silent"
    if bus >= len(audio.buses):
        return f"bus: {bus} is not a bus (there are {len(audio.buses)}: {', '.join(audio.buses)}): it stays silent"
    return None


def _listener(world: Any) -> Listener:
    """The listener's pose and velocity (see the module)."""
    for required in ((AudioListener, Transform), (Camera, Transform)):
        for batch in world.query(*required, write=()):
            if len(batch.entities):
                position, axes = _poses(batch, slice(0, 1))
                velocity = _column(batch, Velocity, "linear")
                moving = np.zeros(3) if velocity is None else np.array(velocity[0], np.float64)
                return Listener(position[0], axes[0, :, 0], -axes[0, :, 2], moving)
    return Listener.at_origin()


def _column(batch: Any, component: type, field: str) -> np.ndarray | None:
    """A column of the batch's table that its query does not name (the table may lack it: then
    None): the system reads WorldMatrix and Velocity where a source or listener has them."""
    column = batch.table.columns.get((component, field))
    return None if column is None else column[: len(batch.entities)]


def _poses(batch: Any, rows: Any, axes: bool = True) -> tuple[np.ndarray, Any]:
    """World positions (k, 3) and, with `axes`, unit axes ((k, 3, 3): columns right, up, back)
    of `rows` (else None)."""
    world = _column(batch, WorldMatrix, "matrix")
    if world is not None:
        matrix = world[rows]
        if not axes:
            return matrix[:, :3, 3], None
        turn = matrix[:, :3, :3]
        lengths = np.linalg.norm(turn, axis=1, keepdims=True)
        return matrix[:, :3, 3], turn / np.where(lengths > 0, lengths, 1.0)
    t = batch[Transform]
    return t.position[rows], quat_to_mat3(t.rotation[rows]) if axes else None


def _sources(world: Any) -> Any:
    """Each table of sources with the rows' world positions, forward axes and velocities."""
    for batch in world.query(AudioSource, Transform, write=()):
        n = len(batch.entities)
        if not n:
            continue
        src = batch[AudioSource]
        coned = bool(((src.cone_inner < 360.0) | (src.cone_outer < 360.0)).any())
        position, axes = _poses(batch, slice(0, n), axes=coned)  # no cone: no direction needed
        velocity = _column(batch, Velocity, "linear")
        velocity = np.zeros((n, 3)) if velocity is None else velocity
        forward = -axes[:, :, 2] if axes is not None else np.zeros((n, 3))
        yield batch, (position, forward, velocity)


def _gains(src: Any, place: tuple[np.ndarray, ...], listener: Listener, doppler: float) -> tuple[np.ndarray, ...]:
    """Left and right gains (before the bus) and Doppler factors of a table's sources."""
    position, forward, velocity = place
    columns = SourceColumns(
        position, forward, velocity, src.model, src.min_distance, src.max_distance, src.rolloff,
        src.cone_inner, src.cone_outer, src.cone_outer_gain,
    )  # fmt: skip
    left, right, factor = spatialize(listener, columns, doppler)
    flat = ~src.spatial
    volume = src.volume
    left = np.where(flat, volume, volume * left)
    right = np.where(flat, volume, volume * right)
    return left, right, np.where(flat, 1.0, factor)


def _write_playing(world: Any, clear: list[int], set_on: list[int]) -> None:
    for batch in world.query(AudioSource, write=(AudioSource,)):
        ids = batch.entities
        for wanted, value in ((clear, False), (set_on, True)):
            rows = np.flatnonzero(np.isin(ids, wanted))
            if len(rows):
                batch[AudioSource].playing[rows] = value
