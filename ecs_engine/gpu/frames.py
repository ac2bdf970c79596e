"""Frames in flight: per frame a command pool (reset whole), a primary command buffer, a fence,
swapchain semaphores and a timestamp query pool read back without waiting.

The frame's GPU time is two timestamps, at the primary's start and end. With `pass_timing` on
(the app's profiler turns it on while someone looks), the renderer also `mark`s the end of each
pass it records (a bottom-of-pipe timestamp: written once everything before it has finished),
so a pass's time is the span from the previous mark and the passes add up to the frame's time
(less what was recorded after the last mark). They are read with the frame's total, once its
fence has signalled (`last_gpu`).

A slot's primary is recorded without ONE_TIME_SUBMIT, so a frame that would record the same
commands again submits it as it stands (`resubmit`; render/frame/replay.py decides when).

The per-frame calls go straight to the cffi library (`vk.lib`) with structs and arrays made
once: the binding's wrappers cost ~3-4 us a call against ~0.7 us, and a small scene's whole CPU
frame budget is 250 us. Results are checked as the wrappers do (same exceptions)."""

from __future__ import annotations

import itertools
import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .device import Device

FRAMES_IN_FLIGHT = 2
MAX_PASSES = (
    64  # marks a frame may time (the culling steps mark one each); queries a slot holds: these, its start and its end
)


@dataclass
class GpuFrame:
    """One frame's GPU work as its timestamps saw it. `start_ns`: the device's clock at its start
    (ns, for placing it on the CPU's timeline: `submitted_ns` and `done_ns` are perf_counter_ns
    just before its submit and once its fence was seen signalled, so it ran between them);
    `passes`: (name, ms) in recorded order."""

    ms: float
    start_ns: int
    passes: list[tuple[str, float]]
    submitted_ns: int
    done_ns: int


@dataclass
class Frame:
    pool: Any
    command_buffer: Any
    fence: Any
    image_available: Any
    render_finished: Any
    queries: Any
    fence_array: Any = None  # VkFence[1] for the raw calls
    submitted: bool = False  # the query pool holds results of a submitted frame
    slot: int = 0  # its index in FrameRing.frames
    plain_submit: Any = None  # (VkSubmitInfo, its address) without semaphores (offscreen), made once
    passes: list[str] = field(default_factory=list)  # the marks its primary holds, in order
    submitted_ns: int = 0  # perf_counter_ns just before its last submit (pass timing only)


