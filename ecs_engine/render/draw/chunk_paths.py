"""The render paths that record draws on the CPU, one secondary command buffer per chunk job:

- `instanced`: one instanced draw per (mesh, winding) run of a chunk, the rows read by the
  vertex shader from the frame's instance buffer;
- `per_entity`: the seed's way, the row in push constants and one draw per entity.

Each job culls its rows, writes the visible ones sorted by key (mesh * 2 + mirrored; see
instance_rows.py) and records them with a recorder picked from RECORDERS: `native` (a numba
loop calling the driver without the GIL, gpu/native_recorder.py) or `python` (the binding's
call per command: the readable baseline). Mirrored rows (negative determinant) use the pipeline
with the opposite front face, so back-face culling stays right.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any, ClassVar

import numpy as np

from ... import native
from ...gpu.gbuffer import GBUFFER_COLORS
from ...gpu.pipeline import GraphicsPipelineSpec, graphics_pipeline, pipeline_layout
from ...gpu.secondary import end_command_buffer
from ..config import choice
from ..extract.frame_data import MODEL_COLUMN, NOT_RECEIVER, Chunk
from ..layouts import (
    FEATURE_ALPHA_MASK,
    FEATURE_CLUSTERED,
    FEATURE_DOUBLE_SIDED,
    FEATURE_TEXTURES,
    INSTANCE,
    MESH_VERTEX,
)
from .instance_rows import masked_keys, write_keyed, write_rows
from .path import FILL_MODES, ChunkResult, FrameInputs, PathContext, summed_counts
from .path_pipelines import PipelinesPerTarget

# The MESH_VERTEX fields mesh_vertex.glsl reads, at locations 0, 1, ...: only those are bound (an
# attribute the shader does not read is a validation performance warning). The textured variants
# (some material has a texture: FEATURE_TEXTURES) read all four.
VERTEX_INPUTS = ("position", "normal")
TEXTURED_VERTEX_INPUTS = ("position", "normal", "uv", "tangent")


def vertex_attributes(vk: Any, inputs: tuple[str, ...] = VERTEX_INPUTS) -> list[tuple[int, int, int]]:
    """(location, format, offset) of the vertex inputs."""
    formats = {2: vk.VK_FORMAT_R32G32_SFLOAT, 3: vk.VK_FORMAT_R32G32B32_SFLOAT, 4: vk.VK_FORMAT_R32G32B32A32_SFLOAT}
    fields: dict[str, Any] = dict(MESH_VERTEX.fields or {})
    return [(location, formats[fields[name][0].shape[0]], fields[name][1]) for location, name in enumerate(inputs)]


def mesh_pipelines(ctx: PathContext, layout: Any, vertex_shader: str, blended: bool = False) -> tuple[Any, Any]:
    """The (plain, mirrored) mesh pipelines of a path: the same but for the front face. Textured
    materials take the `_textured` variants of both shaders (`mesh.vert` -> `mesh_textured.vert`);
    clustered lights the `_clustered` fragment shaders (they need subgroup arithmetic); the
    G-buffer pass (ctx.gbuffer) the `_gbuffer` ones, which light nothing."""
    if ctx.shadow:
        return shadow_pipelines(ctx, layout, vertex_shader)
    textured = bool(ctx.material_features & FEATURE_TEXTURES)
    clustered = bool(ctx.material_features & FEATURE_CLUSTERED)
    lighting = "_gbuffer" if ctx.gbuffer else "_clustered" if clustered else ""
    fragment_shader = f"mesh{'_textured' if textured else ''}{lighting}{'_oit' if ctx.oit else ''}.frag"
    if textured:
        vertex_shader = vertex_shader.replace(".vert", "_textured.vert")
    base = dict(
        layout=layout,
        vertex_stride=MESH_VERTEX.itemsize,
        vertex_attributes=vertex_attributes(ctx.device.vk, TEXTURED_VERTEX_INPUTS if textured else VERTEX_INPUTS),
        fragment_constants=(ctx.material_features,),  # mesh.frag's MATERIAL_FEATURES
        vertex_constants=(ctx.material_features,),  # deform.glsl's (FEATURE_DEFORM)
        polygon_mode=FILL_MODES[ctx.fill],
        samples=ctx.samples,
        # a double-sided material somewhere: back faces reach the fragment shader, which drops
        # those of single-sided materials (one pipeline for all; draws stay split by mesh only)
        cull_back=not ctx.material_features & FEATURE_DOUBLE_SIDED,
        # blended materials (set_aside_pass.py): over what is drawn, without hiding what follows
        alpha_blend=blended and not ctx.oit,
        blend="weighted" if ctx.oit else "",
        depth_write=not blended,
        color_attachments=GBUFFER_COLORS if ctx.gbuffer else 2 if ctx.oit else 1,
    )
    base.update(ctx.pipeline_target())
    vk = ctx.device.vk
    plain = graphics_pipeline(ctx.device, GraphicsPipelineSpec(vertex_shader, fragment_shader, **base))
    try:
        mirrored = graphics_pipeline(
            ctx.device, GraphicsPipelineSpec(vertex_shader, fragment_shader, front_face_ccw=False, **base)
        )
    except BaseException:
        vk.vkDestroyPipeline(ctx.device.handle, plain, None)
        raise
    return plain, mirrored


# A caster's depth pushed away from the light (reverse-Z: towards 0) by the rasteriser, in
# depth-format units and per unit of depth slope; the receivers add Shadow.bias and normal_offset.
SHADOW_DEPTH_BIAS = (-1.0, -1.5)


def shadow_pipelines(ctx: PathContext, layout: Any, vertex_shader: str) -> tuple[Any, Any]:
    """The (plain, mirrored) depth-only pipelines of a path's shadow passes: the position alone
    (shadow.vert, shadow_push.vert for push-constant rows, shadow_indirect.vert for rows culled
    on the GPU), no fragment shader; where some material is alpha-masked or double-sided, the
    _cutout variants and shadow_cutout.frag, which leave the holes out of the map and, culling
    being off for the double-sided, the single-sided materials' back faces."""
    cutout = bool(ctx.material_features & (FEATURE_ALPHA_MASK | FEATURE_DOUBLE_SIDED))
    shader = {
        "mesh.vert": "shadow.vert",
        "mesh_push.vert": "shadow_push.vert",
        "mesh_indirect.vert": "shadow_indirect.vert",  # the GPU-culled views (shadow_indirect.py)
    }[vertex_shader]
    if cutout:
        shader = shader.replace(".vert", "_cutout.vert")
    fragment = "shadow_cutout.frag" if cutout else None
    base = dict(
        layout=layout,
        vertex_stride=MESH_VERTEX.itemsize,
        vertex_attributes=vertex_attributes(ctx.device.vk, ("position", "uv") if cutout else ("position",)),
        fragment_constants=(ctx.material_features,) if cutout else (),
        vertex_constants=(ctx.material_features,),  # deform.glsl's (FEATURE_DEFORM)
        cull_back=not ctx.material_features & FEATURE_DOUBLE_SIDED,
        color_attachments=0,
        depth_bias=SHADOW_DEPTH_BIAS,
    )
    base.update(ctx.pipeline_target())
    plain = graphics_pipeline(ctx.device, GraphicsPipelineSpec(shader, fragment, **base))
    try:
        mirrored = graphics_pipeline(ctx.device, GraphicsPipelineSpec(shader, fragment, front_face_ccw=False, **base))
    except BaseException:
        ctx.device.vk.vkDestroyPipeline(ctx.device.handle, plain, None)
        raise
    return plain, mirrored


