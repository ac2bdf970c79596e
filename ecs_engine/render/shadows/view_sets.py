"""Each shadow view's set 0, per frame slot: the frame's set copied but for the globals, which
hold the light's matrices, so the render path's shaders draw from the light unchanged
(shadow_pass.py). Apart from the pass for size: the pool, the copies and their versions."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ...gpu.descriptors import DescriptorPool, DescriptorSetLayout, write_buffers
from ...gpu.device import Device
from ...gpu.memory import Buffer
from ...gpu.owned import Owned
from ..layouts import BINDING_GLOBALS, GLOBALS


@dataclass
class ViewSet:
    """A shadow view's set 0 in one frame slot: the frame's set copied, its own globals."""

    globals: Buffer
    descriptor_set: Any
    set_array: Any  # VkDescriptorSet[1], for raw calls
    copied: tuple[Any, int] | None = None  # (frame set, its version) last copied from
    holds: Any = None  # the ShadowView its globals were last written for

    def hold(self, view: Any) -> None:
        """Its globals say `view`'s matrices (written only for a new view: a plan kept from the
        last frame holds the same ones)."""
        if self.holds is not view:
            g = self.globals.array(GLOBALS.dtype, 1)
            g[...] = 0
            g["projection"] = view.projection.T
            g["view"] = view.view.T
            self.holds = view


class ShadowViewSets:
    def __init__(self, device: Device, set_layout: DescriptorSetLayout, frames: int) -> None:
        self.device, self.set_layout, self.frames = device, set_layout, frames
        self.pool: DescriptorPool | None = None
        self.owned = Owned(device)  # the pool and the sets' globals, made again when the pool grows
        self._sets: list[list[ViewSet]] = [[] for _ in range(frames)]
        self._pool_sets = 0  # view sets the pool holds per frame slot

    def ensure(self, slot: int, views: int, frame_set: Any, set_version: int) -> list[ViewSet]:
        """`views` sets of `slot`, each a copy of `frame_set` as of `set_version` (copied again
        only when the frame's set was written since)."""
        vk = self.device.vk
        sets = self._sets[slot]
        while len(sets) < views:
            if self.pool is None or len(sets) >= self._pool_sets:
                self._grow_pool(views)
                sets = self._sets[slot]
                continue
            descriptor_set = self.pool.allocate(self.set_layout)
            globals_buffer = self.owned.add(Buffer(self.device, GLOBALS.size, vk.VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT))
            write_buffers(
                self.device, descriptor_set, [(BINDING_GLOBALS, vk.VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, globals_buffer)]
            )
            sets.append(ViewSet(globals_buffer, descriptor_set, vk.ffi.new("VkDescriptorSet[1]", [descriptor_set])))
        stale = [s.descriptor_set for s in sets[:views] if s.copied != (frame_set, set_version)]
        if stale:
            # the frame's set copied whole but for the globals (a driver may read every binding a
            # shader declares, used or not: lavapipe crashed on unwritten ones); at 4 views this
            # cost ~0.2 ms a frame when done every frame, so only after the frame's set changed
            copies = [
                vk.VkCopyDescriptorSet(srcSet=frame_set, srcBinding=b, dstSet=dst, dstBinding=b, descriptorCount=n)
                for dst in stale
                for b, _, _, n in self.set_layout.bindings
                if b != BINDING_GLOBALS
            ]
            self.device.objects_version += 1
            vk.vkUpdateDescriptorSets(self.device.handle, 0, None, len(copies), copies)
            for s in sets[:views]:
                s.copied = (frame_set, set_version)
        return sets

    def _grow_pool(self, views: int) -> None:
        """A pool for `views` sets per frame slot (the old sets go: the device is waited for)."""
        self.device.wait_idle()
        self.destroy()
        per_slot = max(8, views)
        count = per_slot * self.frames
        sizes: dict[int, int] = {}
        for _, kind, _, n in self.set_layout.bindings:
            sizes[kind] = sizes.get(kind, 0) + count * n
        self.pool = self.owned.add(DescriptorPool(self.device, count, sizes))
        self._pool_sets = per_slot

    def destroy(self) -> None:
        self.owned.destroy()  # the globals, then the pool (their sets with it)
        self._sets = [[] for _ in range(self.frames)]
        self.pool = None
