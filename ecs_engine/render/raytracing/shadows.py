"""Ray-traced shadows (issue 18; the renderer's `shadows="raytraced"`), on devices with
ray-tracing pipelines: the same lights with a `Shadow` as the shadow maps, traced instead.

A frame: the chunk jobs' rows become top-level instances (render/raytracing/instances.py, written in
parallel by the job pool, one job a chunk, the kernel without the GIL) in the slot's buffer;
after the G-buffer pass (the deferred form: its depth is the pre-pass, its normals give the rays'
start off the surface) the top level is refitted, or built where the instance count changed or
REBUILD_EVERY frames passed (a refit's quality drifts as things move), then shaders/
shadow_rays.rgen traces, per pixel and light, one ray towards it (a hard shadow) or, for a light
whose Shadow asks for PCSS, SOFT_RAYS rays to a disc of the Shadow's softness (an area light);
the fraction that reached it goes to the shadow mask the deferred lighting reads. Instances of
alpha-masked materials are not opaque to the rays: shaders/shadow_rays.rahit fetches the hit's
uv from the mesh's buffers (by device address) and lets the ray through where the material's
alpha is under its cutoff, as the shadow maps' cutout pass does (the frame set, set 0 of this
pipeline, gives it the materials and textures). A skinned or morphed row's instance names a
bottom level of its own, built from this frame's pose (render/raytracing/deformed.py).

At most `max_lights` (MAX_RAY_LIGHTS) lights are traced (directional, then spot, then point
lights, in world order, as the shadow maps' views are ordered); the renderer draws shadow maps
for those past it (`overflow`), which the deferred lighting reads for them.
Forward-lit surfaces (the rows set aside: blended, wireframe, mirroring; drawn after the deferred
lighting) are not in the mask, which holds the opaque surface behind them: where a frame has such
rows, the renderer draws the casting lights' shadow maps as well and those rows read the maps
(each light's row names both; light_rows.write_light_shadows), as engines that trace the opaque
surfaces' shadows do for translucent ones.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ...components.shadow import SHADOW_PCSS
from ...gpu.acceleration import AS_INSTANCE, TopLevel, ray_input_usage
from ...gpu.array_image import nearest_sampler
from ...gpu.barrier import Barrier
from ...gpu.descriptors import DescriptorPool, DescriptorSetLayout, write_acceleration_structure, write_set
from ...gpu.memory import UPLOAD, Buffer
from ...gpu.pipeline import pipeline_layout
from ...gpu.ray_pipeline import RayPipeline
from ..config import Caps, RenderConfig, Shadows, check
from ..extract.frame_data import NOT_CASTER, Chunk, FrameData
from ..extract.shadows import ShadowCasters, ShadowRows
from ..layouts import (
    ALPHA_MASK,
    BINDING_RAY_DEPTH,
    BINDING_RAY_FRAME,
    BINDING_RAY_MASK,
    BINDING_RAY_MESHES,
    BINDING_RAY_NORMAL,
    BINDING_RAY_ROWS,
    BINDING_RAY_SCENE,
    LIGHT_DIRECTIONAL,
    LIGHT_POINT,
    LIGHT_SPOT,
    MAX_RAY_LIGHTS,
    RAY_FRAME,
    SET_RAY,
)
from ..lighting.rows import local_minus_z
from .deformed import IDENTITY_3X4, DeformedLevels
from .denoise import ShadowDenoise
from .instances import write_instances
from .mask import ShadowMask

SHADOW_METHODS = Shadows.names()
SOFT_RAYS = 4  # rays per pixel of a light whose Shadow asks for PCSS (an area light)
REBUILD_EVERY = 30  # frames between full builds of the top level (refits in between)


def check_shadow_method(method: str, device: Any = None, samples: int = 1) -> None:
    """UsageError for an unknown method, or `raytraced` on a device that cannot trace rays or
    with MSAA (config.RULES; the device's rule waits while `device` is None)."""
    config = RenderConfig.from_strings(shadows=method, msaa=samples)
    check(config, None if device is None else Caps.of(device), only=("shadows",))


@dataclass(frozen=True)
class RayLight:
    entity: int
    kind: int  # LIGHT_*
    position: np.ndarray  # render-relative position, or a directional light's unit direction towards it
    size: float  # 0: a hard shadow; else the area light's radius (directional: the tangent of its angle)
    reach: float  # a point or spot light's radius (0: unbounded)


def ray_lights(casters: ShadowCasters | None, origin: np.ndarray) -> list[RayLight]:
    """The shadow-casting lights of the frame's snapshot (extract/shadows.py), in the shadow
    maps' order."""
    found: list[RayLight] = []
    if casters is None:
        return found

    def size(shadow: ShadowRows, row: int) -> float:
        return float(shadow.softness[row]) if int(shadow.filter[row]) == SHADOW_PCSS else 0.0

    for rows in casters.directional:
        towards = -local_minus_z(rows.rotation)
        for row, entity in enumerate(rows.entities.tolist()):
            found.append(RayLight(entity, LIGHT_DIRECTIONAL, towards[row], size(rows.shadow, row), 0.0))
    for kind, groups in ((LIGHT_SPOT, casters.spot), (LIGHT_POINT, casters.point)):
        for rows in groups:
            position = rows.position - origin
            for row, entity in enumerate(rows.entities.tolist()):
                found.append(RayLight(entity, kind, position[row], size(rows.shadow, row), float(rows.radius[row])))
    return found


def cutouts(materials: Any) -> np.ndarray | None:
    """Per material, whether it is alpha-masked (its instances are not opaque to the rays); None
    when none is."""
    masked = materials.rows()["kind"][:, 1] == ALPHA_MASK
    return masked if masked.any() else None


class _Slot:
    """A frame slot's: the instance rows, the RayFrame, the instances' (mesh, material) pairs and
    the meshes' buffer addresses (for the any-hit shader), the descriptor set and what it names."""

    def __init__(self, device: Any, pool: DescriptorPool, layout: DescriptorSetLayout) -> None:
        vk = device.vk
        storage = vk.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT
        self.frame = Buffer(device, RAY_FRAME.size, storage, UPLOAD)
        self.rows: Buffer | None = None
        self.pairs = Buffer(device, 8, storage, UPLOAD)  # uvec2 per instance (written with cutouts)
        self.meshes = Buffer(device, 16, storage, UPLOAD)  # uvec4 per mesh handle
        self.mesh_version = -1  # the registry's version the addresses were written for
        self.set = pool.allocate(layout)
        self.named: tuple[Any, ...] = ()

    def pairs_for(self, count: int) -> np.ndarray:
        self.pairs = self.pairs.grown(max(count, 1) * 8)
        return self.pairs.array(np.uint32, (max(count, 1), 2))

    def mesh_buffers(self, meshes: Any) -> None:
        """Every mesh's vertex and index buffer addresses (again when meshes were added or replaced)."""
        if self.mesh_version == meshes.version:
            return
        self.meshes = self.meshes.grown(max(len(meshes), 1) * 16)
        table = self.meshes.array(np.uint64, (max(len(meshes), 1), 2))
        for handle in range(len(meshes)):
            table[handle] = (meshes[handle].vertices.address, meshes[handle].indices.address)
        self.mesh_version = meshes.version

    def rows_for(self, device: Any, count: int) -> np.ndarray:
        """The slot's instance rows, room for `count` (its fence was waited for: safe to grow)."""
        need = max(count, 1) * AS_INSTANCE.itemsize
        if self.rows is None:
            self.rows = Buffer(device, need, ray_input_usage(device), UPLOAD)
        self.rows = self.rows.grown(need)
        return self.rows.array(AS_INSTANCE, max(count, 1))

    def destroy(self) -> None:
        for made in (self.frame, self.rows, self.pairs, self.meshes):
            if made is not None:
                made.destroy()


class RayShadows:
    """`frame_set_layout`: the renderer's frame set's (set 0 of the rays' pipeline)."""

    def __init__(self, device: Any, meshes: Any, frames: int, frame_set_layout: Any) -> None:
        check_shadow_method("raytraced", device)  # (the caller checks its target's samples)
        vk, lib = device.vk, device.vk.lib
        self.device, self.meshes = device, meshes
        stage, any_hit = lib.VK_SHADER_STAGE_RAYGEN_BIT_KHR, lib.VK_SHADER_STAGE_ANY_HIT_BIT_KHR
        storage_image, ssbo = vk.VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, vk.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER
        self.set_layout = DescriptorSetLayout(
            device,
            [
                (BINDING_RAY_SCENE, lib.VK_DESCRIPTOR_TYPE_ACCELERATION_STRUCTURE_KHR, stage),
                (BINDING_RAY_FRAME, ssbo, stage),
                (BINDING_RAY_DEPTH, vk.VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, stage),
                (BINDING_RAY_NORMAL, storage_image, stage),
                (BINDING_RAY_MASK, storage_image, stage),
                (BINDING_RAY_MESHES, ssbo, any_hit),
                (BINDING_RAY_ROWS, ssbo, any_hit),
            ],
        )
        self._made: list[Any] = [self.set_layout]
        try:
            sizes = {
                lib.VK_DESCRIPTOR_TYPE_ACCELERATION_STRUCTURE_KHR: frames,
                ssbo: 3 * frames,
                vk.VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER: frames,
                storage_image: 2 * frames,
            }
            self.pool = DescriptorPool(device, frames, sizes)
            self._made.append(self.pool)
            assert SET_RAY == 1  # set 0 is the frame set
            self.layout = pipeline_layout(device, [frame_set_layout, self.set_layout.handle])
            hits = [(None, "shadow_rays.rahit")]  # alpha cutouts: the rest is opaque
            self.pipeline = RayPipeline(device, self.layout, "shadow_rays.rgen", ["shadow_rays.rmiss"], hits)
            self._made.append(self.pipeline)
            self.sampler = nearest_sampler(device)
            self.top = TopLevel(device, 1024)
            self._made.append(self.top)
            self.deformed = DeformedLevels(device, frame_set_layout)  # skinned and morphed rows' bottom levels
            self._made.append(self.deformed)
            self.slots = [_Slot(device, self.pool, self.set_layout) for _ in range(frames)]
        except BaseException:
            self.destroy()
            raise
        rt, compute = lib.VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR, vk.VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT
        written = (
            vk.VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT
            | vk.VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT
            | vk.VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT
            | compute
        )
        access = vk.VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT | vk.VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT
        # the G-buffer's depth and normals to the rays; the last frame's lighting has read the mask
        self._before = Barrier(
            vk,
            written,
            rt,
            access | vk.VK_ACCESS_SHADER_READ_BIT,
            vk.VK_ACCESS_SHADER_READ_BIT | vk.VK_ACCESS_SHADER_WRITE_BIT,
        )
        self._after = Barrier(
            vk, rt, compute, vk.VK_ACCESS_SHADER_WRITE_BIT, vk.VK_ACCESS_SHADER_READ_BIT
        )  # the mask, to the lighting
        self.frame_number = 0
        self._since_build = REBUILD_EVERY
        self._count = 0
        self.lights: list[RayLight] = []
        self.max_lights = MAX_RAY_LIGHTS  # traced; the shadow maps take the rest
        self.overflow: set[int] = set()  # the entities of the casting lights past max_lights
        self.denoise = True  # soft shadows filtered (shadow_denoise.py), made on first use
        self._denoiser: ShadowDenoise | None = None
        self._traced: ShadowMask | None = None  # the rays' mask when they are filtered
        self._cutouts: tuple[Any, int, np.ndarray | None] = (None, -1, None)  # materials, version, cutouts()

    # ------------------------------------------------------------ per frame
    def plan(self, data: FrameData) -> list[RayLight]:
        """The lights traced this frame (`overflow`: those left to the shadow maps)."""
        found = ray_lights(data.shadows, data.origin)
        limit = max(0, min(self.max_lights, MAX_RAY_LIGHTS))
        self.lights, self.overflow = found[:limit], {light.entity for light in found[limit:]}
        return self.lights

    @staticmethod
    def places(lights: list[RayLight]) -> dict[int, int]:
        """Per traced light's entity: its place in the mask, which its light row names
        (light_rows.write_light_shadows)."""
        return {light.entity: i for i, light in enumerate(lights)}

    def prepare(self, slot: int, data: FrameData, jobs: Any, width: int, height: int, materials: Any) -> None:
        """Before the frame's recording: every row with a mesh as an instance (the jobs), the
        top level's room for them, the slot's RayFrame; with alpha-masked `materials`, the
        instances' meshes and materials and the meshes' buffers for the any-hit shader."""
        blas = self.meshes.bottom_levels()
        chunks: list[Chunk] = list(data.chunks) + (list(data.set_aside.casters) if data.set_aside is not None else [])
        count = max((c.offset + len(c.handle) for c in chunks), default=0)
        s = self.slots[slot]
        rows = s.rows_for(self.device, count)
        if count > self.top.capacity:
            self.device.wait_idle()  # the other slots' frames trace the structure being replaced
            self.top.reserve(count)
        covered = sum(len(c.handle) for c in chunks)
        if covered != count:  # rows no chunk writes stay inactive (a strided write: only when needed)
            rows[:count]["blas"] = 0
        cutout = self.cutouts(materials)
        pairs = s.pairs_for(count) if cutout is not None else None
        deformed = self.deformed.plan(chunks if data.deform is not None else [], self.meshes)
        if cutout is not None:
            s.mesh_buffers(self.meshes)

        def job(chunk: Chunk) -> None:
            end = chunk.offset + len(chunk.handle)
            caster = not chunk.flags & NOT_CASTER
            at = slice(chunk.offset, end)
            own = pairs[at] if pairs is not None else None
            out = rows[at]
            write_instances(chunk.model, chunk.handle, blas, chunk.offset, caster, out, chunk.material, cutout, own)
            posed = deformed.get(id(chunk))
            if posed is not None:  # a skinned or morphed row: its own bottom level, already posed in the world
                out["blas"][posed[0]] = posed[1]
                out["transform"][posed[0]] = IDENTITY_3X4

        if jobs is not None and len(chunks) > 1:
            jobs.map(job, chunks)
        else:
            for chunk in chunks:
                job(chunk)
        self._count = count
        f = s.frame.array(RAY_FRAME.dtype, 1)
        f["inverse_projection"] = np.linalg.inv(data.camera.projection).T
        f["view"] = data.view.T
        f["size"] = (width, height, len(self.lights), self.frame_number)
        f["light_position"] = 0
        f["light_params"] = 0
        for i, light in enumerate(self.lights):
            f["light_position"][0, i] = (*light.position, light.kind)
            f["light_params"][0, i] = (light.size, SOFT_RAYS if light.size > 0 else 1, light.reach, 0.0)
        self.frame_number += 1

    def cutouts(self, materials: Any) -> np.ndarray | None:
        """cutouts(materials), kept while the materials stay the same."""
        kept, version, found = self._cutouts
        if kept is not materials or version != materials.version:
            found = cutouts(materials)
            self._cutouts = (materials, materials.version, found)
        return found

    def record_trace(
        self, cb: Any, slot: int, frame_set: Any, attachments: Any, mask: Any, width: int, height: int
    ) -> None:
        """After the G-buffer pass, before the deferred lighting (the output graph's ray_shadows
        pass, render/passes/deferred_passes.py, whose barriers order the G-buffer's depth and
        normals before the rays): the top level, the rays into `mask` (the lighting's
        ShadowMask), or into a mask of their own that record_denoise filters into it where some
        light is soft and `denoise` is on. `frame_set`: the slot's frame descriptor set (the
        materials and textures of the any-hit shader)."""
        lib = self.device.vk.lib
        s = self.slots[slot]
        assert s.rows is not None
        self.deformed.record(cb, frame_set, self.meshes)  # their bottom levels, before the top level
        update = self._since_build < REBUILD_EVERY
        refit = self.top.record(cb, s.rows.address, self._count, update)
        self._since_build = self._since_build + 1 if refit else 1
        traced = self._traced_mask(mask) if self._filtered() else mask
        named = (attachments, traced, self.top.handle, s.pairs.handle, s.meshes.handle)
        if s.named != named:
            self._name(s, attachments, traced)
            s.named = named
        self._before.record(lib, cb)
        self.pipeline.bind(cb, [frame_set, s.set])
        self.pipeline.trace(cb, width, height)
        self._after.record(lib, cb)

    def record_denoise(self, cb: Any, slot: int, attachments: Any, mask: Any, width: int, height: int) -> None:
        """After record_trace (the output graph's ray_denoise pass): its own mask filtered into
        `mask`, where it traced into its own; nothing otherwise."""
        if not self._filtered():
            return
        if self._denoiser is None:
            self._denoiser = ShadowDenoise(self.device, len(self.slots))
        traced = self._traced_mask(mask)
        self._denoiser.record(cb, slot, self.slots[slot].frame, attachments, traced, mask, width, height)

    def _filtered(self) -> bool:
        """Whether this frame's rays go into a mask of their own, denoised into the lighting's."""
        return bool(self.denoise and any(light.size > 0 for light in self.lights))

    def _traced_mask(self, mask: Any) -> ShadowMask:
        """The rays' own mask, the size of the lighting's (made again when that one is)."""
        own = self._traced
        if own is None or (own.width, own.height) != (mask.width, mask.height):
            if own is not None:
                self.device.wait_idle()  # the other slots' frames may read it
                own.destroy()
                self._traced = None
            own = self._traced = ShadowMask(self.device, mask.width, mask.height)
        return own

    def _name(self, s: _Slot, attachments: Any, mask: Any) -> None:
        write_acceleration_structure(self.device, s.set, BINDING_RAY_SCENE, self.top.handle)
        depth_layout = self.device.vk.VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL
        write_set(
            self.device,
            s.set,
            storage_buffers=[(BINDING_RAY_FRAME, s.frame), (BINDING_RAY_MESHES, s.meshes), (BINDING_RAY_ROWS, s.pairs)],
            samplers=[(BINDING_RAY_DEPTH, self.sampler, attachments.depth_view, depth_layout)],
            storage_images=[(BINDING_RAY_NORMAL, attachments.gbuffer.views[0]), (BINDING_RAY_MASK, mask.view)],
        )

    def destroy(self) -> None:
        for part in (getattr(self, "_denoiser", None), getattr(self, "_traced", None)):
            if part is not None:
                part.destroy()
        self._denoiser = self._traced = None
        for s in getattr(self, "slots", []):
            s.destroy()
        self.slots = []
        if getattr(self, "sampler", None) is not None:
            self.device.vk.vkDestroySampler(self.device.handle, self.sampler, None)
            self.sampler = None
        if getattr(self, "layout", None) is not None:
            self.device.vk.vkDestroyPipelineLayout(self.device.handle, self.layout, None)
            self.layout = None
        for made in reversed(self._made):
            made.destroy()
        self._made = []