class PythonRecorder:
    """The readable baseline (and the fallback without numba): the binding's call per command."""

    def __init__(self, path: ChunkPath) -> None:
        self.path = path

    def frame_state(self, frame: FrameInputs) -> None:
        return None

    def record(
        self, rows: np.ndarray, key_counts: np.ndarray, first_instance: int, frame: FrameInputs
    ) -> tuple[Any, int, int]:
        path = self.path
        vk = path.vk
        index_counts = frame.bounds[2]
        keys = np.flatnonzero(key_counts)
        counts = key_counts[keys]
        starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
        run_mesh, flipped = np.divmod(keys, 2)
        draws = len(starts) if path.instanced else int(counts.sum())
        triangles = int((index_counts[run_mesh] // 3 * counts).sum())
        cb = path.ctx.secondaries.begin(frame.slot, frame.target.secondary_begin)
        vk.vkCmdSetViewport(cb, 0, 1, [frame.target.viewport])  # not inherited by secondaries
        vk.vkCmdSetScissor(cb, 0, 1, [frame.target.area])
        vk.vkCmdBindDescriptorSets(
            cb, vk.VK_PIPELINE_BIND_POINT_GRAPHICS, path.layout, 0, 1, [frame.descriptor_set], 0, None
        )
        bound = None
        for start, count, h, mirrored in zip(starts.tolist(), counts.tolist(), run_mesh.tolist(), flipped.tolist()):
            pipeline = path.pipelines[mirrored]
            if pipeline is not bound:
                vk.vkCmdBindPipeline(cb, vk.VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline)
                bound = pipeline
            mesh = path.ctx.meshes.bind(cb, h)
            if path.instanced:
                vk.vkCmdDrawIndexed(cb, mesh.index_count, count, 0, 0, first_instance + start)
                continue
            for i in range(start, start + count):
                vk.vkCmdPushConstants(
                    cb,
                    path.layout,
                    vk.VK_SHADER_STAGE_VERTEX_BIT,
                    0,
                    INSTANCE.size,
                    vk.ffi.from_buffer(rows[i : i + 1]),
                )
                vk.vkCmdDrawIndexed(cb, mesh.index_count, 1, 0, 0, 0)
        end_command_buffer(vk, cb)
        return cb, draws, triangles


def written_from(chunk: Chunk, frame: FrameInputs) -> tuple[Any, ...]:
    """What a chunk's rows are written from: the chunk (its views, kept while its table's layout,
    rows and Mesh columns stay), when its model matrices were last written, the frustum planes
    (one array while the view stays), the mesh bounds and the material count."""
    return (chunk, chunk.ticks[MODEL_COLUMN] if chunk.ticks else -1, frame.planes, frame.bounds, frame.material_count)


def same_inputs(a: tuple[Any, ...] | None, b: tuple[Any, ...]) -> bool:
    """Whether two `written_from` are the same: objects by identity (held, so never a freed
    one's), ticks and counts by value."""
    return a is not None and a[0] is b[0] and a[1] == b[1] and a[2] is b[2] and a[3] is b[3] and a[4] == b[4]


class NativeRecorder:
    """The numba loop of gpu/native_recorder.py; its per-slot frame state lives with the target
    (TargetState.path_state), so both are dropped together when the output state goes."""

    def __init__(self, path: ChunkPath) -> None:
        self.path = path
        self.compiled = path.ctx.native_recorder()  # compiled once per device; UsageError without numba

    def frame_state(self, frame: FrameInputs) -> dict[str, Any]:
        """Made once per target and slot (and after meshes were added)."""
        compiled, meshes = self.compiled, self.path.ctx.meshes
        if compiled.meshes_known != meshes.version:  # added or replaced (hot reload)
            gpu = [meshes[h] for h in range(len(meshes))]
            compiled.set_meshes(
                [m.vertices.handle for m in gpu],
                [m.indices.handle for m in gpu],
                [m.index_count for m in gpu],
                meshes.version,
            )
        key = (self, frame.slot)  # this recorder (not its id: a later one may get the same id)
        state = frame.target.path_state.get(key)
        if state is None:
            vk = self.path.vk
            _, width, height = frame.target.key
            state = frame.target.path_state[key] = compiled.frame_state(
                frame.target.secondary_begin,
                width,
                height,
                frame.descriptor_set,
                self.path.layout,
                vk.VK_SHADER_STAGE_VERTEX_BIT,
                self.path.pipelines,
            )
        return state

    def record(
        self, rows: np.ndarray, key_counts: np.ndarray, first_instance: int, frame: FrameInputs
    ) -> tuple[Any, int, int]:
        cb = self.path.ctx.secondaries.acquire(frame.slot)
        draws, triangles = self.compiled.record(
            cb, rows, self.path.instanced, first_instance, key_counts, frame.path_state
        )
        return cb, draws, triangles


RECORDERS: dict[str, Callable[[ChunkPath], PythonRecorder | NativeRecorder]] = {
    "native": NativeRecorder,
    "python": PythonRecorder,
}


def default_recorder() -> str:
    return "native" if native.AVAILABLE else "python"


def check_recorder(name: str) -> None:
    choice("recorder", name)  # UsageError naming the choices (config.Recorder: RECORDERS' names)


class ChunkPath(PipelinesPerTarget):
    """A CPU-recorded path; subclasses say how a row reaches the vertex shader."""

    name: ClassVar[str]
    uses_recorder: ClassVar[bool] = True  # the CPU records the draws, with one of RECORDERS
    vertex_shader: ClassVar[str]
    instanced: ClassVar[bool]
    replayable: ClassVar[bool]  # a chunk's draws depend on its run counts alone (frame_replay.py)
    push_bytes: ClassVar[int]  # push constant range of the mesh pipelines (0: none)

    def __init__(self, ctx: PathContext, recorder: str) -> None:
        check_recorder(recorder)
        self.ctx = ctx
        self.vk = vk = ctx.device.vk
        self.recorder = recorder
        self._recorder = RECORDERS[recorder](self)  # first: it may refuse (no numba) before anything is made
        push = [(vk.VK_SHADER_STAGE_VERTEX_BIT, 0, self.push_bytes)] if self.push_bytes else []
        self.layout = pipeline_layout(ctx.device, [ctx.frame_set_layout], push)
        try:
            self._first_pipelines()
        except BaseException:
            vk.vkDestroyPipelineLayout(ctx.device.handle, self.layout, None)
            raise

    def rows_needed(self, candidates: int) -> int:
        return candidates

    def begin_frame(self, frame: FrameInputs) -> None:
        frame.path_state = self._recorder.frame_state(frame)

    def rows_for(self, chunk: Chunk, frame: FrameInputs) -> np.ndarray:
        first = frame.row_base + chunk.offset
        return frame.instances[first : first + len(chunk.handle)]

    def record_chunk(self, chunk: Chunk, frame: FrameInputs) -> ChunkResult:
        """One job: cull, write the visible rows sorted by key, record a secondary. A chunk whose
        rows in this slot were written from the same inputs (`written_from`) and recorded is
        given back as it stands: a still camera over still rows writes nothing."""
        written, culling = None, frame.data.culling
        if chunk.ticks is not None and not culling.decides_ahead:
            written = written_from(chunk, frame)
            kept = None if frame.reuse is None else frame.reuse.get(frame.row_base + chunk.offset)
            if kept is not None and same_inputs(kept.written, written):
                return kept
        centers, radii, index_counts = frame.bounds
        rows = self.rows_for(chunk, frame)
        key_counts = np.zeros(2 * len(index_counts), dtype=np.int64)
        visible = culling.kept(frame.data, chunk)
        if visible is not None:  # culled ahead (temporal): write what it kept
            keys = masked_keys(chunk.model, chunk.handle, visible, key_counts)
            return self.record_keyed(chunk, frame, keys, key_counts)
        n = write_rows(
            chunk.model,
            chunk.handle,
            chunk.material,
            centers,
            radii,
            frame.planes,
            frame.material_count,
            rows,
            key_counts,
            chunk.extra,
        )
        result = self._recorded(chunk, frame, rows, n, key_counts)
        result.written = written
        return result

    def record_keyed(self, chunk: Chunk, frame: FrameInputs, keys: np.ndarray, key_counts: np.ndarray) -> ChunkResult:
        """record_chunk for a chunk already culled (instance_rows.cull_views: one view's keys)."""
        rows = self.rows_for(chunk, frame)
        n = write_keyed(chunk.model, chunk.material, keys, key_counts, frame.material_count, rows, chunk.extra)
        result = self._recorded(chunk, frame, rows, n, key_counts)
        result.written = None  # rows from another culling (a kept result may say otherwise): never kept
        return result

    def _recorded(
        self, chunk: Chunk, frame: FrameInputs, rows: np.ndarray, n: int, key_counts: np.ndarray
    ) -> ChunkResult:
        if n == 0:
            return ChunkResult(None, 0, 0, 0)
        if chunk.flags & NOT_RECEIVER:
            rows["misc"][:n, 2] |= 1  # no shadow falls on these (mesh_vertex.glsl)
        first = frame.row_base + chunk.offset
        recorded = (first, n, key_counts.tobytes())  # the draws depend on these alone (instanced)
        if frame.reuse is not None:  # the slot's last frame was recorded like this one (frame_replay.py)
            kept = frame.reuse.get(first)
            if kept is not None and kept.recorded == recorded:
                return kept  # its secondary, still recorded: the same draws over the rows just written
        cb, draws, triangles = self._recorder.record(rows, key_counts, first, frame)
        return ChunkResult(cb, n, draws, triangles, recorded=recorded)

    def finish(self, cb: Any, frame: FrameInputs, results: list[ChunkResult], candidates: int) -> list[Any]:
        return [r.command_buffer for r in results if r.command_buffer is not None]

    def counts(self, frame: FrameInputs, results: list[ChunkResult]) -> tuple[int, int, int]:
        return summed_counts(results)

    def destroy(self) -> None:
        self._destroy_pipelines()
        self.vk.vkDestroyPipelineLayout(self.ctx.device.handle, self.layout, None)

    def _make_pipelines(self, ctx: PathContext) -> tuple[Any, Any]:
        return mesh_pipelines(ctx, self.layout, self.vertex_shader)


class InstancedPath(ChunkPath):
    name = "instanced"
    vertex_shader = "mesh.vert"
    instanced = True
    replayable = True
    push_bytes = 0


class PerEntityPath(ChunkPath):
    name = "per_entity"
    vertex_shader = "mesh_push.vert"
    instanced = False
    replayable = False  # the rows are in the pushes: recorded anew each frame
    push_bytes = INSTANCE.size

    def __init__(self, ctx: PathContext, recorder: str) -> None:
        super().__init__(ctx, recorder)
        self._scratch = threading.local()

    def rows_needed(self, candidates: int) -> int:
        return 0  # the rows only feed push constants

    def rows_for(self, chunk: Chunk, frame: FrameInputs) -> np.ndarray:
        """This thread's reusable rows: cached CPU memory, not the mapped buffer, which is
        write-combined on discrete GPUs and slow to read back for the pushes."""
        n = len(chunk.handle)
        rows = getattr(self._scratch, "rows", None)
        if rows is None or len(rows) < n:
            rows = self._scratch.rows = np.empty(max(n, 1024), INSTANCE.dtype)
        return rows[:n]
