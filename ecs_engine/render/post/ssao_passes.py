"""The SSAO passes (see ssao.py): compute shaders over images the graph hands them. Each makes
its pipeline at its first record (setup only declares) and keeps a descriptor set per set of
image views it was recorded with. A recompile of its graph makes new transients (their views may
even reuse the old handles' values), so the sets are dropped then; the graph waited for the
device before destroying the old transients, so no frame in flight still uses them."""

from __future__ import annotations

from collections.abc import Hashable
from typing import Any

import numpy as np

from ...gpu.array_image import nearest_sampler
from ...gpu.descriptors import DescriptorPool, DescriptorSetLayout, write_set
from ...gpu.functions import handle_int
from ...gpu.owned import Owned
from ...gpu.pipeline import compute_pipeline, pipeline_layout
from ..graph import Access, ImageDesc, Pass, PassBuilder, PassContext
from .ssao_settings import SsaoSettings, SsaoView

GROUP = 8  # the shaders' local size, each way
PUSH_BYTES = 112  # ssao.push_constants
MAX_SETS = 8  # descriptor sets kept per pass before the pool is reset

NOISY = ImageDesc(format="VK_FORMAT_R16G16B16A16_SFLOAT")
AO = ImageDesc(format="VK_FORMAT_R16_SFLOAT")


