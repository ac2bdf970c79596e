"""What each frame slot owns: its mapped buffers (globals, lights, instance rows, materials) and
its set 0, which names them and the texture pages. A slot's buffers are written only after its
fence was waited on, so the editor can edit materials while other frames are in flight."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...gpu.descriptors import DescriptorPool, DescriptorSetLayout, write_buffers, write_images
from ...gpu.device import Device
from ...gpu.memory import DEVICE, UPLOAD, Buffer
from ...gpu.owned import Owned
from .. import layouts
from ..assets.materials import Materials
from ..assets.texture_pages import TexturePages
from ..extract.frame_data import FrameData
from ..layouts import (
    BINDING_CLUSTERS,
    BINDING_ENVIRONMENT,
    BINDING_GLOBALS,
    BINDING_INSTANCES,
    BINDING_JOINTS,
    BINDING_LIGHTS,
    BINDING_MATERIALS,
    BINDING_SHADOW_DEPTH,
    BINDING_SHADOW_MAP,
    BINDING_SHADOW_MAP_HARD,
    BINDING_SHADOW_VIEWS,
    BINDING_SKIN_VERTICES,
    BINDING_TEXTURES,
    GLOBALS,
    INSTANCE,
    LIGHT,
    MATERIAL,
    SHADOW_VIEW,
    TEXTURE_PAGES,
)
from ..lighting.clusters import ClusterGrid
from ..lighting.rows import write_lights
from .camera import CameraMatrices

MIN_LIGHTS = 256
MIN_MATERIALS = 64
MIN_JOINTS = 64
ROW_BYTES = 16  # a vec4 row: a third of a joint matrix, or half a row's morph weights


def frame_sets(device: Device, frames: int) -> tuple[DescriptorSetLayout, DescriptorPool]:
    """Set 0's layout (layouts.py's BINDING_*) and a pool with one set per frame slot."""
    vk = device.vk
    stages = vk.VK_SHADER_STAGE_VERTEX_BIT | vk.VK_SHADER_STAGE_FRAGMENT_BIT | vk.VK_SHADER_STAGE_COMPUTE_BIT
    ssbo = vk.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER
    sampler = vk.VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER
    uniform = vk.VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER
    ssbos = "LIGHTS INSTANCES MATERIALS CLUSTERS SHADOW_VIEWS JOINTS SKIN_VERTICES"
    buffers = tuple(getattr(layouts, f"BINDING_{name}") for name in ssbos.split())
    # the shadow rays' any-hit shader reads the materials and textures (shaders/shadow_rays.rahit)
    any_hit = vk.lib.VK_SHADER_STAGE_ANY_HIT_BIT_KHR if device.ray_tracing is not None else 0
    layout = DescriptorSetLayout(
        device,
        [(BINDING_GLOBALS, uniform, stages)]
        + [(b, ssbo, stages | (any_hit if b == BINDING_MATERIALS else 0)) for b in buffers]
        + [(BINDING_TEXTURES, sampler, vk.VK_SHADER_STAGE_FRAGMENT_BIT | any_hit, TEXTURE_PAGES)]
        + [(b, sampler, stages) for b in (BINDING_SHADOW_MAP, BINDING_SHADOW_MAP_HARD, BINDING_SHADOW_DEPTH)]
        + [(BINDING_ENVIRONMENT, sampler, vk.VK_SHADER_STAGE_FRAGMENT_BIT)],
    )
    try:
        pool = DescriptorPool(
            device, frames, {uniform: frames, ssbo: len(buffers) * frames, sampler: (TEXTURE_PAGES + 4) * frames}
        )
    except BaseException:
        layout.destroy()
        raise
    return layout, pool


@dataclass
class FrameResources:
    globals: Buffer
    lights: Buffer
    instances: Buffer
    materials: Buffer
    clusters: Buffer  # device-local: cluster.comp writes it, the fragment shader reads it
    shadow_views: Buffer  # SHADOW_VIEW rows (render/shadows/maps_pass.py)
    joints: Buffer  # the skins' joint matrices and the morph weights this frame (extract/skins.py), vec4 rows
    skin_vertices: Buffer  # the mesh registry's skinned vertex weights (assets/skin_vertices.py), or a stand-in
    descriptor_set: Any
    set_array: Any  # VkDescriptorSet[1] for raw calls
    written: tuple[Any, ...] | None = None  # what the globals buffer holds
    # (the Materials, its version, the texture pages' generation) in `materials`: the object
    # itself, not its id, which a new registry could reuse once the old one is freed
    materials_written: tuple[Materials, int, int] | None = None
    shadow_maps: Any = None  # the gpu.shadow_maps.ShadowMaps the set names
    pages: Any = None  # the TexturePages the set names
    environment: Any = None  # the render.environment.EnvironmentMap the set names
    set_version: int = 0  # bumped whenever the set is written: copies of it (shadow views') are then stale
    owned: Any = None  # the gpu.owned.Owned scope of the buffers (each made anew in it as it grows)

    @classmethod
    def make(
        cls,
        device: Device,
        pool: DescriptorPool,
        layout: DescriptorSetLayout,
        pages: TexturePages,
        shadow_maps: Any,
        environment: Any,
    ) -> FrameResources:
        vk = device.vk
        ssbo = vk.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT
        descriptor_set = pool.allocate(layout)
        made = Owned(device)  # the buffers: destroyed with the frame, or at once if a later one cannot be made
        try:
            frame = cls(
                globals=made.add(Buffer(device, GLOBALS.size, vk.VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT)),
                lights=made.add(Buffer(device, LIGHT.size * MIN_LIGHTS, ssbo)),
                # the GPU reads every row once a frame (the indirect mode's cull: twice): in device
                # memory the CPU can write, where the device has it (H100, 1M rows, occlusion
                # culling: GPU 9.4 -> 7.1 ms a frame against system memory), else in system memory
                instances=made.add(Buffer(device, INSTANCE.size * 1024, ssbo, UPLOAD)),
                materials=made.add(Buffer(device, MATERIAL.size * MIN_MATERIALS, ssbo)),
                # bound always (the mesh shaders declare it), sized for a grid when lights are clustered
                clusters=made.add(
                    Buffer(
                        device,
                        ClusterGrid(1, 1, 1, 1.0, 1.0, 1, 1, tile=1).buffer_bytes,
                        ssbo | vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                        DEVICE,
                    )
                ),
                shadow_views=made.add(Buffer(device, SHADOW_VIEW.size * 4, ssbo)),
                joints=made.add(Buffer(device, 3 * ROW_BYTES * MIN_JOINTS, ssbo, UPLOAD)),
                skin_vertices=made.add(Buffer(device, 16, ssbo)),  # until a frame has skinned rows
                descriptor_set=descriptor_set,
                set_array=vk.ffi.new("VkDescriptorSet[1]", [descriptor_set]),
                shadow_maps=shadow_maps,
                pages=pages,
                environment=environment,
                owned=made,
            )
            frame.write_set(device, pages)
        except BaseException:
            made.destroy()
            raise
        return frame

    def write_set(self, device: Device, pages: TexturePages) -> None:
        self.pages = pages
        self.set_version += 1
        vk = device.vk
        ssbo = vk.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER
        write_buffers(
            device,
            self.descriptor_set,
            [
                (BINDING_GLOBALS, vk.VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, self.globals),
                (BINDING_LIGHTS, ssbo, self.lights),
                (BINDING_INSTANCES, ssbo, self.instances),
                (BINDING_MATERIALS, ssbo, self.materials),
                (BINDING_CLUSTERS, ssbo, self.clusters),
                (BINDING_SHADOW_VIEWS, ssbo, self.shadow_views),
                (BINDING_JOINTS, ssbo, self.joints),
                (BINDING_SKIN_VERTICES, ssbo, self.skin_vertices),
            ],
        )
        write_images(device, self.descriptor_set, BINDING_TEXTURES, pages.image_infos())
        self.name_shadow_maps(device, self.shadow_maps)
        self.name_environment(device)

    def name_environment(self, device: Device) -> None:
        """Point the set at the environment's cube map (after it was loaded anew)."""
        self.set_version += 1
        write_images(device, self.descriptor_set, BINDING_ENVIRONMENT, [self.environment.image_info()])

    def name_shadow_maps(self, device: Device, maps: Any) -> None:
        """Point the set at `maps` (a gpu.shadow_maps.ShadowMaps), filtering and hard samplers."""
        self.shadow_maps = maps
        self.set_version += 1
        for binding, info in zip(
            (BINDING_SHADOW_MAP, BINDING_SHADOW_MAP_HARD, BINDING_SHADOW_DEPTH), maps.image_infos(), strict=True
        ):
            write_images(device, self.descriptor_set, binding, [info])

    def ensure_capacity(
        self, device: Device, pages: TexturePages, instances: int, lights: int, materials: int, shadow_views: int = 0
    ) -> None:
        """Grow the buffers (and name the new ones in the set), before anything records with it."""
        if shadow_views * SHADOW_VIEW.size > self.shadow_views.size:
            self.shadow_views = self.shadow_views.grown(shadow_views * SHADOW_VIEW.size, self.owned)
            self.write_set(device, pages)
        if (
            instances * INSTANCE.size <= self.instances.size
            and lights * LIGHT.size <= self.lights.size
            and materials * MATERIAL.size <= self.materials.size
        ):
            return  # the usual frame: three comparisons, not three calls
        before = (self.instances, self.lights, self.materials)
        try:
            self.instances = self.instances.grown(instances * INSTANCE.size, self.owned)
            self.lights = self.lights.grown(lights * LIGHT.size, self.owned)
            self.materials = self.materials.grown(materials * MATERIAL.size, self.owned)
        finally:
            if (self.instances, self.lights, self.materials) != before:
                if self.materials is not before[2]:
                    self.materials_written = None
                self.write_set(device, pages)

    def write_deform(self, device: Device, rows: np.ndarray, skin_vertices: Buffer) -> None:
        """The frame's joint matrices and morph weights ((K, 4) float32 rows) into this slot's
        buffer, grown to hold them, and the set naming `skin_vertices` (the mesh registry's, made
        again when a skinned or morphed mesh is added)."""
        grown = self.joints.grown(len(rows) * ROW_BYTES, self.owned)
        if grown is not self.joints or skin_vertices is not self.skin_vertices:
            self.joints, self.skin_vertices = grown, skin_vertices
            self.write_set(device, self.pages)
        self.joints.array(np.float32, rows.shape)[:] = rows

    def ensure_clusters(self, device: Device, pages: TexturePages, grid: ClusterGrid) -> None:
        """Room for `grid`'s light lists (safe: this slot's fence was waited on)."""
        if grid.buffer_bytes > self.clusters.size:
            self.clusters = self.clusters.grown(grid.buffer_bytes, self.owned)
            self.write_set(device, pages)

    def write_frame(
        self,
        device: Device,
        data: FrameData,
        materials: Materials,
        grid: ClusterGrid | None,
        ambient: tuple[float, float, float, float],
        deferred: bool,
        name_lights: Callable[[np.ndarray], None] | None,
    ) -> int:
        """The frame's materials, lights (then `name_lights(rows)`: their shadow views) and
        globals into this slot's buffers; returns the point and spot lights (the billboards)."""
        self.write_materials(materials, self.pages)
        if grid is not None:
            self.ensure_clusters(device, self.pages, grid)
        positional = 0
        if data.light_count:
            rows = self.lights.array(np.float32, (data.light_count, LIGHT.size // 4))
            eye = data.camera.position - data.origin
            positional = write_lights(data.lights, data.directional, data.origin, eye, rows)
            if name_lights is not None:
                name_lights(rows)
        self.write_globals(
            data.camera, data.view, data.origin, data.origin_key, data.light_count, positional, grid, ambient, deferred
        )
        return positional

    def write_globals(
        self,
        cam: CameraMatrices,
        view: np.ndarray,
        origin: np.ndarray,
        origin_key: bytes,
        light_count: int,
        positional: int,
        grid: ClusterGrid | None,
        ambient: tuple[float, float, float, float],
        deferred: bool = False,
    ) -> None:
        """The frame's uniforms, rewritten only when something in them changed (the slot's
        mapped buffer keeps what was last written there)."""
        environment = self.environment
        written = (cam, origin_key, light_count, positional, tuple(ambient), grid, deferred, environment.source)
        last = self.written
        if last is not None and last[0] is cam and last[1:] == written[1:]:
            return
        g = self.globals.array(GLOBALS.dtype, 1)
        g["projection"] = cam.projection.T  # column-major for GLSL
        g["view"] = view.T
        g["eye"][0, :3] = cam.position - origin  # float64 difference, then the cast
        g["ambient"] = ambient
        g["counts"] = (light_count, positional, 0, 0)
        g["environment"], g["irradiance"] = environment.globals()
        if grid is not None or deferred:  # the grid's tile planes; the deferred lighting's positions
            g["inverse_projection"] = np.linalg.inv(cam.projection).T
        g["light_tiles"] = 0  # no grid (the deferred lighting then loops over every light)
        if grid is not None:
            g["light_tiles"] = (grid.tiles_x, grid.tiles_y, grid.words, grid.tile)
            g["light_bins"] = (grid.bounds_start, grid.masks_start, 0, 0)
            g["bin_depth"] = (grid.near, grid.scale, grid.width, grid.height)
        self.written = written

    def write_materials(self, materials: Materials, pages: TexturePages) -> None:
        """The world's material table into this slot's copy, when it changed since last written
        here; texture handles become the pages' refs."""
        key = (materials, materials.version, pages.generation)
        last = self.materials_written
        if last is None or last[0] is not materials or last[1:] != key[1:]:
            rows = materials.rows()
            out = self.materials.array(MATERIAL.dtype, len(rows))
            out[:] = rows
            pages.map_rows(out)
            self.materials_written = key

    def destroy(self) -> None:
        self.owned.destroy()
