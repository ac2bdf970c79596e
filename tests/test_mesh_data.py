"""Mesh data: the cube's winding and normals, bounding spheres, normalising, loading every supported
format, one-line UsageErrors for every kind of bad file, and the shipped default model."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from ecs_engine.errors import UsageError
from ecs_engine.render.assets.mesh_data import MeshData, bounding_sphere, normalized
from ecs_engine.render.assets.mesh_loading import DEFAULT_MODEL, load_mesh
from ecs_engine.render.assets.primitives import cube_mesh

REPO = Path(__file__).resolve().parents[1]


def face_normals(mesh: MeshData) -> np.ndarray:
    """Unit normals from the winding: (v1 - v0) x (v2 - v0)."""
    p = mesh.positions.astype(np.float64)[mesh.indices.reshape(-1, 3)]
    cross = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    return cross / np.linalg.norm(cross, axis=1, keepdims=True)


def assert_well_formed(mesh: MeshData) -> None:
    assert mesh.positions.dtype == np.float32 and mesh.positions.ndim == 2 and mesh.positions.shape[1] == 3
    assert mesh.normals.dtype == np.float32 and mesh.normals.shape == mesh.positions.shape
    assert mesh.indices.dtype == np.uint32 and mesh.indices.ndim == 1 and mesh.indices.size % 3 == 0
    assert mesh.indices.max() < len(mesh.positions)
    for a in (mesh.positions, mesh.normals, mesh.indices, mesh.center):
        assert a.flags.c_contiguous and not a.flags.writeable
    np.testing.assert_allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, atol=1e-5)
    distance = np.linalg.norm(mesh.positions.astype(np.float64) - mesh.center.astype(np.float64), axis=1)
    assert distance.max() <= mesh.radius


def bounds(mesh: MeshData) -> np.ndarray:
    return np.stack([mesh.positions.min(0), mesh.positions.max(0)])


# ------------------------------------------------------------------------------------------------ cube


def test_cube_layout_and_bounds():
    cube = cube_mesh()
    assert_well_formed(cube)
    assert (cube.vertex_count, cube.indices.size, cube.triangle_count, cube.name) == (24, 36, 12, "cube")
    np.testing.assert_array_equal(bounds(cube), [[-0.5] * 3, [0.5] * 3])
    np.testing.assert_array_equal(cube.center, 0)
    assert cube.radius == pytest.approx(np.sqrt(3) / 2, rel=1e-5)


def test_cube_winding_is_ccw_from_outside_and_normals_are_flat_and_outward():
    cube = cube_mesh()
    tris = cube.indices.reshape(-1, 3)
    winding = face_normals(cube)
    for tri, n in zip(tris, winding):
        np.testing.assert_allclose(cube.normals[tri], np.broadcast_to(n, (3, 3)), atol=1e-6)  # flat, from winding
        centre = cube.positions[tri].mean(0)
        assert n @ centre > 0  # outward
        assert np.count_nonzero(np.abs(n) > 0.5) == 1  # axis-aligned
    # each of the six faces owns four vertices that all lie on that face's plane
    for face in range(6):
        verts = cube.positions[face * 4 : face * 4 + 4]
        n = cube.normals[face * 4]
        np.testing.assert_allclose(verts @ n, 0.5)
    assert sorted(map(tuple, np.unique(cube.normals, axis=0).tolist())) == sorted(
        map(tuple, np.concatenate([np.eye(3), -np.eye(3)]).tolist())
    )


def test_mesh_data_is_read_only_and_copies_its_input():
    positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32)
    mesh = MeshData.from_arrays(positions, [[0, 0, 1]] * 3, [0, 1, 2], "tri")
    positions[0, 0] = 99.0
    assert mesh.positions[0, 0] == 0.0
    with pytest.raises(ValueError):
        mesh.positions[0, 0] = 5.0
    with pytest.raises(AttributeError):
        mesh.name = "other"  # type: ignore[misc]


@pytest.mark.parametrize(
    "positions, normals, indices",
    [
        ([[0, 0, 0], [1, 0, 0]], [[0, 0, 1]] * 2, [0, 1]),  # not a multiple of 3
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 0, 1]] * 3, [0, 1, 3]),  # index out of range
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 0, 2]] * 3, [0, 1, 2]),  # not unit
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 0, 1]] * 2, [0, 1, 2]),  # shape mismatch
        ([[0, 0, 0], [1, 0, 0], [0, np.nan, 0]], [[0, 0, 1]] * 3, [0, 1, 2]),
    ],
)
def test_mesh_data_rejects_inconsistent_arrays(positions, normals, indices):
    with pytest.raises(ValueError):
        MeshData.from_arrays(np.array(positions, float), normals, indices, "bad")


# -------------------------------------------------------------------------------- sphere and normalise


@settings(max_examples=60, deadline=None)
@given(arrays(np.float32, st.tuples(st.integers(1, 40), st.just(3)), elements=st.floats(-1e4, 1e4, width=32)))
def test_bounding_sphere_encloses_every_point(points):
    center, radius = bounding_sphere(points)
    assert center.dtype == np.float32 and center.shape == (3,)
    assert np.linalg.norm(points.astype(np.float64) - center, axis=1).max() <= radius
    # and is no worse than the box-centre sphere
    box = (points.min(0).astype(np.float64) + points.max(0)) / 2
    assert radius <= np.linalg.norm(points - box, axis=1).max() * (1 + 1e-5) + 1e-3


def test_normalized_centres_and_scales_to_size():
    rng = np.random.default_rng(3)
    mesh = MeshData.from_arrays(
        rng.normal(size=(30, 3)) * [3, 1, 0.5] + [10, -4, 2],
        np.tile([0.0, 0.0, 1.0], (30, 1)),
        rng.integers(0, 30, size=60),
        "blob",
    )
    for size in (1.0, 2.5):
        out = normalized(mesh, size)
        assert_well_formed(out)
        lo, hi = bounds(out).astype(np.float64)
        assert (hi - lo).max() == pytest.approx(size, rel=1e-6)
        np.testing.assert_allclose((lo + hi) / 2, 0, atol=1e-6)
        np.testing.assert_array_equal(out.normals, mesh.normals)
        np.testing.assert_array_equal(out.indices, mesh.indices)
    with pytest.raises(ValueError):
        normalized(mesh, 0.0)


# ----------------------------------------------------------------------------------------- good files


def sample_mesh() -> trimesh.Trimesh:
    """A 1 x 2 x 3 box off the origin: 12 triangles, known bounds."""
    box = trimesh.creation.box(extents=(1.0, 2.0, 3.0))
    box.apply_translation([1.0, -2.0, 0.5])
    return box


EXPECTED_BOUNDS = [[0.5, -3.0, -1.0], [1.5, -1.0, 2.0]]


def write(path: Path, data: str | bytes) -> Path:
    if isinstance(data, str):
        path.write_text(data)
    else:
        path.write_bytes(data)
    return path


@pytest.mark.parametrize("ext", ["obj", "ply", "stl", "glb", "gltf"])
def test_each_format_round_trips(tmp_path, ext):
    box = sample_mesh()
    if ext == "gltf":
        data = trimesh.exchange.gltf.export_gltf(trimesh.Scene(box), embed_buffers=True)["model.gltf"]
    else:
        data = box.export(file_type=ext)
    mesh = load_mesh(write(tmp_path / f"box.{ext}", data))
    assert_well_formed(mesh)
    assert mesh.triangle_count == 12 and mesh.name == "box"
    np.testing.assert_allclose(bounds(mesh), EXPECTED_BOUNDS, atol=1e-6)
    # a closed box wound counter-clockwise: every face normal points away from the centre
    tris = mesh.positions[mesh.indices.reshape(-1, 3)].mean(1) - np.array([1.0, -2.0, 0.5])
    assert (np.einsum("ij,ij->i", face_normals(mesh), tris) > 0).all()


def test_files_without_normals_get_smooth_ones(tmp_path):
    # STL stores 3 separate vertices per triangle; welding gives the 8 corners, normals along the diagonals.
    mesh = load_mesh(write(tmp_path / "box.stl", sample_mesh().export(file_type="stl")))
    assert mesh.vertex_count == 8
    corners = mesh.positions - np.array([1.0, -2.0, 0.5], np.float32)
    assert (np.sign(mesh.normals) == np.sign(corners)).all()


def test_normals_in_the_file_are_kept(tmp_path):
    text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0.6 0.8\nf 1//1 2//1 3//1\n"
    mesh = load_mesh(write(tmp_path / "tilted.obj", text))
    np.testing.assert_allclose(mesh.normals, [[0, 0.6, 0.8]] * 3, atol=1e-6)


def test_polygons_are_triangulated(tmp_path):
    text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv -1 0.5 0\nf 1 2 3 4\nf 1 4 5\n"
    mesh = load_mesh(write(tmp_path / "quad.obj", text))
    assert mesh.triangle_count == 3
    np.testing.assert_allclose(face_normals(mesh), [[0, 0, 1]] * 3, atol=1e-6)
    # negative (relative) indices are valid OBJ
    mesh = load_mesh(write(tmp_path / "relative.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n"))
    assert mesh.triangle_count == 1


def test_scene_nodes_are_baked_with_their_transforms(tmp_path):
    box = sample_mesh()
    scene = trimesh.Scene()
    scene.add_geometry(box, node_name="moved", transform=trimesh.transformations.translation_matrix([10, 0, 0]))
    scene.add_geometry(box, node_name="mirrored", transform=np.diag([-1.0, 1.0, 1.0, 1.0]))
    mesh = load_mesh(write(tmp_path / "scene.glb", scene.export(file_type="glb")))
    assert mesh.triangle_count == 24
    np.testing.assert_allclose(bounds(mesh), [[-1.5, -3.0, -1.0], [11.5, -1.0, 2.0]], atol=1e-6)
    # the mirrored copy keeps counter-clockwise outward winding: check each copy against its own centre
    tris = mesh.positions[mesh.indices.reshape(-1, 3)].mean(1)
    centre = np.where(tris[:, :1] > 5, [11.0, -2.0, 0.5], [-1.0, -2.0, 0.5])
    assert (np.einsum("ij,ij->i", face_normals(mesh), tris - centre) > 0).all()


def test_degenerate_triangles_are_dropped_when_others_remain(tmp_path):
    text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\n"
    mesh = load_mesh(write(tmp_path / "some_degenerate.obj", text))
    assert mesh.triangle_count == 1 and mesh.vertex_count == 3


def test_max_triangles(tmp_path):
    path = write(tmp_path / "box.stl", sample_mesh().export(file_type="stl"))
    assert load_mesh(path, max_triangles=12).triangle_count == 12
    with pytest.raises(UsageError, match=r"box\.stl: has 12 triangles, more than the limit of 11"):
        load_mesh(path, max_triangles=11)


# ------------------------------------------------------------------------------------------ bad files

TRIANGLE = "v 0 0 0\nv 1 0 0\nv 0 1 0\n"
NOISE = np.random.default_rng(7).integers(0, 256, size=3000, dtype=np.uint8).tobytes()
ASCII_PLY_BAD_INDEX = (
    "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
    "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
    "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n"
)

BAD_FILES = [
    ("noise.obj", NOISE, "binary data, not a text OBJ"),
    ("noise.stl", NOISE, "not a valid STL file"),
    ("noise.glb", NOISE, "not a valid GLB file"),
    ("noise.ply", NOISE, "not a valid PLY file"),
    ("noise.gltf", NOISE, "not a valid glTF file"),
    ("prose.obj", "this is not a mesh\njust some words\n", "contains no vertices or faces"),
    ("prose.stl", "this is not a mesh\njust some words\n", "not a valid STL file"),
    ("prose.glb", "this is not a mesh\njust some words\n", "not a valid GLB file"),
    ("prose.gltf", "this is not a mesh\njust some words\n", "not a valid glTF file"),
    ("fake_solid.stl", "solid nothing\nendsolid nothing\n", "contains no triangles"),
    ("empty.obj", "", "the file is empty"),
    ("empty.stl", b"", "the file is empty"),
    ("comments.obj", "# nothing here\n", "contains no vertices or faces"),
    ("points.obj", TRIANGLE, "has no triangles (only points/lines)"),
    ("lines.obj", TRIANGLE + "l 1 2\nl 2 3\n", "has no triangles (only points/lines)"),
    ("nan.obj", "v 0 0 nan\nv 1 0 0\nv 0 1 inf\nf 1 2 3\n", "2 vertices have NaN or infinite coordinates"),
    ("inf.obj", "v 0 0 0\nv 1 -inf 0\nv 0 1 0\nf 1 2 3\n", "1 vertex has NaN or infinite coordinates"),
    (
        "huge.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1e39 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n",
        "vertex 3 has the coordinate 1e+39, outside float32's range (-3.4e+38 to 3.4e+38)",
    ),
    (
        "past_end.obj",
        TRIANGLE + "f 1 2 3\nf 1 2 7\n",
        "face 2 (line 5) refers to vertex 7 but the file has only 3 vertices",
    ),
    ("zero_index.obj", TRIANGLE + "f 0 1 2\n", "refers to vertex 0, but OBJ vertex numbers start at 1"),
    ("too_negative.obj", TRIANGLE + "f -1 -2 -4\n", "refers to vertex -4 (counted back), but only 3 vertices"),
    ("short_face.obj", TRIANGLE + "f 1 2\n", "face 1 (line 4) has 2 vertices"),
    ("garbled_face.obj", TRIANGLE + "f 1 2 x\n", "unreadable vertex reference 'x'"),
    ("bad_index.ply", ASCII_PLY_BAD_INDEX, "face 1 refers to vertex 7 but the file has only 3 vertices"),
    (
        "flat.obj",
        "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\nf 1 2 3\nf 2 3 4\nf 1 1 2\n",
        "all 3 triangles are degenerate (zero area)",
    ),
    ("mesh.fbx", TRIANGLE, "unsupported mesh format '.fbx'; supported: .obj, .gltf, .glb, .ply, .stl"),
    ("mesh", TRIANGLE, "unsupported mesh file type (no extension)"),
]


@pytest.mark.parametrize("name, data, message", BAD_FILES, ids=[b[0] for b in BAD_FILES])
def test_bad_files_raise_one_line_usage_errors(tmp_path, name, data, message):
    path = write(tmp_path / name, data)
    with pytest.raises(UsageError) as info:
        load_mesh(path)
    text = str(info.value)
    assert "\n" not in text
    assert text.startswith(f"{path}: ")
    assert message in text


def test_missing_file_and_directory(tmp_path):
    with pytest.raises(UsageError, match=r"nope\.obj: no such file"):
        load_mesh(tmp_path / "nope.obj")
    (tmp_path / "folder.obj").mkdir()
    with pytest.raises(UsageError, match=r"folder\.obj: is a directory"):
        load_mesh(tmp_path / "folder.obj")


def test_unreadable_file(tmp_path, monkeypatch):
    path = write(tmp_path / "locked.obj", TRIANGLE + "f 1 2 3\n")

    def denied(path, *args, **kwargs):
        raise PermissionError(13, "Permission denied", str(path))

    # chmod does not stop root, who may run the tests
    monkeypatch.setattr("ecs_engine.render.assets.mesh_loading.read_user_file", denied)
    with pytest.raises(UsageError, match=r"locked\.obj: cannot read the file: Permission denied$"):
        load_mesh(path)


def test_gltf_with_separate_buffers_and_with_them_missing(tmp_path):
    files = trimesh.exchange.gltf.export_gltf(trimesh.Scene(sample_mesh()))  # model.gltf + .bin files
    for name, data in files.items():
        write(tmp_path / name, data)
    mesh = load_mesh(tmp_path / "model.gltf")
    np.testing.assert_allclose(bounds(mesh), EXPECTED_BOUNDS, atol=1e-6)
    for name in files:
        if name.endswith(".bin"):
            (tmp_path / name).unlink()
    with pytest.raises(UsageError, match=r"model\.gltf: refers to a file that is missing: gltf_buffer_\d\.bin$"):
        load_mesh(tmp_path / "model.gltf")


# ------------------------------------------------------------------------------------- default model


def test_default_model_loads_and_normals_agree_with_winding():
    assert DEFAULT_MODEL.is_file() and DEFAULT_MODEL.suffix == ".obj"
    assert DEFAULT_MODEL.stat().st_size < 1.5e6
    mesh = load_mesh(DEFAULT_MODEL)
    assert_well_formed(mesh)
    assert mesh.triangle_count > 5000 and mesh.name == "torus_knot"
    lo, hi = bounds(mesh).astype(np.float64)
    assert (hi - lo).max() == pytest.approx(2.0, abs=1e-5)
    np.testing.assert_allclose((lo + hi) / 2, 0, atol=1e-5)
    vertex_normals = mesh.normals[mesh.indices.reshape(-1, 3)].mean(1)
    vertex_normals /= np.linalg.norm(vertex_normals, axis=1, keepdims=True)
    agreement = np.einsum("ij,ij->i", face_normals(mesh), vertex_normals)
    assert agreement.mean() > 0.9 and agreement.min() > 0.5


def test_default_model_matches_its_generator(tmp_path):
    spec = importlib.util.spec_from_file_location("make_torus_knot", REPO / "demos" / "assets" / "make_torus_knot.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    out = module.main(tmp_path / "torus_knot.obj")
    assert out.read_bytes() == (REPO / "demos" / "assets" / "torus_knot.obj").read_bytes()