class _ComputePass(Pass):
    """One compute shader: `sampled` images (combined image samplers, bindings 0...) then
    `storage` images (the next bindings, GENERAL), dispatched over the image `over`."""

    shader = ""

    def __init__(self, name: str, settings: SsaoSettings, view: SsaoView, graph: Any) -> None:
        self.name, self.settings, self.view, self.graph = name, settings, view, graph
        self._compiles = -1  # the graph's compile the sets were written for
        self.sampled: tuple[str, ...] = ()
        self.storage: tuple[str, ...] = ()
        self.over = ""
        self._owned: Owned | None = None
        self._sets: dict[tuple, Any] = {}

    def key(self) -> Hashable:
        return (self.settings, self.view.key())

    def declares(self) -> Hashable:
        return ()  # its setup reads only what it was made with

    def _make(self, device: Any) -> None:
        vk = device.vk
        owned = Owned(device)
        try:
            stage = vk.VK_SHADER_STAGE_COMPUTE_BIT
            bindings = [(i, vk.VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, stage) for i in range(len(self.sampled))]
            bindings += [
                (len(self.sampled) + i, vk.VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, stage) for i in range(len(self.storage))
            ]
            self._set_layout = owned.add(DescriptorSetLayout(device, bindings))
            sizes = {}
            if self.sampled:
                sizes[vk.VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER] = MAX_SETS * len(self.sampled)
            if self.storage:
                sizes[vk.VK_DESCRIPTOR_TYPE_STORAGE_IMAGE] = MAX_SETS * len(self.storage)
            self._pool = owned.add(DescriptorPool(device, MAX_SETS, sizes))
            handle = device.handle
            layout = pipeline_layout(device, [self._set_layout.handle], [(stage, 0, PUSH_BYTES)])
            self._layout = owned.add(layout, lambda: vk.vkDestroyPipelineLayout(handle, layout, None))
            pipeline = compute_pipeline(device, self.shader, layout)
            self._pipeline = owned.add(pipeline, lambda: vk.vkDestroyPipeline(handle, pipeline, None))
            sampler = nearest_sampler(device)
            self._sampler = owned.add(sampler, lambda: vk.vkDestroySampler(handle, sampler, None))
        except BaseException:
            owned.destroy()
            raise
        self._owned = owned

    def _set(self, ctx: PassContext) -> Any:
        vk, device = ctx.vk, ctx.device
        views = tuple(ctx.image(n).view for n in (*self.sampled, *self.storage))
        key = tuple(v if isinstance(v, int) else handle_int(vk, v) for v in views)
        compiles = self.graph.compiles
        found = self._sets.get(key) if compiles == self._compiles else None
        if found is not None:
            return found
        if compiles != self._compiles or len(self._sets) >= MAX_SETS:
            if compiles == self._compiles:  # only imports changed: frames in flight may use the sets
                device.wait_idle()
            vk.vkResetDescriptorPool(device.handle, self._pool.handle, 0)
            self._sets.clear()
            self._compiles = compiles
        descriptor_set = self._pool.allocate(self._set_layout)
        read_only = vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL  # Access.COMPUTE_SAMPLED's layout
        n = len(self.sampled)
        write_set(
            device,
            descriptor_set,
            samplers=[(i, self._sampler, views[i], read_only) for i in range(n)],
            storage_images=[(n + i, views[n + i]) for i in range(len(self.storage))],
        )
        self._sets[key] = descriptor_set
        return descriptor_set

    def record(self, cb: Any, ctx: PassContext) -> None:
        vk = ctx.vk
        if self._owned is None:
            self._make(ctx.device)
        descriptor_set = self._set(ctx)
        w, h = ctx.image(self.over).extent
        point = vk.VK_PIPELINE_BIND_POINT_COMPUTE
        vk.vkCmdBindPipeline(cb, point, self._pipeline)
        vk.vkCmdBindDescriptorSets(cb, point, self._layout, 0, 1, [descriptor_set], 0, None)
        push = np.frombuffer(self._push(w, h), np.uint8).copy()
        stage = vk.VK_SHADER_STAGE_COMPUTE_BIT
        vk.lib.vkCmdPushConstants(cb, self._layout, stage, 0, PUSH_BYTES, vk.ffi.from_buffer(push))
        vk.vkCmdDispatch(cb, -(-w // GROUP), -(-h // GROUP), 1)

    def _push(self, w: int, h: int) -> bytes:
        return self.view.push_constants(self.settings, (w, h))

    def destroy(self) -> None:
        if self._owned is not None:
            self._owned.destroy()
            self._owned = None
        self._sets.clear()


class GtaoPass(_ComputePass):
    """Depth -> the noisy visibility and the reconstructed view-space normal."""

    shader = "ssao_gtao.comp"

    def __init__(self, name: str, settings: SsaoSettings, view: SsaoView, graph: Any, depth: str, noisy: str) -> None:
        super().__init__(name, settings, view, graph)
        self.sampled, self.storage, self.over = (depth,), (noisy,), noisy
        self.depth, self.noisy = depth, noisy

    def setup(self, b: PassBuilder) -> None:
        b.create(self.noisy, NOISY)
        b.read(self.depth, Access.COMPUTE_SAMPLED)
        b.write(self.noisy, Access.COMPUTE_WRITE)


class DenoisePass(_ComputePass):
    """The noisy visibility -> the "ao" image (depth-aware 5 x 5)."""

    shader = "ssao_denoise.comp"

    def __init__(
        self, name: str, settings: SsaoSettings, view: SsaoView, graph: Any, depth: str, noisy: str, out: str
    ) -> None:
        super().__init__(name, settings, view, graph)
        self.sampled, self.storage, self.over = (depth, noisy), (out,), out
        self.depth, self.noisy, self.out = depth, noisy, out

    def setup(self, b: PassBuilder) -> None:
        b.create(self.out, AO)
        b.read(self.depth, Access.COMPUTE_SAMPLED)
        b.read(self.noisy, Access.COMPUTE_SAMPLED)
        b.write(self.out, Access.COMPUTE_WRITE)


class CompositePass(_ComputePass):
    """hdr.rgb *= ao, in place (the fallback until lighting reads "ao" itself)."""

    shader = "ssao_composite.comp"

    def __init__(self, name: str, settings: SsaoSettings, view: SsaoView, graph: Any, ao: str, hdr: str) -> None:
        super().__init__(name, settings, view, graph)
        self.sampled, self.storage, self.over = (ao,), (hdr,), hdr
        self.ao, self.hdr = ao, hdr

    def key(self) -> Hashable:
        return None  # it reads no projection

    def _push(self, w: int, h: int) -> bytes:
        # only counts.zw, the rectangle: the HDR image may be the window's, larger than the view
        return bytes(PUSH_BYTES - 8) + np.array([w, h], np.int32).tobytes()

    def setup(self, b: PassBuilder) -> None:
        b.read(self.ao, Access.COMPUTE_SAMPLED)
        b.write(self.hdr, Access.COMPUTE_READ_WRITE)
