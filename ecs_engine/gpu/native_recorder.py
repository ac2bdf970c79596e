"""The native recorder: a numba nogil loop that records a chunk's draws by calling Vulkan's
command entry points directly (addresses from vkGetDeviceProcAddr, typed with ctypes).

Through the `vulkan` binding each command costs microseconds of Python and holds the GIL, so
threads cannot help; here the loop runs without the GIL at tens of nanoseconds a command.
Handles and addresses travel as signed 64-bit integers (dispatchable handles are pointers,
non-dispatchable ones 64-bit values; the C calling convention passes int64 and uint64 alike),
so the loop's arithmetic never mixes signed and unsigned (which numba would turn into floats).
The entry-point addresses (gpu/functions.py) are baked into the compiled loop, so it is compiled
once per device (about a second) and not cached on disk.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from .. import native
from .functions import NATIVE_PROTOTYPES, handle_int, native_device_functions

if TYPE_CHECKING:
    from .device import Device

INDEX_TYPE_UINT32 = 1


class NativeRecorder:
    def __init__(self, device: Device) -> None:
        if not native.AVAILABLE:
            raise RuntimeError("the native recorder needs numba (or ECS_ENGINE_NO_NUMBA is set)")
        import numba

        vk = device.vk
        self.vk = vk
        fns = native_device_functions(device, NATIVE_PROTOTYPES)
        bind_pipeline = fns["vkCmdBindPipeline"]
        bind_vertex = fns["vkCmdBindVertexBuffers"]
        bind_index = fns["vkCmdBindIndexBuffer"]
        push = fns["vkCmdPushConstants"]
        draw_indexed = fns["vkCmdDrawIndexed"]
        begin = fns["vkBeginCommandBuffer"]
        end = fns["vkEndCommandBuffer"]
        set_viewport = fns["vkCmdSetViewport"]
        set_scissor = fns["vkCmdSetScissor"]
        bind_sets = fns["vkCmdBindDescriptorSets"]
        self._keep = fns  # the ctypes objects own nothing, but keep them with the compiled code

        def record(
            cb,
            layout,
            push_stage,
            row_bytes,
            rows_addr,
            instanced,
            first_instance,
            key_counts,
            pipelines,
            vertex_handles_addr,
            zero_offset_addr,
            index_handles,
            index_counts,
            begin_info_addr,
            viewport_addr,
            scissor_addr,
            set_addr,
            out,
        ):  # pragma: no cover
            # a secondary sets its own viewport and scissor (they are not inherited) and binds
            # the frame's descriptor set. The rows are sorted by key = mesh * 2 + mirrored, with
            # key_counts[key] rows each: one run per non-empty key, drawn with pipelines[mirrored].
            # Writes (draws, triangles) to out; returns the first failing VkResult, or 0.
            result = begin(cb, begin_info_addr)
            if result != 0:
                return result
            set_viewport(cb, 0, 1, viewport_addr)
            set_scissor(cb, 0, 1, scissor_addr)
            bind_sets(cb, 0, layout, 0, 1, set_addr, 0, 0)
            bound = 0
            start = 0
            draws = 0
            triangles = 0
            for k in range(key_counts.shape[0]):
                count = key_counts[k]
                if count == 0:
                    continue
                pipeline = pipelines[k & 1]
                if pipeline != bound:
                    bind_pipeline(cb, 0, pipeline)
                    bound = pipeline
                h = k >> 1
                bind_vertex(cb, 0, 1, vertex_handles_addr + 8 * h, zero_offset_addr)
                bind_index(cb, index_handles[h], 0, INDEX_TYPE_UINT32)
                indices = index_counts[h]
                if instanced:
                    draw_indexed(cb, indices, count, 0, 0, first_instance + start)
                    draws += 1
                else:
                    for i in range(start, start + count):
                        push(cb, layout, push_stage, 0, row_bytes, rows_addr + i * row_bytes)
                        draw_indexed(cb, indices, 1, 0, 0, 0)
                    draws += count
                triangles += indices // 3 * count
                start += count
            out[0] = draws
            out[1] = triangles
            return end(cb)

        self._record = numba.njit(nogil=True)(record)
        self._zero = np.zeros(1, dtype=np.int64)
        self._zero_addr = self._zero.ctypes.data  # addresses kept as ints: .ctypes costs ~1 us a call
        self._vertex_addr = 0
        self._cb_ints: dict[Any, int] = {}  # secondary -> handle_int (the pools reuse them every frame)
        self._meshes_seen = -1

    def set_meshes(
        self, vertex_handles: list[Any], index_handles: list[Any], index_counts: list[int], version: int
    ) -> None:
        """The meshes' buffers, as the registry's `version` has them."""
        vk = self.vk
        self._vertex = np.array([handle_int(vk, h) for h in vertex_handles], dtype=np.int64)
        self._index = np.array([handle_int(vk, h) for h in index_handles], dtype=np.int64)
        self._counts = np.array(index_counts, dtype=np.int64)
        self._vertex_addr = self._vertex.ctypes.data
        self._meshes_seen = version

    @property
    def meshes_known(self) -> int:
        return self._meshes_seen

    def frame_state(
        self,
        begin_info: Any,
        width: int,
        height: int,
        descriptor_set: Any,
        layout: Any,
        push_stage: int,
        pipelines: tuple[Any, Any],
    ) -> dict[str, Any]:
        """Per-frame inputs of `record`: the begin info (with render-pass inheritance), viewport,
        scissor, descriptor set, pipeline layout and the plain and mirrored pipelines, as memory
        and integers the native loop reads (kept alive in the dict). Made once per target and
        frame slot."""
        vk = self.vk
        viewport = np.array([0.0, 0.0, width, height, 0.0, 1.0], dtype=np.float32)
        scissor = np.array([0, 0, width, height], dtype=np.int32)
        sets = np.array([handle_int(vk, descriptor_set)], dtype=np.int64)
        return {
            "begin_info": begin_info,
            "begin_addr": handle_int(vk, vk.ffi.addressof(begin_info)),
            "viewport": viewport,
            "scissor": scissor,
            "sets": sets,
            "layout": handle_int(vk, layout),
            "push_stage": int(push_stage),
            "pipelines": np.array([handle_int(vk, p) for p in pipelines], dtype=np.int64),
            "viewport_addr": viewport.ctypes.data,
            "scissor_addr": scissor.ctypes.data,
            "sets_addr": sets.ctypes.data,
        }

    def record(
        self,
        cb: Any,
        rows: np.ndarray,
        instanced: bool,
        first_instance: int,
        key_counts: np.ndarray,
        frame: dict[str, Any],
    ) -> tuple[int, int]:
        """Begin `cb` (an allocated secondary), record one chunk's binds and draws, end it.
        `rows` are sorted by key (mesh * 2 + mirrored), `key_counts[key]` of each. Returns
        (draws, triangles). Threads may share one frame state."""
        out = np.empty(2, dtype=np.int64)
        cb_int = self._cb_ints.get(cb)
        if cb_int is None:
            if len(self._cb_ints) > 4096:  # pools of threads long gone
                self._cb_ints.clear()
            cb_int = self._cb_ints[cb] = handle_int(self.vk, cb)  # the address itself: never stale
        result = self._record(
            cb_int,
            frame["layout"],
            frame["push_stage"],
            rows.dtype.itemsize,
            rows.ctypes.data,
            instanced,
            first_instance,
            key_counts,
            frame["pipelines"],
            self._vertex_addr,
            self._zero_addr,
            self._index,
            self._counts,
            frame["begin_addr"],
            frame["viewport_addr"],
            frame["scissor_addr"],
            frame["sets_addr"],
            out,
        )
        if result != 0:
            raise RuntimeError(f"recording a secondary command buffer failed with VkResult {result}")
        return int(out[0]), int(out[1])
