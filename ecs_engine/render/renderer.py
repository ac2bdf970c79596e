"""The renderer: reads the world's derived arrays, writes per-frame GPU buffers, records a frame.

Data goes one way: ModelMatrix/Mesh/PointLight/Camera columns -> mapped per-frame buffers ->
commands. The renderer never writes the world.

The mesh rows are cut into chunks (row ranges of a table); each chunk is one job on the worker
pool: cull its bounding spheres against the frustum, write its visible rows into its own slice
of the per-frame instance buffer, record a secondary command buffer. The primary command buffer
begins the render pass with SECONDARY_COMMAND_BUFFERS contents, executes every chunk's
secondary in subpass 0 and draws the light billboards inline in subpass 1.

Modes: `instanced` (one instanced draw per (mesh, winding) run of a chunk, rows read from the
storage buffer), `per_entity` (the seed's way: the row in push constants, one draw per
entity) and `indirect` (chunks write every row uncull'd; compute shaders cull and write the
draw commands, see indirect_draws.py; one secondary of two indirect draws). Mirrored entities (negative determinant) get the pipeline with the opposite front face
so back-face culling stays right. Light billboards are built only when the scene has lights.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .camera import CameraMatrices, camera_matrices, view_from_origin
from ..components import Mesh, ModelMatrix, PointLight, Transform
from ..maths.culling import frustum_planes
from ..gpu.descriptors import DescriptorPool, DescriptorSetLayout, write_buffers
from ..gpu.device import Device
from ..gpu.frames import FrameRing
from ..gpu.memory import Buffer
from ..gpu.pipeline import GraphicsPipelineSpec, graphics_pipeline, pipeline_layout
from ..gpu.secondary import SecondaryBuffers, end_command_buffer
from .indirect_draws import IndirectDraws, check_support
from .instance_rows import INSTANCE_DTYPE, write_rows
from ..jobs import JobPool, row_chunks
from .light_rows import LIGHT_DTYPE, write_lights
from .mesh_registry import VERTEX_STRIDE, MeshRegistry
from ..components import render_origin
from ..ecs.world import World

MATERIAL_DTYPE = np.dtype([("color", np.float32, 4), ("specular", np.float32, 4)])
GLOBALS_BYTES = 2 * 64 + 3 * 16  # projection, view, eye, ambient, counts (common.glsl)
MIN_LIGHTS = 256
_HANDLE = (Mesh, "handle")  # the column whose writes make the renderer check mesh handles again
MODES = ("instanced", "per_entity", "indirect")
RECORDERS = ("native", "python")
# Rows per job, by default about one job per thread but never under MIN_CHUNK_ROWS. Measured on
# the H100 host (native recorder): 4,096-row jobs were slower on 16 threads than on 4 (per-job
# Python under GIL contention); at 1M entities and 16 threads the instanced CPU frame took
# 21.49 ms with 16,384-row jobs, 17.98 ms with 32,768 and 14.06 ms with 65,536 (one per core);
# but fixed 65,536-row jobs leave 100k entities in two jobs, so the size follows the thread count.
MIN_CHUNK_ROWS = 16_384
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
class Chunk:
    model: np.ndarray
    handle: np.ndarray
    material: np.ndarray
    offset: int  # first row of this chunk's slice of the instance buffer


@dataclass
class FrameContext:
    """What every chunk job of one frame reads (never writes, except its slice of `instances`)."""

    slot: int  # frame-in-flight index
    descriptor_set: Any
    viewport: Any
    scissor: Any
    planes: np.ndarray | None  # None: culling off
    instances: np.ndarray  # the mapped per-frame instance buffer (INSTANCE_DTYPE rows)
    bounds: tuple[np.ndarray, np.ndarray, np.ndarray]  # per mesh: centre, radius, index count
    begin_info: Any
    native_frame: dict[str, Any] | None = None


@dataclass
class ChunkResult:
    command_buffer: Any  # None when nothing in the chunk is visible
    visible: int
    draws: int
    triangles: int
    key_counts: np.ndarray | None = None  # indirect mode: candidate rows per key


@dataclass
class FrameStats:
    """Indirect mode: draws, instances and triangles are counted on the GPU and read back
    without waiting, so they belong to an earlier frame (like gpu_ms), or to this frame when it
    was read back."""

    draws: int
    instances: int  # visible entities drawn
    triangles: int
    lights: int
    gpu_ms: float | None  # of an earlier frame: timestamps are read without waiting
    wait_ms: float = 0.0  # spent waiting for a frame slot (GPU-bound), not CPU work
    record_ms: float = 0.0  # the chunk jobs: cull, write rows, record secondaries
    chunks: int = 0
    candidates: int = 0  # entities with a mesh, before culling


@dataclass
class _TargetState:
    """Structs that depend only on the framebuffer and its size, built once: each binding struct
    costs microseconds of Python, and a small scene's whole frame budget is 250 us."""

    area: Any
    viewport: Any
    secondary_begin: Any  # begin info with render-pass inheritance
    pass_begin: Any  # VkRenderPassBeginInfo with the clear values
    keep: Any  # what the structs point to
    area_ptr: Any = None  # pointers to the structs above, for raw calls
    viewport_ptr: Any = None
    pass_begin_ptr: Any = None
    native: dict[int, dict[str, Any]] = field(default_factory=dict)  # per slot: the native recorder's frame state


