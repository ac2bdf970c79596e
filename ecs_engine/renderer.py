"""The renderer: reads the world's derived arrays, writes per-frame GPU buffers, records a frame.

Data goes one way: ModelMatrix/Mesh/PointLight/Camera columns -> mapped per-frame buffers ->
commands. The renderer never writes the world. One instanced draw per (mesh, winding) run of
entities; mirrored entities (negative determinant) get the pipeline with the opposite front face
so back-face culling stays right. Light billboards are built only when the scene has lights.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .camera_math import CameraMatrices, camera_matrices
from .components import Mesh, ModelMatrix, PointLight, Transform
from .gpu.descriptors import DescriptorPool, DescriptorSetLayout, write_buffers
from .gpu.device import Device
from .gpu.frames import Frame, FrameRing
from .gpu.memory import HOST, Buffer
from .gpu.pipeline import GraphicsPipelineSpec, PipelineCache, graphics_pipeline, pipeline_layout
from .mesh_registry import VERTEX_STRIDE, MeshRegistry
from .world import World

INSTANCE_DTYPE = np.dtype([("model", np.float32, (3, 4)), ("normal", np.float32, (3, 4)), ("misc", np.uint32, 4)])
LIGHT_DTYPE = np.dtype([("position_radius", np.float32, 4), ("color_intensity", np.float32, 4)])
MATERIAL_DTYPE = np.dtype([("color", np.float32, 4), ("specular", np.float32, 4)])
GLOBALS_BYTES = 3 * 64 + 16 + 16
MIN_LIGHTS = 256

# A small default palette (linear RGB); Mesh.material indexes it modulo its length.
DEFAULT_MATERIALS = [
    ((0.80, 0.80, 0.80), 0.5, 32.0),
    ((0.85, 0.35, 0.25), 0.6, 48.0),
    ((0.25, 0.55, 0.85), 0.6, 48.0),
    ((0.35, 0.75, 0.35), 0.5, 32.0),
    ((0.90, 0.75, 0.30), 0.7, 64.0),
    ((0.65, 0.40, 0.80), 0.5, 32.0),
]


@dataclass
class FrameStats:
    draws: int
    instances: int
    triangles: int
    lights: int
    gpu_ms: float | None  # of an earlier frame: timestamps are read without waiting
    wait_ms: float = 0.0  # spent waiting for a frame slot (GPU-bound), not CPU work


@dataclass
class _PerFrame:
    globals: Buffer
    lights: Buffer
    instances: Buffer
    descriptor_set: Any


class Renderer:
    def __init__(self, device: Device, target: Any, meshes: MeshRegistry, *, lights: bool,
                 clear_color: tuple[float, float, float] = (0.02, 0.02, 0.03),
                 ambient: tuple[float, float, float, float] = (1.0, 1.0, 1.0, 0.06),
                 light_size: float = 0.08) -> None:
        vk = self.vk = device.vk
        self.device = device
        self.target = target
        self.meshes = meshes
        self.with_lights = lights
        self.clear_color = clear_color
        self.ambient = ambient
        self.light_size = light_size
        self.frames = FrameRing(device)
        self.cache = PipelineCache(device)
        stages = vk.VK_SHADER_STAGE_VERTEX_BIT | vk.VK_SHADER_STAGE_FRAGMENT_BIT
        ssbo = vk.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER
        self.set_layout = DescriptorSetLayout(device, [
            (0, vk.VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, stages), (1, ssbo, stages), (2, ssbo, stages), (3, ssbo, stages)])
        n = len(self.frames.frames)
        self.pool = DescriptorPool(device, n, {vk.VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER: n, ssbo: 3 * n})
        self.layout = pipeline_layout(device, [self.set_layout.handle], [(vk.VK_SHADER_STAGE_VERTEX_BIT, 0, 4)])
        self.materials = Buffer(device, MATERIAL_DTYPE.itemsize * len(DEFAULT_MATERIALS), vk.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT)
        table = self.materials.array(MATERIAL_DTYPE, len(DEFAULT_MATERIALS))
        for i, (color, strength, shininess) in enumerate(DEFAULT_MATERIALS):
            table[i] = ((*color, 1.0), (strength, shininess, 0.0, 0.0))
        self.per_frame = [self._make_frame_resources() for _ in range(n)]
        self._build_pipelines()

    # ----------------------------------------------------------------- set-up
    def _make_frame_resources(self) -> _PerFrame:
        vk = self.vk
        pf = _PerFrame(
            globals=Buffer(self.device, GLOBALS_BYTES, vk.VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT),
            lights=Buffer(self.device, LIGHT_DTYPE.itemsize * MIN_LIGHTS, vk.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT),
            instances=Buffer(self.device, INSTANCE_DTYPE.itemsize * 1024, vk.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT),
            descriptor_set=self.pool.allocate(self.set_layout),
        )
        self._write_set(pf)
        return pf

    def _write_set(self, pf: _PerFrame) -> None:
        vk = self.vk
        ssbo = vk.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER
        write_buffers(self.device, pf.descriptor_set, [
            (0, vk.VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, pf.globals), (1, ssbo, pf.lights),
            (2, ssbo, pf.instances), (3, ssbo, self.materials)])

    def _build_pipelines(self) -> None:
        vk = self.vk
        attrs = [(0, vk.VK_FORMAT_R32G32B32_SFLOAT, 0), (1, vk.VK_FORMAT_R32G32B32_SFLOAT, 12)]
        base = dict(layout=self.layout, render_pass=self.target.render_pass, subpass=0,
                    vertex_stride=VERTEX_STRIDE, vertex_attributes=attrs)
        self.mesh_pipeline = graphics_pipeline(self.device, self.cache, GraphicsPipelineSpec("mesh.vert", "mesh.frag", **base))
        self.mirrored_pipeline = graphics_pipeline(self.device, self.cache, GraphicsPipelineSpec(
            "mesh.vert", "mesh.frag", front_face_ccw=False, **base))
        self.light_pipeline = None
        if self.with_lights:
            self.light_pipeline = graphics_pipeline(self.device, self.cache, GraphicsPipelineSpec(
                "light.vert", "light.frag", layout=self.layout, render_pass=self.target.render_pass, subpass=1,
                cull_back=False, depth_write=False, alpha_blend=True))

    def _ensure_capacity(self, pf: _PerFrame, instances: int, lights: int) -> None:
        """Grow a frame's buffers (doubling); safe: this frame's fence has been waited on."""
        vk = self.vk
        changed = False
        if instances * INSTANCE_DTYPE.itemsize > pf.instances.size:
            pf.instances.destroy()
            size = max(instances, 2 * pf.instances.size // INSTANCE_DTYPE.itemsize)
            pf.instances = Buffer(self.device, size * INSTANCE_DTYPE.itemsize, vk.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT)
            changed = True
        if lights * LIGHT_DTYPE.itemsize > pf.lights.size:
            pf.lights.destroy()
            size = max(lights, 2 * pf.lights.size // LIGHT_DTYPE.itemsize)
            pf.lights = Buffer(self.device, size * LIGHT_DTYPE.itemsize, vk.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT)
            changed = True
        if changed:
            self._write_set(pf)

    # ------------------------------------------------------------- per frame
    def gather_instances(self, world: World, out: np.ndarray | None = None) -> tuple[np.ndarray, list[tuple[int, bool, int, int]]]:
        """Instance rows sorted by (mesh, mirrored) and the draw runs (handle, mirrored, first, count)."""
        models, normals, handles, materials = [], [], [], []
        for batch in world.query(ModelMatrix, Mesh, write=()):
            m = batch[ModelMatrix]
            models.append(m.model)
            normals.append(m.normal)
            handles.append(batch[Mesh].handle)
            materials.append(batch[Mesh].material)
        if not models:
            return np.empty(0, INSTANCE_DTYPE), []
        model = np.concatenate(models)
        normal = np.concatenate(normals)
        handle = np.concatenate(handles)
        m3 = model[:, :3, :3]
        det = (m3[:, 0, 0] * (m3[:, 1, 1] * m3[:, 2, 2] - m3[:, 1, 2] * m3[:, 2, 1])
               - m3[:, 0, 1] * (m3[:, 1, 0] * m3[:, 2, 2] - m3[:, 1, 2] * m3[:, 2, 0])
               + m3[:, 0, 2] * (m3[:, 1, 0] * m3[:, 2, 1] - m3[:, 1, 1] * m3[:, 2, 0]))
        mirrored = det < 0
        order = np.lexsort((mirrored, handle))
        n = len(order)
        rows = out[:n] if out is not None else np.empty(n, INSTANCE_DTYPE)
        rows["model"] = model[order, :3, :]
        rows["normal"][:, :, :3] = normal[order]
        rows["normal"][:, :, 3] = 0.0
        rows["misc"][:, 0] = np.concatenate(materials)[order] % len(DEFAULT_MATERIALS)
        rows["misc"][:, 1:] = 0
        key = handle[order].astype(np.int64) * 2 + mirrored[order]
        starts = np.flatnonzero(np.diff(key, prepend=-1))
        counts = np.diff(np.append(starts, n))
        runs = [(int(key[s] // 2), bool(key[s] % 2), int(s), int(c)) for s, c in zip(starts, counts)]
        for h, _, _, _ in runs:
            if h >= len(self.meshes):
                raise ValueError(f"Mesh.handle {h} does not name an uploaded mesh ({len(self.meshes)} uploaded)")
        return rows, runs

    def gather_lights(self, world: World, camera_position: np.ndarray) -> np.ndarray:
        """Camera-relative lights sorted far to near (the billboards blend back to front)."""
        parts = []
        for batch in world.query(PointLight, Transform, write=()):
            light, t = batch[PointLight], batch[Transform]
            rows = np.empty(len(batch), LIGHT_DTYPE)
            rows["position_radius"][:, :3] = t.position - camera_position
            rows["position_radius"][:, 3] = light.radius
            rows["color_intensity"][:, :3] = light.color
            rows["color_intensity"][:, 3] = light.intensity
            parts.append(rows)
        if not parts:
            return np.empty(0, LIGHT_DTYPE)
        lights = np.concatenate(parts)
        dist = np.einsum("ij,ij->i", lights["position_radius"][:, :3], lights["position_radius"][:, :3])
        return lights[np.argsort(-dist, kind="stable")]

    def render(self, world: World, readback: bool = False, framebuffer: Any = None,
               extent: tuple[int, int] | None = None, wait: Any = None, signal: Any = None) -> FrameStats:
        """Record and submit one frame. Headless targets read the image back when asked."""
        vk = self.vk
        width, height = extent or (self.target.width, self.target.height)
        frame, gpu_ms = self.frames.begin()
        pf = self.per_frame[self.frames.frames.index(frame)]
        cam = camera_matrices(world, width / height)
        lights = self.gather_lights(world, cam.position) if self.with_lights else np.empty(0, LIGHT_DTYPE)
        instances, runs = self.gather_instances(world)
        self._ensure_capacity(pf, len(instances), len(lights))
        if len(instances):
            pf.instances.array(INSTANCE_DTYPE, len(instances))[:] = instances
        if len(lights):
            pf.lights.array(LIGHT_DTYPE, len(lights))[:] = lights
        self._write_globals(pf, cam, len(lights))
        cb = frame.command_buffer
        self._record(cb, pf, runs, len(lights), framebuffer or self.target.framebuffer, width, height)
        if readback:
            self.target.record_readback(cb)
        self.frames.end(frame, wait=wait, signal=signal)
        if readback:
            self.frames.wait(frame)
        triangles = sum(self.meshes.triangles(h) * c for h, _, _, c in runs)
        return FrameStats(draws=len(runs) + (1 if len(lights) else 0), instances=len(instances),
                          triangles=triangles, lights=len(lights), gpu_ms=gpu_ms, wait_ms=self.frames.last_wait_ms)

    def _write_globals(self, pf: _PerFrame, cam: CameraMatrices, light_count: int) -> None:
        raw = pf.globals.bytes()
        mats = raw[:192].view(np.float32).reshape(3, 4, 4)
        mats[0] = cam.projection.T  # column-major for GLSL
        mats[1] = cam.view.T
        mats[2] = cam.inverse_view.T
        raw[192:208].view(np.float32)[:] = self.ambient
        raw[208:224].view(np.uint32)[:] = (light_count, 0, 0, 0)

    def _record(self, cb: Any, pf: _PerFrame, runs: list[tuple[int, bool, int, int]], light_count: int,
                framebuffer: Any, width: int, height: int) -> None:
        vk = self.vk
        clears = [vk.VkClearValue(color=vk.VkClearColorValue(float32=[*self.clear_color, 1.0])),
                  vk.VkClearValue(depthStencil=vk.VkClearDepthStencilValue(depth=0.0, stencil=0))]  # reverse-Z
        area = vk.VkRect2D(offset=vk.VkOffset2D(0, 0), extent=vk.VkExtent2D(width, height))
        vk.vkCmdBeginRenderPass(cb, vk.VkRenderPassBeginInfo(
            renderPass=self.target.render_pass, framebuffer=framebuffer, renderArea=area, pClearValues=clears),
            vk.VK_SUBPASS_CONTENTS_INLINE)
        viewport = vk.VkViewport(x=0.0, y=0.0, width=float(width), height=float(height), minDepth=0.0, maxDepth=1.0)
        vk.vkCmdSetViewport(cb, 0, 1, [viewport])
        vk.vkCmdSetScissor(cb, 0, 1, [area])
        vk.vkCmdBindDescriptorSets(cb, vk.VK_PIPELINE_BIND_POINT_GRAPHICS, self.layout, 0, 1,
                                   [pf.descriptor_set], 0, None)
        bound = None
        for handle, mirrored, first, count in runs:
            pipeline = self.mirrored_pipeline if mirrored else self.mesh_pipeline
            if pipeline is not bound:
                vk.vkCmdBindPipeline(cb, vk.VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline)
                bound = pipeline
            mesh = self.meshes.bind(cb, handle)
            vk.vkCmdDrawIndexed(cb, mesh.index_count, count, 0, 0, first)
        vk.vkCmdNextSubpass(cb, vk.VK_SUBPASS_CONTENTS_INLINE)
        if light_count and self.light_pipeline is not None:
            vk.vkCmdBindPipeline(cb, vk.VK_PIPELINE_BIND_POINT_GRAPHICS, self.light_pipeline)
            size = np.array([self.light_size], dtype=np.float32)
            vk.vkCmdPushConstants(cb, self.layout, vk.VK_SHADER_STAGE_VERTEX_BIT, 0, 4, vk.ffi.from_buffer(size))
            vk.vkCmdDraw(cb, 6, light_count, 0, 0)
        vk.vkCmdEndRenderPass(cb)

    def destroy(self) -> None:
        vk = self.vk
        self.device.wait_idle()
        for pipeline in (self.mesh_pipeline, self.mirrored_pipeline, self.light_pipeline):
            if pipeline is not None:
                vk.vkDestroyPipeline(self.device.handle, pipeline, None)
        vk.vkDestroyPipelineLayout(self.device.handle, self.layout, None)
        for pf in self.per_frame:
            pf.globals.destroy()
            pf.lights.destroy()
            pf.instances.destroy()
        self.materials.destroy()
        self.pool.destroy()
        self.set_layout.destroy()
        self.cache.destroy()
        self.frames.destroy()
