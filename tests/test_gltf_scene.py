"""glTF files as entities (render/assets/gltf): accessors decoded as the specification says
(strides, normalized integers, sparse substitutions, column-major matrices), the same from a
.gltf with its buffer embedded or beside it and from a .glb; a scene's node tree spawned as
entities whose world matrices are the NumPy product of the nodes' TRS, any number of times;
meshes per primitive with their materials, cameras and lights; broken files one GltfError
naming the file and the field."""

from __future__ import annotations

import math

import numpy as np
import pytest
from gltf_files import GltfBuilder

from ecs_engine import World
from ecs_engine.components import Camera, Mesh, Name, PointLight, SpotLight, Transform
from ecs_engine.components.hierarchy import Parent, WorldMatrix
from ecs_engine.maths.decompose import trs_matrices
from ecs_engine.render.assets.gltf import GltfDocument, GltfError
from ecs_engine.render.assets.gltf.scene import load_gltf
from ecs_engine.render.assets.materials import Materials
from ecs_engine.systems import HierarchySystem, TransformSystem

UBYTE, USHORT, BYTE, SHORT, UINT = 5121, 5123, 5120, 5122, 5125


def quat(axis, angle):
    axis = np.asarray(axis, np.float64) / np.linalg.norm(axis)
    return np.array([*(axis * math.sin(angle / 2)), math.cos(angle / 2)])


def forms(builder, tmp_path):
    """The builder's file as .gltf (embedded), .gltf with a .bin and .glb."""
    return [
        builder.gltf(tmp_path / "embedded.gltf", embed=True),
        builder.gltf(tmp_path / "outside.gltf", embed=False),
        builder.glb(tmp_path / "binary.glb"),
    ]


def test_accessors_decode_strides_normalized_integers_sparse_and_matrices_in_every_form(tmp_path):
    rng = np.random.default_rng(4)
    b = GltfBuilder()
    points = rng.normal(size=(7, 3)).astype(np.float32)
    unit = rng.uniform(0, 1, (5, 2))
    signed = rng.uniform(-1, 1, (5, 4))
    matrices = rng.normal(size=(3, 4, 4)).astype(np.float32)
    small = rng.uniform(-1, 1, (3, 2, 2))
    made = {
        "strided": b.accessor(points, stride=20),
        "u16": b.accessor(unit, USHORT, normalized=True),
        "u8": b.accessor(unit, UBYTE, normalized=True),
        "i8": b.accessor(signed, BYTE, normalized=True),
        "i16": b.accessor(signed, SHORT, normalized=True),
        "mat4": b.accessor(matrices),
        "mat2_i8": b.accessor(small, BYTE, normalized=True),
        "sparse": b.accessor(points, sparse={"indices": np.array([1, 4]), "values": np.ones((2, 3), np.float32)}),
        "sparse_zeros": b.accessor(
            None,
            5126,
            type="VEC3",
            count=6,
            sparse={"indices": np.array([0, 5], np.uint16), "values": points[:2], "index_component_type": USHORT},
        ),
        "indices_u8": b.accessor(np.array([0, 2, 1, 3], np.uint8), UBYTE),
    }
    expected_sparse = points.copy()
    expected_sparse[[1, 4]] = 1.0
    zeros = np.zeros((6, 3), np.float32)
    zeros[[0, 5]] = points[:2]
    for path in forms(b, tmp_path):
        d = GltfDocument.read(path)
        a = {name: d.accessor(i, name) for name, i in made.items()}
        np.testing.assert_array_equal(a["strided"], points)
        np.testing.assert_allclose(a["u16"], unit, atol=0.5 / 65535)
        np.testing.assert_allclose(a["u8"], unit, atol=0.5 / 255 + 1e-7)
        np.testing.assert_allclose(a["i8"], signed, atol=0.5 / 127 + 1e-7)
        np.testing.assert_allclose(a["i16"], signed, atol=0.5 / 32767 + 1e-7)
        assert a["u16"].dtype == np.float32 and a["indices_u8"].dtype == np.uint8
        np.testing.assert_array_equal(a["mat4"], matrices)  # row-major again, though stored by columns
        np.testing.assert_allclose(a["mat2_i8"], small, atol=0.5 / 127 + 1e-7)  # columns padded to 4 bytes
        np.testing.assert_array_equal(a["sparse"], expected_sparse)
        np.testing.assert_array_equal(a["sparse_zeros"], zeros)
        np.testing.assert_array_equal(a["indices_u8"], [0, 2, 1, 3])


