"""Acceleration structures and ray casting (gpu/acceleration.py, gpu/ray_cast.py,
render/raytracing/instances.py). The instance layout and the row-writing kernel are checked everywhere;
building and tracing need a device with ray-tracing pipelines (the GPU host: lavapipe has none,
so those tests skip there, saying why), with the validation layers on."""

from __future__ import annotations

import numpy as np
import pytest
import vulkan as vk
from gpu_context import shared_device

from ecs_engine.gpu.acceleration import AS_INSTANCE, MeshInput, TopLevel, build_bottom_levels, functions
from ecs_engine.gpu.memory import UPLOAD, Buffer
from ecs_engine.render.assets.mesh_registry import MeshRegistry
from ecs_engine.render.assets.primitives import cube_mesh, sphere_mesh
from ecs_engine.render.layouts import MESH_VERTEX
from ecs_engine.render.raytracing.instances import (
    FACING_CULL_DISABLE,
    FORCE_NO_OPAQUE,
    INDEX_LIMIT,
    write_instances,
    write_instances_numpy,
)


def test_instance_dtype_is_the_vulkan_struct():
    ffi = vk.ffi
    x = ffi.new("VkAccelerationStructureInstanceKHR*")
    x.instanceCustomIndex, x.mask = 0xABCDEF, 0x5A
    x.instanceShaderBindingTableRecordOffset, x.flags = 0x123456, 0x0F
    x.accelerationStructureReference = 0x0123456789ABCDEF
    for r in range(3):
        for c in range(4):
            x.transform.matrix[r][c] = r * 4 + c + 0.5
    row = np.zeros(1, AS_INSTANCE)
    row["transform"] = np.arange(12, dtype=np.float32).reshape(3, 4) + 0.5
    row["index_mask"] = 0xABCDEF | 0x5A << 24
    row["sbt_flags"] = 0x123456 | 0x0F << 24
    row["blas"] = 0x0123456789ABCDEF
    assert ffi.sizeof("VkAccelerationStructureInstanceKHR") == AS_INSTANCE.itemsize
    assert bytes(ffi.buffer(x)) == row.tobytes()


@pytest.mark.parametrize("caster", [True, False])
def test_instance_kernel_matches_the_reference(caster):
    rng = np.random.default_rng(7)
    n = 513
    model = rng.normal(size=(n, 4, 4)).astype(np.float32)
    handle = rng.integers(0, 4, n).astype(np.int32)
    blas = np.array([0, 1 << 40, (2 << 40) + 256, 3 << 50], dtype=np.uint64)
    first = INDEX_LIMIT - 100  # the custom index wraps at 24 bits
    got, want = np.zeros(n, AS_INSTANCE), np.zeros(n, AS_INSTANCE)
    write_instances(model, handle, blas, first, caster, got)
    write_instances_numpy(model, handle, blas, first, caster, want)
    assert got.tobytes() == want.tobytes()
    assert (want["transform"] == model[:, :3, :]).all()
    assert (want["blas"] == blas[handle]).all()
    assert (want["index_mask"] >> 24 == (0xFF if caster else 0)).all()
    assert want["index_mask"][100] & 0xFFFFFF == 0  # row INDEX_LIMIT: wrapped
    assert (want["sbt_flags"] >> 24 == FACING_CULL_DISABLE).all()  # no cutouts: every instance opaque


