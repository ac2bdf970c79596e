"""Rows drawn apart from the chunks (frame_data.SetAsideRows), after every chunk's rows in the
same rendering, with pipelines the render paths do not have:

- materials with a fill of their own (`Material.fill`: wireframe or points), drawn first, with
  depth writes, grouped by fill and (mesh, winding);
- alpha-blended materials, drawn last, back to front by the distance of their bounding sphere's
  centre from the eye, blending on and depth writes off (the opaque depth still hides them).
  Sorting is per frame and vectorised. Objects that intersect or interleave can still blend in
  the wrong order within a pixel: sorting is by object, as in glTF viewers and most engines.

Consecutive rows of one (mesh, winding, fill) are one instanced draw. A device without
fillModeNonSolid draws those materials solid, with one warning. With weighted blended
transparency (oit_pass.py) the blended rows go to a secondary of that pass instead, in any order.
"""

from __future__ import annotations

import logging
from dataclasses import replace
from typing import Any

import numpy as np

from ...gpu.pipeline import pipeline_layout
from ...gpu.secondary import end_command_buffer
from ...maths.culling import bounding_spheres, spheres_visible
from ..assets.materials import FILLS, Materials
from ..draw.chunk_paths import mesh_pipelines
from ..draw.instance_rows import write_rows
from ..draw.path import FrameInputs, PathContext
from ..extract.frame_data import SetAsideRows

log = logging.getLogger("ecs_engine")