def tree_file(tmp_path, form="gltf"):
    """A hierarchy three deep with rotations and non-uniform scale (a node given as a matrix),
    a mesh of two primitives with materials, one without normals, a camera and two lights."""
    b = GltfBuilder()
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], np.float32)
    red = b.material("red", base_color=(1.0, 0.0, 0.0, 1.0), metallic=0.2, roughness=0.7)
    blue = b.material("blue", base_color=(0.0, 0.0, 1.0, 0.5), alpha_mode="BLEND", double_sided=True)
    mesh = b.mesh(
        [
            b.primitive(square, np.array([0, 1, 2, 0, 2, 3]), normals=np.tile([0, 0, 1.0], (4, 1)), material=red),
            b.primitive(square + (0, 0, 1), np.array([0, 1, 2]), material=blue),  # flat normals made
        ],
        name="squares",
    )
    cam = b.camera_perspective(0.8, 0.05, 200.0, aspect=1.5)
    lamp = b.light("spot", color=(1.0, 0.5, 0.25), intensity=30.0, range=12.0, inner=0.2, outer=0.6)
    bulb = b.light("point", intensity=5.0)
    skew = trs_matrices(np.array([[0.5, -1.0, 2.0]]), quat((0, 1, 0), 0.9)[None], np.array([[1.0, 1.5, 0.5]]))[0]
    leaf = b.node("leaf", translation=(0.0, 2.0, 0.0), rotation=quat((1, 1, 0), 0.4), scale=(0.5, 2.0, 1.0), mesh=mesh)
    lit = b.node("lit", matrix=skew, light=lamp, children=[leaf])
    top = b.node("top", translation=(1.0, 0.0, -3.0), rotation=quat((0, 0, 1), 1.1), scale=(2.0, 1.0, 3.0),
                 children=[lit])  # fmt: skip
    eye = b.node("eye", translation=(0.0, 1.0, 5.0), camera=cam)
    glow = b.node("glow", translation=(0.0, 3.0, 0.0), light=bulb)
    b.scene([top, eye, glow])
    path = b.glb(tmp_path / "tree.glb") if form == "glb" else b.gltf(tmp_path / "tree.gltf")
    locals_ = {
        "top": trs_matrices(np.array([[1.0, 0, -3]]), quat((0, 0, 1), 1.1)[None], np.array([[2.0, 1, 3]]))[0],
        "lit": skew,
        "leaf": trs_matrices(np.array([[0.0, 2, 0]]), quat((1, 1, 0), 0.4)[None], np.array([[0.5, 2, 1]]))[0],
    }
    return path, locals_


def spawned(path, copies=1, at=None):
    world, meshes, registry = World(), [], Materials()

    def add(mesh):
        meshes.append(mesh)
        return len(meshes) - 1

    scene = load_gltf(path, add, registry)
    if copies == 1:
        roots = np.array([scene.spawn(world, at)])
    else:
        roots = scene.spawn_many(world, copies, np.arange(copies * 3, dtype=np.float64).reshape(copies, 3))
    TransformSystem().run(world, 0.0)
    HierarchySystem().run(world, 0.0)
    return world, scene, roots, meshes, registry


def by_name(world, name):
    return [int(e) for e in world.query(Name).entities() if world.get(int(e), Name).value == name]