def test_instance_kernel_marks_alpha_masked_rows_non_opaque():
    """With cutouts (per material), the rows of alpha-masked materials lose the opaque flag (the
    any-hit shader runs for them) and every instance's mesh and material are written beside."""
    rng = np.random.default_rng(8)
    n = 300
    model = rng.normal(size=(n, 4, 4)).astype(np.float32)
    handle = rng.integers(0, 3, n).astype(np.int32)
    material = rng.integers(0, 5, n).astype(np.uint32)
    cutout = np.array([False, True, False, True, False])
    blas = np.array([1 << 40, 2 << 40, 3 << 40], dtype=np.uint64)
    got, want = np.zeros(n, AS_INSTANCE), np.zeros(n, AS_INSTANCE)
    got_rows, want_rows = np.zeros((n, 2), np.uint32), np.zeros((n, 2), np.uint32)
    write_instances(model, handle, blas, 10, True, got, material, cutout, got_rows)
    write_instances_numpy(model, handle, blas, 10, True, want, material, cutout, want_rows)
    assert got.tobytes() == want.tobytes() and (got_rows == want_rows).all()
    flags = want["sbt_flags"] >> 24
    assert (flags == np.where(cutout[material], FACING_CULL_DISABLE | FORCE_NO_OPAQUE, FACING_CULL_DISABLE)).all()
    assert 50 < cutout[material].sum() < 250
    assert (want_rows[:, 0] == handle).all() and (want_rows[:, 1] == material).all()
    with pytest.raises(ValueError, match="cutout needs the rows' materials"):
        write_instances(model, handle, blas, 10, True, got, None, cutout, got_rows)


def test_a_device_without_ray_tracing_refuses_in_one_message():
    device = shared_device()
    if device.ray_tracing is not None:
        pytest.skip("this device traces rays")
    assert device.features["rayTracing"] is False
    with pytest.raises(RuntimeError, match="has no ray tracing"):
        functions(device)


def _needs_ray_tracing():
    device = shared_device()
    if device.ray_tracing is None:
        pytest.skip(f"{device.info.name} has no ray-tracing pipelines (VK_KHR_ray_tracing_pipeline)")
    return device


def _instances(positions, handles, blas, casters=None):
    n = len(positions)
    model = np.tile(np.eye(4, dtype=np.float32), (n, 1, 1))
    model[:, :3, 3] = positions
    out = np.zeros(n, AS_INSTANCE)
    write_instances(model, np.asarray(handles, dtype=np.int32), blas, 0, True, out)
    if casters is not None:
        out["index_mask"] = np.where(casters, out["index_mask"], out["index_mask"] & 0xFFFFFF)
    return out


class Scene:
    """A mesh registry's cube and sphere, a top level over instance rows, a ray caster."""

    def __init__(self, device, capacity=64):
        from ecs_engine.gpu.ray_cast import RayCaster

        self.device = device
        self.meshes = MeshRegistry(device)
        self.cube = self.meshes.add(cube_mesh())
        self.sphere = self.meshes.add(sphere_mesh())
        self.blas = self.meshes.bottom_levels()
        self.top = TopLevel(device, capacity)
        self.rows = None
        self.caster = RayCaster(device)

    def build(self, rows, update=False):
        usage = (
            vk.lib.VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT
            | vk.lib.VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_BIT_KHR
        )
        if self.rows is None or self.rows.size < rows.nbytes:
            if self.rows is not None:
                self.rows.destroy()
            self.rows = Buffer(self.device, max(rows.nbytes, 64), usage, UPLOAD)
        self.rows.bytes()[: rows.nbytes] = rows.view(np.uint8)
        self.top.reserve(len(rows))
        refit = []
        self.device.submit_once(lambda cb: refit.append(self.top.record(cb, self.rows.address, len(rows), update)))
        return refit[0]

    def down(self, xy, mask=0xFF):
        """Rays straight down -z from z = 10 at the points `xy`."""
        origins = np.column_stack([xy, np.full(len(xy), 10.0)])
        directions = np.tile([0.0, 0.0, -1.0], (len(xy), 1))
        return self.caster.cast(self.top, origins, directions, mask=mask)

    def close(self):
        self.caster.destroy()
        self.top.destroy()
        if self.rows is not None:
            self.rows.destroy()
        self.meshes.destroy()


@pytest.fixture
def rt_scene():
    s = Scene(_needs_ray_tracing())
    try:
        yield s
    finally:
        s.close()