class FrameRing:
    def __init__(self, device: Device, count: int = FRAMES_IN_FLIGHT) -> None:
        vk = device.vk
        self.device = device
        self.frames: list[Frame] = []
        self.index = 0
        self.last_wait_ms = 0.0  # time begin() spent waiting for the GPU (not CPU work)
        bits = device.info.timestamp_valid_bits
        self.timestamps = bits > 0
        self._mask = (1 << bits) - 1 if 0 < bits < 64 else (1 << 64) - 1  # the ticks' valid bits
        self._period_ms = device.info.timestamp_period_ns / 1e6  # ms a tick
        self.pass_timing = False  # mark() writes timestamps (from the next recorded frame)
        self.last_gpu: GpuFrame | None = None  # what acquire() read, with pass_timing on
        self._begin_info = vk.VkCommandBufferBeginInfo(flags=0)  # not one-time: it may be submitted again
        self._begin_info_ptr = vk.ffi.addressof(self._begin_info)
        self._stamps = vk.ffi.new(f"uint64_t[{MAX_PASSES + 2}]")
        for _ in range(count):
            pool = vk.vkCreateCommandPool(
                device.handle,
                vk.VkCommandPoolCreateInfo(
                    flags=vk.VK_COMMAND_POOL_CREATE_TRANSIENT_BIT, queueFamilyIndex=device.queue_family
                ),
                None,
            )
            cb = vk.vkAllocateCommandBuffers(
                device.handle,
                vk.VkCommandBufferAllocateInfo(
                    commandPool=pool, level=vk.VK_COMMAND_BUFFER_LEVEL_PRIMARY, commandBufferCount=1
                ),
            )[0]
            fence = vk.vkCreateFence(device.handle, vk.VkFenceCreateInfo(flags=vk.VK_FENCE_CREATE_SIGNALED_BIT), None)
            sem = [vk.vkCreateSemaphore(device.handle, vk.VkSemaphoreCreateInfo(), None) for _ in range(2)]
            queries = vk.vkCreateQueryPool(
                device.handle,
                vk.VkQueryPoolCreateInfo(queryType=vk.VK_QUERY_TYPE_TIMESTAMP, queryCount=MAX_PASSES + 2),
                None,
            )
            fences = vk.ffi.new("VkFence[1]", [fence])
            self.frames.append(Frame(pool, cb, fence, sem[0], sem[1], queries, fences, slot=len(self.frames)))
        self._submits: dict[tuple[int, int, int], Any] = {}

    def begin(self) -> tuple[Frame, float | None]:
        """`acquire`, then `open`: the next slot, its primary ready to record."""
        frame, gpu_ms = self.acquire()
        self.open(frame)
        return frame, gpu_ms

    def acquire(self) -> tuple[Frame, float | None]:
        """Wait for the next frame slot; return it with the GPU time (ms) of the work it last
        carried, which is complete once its fence is signalled (no extra wait). Its primary still
        holds what was recorded last: `open` it to record, or `resubmit` it."""
        frame = self.frames[self.index]
        t0 = time.perf_counter()
        self.wait(frame)
        self.last_gpu = None
        # some drivers (lavapipe) still block here until the queries land: count it as waiting
        gpu_ms = self._read_timestamps(frame) if frame.submitted else None
        self.last_wait_ms = (time.perf_counter() - t0) * 1e3
        return frame, gpu_ms

    def open(self, frame: Frame) -> None:
        """Reset the slot's pool and begin its primary (the timestamps first)."""
        vk = self.device.vk
        lib = vk.lib
        check(vk, lib.vkResetCommandPool(self.device.handle, frame.pool, 0))
        check(vk, lib.vkBeginCommandBuffer(frame.command_buffer, self._begin_info_ptr))
        if frame.passes:
            frame.passes = []
        if self.timestamps:
            lib.vkCmdResetQueryPool(frame.command_buffer, frame.queries, 0, MAX_PASSES + 2)
            lib.vkCmdWriteTimestamp(frame.command_buffer, vk.VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, frame.queries, 0)

    def marker(self, frame: Frame) -> Any:
        """mark(name) for the frame being recorded, or None when passes are not timed."""
        if not (self.pass_timing and self.timestamps):
            return None
        return lambda name: self.mark(frame, name)

    def mark(self, frame: Frame, name: str) -> None:
        """The pass called `name` ends here (recorded after it; see the module)."""
        passes = frame.passes
        if len(passes) < MAX_PASSES:
            vk = self.device.vk
            stage = vk.VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT
            vk.lib.vkCmdWriteTimestamp(frame.command_buffer, stage, frame.queries, len(passes) + 1)
            passes.append(name)

    def end(self, frame: Frame, wait: Any = None, signal: Any = None) -> None:
        """End the slot's primary (the last timestamp) and submit it."""
        vk = self.device.vk
        lib = vk.lib
        if self.timestamps:
            stage = vk.VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT
            lib.vkCmdWriteTimestamp(frame.command_buffer, stage, frame.queries, len(frame.passes) + 1)
        check(vk, lib.vkEndCommandBuffer(frame.command_buffer))
        self.resubmit(frame, wait, signal)

    def resubmit(self, frame: Frame, wait: Any = None, signal: Any = None) -> None:
        """Submit the slot's primary as it was last recorded (its timestamps with it)."""
        vk = self.device.vk
        lib = vk.lib
        # (the results checked inline, not by check(): this runs every frame)
        result = lib.vkResetFences(self.device.handle, 1, frame.fence_array)
        if result:
            check(vk, result)
        if frame.passes:  # before the call: the GPU may start before it returns
            frame.submitted_ns = time.perf_counter_ns()
        result = lib.vkQueueSubmit(self.device.queue, 1, self._submit_info(frame, wait, signal), frame.fence)
        if result:
            check(vk, result)
        frame.submitted = self.timestamps
        self.index = (self.index + 1) % len(self.frames)

    def _submit_info(self, frame: Frame, wait: Any, signal: Any) -> Any:
        """VkSubmitInfo* for this frame and semaphores, made once per combination."""
        if wait is None and signal is None:  # offscreen: no semaphores, no key to make
            if frame.plain_submit is None:
                frame.plain_submit = self._made_submit(frame, None, None)
            return frame.plain_submit[1]
        vk = self.device.vk
        key = (frame.slot, _address(vk, wait), _address(vk, signal))
        info = self._submits.get(key)
        if info is None:
            if len(self._submits) > 64:  # semaphores of old swapchains
                self._submits.clear()
            info = self._submits[key] = self._made_submit(frame, wait, signal)
        return info[1]

    def _made_submit(self, frame: Frame, wait: Any, signal: Any) -> tuple[Any, Any]:
        vk = self.device.vk
        made = vk.VkSubmitInfo(
            pCommandBuffers=[frame.command_buffer],
            pWaitSemaphores=[wait] if wait is not None else None,
            pWaitDstStageMask=[vk.VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT] if wait is not None else None,
            pSignalSemaphores=[signal] if signal is not None else None,
        )
        return made, vk.ffi.addressof(made)

    def wait(self, frame: Frame) -> None:
        vk = self.device.vk
        result = vk.lib.vkWaitForFences(self.device.handle, 1, frame.fence_array, 1, _FOREVER)
        if result:
            check(vk, result)

    def _read_timestamps(self, frame: Frame) -> float | None:
        """The frame's GPU ms; with marks, its passes too (`last_gpu`)."""
        vk = self.device.vk
        data = self._stamps
        count = len(frame.passes) + 2
        result = vk.lib.vkGetQueryPoolResults(
            self.device.handle, frame.queries, 0, count, 8 * count, data, 8, vk.VK_QUERY_RESULT_64_BIT
        )
        if result:  # (VK_SUCCESS is 0; VK_NOT_READY and errors are not)
            return None
        mask, period_ms = self._mask, self._period_ms
        ms: float = ((data[count - 1] - data[0]) & mask) * period_ms
        if frame.passes:
            stamps = [int(data[k]) for k in range(count - 1)]
            spans = [((b - a) & mask) * period_ms for a, b in itertools.pairwise(stamps)]
            done = time.perf_counter_ns()
            passes = list(zip(frame.passes, spans, strict=True))
            self.last_gpu = GpuFrame(ms, round(stamps[0] * period_ms * 1e6), passes, frame.submitted_ns, done)
        return ms

    def destroy(self) -> None:
        vk = self.device.vk
        for f in self.frames:
            vk.vkDestroyQueryPool(self.device.handle, f.queries, None)
            vk.vkDestroySemaphore(self.device.handle, f.image_available, None)
            vk.vkDestroySemaphore(self.device.handle, f.render_finished, None)
            vk.vkDestroyFence(self.device.handle, f.fence, None)
            vk.vkDestroyCommandPool(self.device.handle, f.pool, None)
        self.frames.clear()


_FOREVER = 2**64 - 1  # vkWaitForFences' timeout, ns


def check(vk: Any, result: int) -> None:
    """Raise what the binding's wrapper would have raised for a failed raw call."""
    if result != vk.VK_SUCCESS:
        raise vk.exception_codes[result]


def _address(vk: Any, handle: Any) -> int:
    return 0 if handle is None else int(vk.ffi.cast("uintptr_t", handle))
