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

What a recording depends on goes into the key (`frame_key`), taken before the jobs; anything
else makes the frame record as before. The key is the output frame graph's: the frame slot's
kept entry (passes/output_graph.py: the inputs its graph, imports and plan follow from, the graph
and its imports; held by identity, so the graph's compile, the extent and the imported images'
handles come with it) and each running pass's `key()` in order (render/graph/graph.py
`pass_keys()`), so a pass keys what it records from and one that forgets cannot replay a stale
frame; and a prelude of what is still recorded by hand outside the graph (`prelude_key`), which
shrinks as that work becomes passes:
- the device's `objects_version`, bumped by every buffer, image or pipeline made, every buffer,
  image or descriptor pool destroyed, every descriptor set written (a command buffer is invalid
  once a set it binds is written) and the worker threads' command pools destroyed (a resized
  pool): it stays beside the graph's key;
- the forward pass's secondaries, gathered outside the graph: the path object (a switched mode
  or recorder, or pipelines made again, is a new path; held and compared by identity), the mesh
  registry's version, the light billboards' count and size, the sky;
- the deferred lighting's material features, the read-back, the clustered lights' grid, whether
  the shadow maps were cleared once, a swapchain's remakes (its new images may reuse handles).
The tone map and exposure (`tone_map`), the post effects' keys (`post`, the ldr effects' own
passes), the target's form (`forward`, and the graph per form) and output image (the "target"
import) are the graph's.

Frames that always record: a path that is not `replayable` (per_entity pushes each row's data;
indirect records its own passes), shadow maps drawn (their views' jobs), ray-traced shadows and
blended rows (sorted each frame): `frame_key`'s `stops`; and a pass whose key is UNREPLAYABLE
(`graph.replayable()`): the overlay (the UI draws anew each frame), a post effect without a key.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ..draw.path import ChunkResult

Key = tuple[Any, ...]


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


def prelude_key(renderer: Any, positional: int, grid: Any, light_count: int, readback: bool) -> Key:
    """What a frame's recording depends on that no pass of the output graph keys yet (see the
    module): the device's objects, and the work recorded by hand before and after the graph.
    Each field leaves this list when the pass that records it joins the graph with its key()."""
    return (
        renderer.device.objects_version,  # the device's: stays beside the graph's key
        renderer.path,  # the chunks' secondaries (forward executes them; held, equal only to itself)
        renderer.meshes.version,  # the chunks' meshes: their buffers
        getattr(renderer.target, "recreations", 0),  # a remade swapchain's images may reuse handles
        positional,  # forward's light billboards (output_passes.py gathers its secondaries)
        renderer.output.light_pass.size,  # the billboards' too
        renderer.environment.sky,  # forward's sky secondary
        renderer.material_features,  # the deferred lighting (recorded before the graph)
        readback,  # the copy recorded after the graph (until a readback pass)
        None if grid is None else (grid.tiles_x, grid.tiles_y, light_count),  # light clusters (compute)
    )


def frame_key(renderer: Any, state: Any, slot: int, prelude: tuple[Any, ...], stops: tuple[Any, ...]) -> Key | None:
    """This frame's replay key: the prelude's (`prelude`: prelude_key's arguments) and the output
    graph's (OutputGraph.key_again: the slot's kept entry and the passes' keys, when the entry
    was made from this frame's inputs; else the graph prepared before the jobs, its shape,
    imports and the frame's settings, which the frame's recording reuses, and its keys then; a
    frame reading back keys as graph.key(): the passes' keys, the extent and the handles).
    None when the frame must record: the work outside the graph may not be submitted again
    (`stops`: the shadow views drawn, the traced lights, blended rows; a path that is not
    `replayable`: per_entity's, indirect's), or a pass returned UNREPLAYABLE. Run every frame:
    its few calls are kept few."""
    output = renderer.output
    outputs = output.graph
    if outputs is None:
        return None
    readback = prelude[-1]
    views, traced, forward = stops
    if (
        views
        or traced
        or forward
        or not renderer.replay.enabled
        or not getattr(renderer.path, "replayable", False)
        # a screenshot of a window's image records (asking prepare would take its readback request)
        or (readback and getattr(renderer.target, "readback_image", None) is not None)
    ):
        outputs.forget_prepared()  # an earlier frame's: this one records, and prepares anew
        return None
    tone_map, overlay = (renderer.tone_map, renderer.exposure), renderer.overlay
    # (key_again and prepare leave only this frame's prepared graph behind)
    key = False if readback else outputs.key_again(state, tone_map, overlay, slot)
    if key is False:  # the graph prepared now (kept for the frame's recording)
        graph = outputs.prepare(state, output._rendering(state), tone_map, overlay, slot, readback)
        key = graph.key(replayable=True) if readback else outputs.steady_key(slot)
    return None if key is None else (prelude_key(renderer, *prelude), key)
