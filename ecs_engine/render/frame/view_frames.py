"""Each camera view's own recording per frame slot, so that more views than slots still replay.

Frame replay (replay.py) resubmits a slot's primary when the slot's next frame has the key the
primary was recorded with. The views (views.py) take the slots in turn, so with more views than
slots a slot never draws the same view twice running and the one recording it holds is always
another view's: nothing replayed (0 of 148 view-frames, 4 views over 2 slots). So each view keeps,
per slot, what a slot's recording is made of, and lends it to the slot while its frame draws
there (`take`, just after the slot's fence was waited for; `give_back` after the frame):

- the primary and its command pool (gpu/frames.py's Frame: `pool`, `command_buffer`, its submit
  infos, which name the primary, and the timestamp marks it holds);
- the slot's secondaries' per-thread pools (gpu/secondary.py), which the chunks and the output
  passes record into and a replayed frame executes again;
- the slot's replay record (replay.py's `Recorded`).

The slot's fence, semaphores, query pool and buffers (FrameResources) stay the slot's: every
view's frame writes its rows, globals and lights into them again before its submit, after the
fence of the slot's last frame, whichever view's that was. One shortcut is undone: a chunk whose
rows in this slot were written from the same inputs skips writing them (chunk_paths.py's
`written_from`); where another view drew in the slot since, those rows are that view's, so the
view's kept chunks forget what they were written from (they write their rows, and still give
back their secondaries when the draws are the same).

A view's recordings are destroyed when the view goes (`drop`), after the device is idle (frames
in flight may execute them); the secondaries' pools of worker threads that are gone, when the
renderer's pool was resized (as the slots' own: gpu/secondary.py's keep_threads).

The frame ring, secondaries and replay are reached by their private parts here (`_submits`,
`_pools`, `_recorded`): what is lent and given back is exactly what those keep per slot."""

from __future__ import annotations

import threading
from typing import Any

from ...gpu.owned import Owned


class SlotRecording:
    """One view's recording in one frame slot: its primary (and pool), the secondaries' pools,
    the replay record and what the frame ring keeps of the primary (see the module)."""

    def __init__(self, device: Any) -> None:
        vk = device.vk
        self.owned = Owned(device)
        info = vk.VkCommandPoolCreateInfo(
            flags=vk.VK_COMMAND_POOL_CREATE_TRANSIENT_BIT, queueFamilyIndex=device.queue_family
        )
        # registered, not `create`d: a new pool leaves the other recordings valid (no version bump)
        self.pool = vk.vkCreateCommandPool(device.handle, info, None)
        self.owned.add(self.pool, lambda: vk.vkDestroyCommandPool(device.handle, self.pool, None))
        info = vk.VkCommandBufferAllocateInfo(
            commandPool=self.pool, level=vk.VK_COMMAND_BUFFER_LEVEL_PRIMARY, commandBufferCount=1
        )
        self.command_buffer = vk.vkAllocateCommandBuffers(device.handle, info)[0]
        self.plain_submit: Any = None  # the ring's submit info without semaphores, made for this primary
        self.submits: dict[tuple[int, int, int], Any] = {}  # and with them (FrameRing._submits' of the slot)
        self.passes: list[str] = []  # the timestamp marks the primary holds
        self.secondaries: dict[int, Any] = {}  # SecondaryBuffers' per-thread pools of the slot
        self.recorded: Any = None  # FrameReplay's record of the slot

    def destroy(self, device: Any) -> None:
        """After the device is idle."""
        for pool in self.secondaries.values():
            pool.destroy(device)  # (SecondaryBuffers' thread pools, lent to this view)
        self.secondaries.clear()
        self.owned.destroy()