@dataclass
class _PerFrame:
    globals: Buffer
    lights: Buffer
    instances: Buffer
    descriptor_set: Any
    set_array: Any = None  # VkDescriptorSet[1] for raw calls


def _chunk_name(chunk: Chunk) -> str:
    return f"rows {chunk.offset}:{chunk.offset + len(chunk.handle)}"


class Renderer:
    def __init__(self, device: Device, target: Any, meshes: MeshRegistry, *, lights: bool,
                 mode: str = "instanced", jobs: JobPool | None = None, culling: bool = True,
                 chunk_rows: int | None = None, recorder: str = "native", native_recorder: Any = None,
                 clear_color: tuple[float, float, float] = (0.02, 0.02, 0.03),
                 ambient: tuple[float, float, float, float] = (1.0, 1.0, 1.0, 0.06),
                 light_size: float = 0.08) -> None:
        if mode not in MODES:
            raise ValueError(f"unknown render mode {mode!r}; modes: {', '.join(MODES)}")
        if recorder not in RECORDERS:
            raise ValueError(f"unknown recorder {recorder!r}; recorders: {', '.join(RECORDERS)}")
        if mode == "indirect":
            check_support(device)  # before anything is created
        vk = self.vk = device.vk
        self.device = device
        self.target = target
        self.meshes = meshes
        self.with_lights = lights
        self.clear_color = clear_color
        self.ambient = ambient
        self.light_size = light_size
        self.mode = mode
        self.jobs = jobs
        self.culling = culling
        self.chunk_rows = chunk_rows  # None: about one job per thread (see MIN_CHUNK_ROWS)
        self.native = None
        if recorder == "native" and mode != "indirect":  # indirect: jobs write rows, record nothing
            from ..gpu.native_recorder import NativeRecorder

            # compiling one costs about a second: callers rendering many configurations share one
            self.native = native_recorder or NativeRecorder(device)
        self.recorder = recorder
        self.frames = FrameRing(device)
        self.secondaries = SecondaryBuffers(device, len(self.frames.frames))
        stages = vk.VK_SHADER_STAGE_VERTEX_BIT | vk.VK_SHADER_STAGE_FRAGMENT_BIT
        if mode == "indirect":
            stages |= vk.VK_SHADER_STAGE_COMPUTE_BIT
        ssbo = vk.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER
        storage = 7 if mode == "indirect" else 3
        self.set_layout = DescriptorSetLayout(device, [(0, vk.VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, stages)]
                                              + [(b, ssbo, stages) for b in range(1, storage + 1)])
        n = len(self.frames.frames)
        self.pool = DescriptorPool(device, n, {vk.VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER: n, ssbo: storage * n})
        self.indirect = IndirectDraws(device, self.set_layout, n) if mode == "indirect" else None
        # one push range for both users: the billboard size (4 bytes), a per_entity row (64)
        self.layout = pipeline_layout(device, [self.set_layout.handle],
                                      [(vk.VK_SHADER_STAGE_VERTEX_BIT, 0, INSTANCE_DTYPE.itemsize)])
        self.materials = Buffer(device, MATERIAL_DTYPE.itemsize * len(DEFAULT_MATERIALS), vk.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT)
        table = self.materials.array(MATERIAL_DTYPE, len(DEFAULT_MATERIALS))
        for i, (color, strength, shininess) in enumerate(DEFAULT_MATERIALS):
            table[i] = ((*color, 1.0), (strength, shininess, 0.0, 0.0))
        self.per_frame = [self._make_frame_resources(slot) for slot in range(n)]
        self._build_pipelines()
        self._targets: dict[tuple[int, int, int], _TargetState] = {}
        self._scratch = threading.local()
        self._planes_for: np.ndarray | None = None  # the view matrix the planes were made with
        self._planes_value = np.zeros((0, 4))
        self._view_cache: tuple[CameraMatrices, bytes, np.ndarray] | None = None
        self._globals_written: list[tuple[Any, ...] | None] = [None] * n  # per slot: what its buffer holds
        self._chunks_key: tuple[Any, ...] = ()
        self._chunks: list[Chunk] = []
        # drawn last in the overlay subpass: an object with prepare(slot, frames_in_flight) and
        # record(cb, slot, width, height), e.g. imgui_vulkan.ImGuiRenderer
        self.overlay: Any = None
        self._light_size = np.array([light_size], dtype=np.float32)
        self._light_push = vk.ffi.from_buffer(self._light_size)

    # ----------------------------------------------------------------- set-up
    def _make_frame_resources(self, slot: int) -> _PerFrame:
        vk = self.vk
        pf = _PerFrame(
            globals=Buffer(self.device, GLOBALS_BYTES, vk.VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT),
            lights=Buffer(self.device, LIGHT_DTYPE.itemsize * MIN_LIGHTS, vk.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT),
            instances=Buffer(self.device, INSTANCE_DTYPE.itemsize * 1024, vk.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT),
            descriptor_set=self.pool.allocate(self.set_layout),
        )
        pf.set_array = self.vk.ffi.new("VkDescriptorSet[1]", [pf.descriptor_set])
        self._write_set(pf, slot)
        return pf

    def _write_set(self, pf: _PerFrame, slot: int) -> None:
        vk = self.vk
        ssbo = vk.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER
        extra = self.indirect.bindings(slot) if self.indirect is not None else []
        write_buffers(self.device, pf.descriptor_set, [
            (0, vk.VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, pf.globals), (1, ssbo, pf.lights),
            (2, ssbo, pf.instances), (3, ssbo, self.materials)] + extra)

    def _build_pipelines(self) -> None:
        vk = self.vk
        attrs = [(0, vk.VK_FORMAT_R32G32B32_SFLOAT, 0), (1, vk.VK_FORMAT_R32G32B32_SFLOAT, 12)]
        base = dict(layout=self.layout, render_pass=self.target.render_pass, subpass=0,
                    vertex_stride=VERTEX_STRIDE, vertex_attributes=attrs)
        vert = {"instanced": "mesh.vert", "per_entity": "mesh_push.vert", "indirect": "mesh_indirect.vert"}[self.mode]
        self.mesh_pipeline = graphics_pipeline(self.device, GraphicsPipelineSpec(vert, "mesh.frag", **base))
        self.mirrored_pipeline = graphics_pipeline(self.device, GraphicsPipelineSpec(
            vert, "mesh.frag", front_face_ccw=False, **base))
        self.light_pipeline = None
        if self.with_lights:
            self.light_pipeline = graphics_pipeline(self.device, GraphicsPipelineSpec(
                "light.vert", "light.frag", layout=self.layout, render_pass=self.target.render_pass, subpass=1,
                cull_back=False, depth_write=False, alpha_blend=True))

    def _target_state(self, framebuffer: Any, width: int, height: int) -> _TargetState:
        vk = self.vk
        key = (int(vk.ffi.cast("uintptr_t", framebuffer)), width, height)
        state = self._targets.get(key)
        if state is None:
            if len(self._targets) > 16:  # swapchains come and go: drop the old framebuffers' entries
                self._targets.clear()
            area = vk.VkRect2D(offset=vk.VkOffset2D(0, 0), extent=vk.VkExtent2D(width, height))
            clears = [vk.VkClearValue(color=vk.VkClearColorValue(float32=[*self.clear_color, 1.0])),
                      vk.VkClearValue(depthStencil=vk.VkClearDepthStencilValue(depth=0.0, stencil=0))]  # reverse-Z
            state = self._targets[key] = _TargetState(
                area=area,
                viewport=vk.VkViewport(x=0.0, y=0.0, width=float(width), height=float(height), minDepth=0.0,
                                       maxDepth=1.0),
                secondary_begin=self.secondaries.begin_info(self.target.render_pass, 0, framebuffer),
                pass_begin=vk.VkRenderPassBeginInfo(renderPass=self.target.render_pass, framebuffer=framebuffer,
                                                    renderArea=area, pClearValues=clears),
                keep=(clears, framebuffer))
            state.area_ptr = vk.ffi.addressof(state.area)
            state.viewport_ptr = vk.ffi.addressof(state.viewport)
            state.pass_begin_ptr = vk.ffi.addressof(state.pass_begin)
        return state

    def _ensure_capacity(self, slot: int, instances: int, lights: int) -> None:
        """Grow a frame's buffers (doubling); safe: this frame's fence has been waited on."""
        vk = self.vk
        pf = self.per_frame[slot]
        changed = self.indirect is not None and self.indirect.ensure_capacity(slot, 2 * len(self.meshes), instances)
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
            self._write_set(pf, slot)

    # ------------------------------------------------------------- per frame
    def chunks(self, world: World) -> list[Chunk]:
        """Row ranges of every table with a ModelMatrix and a Mesh, each with its buffer slice.
        Kept while the world is the same and its tables keep their rows, layout and Mesh.handle
        column (the views stay valid and see every value written since)."""
        query = world.query(ModelMatrix, Mesh, write=())
        tables = query.tables
        key = (world, self.chunk_rows, self.jobs.threads if self.jobs is not None else 1, len(self.meshes),
               *[(t.id, t.version, t.count, t.column_ticks[_HANDLE]) for t in tables])
        if key == self._chunks_key:
            return self._chunks
        out: list[Chunk] = []
        offset = 0
        for batch in query:
            m, mesh = batch[ModelMatrix], batch[Mesh]
            for s in row_chunks(len(batch), self._rows_per_job(len(batch))):
                out.append(Chunk(m.model[s], mesh.handle[s], mesh.material[s], offset))
                offset += s.stop - s.start
        if out:
            top = max(int(c.handle.max()) for c in out)
            if top >= len(self.meshes):
                raise ValueError(f"Mesh.handle {top} does not name an uploaded mesh ({len(self.meshes)} uploaded)")
        self._chunks_key, self._chunks = key, out
        return out

    def _rows_per_job(self, rows: int) -> int:
        if self.chunk_rows is not None:
            return self.chunk_rows
        threads = self.jobs.threads if self.jobs is not None else 1
        return max(MIN_CHUNK_ROWS, -(-rows // threads))

    def _planes(self, projection: np.ndarray, view: np.ndarray) -> np.ndarray:
        """Frustum planes, kept while the view is the same object: `_view` makes a new one
        whenever the camera matrices (projection included) or the origin change."""
        if view is not self._planes_for:
            self._planes_for, self._planes_value = view, frustum_planes(projection, view)
        return self._planes_value

    def _view(self, cam: CameraMatrices, origin: np.ndarray, origin_key: bytes) -> np.ndarray:
        """view_from_origin, kept while the camera matrices and the origin stay the same."""
        cached = self._view_cache
        if cached is None or cached[0] is not cam or cached[1] != origin_key:
            cached = self._view_cache = (cam, origin_key, view_from_origin(cam, origin))
        return cached[2]

    def _scratch_rows(self, n: int) -> np.ndarray:
        """This thread's reusable rows (per_entity mode), at least n long."""
        rows = getattr(self._scratch, "rows", None)
        if rows is None or len(rows) < n:
            rows = self._scratch.rows = np.empty(max(n, 1024), INSTANCE_DTYPE)
        return rows[:n]

    def _mesh_bounds(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        n = len(self.meshes)
        if getattr(self, "_bounds_n", -1) != n:
            self._bounds = (np.array([self.meshes[h].data.center for h in range(n)], dtype=np.float64).reshape(n, 3),
                            np.array([self.meshes[h].data.radius for h in range(n)], dtype=np.float64),
                            np.array([self.meshes[h].index_count for h in range(n)], dtype=np.int64))
            self._bounds_n = n
        return self._bounds

    def record_chunk(self, chunk: Chunk, ctx: FrameContext) -> ChunkResult:
        """One job: cull, write the visible rows into this chunk's slice, record a secondary."""
        vk = self.vk
        centers_m, radii_m, index_counts = ctx.bounds
        if self.mode == "per_entity":
            # the rows only feed push constants: write them to cached CPU memory, not to the mapped
            # buffer, which is write-combined on discrete GPUs and slow to read back
            rows = self._scratch_rows(len(chunk.handle))
        else:
            rows = ctx.instances[chunk.offset : chunk.offset + len(chunk.handle)]
        key_counts = np.zeros(2 * len(index_counts), dtype=np.int64)
        planes = None if self.indirect is not None else ctx.planes  # indirect: the GPU culls
        n = write_rows(chunk.model, chunk.handle, chunk.material, centers_m, radii_m, planes,
                       len(DEFAULT_MATERIALS), rows, key_counts)
        if self.indirect is not None:
            return ChunkResult(None, 0, 0, 0, key_counts)
        if n == 0:
            return ChunkResult(None, 0, 0, 0)
        instanced = self.mode == "instanced"
        if self.native is not None:
            cb = self.secondaries.acquire(ctx.slot)
            draws, triangles = self.native.record(cb, rows, instanced, chunk.offset, key_counts, ctx.native_frame)
            return ChunkResult(cb, n, draws, triangles)
        keys = np.flatnonzero(key_counts)
        counts = key_counts[keys]
        starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
        run_mesh, flipped = np.divmod(keys, 2)
        draws = len(starts) if instanced else n
        triangles = int((index_counts[run_mesh] // 3 * counts).sum())
        cb = self.secondaries.begin(ctx.slot, ctx.begin_info)
        vk.vkCmdSetViewport(cb, 0, 1, [ctx.viewport])  # not inherited by secondaries
        vk.vkCmdSetScissor(cb, 0, 1, [ctx.scissor])
        vk.vkCmdBindDescriptorSets(cb, vk.VK_PIPELINE_BIND_POINT_GRAPHICS, self.layout, 0, 1, [ctx.descriptor_set],
                                   0, None)
        self._record_runs_python(cb, rows, instanced, chunk.offset, starts, counts, run_mesh, flipped)
        vk.vkEndCommandBuffer(cb)
        return ChunkResult(cb, n, draws, triangles)

    def _record_runs_python(self, cb: Any, rows: np.ndarray, instanced: bool, first: int, starts: np.ndarray,
                            counts: np.ndarray, run_mesh: np.ndarray, flipped: np.ndarray) -> None:
        """The readable baseline (and fallback without numba): the binding's call per command."""
        vk = self.vk
        bound = None
        for start, count, h, mirrored in zip(starts.tolist(), counts.tolist(), run_mesh.tolist(), flipped.tolist()):
            pipeline = self.mirrored_pipeline if mirrored else self.mesh_pipeline
            if pipeline is not bound:
                vk.vkCmdBindPipeline(cb, vk.VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline)
                bound = pipeline
            mesh = self.meshes.bind(cb, h)
            if instanced:
                vk.vkCmdDrawIndexed(cb, mesh.index_count, count, 0, 0, first + start)
                continue
            for i in range(start, start + count):
                vk.vkCmdPushConstants(cb, self.layout, vk.VK_SHADER_STAGE_VERTEX_BIT, 0,
                                      INSTANCE_DTYPE.itemsize, vk.ffi.from_buffer(rows[i : i + 1]))
                vk.vkCmdDrawIndexed(cb, mesh.index_count, 1, 0, 0, 0)

    @staticmethod
    def light_columns(world: World) -> list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
        """Per table of lights: position, radius, color and intensity columns (see write_lights)."""
        out = []
        for batch in world.query(PointLight, Transform, write=()):
            light = batch[PointLight]
            out.append((batch[Transform].position, light.radius, light.color, light.intensity))
        return out

    def render(self, world: World, readback: bool = False, framebuffer: Any = None,
               extent: tuple[int, int] | None = None, wait: Any = None, signal: Any = None) -> FrameStats:
        """Record and submit one frame. Headless targets read the image back when asked."""
        vk = self.vk
        width, height = extent or (self.target.width, self.target.height)
        framebuffer = framebuffer or self.target.framebuffer
        frame, gpu_ms = self.frames.begin()
        slot = self.frames.frames.index(frame)
        pf = self.per_frame[slot]
        # indirect mode: the slot's last counts, before this frame overwrites them (a read-back
        # frame reads its own counts after the wait instead)
        previous = None if self.indirect is None or readback else self.indirect.counts(slot, self._mesh_bounds()[2])
        self.secondaries.reset(slot)
        if self.overlay is not None:
            self.overlay.prepare(slot, len(self.frames.frames))
        cam = camera_matrices(world, width / height)
        origin = render_origin(world)
        origin_key = origin.tobytes()
        view = self._view(cam, origin, origin_key)
        lights = self.light_columns(world) if self.with_lights else []
        light_count = sum(len(part[0]) for part in lights)
        chunks = self.chunks(world)
        candidates = sum(len(c.handle) for c in chunks)
        self._ensure_capacity(slot, 0 if self.mode == "per_entity" else candidates, light_count)
        if light_count:
            write_lights(lights, origin, cam.position - origin,
                         pf.lights.array(np.float32, (light_count, LIGHT_DTYPE.itemsize // 4)))
        self._write_globals(slot, cam, view, origin, origin_key, light_count)
        target = self._target_state(framebuffer, width, height)
        ctx = FrameContext(
            slot=slot, descriptor_set=pf.descriptor_set, scissor=target.area, viewport=target.viewport,
            planes=self._planes(cam.projection, view) if self.culling else None,
            instances=pf.instances.array(INSTANCE_DTYPE),
            bounds=self._mesh_bounds(),
            begin_info=target.secondary_begin,
        )
        if self.native is not None:
            if self.native.meshes_known != len(self.meshes):
                gpu = [self.meshes[h] for h in range(len(self.meshes))]
                self.native.set_meshes([m.vertices.handle for m in gpu], [m.indices.handle for m in gpu],
                                       [m.index_count for m in gpu])
            if slot not in target.native:
                target.native[slot] = self.native.frame_state(
                    ctx.begin_info, width, height, pf.descriptor_set, self.layout, vk.VK_SHADER_STAGE_VERTEX_BIT,
                    (self.mesh_pipeline, self.mirrored_pipeline))
            ctx.native_frame = target.native[slot]
        t0 = time.perf_counter()
        job = lambda chunk: self.record_chunk(chunk, ctx)
        results = self.jobs.map(job, chunks, _chunk_name) \
            if self.jobs is not None else [job(c) for c in chunks]
        record_ms = (time.perf_counter() - t0) * 1e3
        cb = frame.command_buffer
        secondaries = [r.command_buffer for r in results if r.command_buffer is not None]
        if self.indirect is not None:
            secondaries = self._record_indirect(cb, ctx, results, candidates)
        self._record_primary(cb, secondaries, light_count, target, slot)
        if readback:
            self.target.record_readback(cb)
        self.frames.end(frame, wait=wait, signal=signal)
        if readback:
            self.frames.wait(frame)
        stats = FrameStats(draws=sum(r.draws for r in results), instances=sum(r.visible for r in results),
                           triangles=sum(r.triangles for r in results), lights=light_count, gpu_ms=gpu_ms,
                           wait_ms=self.frames.last_wait_ms, record_ms=record_ms, chunks=len(chunks),
                           candidates=candidates)
        if self.indirect is not None:
            # counted on the GPU: this frame's when it was waited for, else the slot's previous one
            counts = self.indirect.counts(slot, ctx.bounds[2]) if readback else previous
            if counts is not None:
                stats.draws, stats.instances, stats.triangles = counts.draws, counts.visible, counts.triangles
        stats.draws += 1 if light_count else 0
        return stats

    def _record_indirect(self, cb: Any, ctx: FrameContext, results: list[ChunkResult], candidates: int) -> list[Any]:
        """The compute passes into the primary (before the render pass) and the one secondary
        that draws what they wrote."""
        assert self.indirect is not None
        keys = 2 * len(self.meshes)
        key_counts = np.zeros(keys, dtype=np.int64)
        for r in results:
            key_counts += r.key_counts
        merged = self.meshes.merged()
        self.indirect.prepare(ctx.slot, key_counts, merged, ctx.bounds)
        set_array = self.per_frame[ctx.slot].set_array
        planes = None if ctx.planes is None else ctx.planes.astype(np.float32)
        self.indirect.record_compute(cb, ctx.slot, set_array, planes, candidates, keys)
        vk = self.vk
        lib = vk.lib
        secondary = self.secondaries.begin(ctx.slot, ctx.begin_info)
        lib.vkCmdSetViewport(secondary, 0, 1, vk.ffi.addressof(ctx.viewport))
        lib.vkCmdSetScissor(secondary, 0, 1, vk.ffi.addressof(ctx.scissor))
        lib.vkCmdBindDescriptorSets(secondary, vk.VK_PIPELINE_BIND_POINT_GRAPHICS, self.layout, 0, 1, set_array, 0,
                                    vk.ffi.NULL)
        self.indirect.record_draws(secondary, ctx.slot, (self.mesh_pipeline, self.mirrored_pipeline), merged,
                                   key_counts)
        end_command_buffer(vk, secondary)
        return [secondary]

    def _write_globals(self, slot: int, cam: CameraMatrices, view: np.ndarray, origin: np.ndarray,
                       origin_key: bytes, light_count: int) -> None:
        """The frame's uniforms, rewritten only when something in them changed (the slot's
        mapped buffer keeps what was last written there)."""
        written = (cam, origin_key, light_count, tuple(self.ambient))
        last = self._globals_written[slot]
        if last is not None and last[0] is cam and last[1:] == written[1:]:
            return
        raw = self.per_frame[slot].globals.bytes()
        mats = raw[:128].view(np.float32).reshape(2, 4, 4)
        mats[0] = cam.projection.T  # column-major for GLSL
        mats[1] = view.T
        raw[128:140].view(np.float32)[:] = cam.position - origin  # float64 difference, then the cast
        raw[144:160].view(np.float32)[:] = self.ambient
        raw[160:176].view(np.uint32)[:] = (light_count, 0, 0, 0)
        self._globals_written[slot] = written

    def _record_primary(self, cb: Any, secondaries: list[Any], light_count: int, target: _TargetState,
                        slot: int) -> None:
        """Raw cffi calls with structs made once (see gpu/frames.py for why)."""
        vk = self.vk
        lib = vk.lib
        lib.vkCmdBeginRenderPass(cb, target.pass_begin_ptr, vk.VK_SUBPASS_CONTENTS_SECONDARY_COMMAND_BUFFERS)
        if secondaries:
            lib.vkCmdExecuteCommands(cb, len(secondaries), vk.ffi.new("VkCommandBuffer[]", secondaries))
        lib.vkCmdNextSubpass(cb, vk.VK_SUBPASS_CONTENTS_INLINE)
        if light_count and self.light_pipeline is not None:
            lib.vkCmdSetViewport(cb, 0, 1, target.viewport_ptr)
            lib.vkCmdSetScissor(cb, 0, 1, target.area_ptr)
            lib.vkCmdBindPipeline(cb, vk.VK_PIPELINE_BIND_POINT_GRAPHICS, self.light_pipeline)
            lib.vkCmdBindDescriptorSets(cb, vk.VK_PIPELINE_BIND_POINT_GRAPHICS, self.layout, 0, 1,
                                        self.per_frame[slot].set_array, 0, vk.ffi.NULL)
            self._light_size[0] = self.light_size
            lib.vkCmdPushConstants(cb, self.layout, vk.VK_SHADER_STAGE_VERTEX_BIT, 0, 4, self._light_push)
            lib.vkCmdDraw(cb, 6, light_count, 0, 0)
        if self.overlay is not None:
            self.overlay.record(cb, slot, target.area.extent.width, target.area.extent.height)
        lib.vkCmdEndRenderPass(cb)

    def destroy(self) -> None:
        vk = self.vk
        self.device.wait_idle()
        for pipeline in (self.mesh_pipeline, self.mirrored_pipeline, self.light_pipeline):
            if pipeline is not None:
                vk.vkDestroyPipeline(self.device.handle, pipeline, None)
        vk.vkDestroyPipelineLayout(self.device.handle, self.layout, None)
        self.secondaries.destroy()
        if self.indirect is not None:
            self.indirect.destroy()
        for pf in self.per_frame:
            pf.globals.destroy()
            pf.lights.destroy()
            pf.instances.destroy()
        self.materials.destroy()
        self.pool.destroy()
        self.set_layout.destroy()
        self.frames.destroy()
