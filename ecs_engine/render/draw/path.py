"""The interface every render path implements, and what the renderer hands a path each frame.

A render path is one way of drawing the scene's mesh rows: `instanced` and `per_entity`
(chunk_paths.py) record draws on the CPU, `indirect` (indirect_path.py) lets compute shaders
write them. The renderer picks one from its table by name and swaps it when the mode changes;
everything else (frame slots, per-frame buffers, the light pass, the overlay) stays.

Per frame:
1. `rows_needed(candidates)`: instance rows the path writes into the frame's mapped buffer;
2. `record_chunk(chunk, frame)` for every chunk, on the worker pool (cull, write rows, record a
   secondary command buffer, or only write rows);
3. `finish(cb, frame, results, candidates)` on the main thread: commands for the primary before the render
   pass (compute), and the secondaries to execute in the scene's (or G-buffer's) rendering;
4. after submit, `counts(frame, results)`: draws, visible rows and triangles.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from ...gpu.device import Device
from ...gpu.pipeline import AttachmentFormats
from ...gpu.secondary import SecondaryBuffers
from ..assets.mesh_registry import MeshRegistry
from ..extract.frame_data import Chunk, FrameData

#: --fill: name -> VkPolygonMode (wireframe and points need the device's fillModeNonSolid)
FILL_MODES = {"solid": 0, "wireframe": 1, "points": 2}  # the names are materials.FILLS

MeshBounds = tuple[np.ndarray, np.ndarray, np.ndarray]  # per mesh: centre (n, 3), radius, index count


@dataclass
class TargetState:
    """Structs that depend only on the output image, the form and the size, built once: each
    binding struct costs microseconds of Python, and a small scene's whole CPU frame is 100 us."""

    key: tuple[int, int, int]  # an attachment view's address, width, height
    area: Any
    viewport: Any
    secondary_begin: Any  # the chunks' begin info with rendering inheritance (gpu/secondary.py)
    aside_begin: Any  # the set-aside rows', sky's, billboards' (the deferred form: the scene's; else the same)
    keep: Any  # what the structs point to
    area_ptr: Any = None  # pointers to the structs above, for raw calls
    viewport_ptr: Any = None
    path_state: dict[Any, Any] = field(default_factory=dict)  # what paths keep per target and slot

    @classmethod
    def make(
        cls,
        vk: Any,
        key: tuple[int, int, int],
        output: Any,
        secondary_begin: Any,
        clear_color: tuple[float, float, float],
        depth_only: bool = False,
    ) -> TargetState:
        """`output`: what the state draws into, kept (the scene's own rendering is the output
        graph's: render/passes/forward.py; the deferred form's G-buffer pass sets
        `secondary_begin` after). `clear_color` and `depth_only` are what those renderings
        clear (kept for the callers that pass them)."""
        width, height = key[1], key[2]
        area = vk.VkRect2D(offset=vk.VkOffset2D(0, 0), extent=vk.VkExtent2D(width, height))
        state = cls(
            key=key,
            area=area,
            viewport=vk.VkViewport(x=0.0, y=0.0, width=float(width), height=float(height), minDepth=0.0, maxDepth=1.0),
            secondary_begin=secondary_begin,
            aside_begin=secondary_begin,
            keep=[output],
        )
        state.area_ptr = vk.ffi.addressof(state.area)
        state.viewport_ptr = vk.ffi.addressof(state.viewport)
        return state