class ViewRecordings:
    """The views' recordings (see the module): `owner` names the view whose frame draws next
    (None: the window's one camera, which keeps the slots' own)."""

    def __init__(self) -> None:
        self.views: dict[Any, list[SlotRecording | None]] = {}  # per view key, per slot
        self.owner: Any = None
        self.device: Any = None  # (its recordings')
        self._last: dict[int, Any] = {}  # per slot: the view whose frame drew there last
        self._lent: tuple[Any, int, SlotRecording, tuple[Any, ...]] | None = None  # take's: what to give back
        self._jobs = 0  # the renderer's worker pool generation the recordings' thread pools are of

    def take(self, r: Any, frame: Any) -> None:
        """Renderer `r`'s slot `frame` (its fence waited for) gets the owner's recording there
        (made on first use); nothing without an owner."""
        owner = self.owner
        if owner is None:
            return
        if r._jobs_generation != self._jobs:
            self._keep_threads(r)
        slot = frame.slot
        slots = self.views.setdefault(owner, [None] * len(r.frames.frames))
        rec = slots[slot]
        if rec is None:
            self.device = r.device
            rec = slots[slot] = SlotRecording(r.device)
        ring, pools, replay = r.frames, r.secondaries._pools, r.replay._recorded
        submits = {k: ring._submits.pop(k) for k in [k for k in ring._submits if k[0] == slot]}
        self._lent = (owner, slot, rec, (frame.pool, frame.command_buffer, frame.plain_submit, pools[slot], submits))
        frame.pool, frame.command_buffer, frame.plain_submit = rec.pool, rec.command_buffer, rec.plain_submit
        frame.passes = rec.passes  # (`acquire` read the last submit's marks already)
        pools[slot], replay[slot] = rec.secondaries, rec.recorded
        ring._submits.update(rec.submits)
        if self._last.get(slot, owner) != owner and rec.recorded is not None:
            for kept in rec.recorded.kept.values():  # the slot's rows are another view's now
                kept.written = None
        self._last[slot] = owner

    def give_back(self, r: Any) -> None:
        """The recording lent by `take` back to its view, the slot's own back to the slot (its
        replay record forgotten: the slot's rows are a view's now)."""
        lent, self._lent = self._lent, None
        if lent is None:
            return
        _, slot, rec, (pool, command_buffer, plain_submit, secondaries, submits) = lent
        frame, ring = r.frames.frames[slot], r.frames
        rec.plain_submit, rec.passes = frame.plain_submit, frame.passes  # frame.passes: the last submit's
        rec.secondaries, rec.recorded = r.secondaries._pools[slot], r.replay._recorded[slot]
        rec.submits = {k: ring._submits.pop(k) for k in [k for k in ring._submits if k[0] == slot]}
        frame.pool, frame.command_buffer, frame.plain_submit = pool, command_buffer, plain_submit
        r.secondaries._pools[slot], r.replay._recorded[slot] = secondaries, None
        ring._submits.update(submits)

    def _keep_threads(self, r: Any) -> None:
        """The pools of worker threads that are gone, destroyed (the renderer's own were, with the
        device idle, just before this frame's slot was waited for: Renderer._forget_old_threads)."""
        self._jobs = r._jobs_generation
        alive = {t.ident for t in threading.enumerate()}
        for rec in [rec for slots in self.views.values() for rec in slots if rec is not None]:
            for ident in [k for k in rec.secondaries if k not in alive]:
                rec.secondaries.pop(ident).destroy(r.device)

    def drop(self, r: Any, keep: set[Any]) -> None:
        """The recordings of views not in `keep`, once the device is idle."""
        gone = [key for key in self.views if key not in keep]
        if not gone:
            return
        r.device.wait_idle()  # frames in flight may execute them
        for key in gone:
            for rec in self.views.pop(key):
                if rec is not None:
                    rec.destroy(r.device)
        self._last = {slot: owner for slot, owner in self._last.items() if owner in keep}

    def destroy(self) -> None:
        """After the device is idle."""
        for slots in self.views.values():
            for rec in slots:
                if rec is not None:
                    rec.destroy(self.device)
        self.views.clear()
        self._last.clear()