def test_rays_hit_the_instances_where_they_stand(rt_scene):
    s = rt_scene
    positions = np.array([[x * 3.0, y * 3.0, z] for x, y, z in [(0, 0, 0), (1, 0, 2), (2, 1, -1), (0, 2, 1)]])
    handles = [s.cube, s.cube, s.sphere, s.sphere]
    assert s.build(_instances(positions, handles, s.blas)) is False  # a first build, not a refit
    hits = s.down(positions[:, :2] + [0.01, 0.013])  # off the sphere's vertices
    tolerance = np.array([1e-4, 1e-4, 1e-2, 1e-2])  # the cube's flat top; the sphere's facets
    assert (np.abs(hits["t"] - (10.0 - positions[:, 2] - 0.5)) < tolerance).all()
    assert (hits["custom_index"] == np.arange(4)).all()  # the row index
    assert (hits["instance"] == np.arange(4)).all()
    miss = s.down(np.array([[1.5, 1.5], [-2.0, 0.0]]))
    assert (miss["t"] == -1).all()


def test_masks_and_missing_bottom_levels_hide_instances(rt_scene):
    s = rt_scene
    positions = np.array([[0.0, 0, 0], [3.0, 0, 0], [6.0, 0, 0]])
    blas = s.blas.copy()
    rows = _instances(positions, [s.cube, s.cube, s.sphere], blas, casters=[True, False, True])
    rows["blas"][2] = 0  # inactive
    s.build(rows)
    hits = s.down(positions[:, :2])
    assert hits["t"][0] == pytest.approx(9.5, abs=1e-4)
    assert (hits["t"][1:] == -1).all()  # mask 0: not a caster; address 0: inactive


def test_an_update_follows_moved_instances_and_a_new_count_rebuilds(rt_scene):
    s = rt_scene
    positions = np.array([[0.0, 0, 0], [3.0, 0, 0]])
    s.build(_instances(positions, [s.cube, s.cube], s.blas))
    moved = positions + [[0.0, 0.0, 2.0], [0.2, 0.0, -3.0]]
    assert s.build(_instances(moved, [s.cube, s.cube], s.blas), update=True) is True  # a refit
    hits = s.down(moved[:, :2])
    assert np.allclose(hits["t"], 10.0 - moved[:, 2] - 0.5, atol=1e-4)
    more = np.vstack([moved, [[6.0, 0, 1.0]]])
    assert s.build(_instances(more, [s.cube] * 3, s.blas), update=True) is False  # the count changed
    assert np.allclose(s.down(more[:, :2])["t"], 10.0 - more[:, 2] - 0.5, atol=1e-4)


def test_the_top_level_grows(rt_scene):
    s = rt_scene
    n = 1000  # over the capacity of 64 it was made with
    grid = np.stack(np.meshgrid(np.arange(40) * 2.0, np.arange(25) * 2.0), -1).reshape(-1, 2)[:n]
    positions = np.column_stack([grid, np.zeros(n)])
    s.build(_instances(positions, [s.cube] * n, s.blas))
    assert s.top.capacity >= n
    hits = s.down(grid)
    assert np.allclose(hits["t"], 9.5, atol=1e-4) and (hits["custom_index"] == np.arange(n)).all()


def test_compaction_keeps_the_hits_and_shrinks_the_structure():
    device = _needs_ray_tracing()
    meshes = MeshRegistry(device)
    try:
        mesh = meshes[meshes.add(sphere_mesh(64, 32))]
        data = MeshInput(mesh.vertices, len(mesh.data.positions), MESH_VERTEX.itemsize, mesh.indices, mesh.index_count)
        full, small = build_bottom_levels(device, [data], compact=False), build_bottom_levels(device, [data])
        try:
            assert 0 < small[0].size < full[0].size
        finally:
            for s in full + small:
                s.destroy()
    finally:
        meshes.destroy()
