"""Meshes uploaded once to device-local memory and shared: entities hold only a handle.

The indirect render mode draws every mesh from one vertex and one index buffer (a draw command
names its mesh by first index and vertex offset): `merged()` builds those on first use. A mesh
with enough triangles gets coarser levels of detail (mesh_lod.py) the first time they are asked
for: the indirect path asks for those of the meshes it draws, with levels on (`build_levels`).
A mesh that is only added (a scene file's unused entry, a model shown in another mode) never
pays for them: building them costs a few seconds at 263k vertices on a 2-core box. The levels
live only in the merged buffers, as draw meshes after the meshes themselves, so handles, scene
files and the CPU-culled modes never see them."""

from __future__ import annotations

import hashlib
from collections import OrderedDict
from collections.abc import Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ...gpu.acceleration import MeshInput, Structure, build_bottom_levels, ray_input_usage
from ...gpu.memory import Buffer, upload
from ...gpu.owned import Owned
from ..layouts import MAX_LODS, MESH_VERTEX
from .lod_worker import LevelBuilder
from .mesh_data import MeshData
from .mesh_lod import Lod, build_lods
from .skin_vertices import SkinVertices

if TYPE_CHECKING:
    from ...gpu.device import Device

#: A mesh with fewer triangles has its levels built on the frame that first draws it even with
#: `background_levels`: about 0.3 s on the 2-core box, less than starting the child process.
BACKGROUND_TRIANGLES = 32_768
_POSITION = int(MESH_VERTEX.fields["position"][1]) if MESH_VERTEX.fields else 0  # the position's byte offset


@dataclass
class MergedMeshes:
    """Draw meshes: the meshes (handles 0..count-1), then every mesh's coarser levels."""

    vertices: Buffer
    indices: Buffer
    first_index: np.ndarray  # per draw mesh
    vertex_offset: np.ndarray
    index_count: np.ndarray
    count: int  # meshes included (handles 0..count-1)
    lod_first: np.ndarray  # per mesh: the draw mesh of its first coarser level (0: none)
    lod_levels: np.ndarray  # per mesh: its coarser levels
    lod_error: np.ndarray  # (count, MAX_LODS) float32: their errors
    vertex_array: Any = None  # VkBuffer[1] for raw calls, made on first use

    @property
    def draw_meshes(self) -> int:
        return len(self.index_count)

    @property
    def owners(self) -> np.ndarray:
        """Per draw mesh, the mesh it draws: itself, or the mesh a level of detail belongs to."""
        n = self.count
        return np.concatenate([np.arange(n), np.repeat(np.arange(n), self.lod_levels.astype(np.int64))])


@dataclass
class GpuMesh:
    data: MeshData
    vertices: Buffer
    indices: Buffer
    index_count: int


