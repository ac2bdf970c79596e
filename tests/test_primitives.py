"""The shapes made in code, tangent frames, and texture coordinates read from files: winding and
normals agree, every shape fits the unit box, the texture is not mirrored anywhere, tangents follow
+u and their handedness makes the bitangent point up the image (glTF's convention)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh

from ecs_engine.errors import UsageError
from ecs_engine.render.assets.mesh_data import MeshData, tangent_frames
from ecs_engine.render.assets.mesh_loading import load_mesh
from ecs_engine.render.assets.mesh_registry import _interleaved
from ecs_engine.render.assets.primitives import (
    PRIMITIVES,
    cone_mesh,
    cylinder_mesh,
    plane_mesh,
    primitive_vertices,
    sphere_mesh,
    torus_mesh,
)
from ecs_engine.render.layouts import MESH_VERTEX


def triangle_frames(mesh: MeshData) -> tuple[np.ndarray, ...]:
    """Per triangle: unit face normal (from the winding), d position / du, d position / dv, and
    which triangles have a usable UV mapping."""
    tris = mesh.indices.reshape(-1, 3)
    p = mesh.positions.astype(np.float64)[tris]
    uv = mesh.uvs.astype(np.float64)[tris]
    e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    d1, d2 = uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 0]
    r = d1[:, 0] * d2[:, 1] - d2[:, 0] * d1[:, 1]
    ok = np.abs(r) > 1e-9
    r = np.where(ok, r, 1.0)[:, None]
    dpdu = (e1 * d2[:, 1:2] - e2 * d1[:, 1:2]) / r
    dpdv = (e2 * d1[:, 0:1] - e1 * d2[:, 0:1]) / r
    n = np.cross(e1, e2)
    return n / np.linalg.norm(n, axis=1, keepdims=True), dpdu, dpdv, ok


@pytest.mark.parametrize("name", list(PRIMITIVES))
def test_primitive_is_well_formed(name):
    mesh = PRIMITIVES[name]()
    assert mesh.name == name and mesh.triangle_count > 0
    extent = mesh.positions.max(0) - mesh.positions.min(0)
    assert extent.max() == pytest.approx(1.0, abs=1e-6)
    np.testing.assert_allclose((mesh.positions.max(0) + mesh.positions.min(0)) / 2, 0, atol=1e-6)
    face_n, dpdu, dpdv, ok = triangle_frames(mesh)
    tris = mesh.indices.reshape(-1, 3)
    # counter-clockwise from outside: each face normal agrees with its vertices' normals
    assert ((mesh.normals[tris] * face_n[:, None, :]).sum(-1) > 0.5).all()
    assert ok.mean() > 0.9  # nearly every triangle has a UV mapping (the poles' are thin)
    # no mirrored texture: +u, +v and the normal form a left-handed frame (v runs down the image)
    assert (np.einsum("ij,ij->i", np.cross(dpdu[ok], dpdv[ok]), face_n[ok]) < 0).all()
    assert (mesh.uvs >= 0).all() and (mesh.uvs <= 1).all()
    # tangents along +u, bitangents up the image (-v), handedness +1 everywhere
    t = mesh.tangents[tris]
    assert (np.einsum("ikj,ij->ik", t[..., :3], dpdu)[ok] > 0).all()
    bitangent = t[..., 3:] * np.cross(mesh.normals[tris], t[..., :3])
    assert (np.einsum("ikj,ij->ik", bitangent, -dpdv)[ok] > 0).all()
    assert (mesh.tangents[:, 3] == 1).all()
    np.testing.assert_allclose((mesh.tangents[:, :3] * mesh.normals).sum(1), 0, atol=1e-5)


def test_curved_primitives_have_the_analytic_normals():
    s = sphere_mesh(radius=2.0)
    np.testing.assert_allclose(s.normals, s.positions / 2.0, atol=1e-6)
    t = torus_mesh(major=0.35, minor=0.15)
    ring = t.positions.copy()
    ring[:, 1] = 0
    centre = ring / np.linalg.norm(ring, axis=1, keepdims=True) * 0.35
    np.testing.assert_allclose(t.normals, (t.positions - centre) / 0.15, atol=1e-5)
    cone = cone_mesh()
    side = cone.normals[:, 1] > -0.99  # not the base
    # the side's normals are perpendicular to the slant line from the rim to the apex
    horizontal = cone.positions[side].copy()
    horizontal[:, 1] = 0
    radial = horizontal / np.maximum(np.linalg.norm(horizontal, axis=1, keepdims=True), 1e-9)
    slant = np.array([0.0, 1.0, 0.0]) - radial * 0.5  # apex (0, 0.5, 0) minus rim (r=0.5, y=-0.5)
    at_apex = np.linalg.norm(horizontal, axis=1) < 1e-9
    dots = (cone.normals[side] * slant).sum(1)
    np.testing.assert_allclose(dots[~at_apex], 0, atol=1e-6)


def test_primitive_sizes_and_counts():
    assert sphere_mesh(8, 4).vertex_count == 9 * 5
    assert plane_mesh(subdivisions=3).triangle_count == 18
    assert plane_mesh(size=4.0).positions[:, 0].max() == 2.0
    assert cylinder_mesh(8, caps=False).triangle_count == 16
    assert cylinder_mesh(8).triangle_count == 32
    for bad in (lambda: sphere_mesh(2), lambda: plane_mesh(0.0), lambda: torus_mesh(major=0.1, minor=0.2)):
        with pytest.raises(ValueError):
            bad()


def test_tangent_frames_without_uvs_are_still_unit_and_perpendicular():
    mesh = MeshData.from_arrays([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 0, 1]] * 3, [0, 1, 2], "tri")
    np.testing.assert_array_equal(mesh.uvs, 0)
    np.testing.assert_allclose(np.linalg.norm(mesh.tangents[:, :3], axis=1), 1, atol=1e-6)
    np.testing.assert_allclose(mesh.tangents[:, :3] @ [0, 0, 1], 0, atol=1e-6)
    assert (mesh.tangents[:, 3] == 1).all()


def test_mirrored_uvs_give_handedness_minus_one():
    positions = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
    plain = tangent_frames(
        np.array(positions, float),
        np.array([[0, 0, 1.0]] * 3),
        np.array([[0, 1], [1, 1], [0, 0.0]]),
        np.array([0, 1, 2]),
    )
    mirrored = tangent_frames(
        np.array(positions, float),
        np.array([[0, 0, 1.0]] * 3),
        np.array([[1, 1], [0, 1], [1, 0.0]]),
        np.array([0, 1, 2]),
    )
    np.testing.assert_allclose(plain, [[1, 0, 0, 1]] * 3, atol=1e-6)
    np.testing.assert_allclose(mirrored, [[-1, 0, 0, -1]] * 3, atol=1e-6)


@pytest.mark.parametrize(
    "field, value, message",
    [
        ("uvs", np.full((3, 2), np.nan), "uvs must be finite"),
        ("uvs", np.zeros((2, 2)), "uvs must be finite and (V, 2)"),
        ("tangents", np.zeros((3, 4)), "tangents must be unit"),
        ("tangents", np.tile([1.0, 0, 0, 0.5], (3, 1)), "w = +1 or -1"),
    ],
)
def test_mesh_data_rejects_bad_uvs_and_tangents(field, value, message):
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)").replace("+", r"\+")):
        MeshData.from_arrays([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 0, 1]] * 3, [0, 1, 2], "tri", **{field: value})


def test_vertex_buffer_layout_holds_every_attribute():
    mesh = sphere_mesh(6, 3)
    out = _interleaved(mesh)
    assert out.dtype == MESH_VERTEX and MESH_VERTEX.itemsize == 48
    for name, array in (
        ("position", mesh.positions),
        ("normal", mesh.normals),
        ("uv", mesh.uvs),
        ("tangent", mesh.tangents),
    ):
        np.testing.assert_array_equal(out[name], array)


# ------------------------------------------------------------------------------- UVs read from files


def quad_obj(tmp_path: Path, normals: bool) -> Path:
    vn = "vn 0 0 1\n" if normals else ""
    ref = "/1" if normals else ""
    text = (
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
        + vn
        + f"f 1/1{ref} 2/2{ref} 3/3{ref}\nf 1/1{ref} 3/3{ref} 4/4{ref}\n"
    )
    path = tmp_path / "quad.obj"
    path.write_text(text)
    return path


@pytest.mark.parametrize("normals", [False, True])
def test_obj_texture_coordinates_are_kept_with_v_flipped(tmp_path, normals):
    mesh = load_mesh(quad_obj(tmp_path, normals))
    by_position = {tuple(p): tuple(uv) for p, uv in zip(mesh.positions.tolist(), mesh.uvs.tolist())}
    # OBJ's (0, 0) is the image's bottom-left; ours is its top-left
    assert by_position == {(0, 0, 0): (0, 1), (1, 0, 0): (1, 1), (1, 1, 0): (1, 0), (0, 1, 0): (0, 0)}
    np.testing.assert_allclose(mesh.tangents, [[1, 0, 0, 1]] * 4, atol=1e-6)


def test_uv_seams_keep_their_vertices_apart_but_share_one_smooth_normal(tmp_path):
    # a cylinder without normals whose seam column has two UVs: split vertices, one normal each
    source = cylinder_mesh(12, caps=False)
    mesh_tm = trimesh.Trimesh(source.positions, source.indices.reshape(-1, 3), process=False)
    uv = source.uvs.astype(np.float64).copy()
    uv[:, 1] = 1 - uv[:, 1]
    mesh_tm.visual = trimesh.visual.TextureVisuals(uv=uv)
    path = tmp_path / "cyl.obj"
    path.write_text(mesh_tm.export(file_type="obj", include_normals=False))
    mesh = load_mesh(path)
    assert mesh.vertex_count == source.vertex_count  # the seam's 2 x 2 vertices stay split
    np.testing.assert_allclose(mesh.normals[:, 1], 0, atol=1e-6)  # smooth: horizontal
    assert ((mesh.normals * mesh.positions).sum(1) > 0.45).all()  # and outward, near radial
    _, groups = np.unique(mesh.positions, axis=0, return_inverse=True)
    groups = groups.reshape(-1)
    seam = [g for g in range(groups.max() + 1) if (groups == g).sum() == 2]
    assert len(seam) == 2  # the seam's two positions each hold two vertices (u = 0 and u = 1)
    for g in seam:
        a, b = np.flatnonzero(groups == g)
        assert mesh.uvs[a, 0] != mesh.uvs[b, 0]
        np.testing.assert_array_equal(mesh.normals[a], mesh.normals[b])


def test_gltf_texture_coordinates_round_trip(tmp_path):
    source = torus_mesh(12, 6)
    tm = trimesh.Trimesh(source.positions, source.indices.reshape(-1, 3), vertex_normals=source.normals, process=False)
    uv = source.uvs.astype(np.float64).copy()
    uv[:, 1] = 1 - uv[:, 1]  # trimesh keeps OBJ's bottom-left origin and flips for glTF itself
    tm.visual = trimesh.visual.TextureVisuals(uv=uv)
    path = tmp_path / "torus.glb"
    path.write_bytes(trimesh.Scene(tm).export(file_type="glb"))
    mesh = load_mesh(path)
    np.testing.assert_allclose(mesh.uvs, source.uvs, atol=1e-6)
    np.testing.assert_allclose(mesh.tangents, source.tangents, atol=1e-4)


def test_nan_texture_coordinate_is_one_line_usage_error(tmp_path):
    path = tmp_path / "bad.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt nan 0\nvt 0 1\nf 1/1 2/2 3/3\n")
    with pytest.raises(UsageError, match="1 vertex has NaN or infinite texture coordinates"):
        load_mesh(path)


BAD_ARGUMENTS = [
    # issue 34: these raised ZeroDivisionError out of load_world ("internal error", exit 1)
    ("cylinder", {"radius": 0}, "cylinder: radius"),
    ("cone", {"radius": 0}, "cone: radius"),
    ("cone", {"height": 0}, "cone: height"),
    ("cylinder", {"height": -1.0}, "cylinder: height"),
    ("sphere", {"radius": float("nan")}, "sphere: radius"),
    ("sphere", {"radius": 1e300}, "sphere: radius"),
    ("plane", {"size": float("inf")}, "plane: size"),
    ("torus", {"minor": 0.0}, "torus: minor"),
    ("torus", {"major": -0.35}, "torus: major"),
    ("torus", {"major": 0.1, "minor": 0.2}, "torus: the tube radius"),
    ("cylinder", {"radius": "0.5"}, "cylinder: radius must be a number"),
    ("cone", {"height": True}, "cone: height must be a number"),
    ("cylinder", {"caps": 3}, "cylinder: caps must be true or false"),
    ("sphere", {"segments": 2}, "sphere: segments"),
    ("sphere", {"rings": 8.0}, "sphere: rings"),
    ("cone", {"rings": 0}, "cone: rings"),
    ("torus", {"sides": "12"}, "torus: sides"),
    ("plane", {"subdivisions": None}, "plane: subdivisions"),
    ("cylinder", {"segments": False}, "cylinder: segments"),
]


@pytest.mark.parametrize(("name", "args", "message"), BAD_ARGUMENTS)
def test_every_recipe_argument_is_checked(name, args, message):
    """Zero, negative, NaN, huge and wrongly typed arguments: one ValueError naming the shape and
    the argument, never a ZeroDivisionError or a mesh of NaN."""
    with pytest.raises(ValueError, match=f"^{message}"):
        PRIMITIVES[name](**args)


@pytest.mark.parametrize(
    ("name", "args"),
    [
        ("cube", {}),
        ("sphere", {"segments": 7, "rings": 3}),
        ("plane", {"subdivisions": 5}),
        ("cylinder", {"segments": 9}),
        ("cylinder", {"segments": 9, "caps": False}),
        ("cone", {"segments": 5, "rings": 4}),
        ("torus", {"segments": 6, "sides": 4}),
        *((name, {}) for name in PRIMITIVES),
    ],
)
def test_vertex_counts_are_known_before_making(name, args):
    assert primitive_vertices(name, args) == PRIMITIVES[name](**args).vertex_count


def test_vertex_count_of_an_unknown_shape_or_argument_is_refused():
    assert primitive_vertices("sphere", {"segments": 1024, "rings": 1024}) == 1025 * 1025
    with pytest.raises(ValueError, match="unknown primitive 'teapot'"):
        primitive_vertices("teapot", {})
    with pytest.raises(ValueError, match="sphere: unknown argument 'segs'"):
        primitive_vertices("sphere", {"segs": 8})
    with pytest.raises(ValueError, match="sphere: segments must be an integer"):
        primitive_vertices("sphere", {"segments": 1e9})
