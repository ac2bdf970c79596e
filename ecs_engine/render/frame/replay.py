"""Frames submitted again instead of recorded again.

Most frames record what the frame before recorded: the rows move (they are data in the mapped
instance buffer), the draws do not. The CPU-recorded instanced path's draws depend only on how
many visible rows each (mesh, winding) run of a chunk has, and the primary's passes only on the
target, the settings and a few counts. So each frame slot keeps what its primary was last recorded
from (`Recorded`); the next frame on that slot whose key is the same leaves the slot's
secondaries alone (no pool reset), and its chunk jobs cull and write their rows (unless the slot's
rows were written from the same chunk, model tick and planes: chunk_paths.py's `written_from`) but
give back the chunk's old secondary when the run counts are those it was recorded with
(chunk_paths.py's `_recorded`). When every chunk did, the slot's primary is submitted as it
stands (gpu/frames.py's `resubmit`): no recording at all. When some chunk recorded anew, the
primary is recorded again around old and new secondaries, and the slot starts clean next time.

What a recording depends on goes into the key; anything else makes the frame record as before:
- the device's `objects_version`, bumped by every buffer, image, framebuffer or pipeline made,
  every buffer, image or descriptor pool destroyed, every descriptor set written (a command
  buffer is invalid once a set it binds is written) and the worker threads' command pools
  destroyed (a resized pool);
- the path object (a switched mode or recorder, or pipelines made again, is a new path), the
  target's state object (both held and compared by identity: an id could be a freed object's),
  its form and swapchain remakes, the mesh registry's version (meshes added or replaced);
- the counts and settings the primary records: billboards, light size, tone map and exposure,
  material features, the sky, the read-back, the clustered lights' grid, whether the shadow maps
  were cleared once, and the post effects' keys (which are on, their settings).

Frames that always record: a path that is not `replayable` (per_entity pushes each row's data;
indirect records its own passes), an overlay (the UI draws anew each frame), shadow maps drawn
(their views' jobs), ray-traced shadows, and blended rows (sorted each frame).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ..draw.path import ChunkResult

Key = tuple[Any, ...]


class Same:
    """A key's part that equals only the same object (held: an id could be a freed one's)."""

    __slots__ = ("obj",)

    def __init__(self, obj: Any) -> None:
        self.obj = obj

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Same) and other.obj is self.obj

    __hash__ = None  # type: ignore[assignment]


@dataclass
class Recorded:
    """What one slot's primary was last recorded from."""

    key: Key
    executed: list[ChunkResult]  # the chunks' results whose secondaries it executes, in order
    kept: dict[int, ChunkResult]  # by a chunk's first row (its `recorded` says from what)
    light_draws: int


class FrameReplay:
    def __init__(self, slots: int) -> None:
        self.enabled = True  # False: every frame is recorded (the bench's comparison)
        self._recorded: list[Recorded | None] = [None] * slots
        self.replayed = 0  # frames submitted again
        self.recorded = 0  # frames recorded

    def offer(self, slot: int, key: Key | None) -> dict[int, ChunkResult] | None:
        """Before the chunk jobs: the slot's kept chunks (FrameInputs.reuse) when its last frame
        had this key (the caller then keeps the slot's secondaries), else None (reset them)."""
        last = self._recorded[slot]
        if key is None or last is None or last.key != key or not self.enabled:
            self._recorded[slot] = None
            return None
        return last.kept

    def replay(self, slot: int, results: list[ChunkResult]) -> Recorded | None:
        """After the jobs of a frame that was offered its slot's chunks: the slot's recording
        when every chunk gave back its kept secondary (submit it again), else None. Then the
        primary is recorded again, and the slot starts clean next time (`keep` is not called)."""
        last = self._recorded[slot]
        assert last is not None
        executed = last.executed
        i = 0
        for r in results:
            if r.command_buffer is None:
                continue
            if i == len(executed) or executed[i] is not r:
                self._record_after(slot)
                return None
            i += 1
        if i != len(executed):
            self._record_after(slot)
            return None
        self.replayed += 1
        return last

    def _record_after(self, slot: int) -> None:
        """The frame offered its slot's chunks is recorded after all (and counted so)."""
        self._recorded[slot] = None
        self.recorded += 1

    def keep(self, slot: int, key: Key | None, results: list[ChunkResult], light_draws: int) -> None:
        """After a frame recorded whole (no chunk given back): what it was recorded from."""
        self.recorded += 1
        if key is None or not self.enabled:
            self._recorded[slot] = None
            return
        executed = [r for r in results if r.command_buffer is not None]
        kept = {r.recorded[0]: r for r in executed if r.recorded is not None}
        if len(kept) != len(executed):  # a chunk that cannot say what it recorded
            self._recorded[slot] = None
            return
        self._recorded[slot] = Recorded(key, executed, kept, light_draws)


def replay_key(renderer: Any, target: Any, positional: int, grid: Any, light_count: int, readback: bool) -> Key:
    """What this frame's primary records besides the chunks' secondaries (see the module), for a
    frame `replayable` allows."""
    output, form = renderer.output, renderer.target
    return (
        renderer.device.objects_version,
        Same(renderer.path),
        Same(target),
        form.form,
        getattr(form, "recreations", 0),
        renderer.meshes.version,  # meshes added or replaced: their buffers
        positional,
        output.light_pass.size,
        renderer.tone_map,
        renderer.exposure,
        renderer.material_features,
        renderer.environment.sky,
        readback,
        None if grid is None else (grid.tiles_x, grid.tiles_y, light_count),
        renderer.shadows.cleared,
        renderer.post_key(),  # the post effects on and their settings (post/effects.py)
    )


def replayable(renderer: Any, views: list[Any], traced: list[Any], forward: bool) -> bool:
    """Whether this frame may be submitted again later (see the module for those that may not)."""
    return (
        renderer.replay.enabled
        and getattr(renderer.path, "replayable", False)
        and renderer.overlay is None
        and not views
        and not traced
        and not forward
    )
