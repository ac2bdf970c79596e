"""Alpha-blended materials: their rows leave the chunks (frame_data.BlendedRows) and are drawn
after every opaque row, in the same subpass, back to front by the distance of their bounding
sphere's centre from the eye, with blending on and depth writes off (the opaque depth still
hides them). Sorting is per frame and vectorised; consecutive rows of one (mesh, winding) are one
instanced draw. Objects that intersect or interleave can still blend in the wrong order within a
pixel: sorting by object, as glTF viewers and most engines do, not per fragment.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..gpu.pipeline import pipeline_layout
from ..gpu.secondary import end_command_buffer
from ..maths.culling import bounding_spheres, spheres_visible
from .chunk_paths import mesh_pipelines
from .frame_data import BlendedRows
from .path import FrameInputs, PathContext


class TransparentPass:
    def __init__(self, ctx: PathContext) -> None:
        self.ctx = ctx
        self.layout = pipeline_layout(ctx.device, [ctx.frame_set_layout])
        self.pipelines: tuple[Any, Any] | None = None  # made on first use: most scenes blend nothing

    def record(
        self, frame: FrameInputs, rows: BlendedRows, first_row: int, eye: np.ndarray
    ) -> tuple[Any, int, int, int]:
        """Cull, sort far to near, write instance rows from `first_row`, record the draws:
        (secondary command buffer or None, draws, rows drawn, triangles)."""
        centers, radii, index_counts = frame.bounds
        model, handle, material = rows.model, rows.handle, rows.material
        c, r = bounding_spheres(model, centers[handle], radii[handle])
        if frame.planes is not None:
            keep = np.flatnonzero(spheres_visible(c, r, frame.planes))
            model, handle, material, c = model[keep], handle[keep], material[keep], c[keep]
        n = len(handle)
        if n == 0:
            return None, 0, 0, 0
        d = c - eye
        order = np.argsort(-np.einsum("ij,ij->i", d, d), kind="stable")
        m3 = model[order, :3, :3].astype(np.float64)
        mirrored = np.linalg.det(m3) < 0
        keys = handle[order].astype(np.int64) * 2 + mirrored
        out = frame.instances[first_row : first_row + n]
        out["model"] = model[order, :3, :]
        out["misc"] = 0
        out["misc"][:, 0] = material[order]
        out["misc"][:, 1] = keys
        starts = np.flatnonzero(np.r_[True, keys[1:] != keys[:-1]])
        counts = np.diff(np.r_[starts, n])
        return (
            self._draw(frame, first_row, keys[starts], starts, counts),
            len(starts),
            n,
            int((index_counts[keys[starts] // 2] // 3 * counts).sum()),
        )

    def _draw(
        self, frame: FrameInputs, first_row: int, keys: np.ndarray, starts: np.ndarray, counts: np.ndarray
    ) -> Any:
        ctx = self.ctx
        vk = ctx.device.vk
        if self.pipelines is None:
            self.pipelines = mesh_pipelines(ctx, self.layout, "mesh.vert", blended=True)
        cb = ctx.secondaries.begin(frame.slot, frame.target.secondary_begin)
        vk.vkCmdSetViewport(cb, 0, 1, [frame.target.viewport])
        vk.vkCmdSetScissor(cb, 0, 1, [frame.target.area])
        vk.vkCmdBindDescriptorSets(
            cb, vk.VK_PIPELINE_BIND_POINT_GRAPHICS, self.layout, 0, 1, [frame.descriptor_set], 0, None
        )
        bound = None
        for key, start, count in zip(keys.tolist(), starts.tolist(), counts.tolist()):
            pipeline = self.pipelines[key % 2]
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
        if self.pipelines is not None:
            for pipeline in self.pipelines:
                vk.vkDestroyPipeline(handle, pipeline, None)
        vk.vkDestroyPipelineLayout(handle, self.layout, None)