class SetAsidePass:
    def __init__(self, ctx: PathContext) -> None:
        self.ctx = ctx
        self.layout = pipeline_layout(ctx.device, [ctx.frame_set_layout])
        # (blended, fill, oit, the scene's formats) -> (plain, mirrored): `ctx.formats` is the scene's
        # rendering's in the target's form now (the renderer sets `ctx` when the form changes)
        self.pipelines: dict[tuple[bool, str, bool, Any], tuple[Any, Any]] = {}
        self.can_fill = bool(ctx.device.features.get("fillModeNonSolid"))
        self._warned = False

    def record(
        self,
        frame: FrameInputs,
        rows: SetAsideRows,
        first_row: int,
        eye: np.ndarray,
        materials: Materials,
        oit: Any = None,
    ) -> tuple[Any, int, int, int, Any]:
        """Cull, order, write instance rows from `first_row`, record the draws: (secondary
        command buffer or None, draws, rows drawn, triangles, the weighted transparency pass's
        secondary or None). `oit`: a WeightedTransparency the blended rows accumulate in."""
        blended = materials.blend[rows.material]
        known = len(materials)
        solid = not materials.fills[:known][materials.blend[:known]].any()  # no blended wireframe
        if oit is not None and solid and blended.all():
            return (None, *self._record_unordered(frame, rows, first_row, oit))
        return self._record_ordered(frame, rows, first_row, eye, materials, oit)

    def _record_unordered(self, frame: FrameInputs, rows: SetAsideRows, first_row: int, oit: Any) -> tuple[Any, ...]:
        """Blended rows alone, for weighted transparency, which needs no order: culled and written
        by key with the chunk jobs' native kernel (instance_rows.write_rows), not by the NumPy
        path below (measured on the GPU host at 100k blended cubes: 80-130 ms a frame for it)."""
        centers, radii, index_counts = frame.bounds
        key_counts = np.zeros(2 * len(index_counts), np.int64)
        out = frame.instances[first_row : first_row + len(rows)]
        n = write_rows(
            rows.model, rows.handle, rows.material, centers, radii, frame.planes, frame.material_count, out, key_counts,
            rows.extra,
        )  # fmt: skip
        if n == 0:
            return 0, 0, 0, None
        keys = np.flatnonzero(key_counts)
        counts = key_counts[keys]
        starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
        triangles = int((index_counts[keys // 2] // 3 * counts).sum())
        runs = [(int(k), 0, 1, int(a), int(c)) for k, a, c in zip(keys, starts, counts, strict=True)]
        cb = self._draw(replace(frame, target=oit.state), first_row, runs, oit.state.secondary_begin, oit)
        return len(runs), n, triangles, cb

    def _record_ordered(
        self, frame: FrameInputs, rows: SetAsideRows, first_row: int, eye: np.ndarray, materials: Materials, oit: Any
    ) -> tuple[Any, int, int, int, Any]:
        centers, radii, index_counts = frame.bounds
        model, handle, material, extra = rows.model, rows.handle, rows.material, rows.extra
        c, r = bounding_spheres(model, centers[handle], radii[handle])
        if frame.planes is not None:
            keep = np.flatnonzero(spheres_visible(c, r, frame.planes))
            model, handle, material, c = model[keep], handle[keep], material[keep], c[keep]
            extra = None if extra is None else extra[keep]
        n = len(handle)
        if n == 0:
            return None, 0, 0, 0, None
        blended = materials.blend[material]
        fill = materials.fills[material].astype(np.int64)
        if not self.can_fill and fill.any():
            if not self._warned:
                log.warning(
                    "%s cannot draw wireframe or points (no fillModeNonSolid): drawn solid", self.ctx.device.info.name
                )
                self._warned = True
            fill[:] = 0
        mirrored = np.linalg.det(model[:, :3, :3].astype(np.float64)) < 0
        keys = handle.astype(np.int64) * 2 + mirrored
        d = c - eye
        distance = np.einsum("ij,ij->i", d, d)
        # unblended first, grouped by (fill, key); then blended, far to near (lexsort: last key first)
        order = np.lexsort(
            (np.where(blended, 0, keys), np.where(blended, 0, fill), np.where(blended, -distance, 0), blended)
        )
        keys, fill, blended = keys[order], fill[order], blended[order]
        out = frame.instances[first_row : first_row + n]
        out["model"] = model[order, :3, :]
        out["misc"] = 0
        out["misc"][:, 0] = material[order]
        out["misc"][:, 1] = keys
        if extra is not None:  # a skinned or morphed row's (extract/skins.py)
            out["misc"][:, 2:] = extra[order].view(np.uint32).reshape(-1, 2)
        group = (keys * len(FILLS) + fill) * 2 + blended
        starts = np.flatnonzero(np.r_[True, group[1:] != group[:-1]])
        counts = np.diff(np.r_[starts, n])
        triangles = int((index_counts[keys[starts] // 2] // 3 * counts).sum())
        runs = list(
            zip(
                keys[starts].tolist(), fill[starts].tolist(), blended[starts].tolist(), starts.tolist(), counts.tolist()
            )
        )
        if oit is None:
            return self._draw(frame, first_row, runs, frame.target.aside_begin), len(starts), n, triangles, None
        solid = [r for r in runs if not r[2]]
        cb = self._draw(frame, first_row, solid, frame.target.aside_begin) if solid else None
        state = oit.state
        oit_frame = replace(frame, target=state)
        accumulated = self._draw(oit_frame, first_row, [r for r in runs if r[2]], state.secondary_begin, oit)
        return cb, len(starts), n, triangles, accumulated

    def _pipeline(self, blended: bool, fill: int, mirrored: int, oit: Any = None) -> Any:
        key = (blended, FILLS[fill], oit is not None, None if oit is not None else self.ctx.formats)
        found = self.pipelines.get(key)
        if found is None:
            ctx = self.ctx if fill == 0 else replace(self.ctx, fill=FILLS[fill])
            if oit is not None:  # the weighted transparency pass: one sample, two targets
                ctx = replace(ctx, formats=oit.formats, oit=True, samples=1)
            found = self.pipelines[key] = mesh_pipelines(ctx, self.layout, "mesh.vert", blended=blended)
        return found[mirrored]

    def _draw(self, frame: FrameInputs, first_row: int, runs: Any, begin: Any, oit: Any = None) -> Any:
        ctx = self.ctx
        vk = ctx.device.vk
        cb = ctx.secondaries.begin(frame.slot, begin)
        vk.vkCmdSetViewport(cb, 0, 1, [frame.target.viewport])
        vk.vkCmdSetScissor(cb, 0, 1, [frame.target.area])
        vk.vkCmdBindDescriptorSets(
            cb, vk.VK_PIPELINE_BIND_POINT_GRAPHICS, self.layout, 0, 1, [frame.descriptor_set], 0, None
        )
        bound = None
        for key, fill, blended, start, count in runs:
            pipeline = self._pipeline(bool(blended), fill, key % 2, oit)
            if pipeline is not bound:
                vk.vkCmdBindPipeline(cb, vk.VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline)
                bound = pipeline
            mesh = ctx.meshes.bind(cb, key // 2)
            vk.vkCmdDrawIndexed(cb, mesh.index_count, count, 0, 0, first_row + start)
        end_command_buffer(vk, cb)
        return cb

    def destroy(self) -> None:
        vk = self.ctx.device.vk
        handle = self.ctx.device.handle
        for pair in self.pipelines.values():
            for pipeline in pair:
                vk.vkDestroyPipeline(handle, pipeline, None)
        vk.vkDestroyPipelineLayout(handle, self.layout, None)