class MeshRegistry:
    """`background_levels`: build a big mesh's levels of detail in a child process (lod_worker.py),
    drawing it at full detail until they arrive: for windows, where a build of seconds would freeze
    the frames. Off (headless), they are built on the frame that first draws the mesh, so what a
    frame shows never depends on timing."""

    def __init__(self, device: Device, background_levels: bool = False) -> None:
        self.device = device
        self._builder = LevelBuilder() if background_levels else None
        self._meshes: list[GpuMesh] = []
        self._lods: list[list[Lod] | None] = []  # per handle, its coarser levels (mesh_lod.py); None: not built
        self._digests: list[bytes] = []  # per handle, its content's digest (the levels' cache key)
        self._levels_built = 0  # bumped when a mesh's levels arrive: merged buffers and bounds change
        self._by_data: dict[int, int] = {}  # id(MeshData) -> handle: the same object again
        self._by_content: dict[bytes, int] = {}  # digest of the arrays -> handle: an equal mesh again
        self._bounds: tuple[tuple[int, int], tuple[np.ndarray, np.ndarray, np.ndarray]] | None = None
        self._merged: MergedMeshes | None = None
        self._merged_for = (0, 0)  # (meshes, levels built) the merged buffers hold
        self._bottom: list[Structure] = []  # per handle, its bottom-level acceleration structure
        self._bottom_addresses = np.zeros(0, dtype=np.uint64)
        self.version = 0  # counts meshes added and replaced: what caches of buffer handles are keyed on
        # the meshes' buffers; the merged buffers and the bottom levels, each made again as a whole
        self._mesh_buffers = Owned(device)
        self._merged_buffers = Owned(device)
        self._bottom_levels = Owned(device)
        self._skins = SkinVertices(device)  # the skinned meshes' weights, for the vertex shaders
        self._skin_kept: tuple[tuple[Any, ...], Buffer] | None = None  # skin_buffer's last answer

    def add(self, mesh: MeshData) -> int:
        """Upload `mesh` once: the same MeshData, or an equal one (the same vertices and indices,
        as a scene built again makes), gives the same handle. Without this, switching scenes in
        the editor uploaded their meshes again every time."""
        key = id(mesh)
        if key in self._by_data and self._meshes[self._by_data[key]].data is mesh:
            return self._by_data[key]
        digest = _digest(mesh)
        if digest in self._by_content:
            return self._by_content[digest]
        vertices, indices = self._upload(mesh)
        handle = len(self._meshes)
        self._meshes.append(GpuMesh(mesh, vertices, indices, len(mesh.indices)))
        self._lods.append(None)
        self._digests.append(digest)
        self._by_data[key] = self._by_content[digest] = handle
        self.version += 1
        return handle

    def replace(self, handle: int, mesh: MeshData) -> None:
        """`mesh` uploaded under `handle` in place of the one there (hot reload), after the GPU is
        idle; its levels of detail, the merged buffers, the bounds and the bottom levels are
        made again as they are needed."""
        self.device.wait_idle()  # frames in flight may draw from the buffers destroyed here
        old = self._meshes[handle]
        vertices, indices = self._upload(mesh)
        self._mesh_buffers.release(old.vertices)
        self._mesh_buffers.release(old.indices)
        for key in [k for k, h in self._by_data.items() if h == handle]:
            del self._by_data[key]
        if self._by_content.get(self._digests[handle]) == handle:
            del self._by_content[self._digests[handle]]
        digest = _digest(mesh)
        self._meshes[handle] = GpuMesh(mesh, vertices, indices, len(mesh.indices))
        self._lods[handle] = None
        self._digests[handle] = digest
        self._by_data[id(mesh)] = handle
        self._by_content.setdefault(digest, handle)
        self._bounds, self._merged_for = None, (-1, -1)
        self._bottom_levels.destroy()
        self._bottom.clear()
        self.version += 1

    def _upload(self, mesh: MeshData) -> tuple[Buffer, Buffer]:
        """`mesh`'s vertex and index buffers, owned here. A bottom level may be built from them;
        a deformed mesh's vertices are also read as storage (render/draw/posed_vertices.py)."""
        vk = self.device.vk
        ray = ray_input_usage(self.device)
        deformed = mesh.skin is not None or mesh.morph is not None
        storage = vk.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT if deformed else 0
        vertices = self._mesh_buffers.add(
            upload(self.device, _interleaved(mesh), vk.VK_BUFFER_USAGE_VERTEX_BUFFER_BIT | ray | storage)
        )
        indices = self._mesh_buffers.add(upload(self.device, mesh.indices, vk.VK_BUFFER_USAGE_INDEX_BUFFER_BIT | ray))
        return vertices, indices

    def skin_buffer(self, levels: bool = False) -> Buffer:
        """The skinned and morphed meshes' joints, weights and morph deltas as the vertex shaders
        read them (skin_vertices.py); with `levels` (the indirect mode, which draws levels of
        detail), their coarser levels' too, built now where they were not yet. Looked at again
        only when meshes or levels change (it is asked every frame with deformed rows)."""
        kept = self._skin_kept
        if kept is not None and kept[0] == (self.version, levels, self._levels_built):
            return kept[1]
        datas = [m.data for m in self._meshes]
        coarser = {}
        if levels:
            for h, data in enumerate(datas):
                if data.skin is not None or data.morph is not None:
                    coarser[h] = [lod.mesh for lod in self.lods(h)]
        key = (self.version, levels, self._levels_built)  # (after the levels built just now)
        buffer = self._skins.buffer(datas, key, coarser)
        self._skin_kept = (key, buffer)
        return buffer

    def __getitem__(self, handle: int) -> GpuMesh:
        return self._meshes[handle]

    def __len__(self) -> int:
        return len(self._meshes)

    def lods(self, handle: int) -> list[Lod]:
        """The mesh's coarser levels of detail, finest first (none for a small mesh), built now
        (or waited for) if they were not yet."""
        levels = self._lods[handle]
        if levels is None:
            digest = self._digests[handle]
            if self._builder is not None and self._builder.pending(handle):
                levels = self._builder.wait(handle)
                _remember(digest, levels)
            else:
                levels = _levels(self._meshes[handle].data, digest)
            self._install(handle, levels)
        return levels

    def has_levels_built(self, handle: int) -> bool:
        return self._lods[handle] is not None

    def build_levels(self, handles: Iterable[int]) -> None:
        """Build the levels of detail of `handles` that have none yet (the meshes a frame draws):
        now, or in the background for a big mesh when `background_levels`. The next `merged()`
        and `bounds()` include those that are ready."""
        for handle in map(int, handles):
            if self._lods[handle] is not None:
                continue
            mesh = self._meshes[handle].data
            if self._builder is None or mesh.triangle_count < BACKGROUND_TRIANGLES or self._digests[handle] in _LEVELS:
                self.lods(handle)
            else:
                self._builder.submit(handle, mesh)

    def _install(self, handle: int, levels: list[Lod]) -> None:
        self._lods[handle] = levels
        if levels:
            self._levels_built += 1

    def _collect(self) -> None:
        """Levels built in the background since the last frame."""
        if self._builder is not None:
            for handle, levels in self._builder.finished():
                _remember(self._digests[handle], levels)
                self._install(handle, levels)

    def bounds(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Per mesh: bounding sphere centre (n, 3) and radius, index count (kept until meshes are
        added). The sphere holds the mesh's levels of detail too: whichever is drawn, culling it
        by the sphere is safe."""
        if self._builder is not None:  # (asked twice a frame: the culling's and the frame's inputs)
            self._collect()
        n = len(self._meshes)
        if self._bounds is None or self._bounds[0] != (n, self._levels_built):
            meshes = self._meshes
            centers = np.array([m.data.center for m in meshes], dtype=np.float64).reshape(n, 3)
            radii = np.array([m.data.radius for m in meshes], dtype=np.float64)
            for handle, lods in enumerate(self._lods):
                for lod in lods or ():
                    reach = np.linalg.norm(lod.mesh.positions - centers[handle], axis=1).max(initial=0.0)
                    radii[handle] = max(radii[handle], float(reach))
            self._bounds = (
                (n, self._levels_built),
                (centers, radii, np.array([m.index_count for m in meshes], dtype=np.int64)),
            )
        return self._bounds[1]

    def triangles(self, handle: int) -> int:
        return self._meshes[handle].index_count // 3

    def bind(self, cb: Any, handle: int) -> GpuMesh:
        vk = self.device.vk
        mesh = self._meshes[handle]
        vk.vkCmdBindVertexBuffers(cb, 0, 1, [mesh.vertices.handle], [0])
        vk.vkCmdBindIndexBuffer(cb, mesh.indices.handle, 0, vk.VK_INDEX_TYPE_UINT32)
        return mesh

    def bottom_levels(self) -> np.ndarray:
        """Per mesh handle, the device address of its bottom-level acceleration structure (ray
        tracing): built and compacted once per mesh, on the first call after it was added (a
        device that never traces rays builds none)."""
        done = len(self._bottom)
        if done < len(self._meshes):
            inputs = [
                MeshInput(m.vertices, len(m.data.positions), MESH_VERTEX.itemsize, m.indices, m.index_count, _POSITION)
                for m in self._meshes[done:]
            ]
            self._bottom += [self._bottom_levels.add(s) for s in build_bottom_levels(self.device, inputs)]
            self._bottom_addresses = np.array([s.address for s in self._bottom], dtype=np.uint64)
        return self._bottom_addresses

    def merged(self) -> MergedMeshes:
        """Every mesh, and the levels built so far, in one vertex and one index buffer: rebuilt
        when meshes were added or levels built."""
        self._collect()
        built = (len(self._meshes), self._levels_built)
        if self._merged is not None and self._merged_for == built:
            return self._merged
        vk = self.device.vk
        if self._merged is not None:
            self.device.wait_idle()  # a frame in flight may still draw from the old buffers
            self._destroy_merged()
        n = len(self._meshes)
        per_mesh = [lods or [] for lods in self._lods]
        levels = np.array([len(lods) for lods in per_mesh], dtype=np.int64)
        lod_first = np.where(levels > 0, n + np.concatenate([[0], np.cumsum(levels)[:-1]]), 0) if n else levels
        lod_error = np.zeros((n, MAX_LODS), dtype=np.float32)
        for handle, lods in enumerate(per_mesh):
            lod_error[handle, : len(lods)] = [lod.error for lod in lods]
        datas = [m.data for m in self._meshes] + [lod.mesh for lods in per_mesh for lod in lods]
        index_counts = np.array([len(d.indices) for d in datas], dtype=np.int64)
        vertex_counts = np.array([len(d.positions) for d in datas], dtype=np.int64)
        first_index = np.concatenate([[0], np.cumsum(index_counts)[:-1]]).astype(np.uint32)
        vertex_offset = np.concatenate([[0], np.cumsum(vertex_counts)[:-1]]).astype(np.int32)
        vertices = np.concatenate([_interleaved(d) for d in datas]) if datas else np.zeros(1, MESH_VERTEX)
        indices = np.concatenate([d.indices for d in datas]).astype(np.uint32) if datas else np.zeros(1, np.uint32)
        merged = self._merged_buffers
        self._merged = MergedMeshes(
            merged.add(upload(self.device, vertices, vk.VK_BUFFER_USAGE_VERTEX_BUFFER_BIT)),
            merged.add(upload(self.device, indices, vk.VK_BUFFER_USAGE_INDEX_BUFFER_BIT)),
            first_index,
            vertex_offset,
            index_counts,
            n,
            lod_first.astype(np.uint32),
            levels.astype(np.uint32),
            lod_error,
        )
        self._merged_for = built
        return self._merged

    def _destroy_merged(self) -> None:
        self._merged_buffers.destroy()
        self._merged = None

    def destroy(self) -> None:
        if self._builder is not None:
            self._builder.close()
        self._destroy_merged()
        self._skins.destroy()
        self._skin_kept = None
        self._bottom_levels.destroy()  # built from the meshes' buffers: before them
        self._bottom.clear()
        self._mesh_buffers.destroy()
        self._meshes.clear()
        self._lods.clear()
        self._digests.clear()
        self._by_data.clear()
        self._by_content.clear()


# Levels of detail by mesh content, for registries made again (tests, benchmarks, a new device):
# simplifying a 12k-triangle mesh and measuring its error takes a good part of a second.
_LEVELS: OrderedDict[bytes, list[Lod]] = OrderedDict()
_LEVELS_KEPT = 32


def _levels(mesh: MeshData, digest: bytes) -> list[Lod]:
    levels = _LEVELS.get(digest)
    if levels is None:
        levels = build_lods(mesh)[:MAX_LODS]
    _remember(digest, levels)
    return levels


def _remember(digest: bytes, levels: list[Lod]) -> None:
    _LEVELS[digest] = levels
    _LEVELS.move_to_end(digest)
    while len(_LEVELS) > _LEVELS_KEPT:
        _LEVELS.popitem(last=False)


def _interleaved(mesh: MeshData) -> np.ndarray:
    out = np.empty(len(mesh.positions), dtype=MESH_VERTEX)
    out["position"] = mesh.positions
    out["normal"] = mesh.normals
    out["uv"] = mesh.uvs
    out["tangent"] = mesh.tangents
    return out


def _digest(mesh: MeshData) -> bytes:
    h = hashlib.blake2b(digest_size=16)
    skin = () if mesh.skin is None else (mesh.skin.joints, mesh.skin.weights)
    morph = () if mesh.morph is None else (mesh.morph.positions, mesh.morph.normals, mesh.morph.tangents)
    for array in (mesh.positions, mesh.normals, mesh.uvs, mesh.tangents, mesh.indices, *skin, *morph):
        h.update(str(array.shape).encode())
        h.update(np.ascontiguousarray(array).tobytes())
    return h.digest()