@pytest.mark.parametrize("form", ["gltf", "glb"])
def test_a_node_tree_spawns_as_entities_whose_world_matrices_are_the_product_of_the_nodes(tmp_path, form):
    path, local = tree_file(tmp_path, form)
    at = Transform(position=(10.0, 0.0, 0.0), rotation=quat((0, 1, 0), 0.3), scale=(2.0, 2.0, 2.0))
    world, _, _, meshes, registry = spawned(path, at=at)
    root = trs_matrices(*(np.asarray(v, np.float64)[None] for v in (at.position, at.rotation, at.scale)))[0]
    expected = {"top": root @ local["top"]}
    expected["lit"] = expected["top"] @ local["lit"]
    expected["leaf"] = expected["lit"] @ local["leaf"]
    for name, matrix in expected.items():
        (e,) = by_name(world, name)
        np.testing.assert_allclose(world.get(e, WorldMatrix).matrix, matrix, atol=1e-9)
    (leaf,) = by_name(world, "leaf")
    parts = [int(e) for e in world.query(Mesh, Parent).entities() if world.get(int(e), Parent).entity == leaf]
    assert len(parts) == 2  # one entity a primitive, children of the node
    red, blue = (registry[int(world.get(e, Mesh).material)] for e in parts)
    assert red.base_color == (1.0, 0.0, 0.0, 1.0) and red.metallic == pytest.approx(0.2)
    assert red.roughness == pytest.approx(0.7)
    assert blue.alpha_mode == "blend" and blue.double_sided and blue.base_color[3] == 0.5
    flat = meshes[world.get(parts[1], Mesh).handle]
    np.testing.assert_allclose(flat.normals, np.tile([0.0, 0.0, 1.0], (3, 1)), atol=1e-6)
    (eye,) = by_name(world, "eye")
    camera = world.get(eye, Camera)
    assert camera.fov_y == pytest.approx(0.8) and camera.near == pytest.approx(0.05) and camera.far == 200.0
    assert camera.aspect == pytest.approx(1.5)
    (lit,) = by_name(world, "lit")
    spot = world.get(lit, SpotLight)
    assert spot.inner_angle == pytest.approx(0.2) and spot.outer_angle == pytest.approx(0.6)
    assert spot.radius == pytest.approx(12.0) and spot.intensity == pytest.approx(30.0)
    assert world.has(by_name(world, "glow")[0], PointLight)


def test_a_scene_spawns_many_times_sharing_its_meshes(tmp_path):
    path, local = tree_file(tmp_path)
    world, _, roots, meshes, _ = spawned(path, copies=4)
    assert len(roots) == 4 and len(meshes) == 2  # uploaded once
    leaves = by_name(world, "leaf")
    assert len(leaves) == 4
    tops = sorted(by_name(world, "top"), key=lambda e: world.get(e, WorldMatrix).matrix[0, 3])
    for k, e in enumerate(tops):
        root = trs_matrices(np.array([[3.0 * k, 3 * k + 1, 3 * k + 2]]), np.array([[0, 0, 0, 1.0]]), np.ones((1, 3)))
        np.testing.assert_allclose(world.get(e, WorldMatrix).matrix, root[0] @ local["top"], atol=1e-9)


def broken(tmp_path, edit, form="gltf"):
    path, _ = tree_file(tmp_path, form)
    if edit is not None:
        import json

        document = json.loads(path.read_text())
        edit(document)
        path.write_text(json.dumps(document))
    return path


@pytest.mark.parametrize(
    ("edit", "field"),
    [
        (lambda d: d["accessors"][1].update(count=99), "accessors[1]"),
        (lambda d: d["accessors"][1].update(bufferView=77), "accessors[1].bufferView"),
        (lambda d: d["accessors"][1].update(componentType=5130), "accessors[1].componentType"),
        (lambda d: d["meshes"][0]["primitives"][0].update(material=9), "meshes[0].primitives[0].material"),
        (lambda d: d["nodes"][0].update(rotation=[0, 0, 2, 0]), ".rotation"),
        (lambda d: d["nodes"][0].update(children=[0]), "children"),
        (lambda d: d["nodes"][1].update(matrix=[1, 0.5, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]), ".matrix"),
        (lambda d: d["buffers"][0].update(byteLength=10**7), "buffers[0].byteLength"),
        (lambda d: d["asset"].update(version="1.0"), "asset.version"),
    ],
)
def test_a_broken_file_is_one_error_naming_the_file_and_the_field(tmp_path, edit, field):
    path = broken(tmp_path, edit)
    with pytest.raises(GltfError) as caught:
        spawned(path)
    assert str(path) in str(caught.value) and field in str(caught.value), str(caught.value)


def test_an_index_past_the_vertices_or_a_missing_bin_is_one_error(tmp_path):
    b = GltfBuilder()
    square = np.zeros((4, 3), np.float32)
    b.node("bad", mesh=b.mesh([b.primitive(square, np.array([0, 1, 7]))]))
    b.scene([0])
    with pytest.raises(GltfError, match=r"indices: index 7 is past the primitive's 4 vertices"):
        spawned(b.gltf(tmp_path / "bad.gltf"))
    outside = b.gltf(tmp_path / "out.gltf", embed=False)
    for bin_file in tmp_path.glob("out*.bin"):
        bin_file.unlink()
    with pytest.raises(GltfError, match=r"buffers\[0\]\.uri: .* cannot be read"):
        spawned(outside)
