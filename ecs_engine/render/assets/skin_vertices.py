"""The skinned and morphed meshes' vertex data as one storage buffer the vertex shaders read
(shaders/deform.glsl), as 32-bit words. First the number of meshes the header covers, then per
mesh handle up to the last such mesh, SKIN_HEADER_WORDS words: for the mesh and then each of
its coarser levels of detail (the indirect mode draws those), where its skin records start and
where its morph block starts (SKIN_NONE for none). A skin record (SKIN_WORDS words, one per
vertex, in vertex order): its eight joint indices, two 16-bit halves a word (the lower half
first), then its eight weights as floats. A morph block: its target count T, its vertex count V,
then per target, per vertex, MORPH_WORDS floats (the position's, normal's and tangent's deltas).
A vertex is found by its index in its own mesh or level (gl_VertexIndex - gl_BaseVertex), so the
instanced paths' per-mesh buffers and the indirect path's merged one read the same records."""

from __future__ import annotations

from typing import Any

import numpy as np

from ...gpu.memory import Buffer, upload
from ...gpu.owned import Owned
from ..layouts import MAX_LODS, MORPH_WORDS, SKIN_HEADER_WORDS, SKIN_WORDS
from .mesh_data import MeshData

SKIN_NONE = 0xFFFFFFFF


def skin_words(meshes: list[MeshData], levels: dict[int, list[MeshData]] | None = None) -> np.ndarray:
    """The buffer's words for `meshes` (by handle) and the coarser `levels` of some of them (by
    handle, finest first; at most MAX_LODS are named); a header of no mesh when none deforms."""
    deformed = [h for h, m in enumerate(meshes) if m.skin is not None or m.morph is not None]
    covered = max(deformed) + 1 if deformed else 0
    header = np.full(1 + SKIN_HEADER_WORDS * covered, SKIN_NONE, np.uint32)
    header[0] = covered
    parts, at = [header], len(header)
    for h in deformed:
        for level, mesh in enumerate([meshes[h], *(levels or {}).get(h, [])][: 1 + MAX_LODS]):
            slot = 1 + SKIN_HEADER_WORDS * h + 2 * level
            skin, morph = mesh.skin, mesh.morph
            if skin is not None:
                records = np.empty((skin.vertex_count, SKIN_WORDS), np.uint32)
                records[:, :4] = np.ascontiguousarray(skin.joints, "<u2").view("<u4")
                records[:, 4:] = np.ascontiguousarray(skin.weights, "<f4").view("<u4")
                header[slot] = at
                parts.append(records.reshape(-1))
                at += records.size
            if morph is not None:
                deltas = np.concatenate([morph.positions, morph.normals, morph.tangents], axis=2)  # (T, V, 9)
                assert deltas.shape[2] == MORPH_WORDS
                words = deltas.astype("<f4").view("<u4").reshape(-1)
                block = np.r_[np.array([morph.count, morph.vertex_count], np.uint32), words]
                header[slot + 1] = at
                parts.append(block)
                at += block.size
    return np.concatenate(parts)


class SkinVertices:
    """The buffer for a mesh registry's meshes, made again when its skinned meshes change."""

    def __init__(self, device: Any) -> None:
        self.device = device
        self._owned = Owned(device)
        self._buffer: Buffer | None = None
        self._made_for: tuple[Any, ...] | None = None  # the skinned meshes it holds: (handle, MeshData id)
        self._checked = -1  # the registry version last looked at

    def buffer(self, meshes: list[MeshData], version: Any, levels: dict[int, list[MeshData]] | None = None) -> Buffer:
        """The buffer for `meshes` (a registry's, at `version`) and their coarser `levels`. Making it
        anew waits for the GPU (frames in flight read the old one): only when a skinned mesh or
        its levels are added or replaced."""
        if self._buffer is not None and version == self._checked:
            return self._buffer
        self._checked = version
        coarser = levels or {}
        made_for = tuple(
            (h, id(m), tuple(id(level) for level in coarser.get(h, [])))
            for h, m in enumerate(meshes)
            if m.skin is not None or m.morph is not None
        )
        if self._buffer is None or made_for != self._made_for:
            usage = self.device.vk.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT
            fresh = upload(self.device, skin_words(meshes, coarser), usage)
            if self._buffer is not None:
                self.device.wait_idle()
                self._owned.release(self._buffer)
            self._buffer, self._made_for = self._owned.add(fresh), made_for
        return self._buffer

    def destroy(self) -> None:
        self._owned.destroy()
        self._buffer = None
