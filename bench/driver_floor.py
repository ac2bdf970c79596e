"""The driver's own cost per per-entity draw: numba loops that call vkCmdPushConstants (64 bytes,
the per_entity row) and vkCmdDrawIndexed with nothing else in the loop (no culling, no row
writes), into secondaries of a fixed number of draws, on one thread. The per_entity recorder
cannot go below this; bench scaling reports it beside the 50 ns per draw target.

JSON part: {"draws", "per_buffer", "push_draw_ns", "draw_ns", "push_ns"} (ns per call pair or
call, medians of `repeats` timed frames after one warm-up).
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from ecs_engine.gpu.functions import handle_int, native_device_functions


def _loops(device: Any) -> dict[str, Any]:
    import numba

    fns = native_device_functions(device, ("vkCmdPushConstants", "vkCmdDrawIndexed"))
    push, draw = fns["vkCmdPushConstants"], fns["vkCmdDrawIndexed"]

    def push_draw(cb, layout, stage, addr, n, indices):  # pragma: no cover - compiled
        for i in range(n):
            push(cb, layout, stage, 0, 64, addr + i * 64)
            draw(cb, indices, 1, 0, 0, 0)

    def draw_only(cb, layout, stage, addr, n, indices):  # pragma: no cover - compiled
        for i in range(n):
            draw(cb, indices, 1, 0, 0, i)

    def push_only(cb, layout, stage, addr, n, indices):  # pragma: no cover - compiled
        for i in range(n):
            push(cb, layout, stage, 0, 64, addr + i * 64)

    jit = numba.njit(nogil=True)
    return {"push_draw_ns": jit(push_draw), "draw_ns": jit(draw_only), "push_ns": jit(push_only), "_keep": fns}


def measure(
    device: Any, target: Any, meshes: Any, draws: int, per_buffer: int = 16_384, repeats: int = 5
) -> dict[str, Any]:
    from ecs_engine.render.frame.renderer import Renderer

    vk = device.vk
    renderer = Renderer(device, target, meshes, mode="per_entity")
    try:
        loops = _loops(device)
        rows = np.zeros((draws, 16), np.float32)
        rows[:, 0] = rows[:, 5] = rows[:, 10] = 1.0
        state = renderer.target_state(target.framebuffer, target.width, target.height)
        layout = handle_int(vk, renderer.path.layout)
        stage = vk.VK_SHADER_STAGE_VERTEX_BIT
        mesh = meshes[0]
        out: dict[str, Any] = {"draws": draws, "per_buffer": per_buffer}
        for name in ("push_draw_ns", "draw_ns", "push_ns"):
            loop = loops[name]
            times = []
            for _ in range(repeats + 1):
                frame, _ = renderer.frames.begin()
                slot = renderer.frames.frames.index(frame)
                renderer.secondaries.reset(slot)
                spent = 0.0
                for start in range(0, draws, per_buffer):
                    cb = renderer.secondaries.begin(slot, state.secondary_begin)
                    vk.vkCmdBindPipeline(cb, vk.VK_PIPELINE_BIND_POINT_GRAPHICS, renderer.path.pipelines[0])
                    meshes.bind(cb, 0)
                    handle = handle_int(vk, cb)
                    t0 = time.perf_counter()
                    loop(
                        handle,
                        layout,
                        stage,
                        rows.ctypes.data + start * 64,
                        min(per_buffer, draws - start),
                        mesh.index_count,
                    )
                    spent += time.perf_counter() - t0
                    vk.vkEndCommandBuffer(cb)
                renderer.frames.end(frame)  # recorded, never executed: only the recording is timed
                times.append(spent * 1e9 / draws)
            out[name] = float(np.median(times[1:]))
        return out
    finally:
        renderer.destroy()