@dataclass
class FrameInputs:
    """What every chunk job of one frame reads (never writes, except its slice of `instances`)."""

    slot: int  # frame-in-flight index
    descriptor_set: Any  # the frame's set 0
    set_array: Any  # VkDescriptorSet[1] of it, for raw calls
    target: TargetState
    planes: np.ndarray | None  # what the rows are tested against (the view's; None: no test)
    instances: np.ndarray  # the mapped per-frame instance buffer (INSTANCE rows)
    bounds: MeshBounds
    readback: bool  # the frame is waited for: the path may read back what it counted on the GPU
    data: FrameData  # the frame's snapshot: its culling (render/culling/) is what the jobs and GPU passes ask
    material_count: int = 1  # Mesh.material is below it (the extractor checked)
    path_state: Any = None  # what the path's begin_frame keeps for its jobs
    row_base: int = 0  # where this view's rows start in `instances` (a shadow view's come after the camera's)
    lod: bool = False  # the indirect path draws each row at the coarsest level of detail its size allows
    reuse: Any = None  # the chunks the slot's last frame recorded, to give back when unchanged (frame_replay.py)

    def but(self, **changes: Any) -> FrameInputs:
        """A copy with `changes` (a shadow view's inputs, eleven a frame in the shadows demo):
        dataclasses.replace's result without its per-field __init__, which cost more."""
        if not changes.keys() <= self.__dict__.keys():
            raise TypeError(f"FrameInputs has no field {sorted(changes.keys() - self.__dict__.keys())}")
        made = object.__new__(FrameInputs)
        made.__dict__.update(self.__dict__, **changes)
        return made


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
    replayed: bool = False  # the slot's last recording was submitted again (frame_replay.py)


@dataclass
class ChunkResult:
    command_buffer: Any  # None when nothing in the chunk is visible (or the GPU records it)
    visible: int
    draws: int
    triangles: int
    key_counts: np.ndarray | None = None  # rows per key (indirect: the GPU's regions)
    recorded: tuple[int, int, bytes] | None = None  # what its secondary was recorded from (frame_replay.py)
    written: tuple[Any, ...] | None = None  # what the slot's rows of it were last written from (chunk_paths.py)


@dataclass
class PathContext:
    """What paths are built from: shared by every path of one renderer."""

    device: Device
    meshes: MeshRegistry
    frame_set_layout: Any  # set 0's VkDescriptorSetLayout
    secondaries: SecondaryBuffers
    frames_in_flight: int
    material_features: int  # what the mesh pipelines are specialised for (Materials.features)
    fill: str  # FILL_MODES: how the mesh pipelines rasterise triangles
    samples: int  # the target's MSAA count
    native_recorder: Callable[[], Any]  # gpu.native_recorder.NativeRecorder, compiled on first call, once a device
    gbuffer: bool = False  # the chunks draw into the G-buffer pass (the deferred form), lit later
    shadow: bool = False  # the chunks draw depth alone into a shadow map (render/shadows/maps_pass.py)
    oit: bool = False  # blended rows accumulate weighted transparency (render/passes/oit.py)
    formats: AttachmentFormats | None = None  # what the pipelines draw into (dynamic rendering)

    def pipeline_target(self) -> dict[str, Any]:
        """GraphicsPipelineSpec fields that say where its pipelines draw: the attachment formats."""
        if self.formats is None:
            raise ValueError("a path context needs the attachment formats its pipelines draw into")
        return self.formats.spec_kwargs()


class RenderPath(Protocol):
    ctx: PathContext

    @property
    def name(self) -> str: ...

    @property
    def uses_recorder(self) -> bool:
        """Whether the CPU records the draws (with the renderer's recorder setting)."""
        ...

    @property
    def recorder(self) -> str:
        """native or python; gpu when the GPU writes the draws."""
        ...

    def draw_into(self, formats: AttachmentFormats, gbuffer: bool) -> None:
        """The pipelines for attachments of `formats` from now (path_pipelines.py)."""
        ...

    def rows_needed(self, candidates: int) -> int: ...

    def begin_frame(self, frame: FrameInputs) -> None: ...

    def record_chunk(self, chunk: Chunk, frame: FrameInputs) -> ChunkResult: ...

    def finish(self, cb: Any, frame: FrameInputs, results: list[ChunkResult], candidates: int) -> list[Any]: ...

    def counts(self, frame: FrameInputs, results: list[ChunkResult]) -> tuple[int, int, int]: ...

    def destroy(self) -> None: ...


def summed_counts(results: list[ChunkResult]) -> tuple[int, int, int]:
    """(draws, visible, triangles) over the chunks recorded on the CPU."""
    draws = visible = triangles = 0
    for r in results:
        draws, visible, triangles = draws + r.draws, visible + r.visible, triangles + r.triangles
    return draws, visible, triangles


class PathFactory(Protocol):
    """A render path class, as the renderer's table holds it."""

    uses_recorder: bool

    def __call__(self, ctx: PathContext, recorder: str) -> RenderPath: ...
