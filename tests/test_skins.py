"""Skins (ecs_engine/animation/skins.py, render/assets/gltf/skins.py): a glTF skin's joints spawn
as entities and its meshes carry Skinned; each frame SkinSystem makes every copy's joint
matrices from the joints' world matrices, and the vertices they give match the specification's
formula computed here on its own (joint globals composed from the nodes' TRS, vertex by vertex),
with eight influences per vertex, weights the file did not normalise and non-uniform scale. The
rest pose is the bind pose, the pose's sphere holds every vertex, and a broken skin is one error
naming the file and the field."""

from __future__ import annotations

import json

import numpy as np
import pytest
from gltf_files import ARRAY_BUFFER, UNSIGNED_BYTE, UNSIGNED_SHORT, GltfBuilder
from skinned_files import ORDER, globals_of

from ecs_engine import World
from ecs_engine.animation.skins import Skins, SkinSystem, skinned_positions
from ecs_engine.components import Mesh, ModelMatrix, Name, Transform, render_origin
from ecs_engine.components.animation import Skinned
from ecs_engine.render.assets.gltf import GltfError
from ecs_engine.render.assets.gltf.scene import load_gltf
from ecs_engine.render.assets.materials import Materials
from ecs_engine.render.assets.skin_weights import SkinWeights
from ecs_engine.systems import HierarchySystem, TransformSystem

# the bind pose: hips at the origin, spine 1 up (scaled unevenly), head 1 above the spine
BIND = {
    "hips": ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0), (1.0, 1.0, 1.0)),
    "spine": ((0.0, 1.0, 0.0), (0.0, 0.0, np.sin(0.2), np.cos(0.2)), (1.0, 1.5, 0.8)),
    "head": ((0.0, 1.0, 0.0), (np.sin(0.1), 0.0, 0.0, np.cos(0.1)), (1.0, 1.0, 1.0)),
}
# (ORDER: the skin's joints, in this order; globals_of composes the joints' global matrices from
# the nodes' TRS, not by the engine: tests/skinned_files.py)


def body(n=24, seed=3):
    """A strip of `n` vertices up the skeleton, each moved by up to 8 influences (the weights
    as the file stores them: not summing to 1, some zero)."""
    rng = np.random.default_rng(seed)
    y = np.linspace(-0.2, 2.4, n)
    positions = np.c_[rng.uniform(-0.3, 0.3, n), y, rng.uniform(-0.3, 0.3, n)].astype(np.float32)
    joints = rng.integers(0, 3, (n, 8)).astype(np.uint16)
    weights = rng.uniform(0.0, 2.0, (n, 8)).astype(np.float32)
    weights[rng.random((n, 8)) < 0.3] = 0.0
    weights[:, 0] += 0.05  # none sums to 0
    weights[0] = (1, 0, 0, 0, 0, 0, 0, 0)  # one vertex wholly on the hips
    indices = np.array([[i, i + 1, i + 2] for i in range(n - 2)]).reshape(-1)
    return positions, indices, joints, weights


def skinned_file(tmp_path, edit=None, weights_as=None, poison=None):
    b = GltfBuilder()
    positions, indices, joints, weights = body()
    if poison is not None:  # one weight of WEIGHTS_1 that no file may hold
        weights = weights.copy()
        weights[5, 6] = poison
    if weights_as == "bytes":  # WEIGHTS_0 as normalized unsigned bytes
        top = weights[:, :4] / weights[:, :4].sum(1, keepdims=True).clip(1e-9)
        weights_0 = b.accessor(top, UNSIGNED_BYTE, normalized=True, target=ARRAY_BUFFER)
    else:
        weights_0 = weights[:, :4]
    joints_1 = b.accessor(joints[:, 4:], UNSIGNED_SHORT, target=ARRAY_BUFFER)
    primitive = b.primitive(
        positions, indices, normals=np.tile([0.0, 0.0, 1.0], (len(positions), 1)),
        joints=joints[:, :4], weights=weights_0, JOINTS_1=joints_1, WEIGHTS_1=weights[:, 4:],
    )  # fmt: skip
    mesh = b.mesh([primitive], name="body")
    head = b.node("head", translation=BIND["head"][0], rotation=BIND["head"][1], scale=BIND["head"][2])
    spine = b.node(
        "spine", translation=BIND["spine"][0], rotation=BIND["spine"][1], scale=BIND["spine"][2], children=[head]
    )
    hips = b.node("hips", children=[spine])
    bind = globals_of(BIND)
    skin = b.skin([hips, spine, head], np.stack([np.linalg.inv(bind[name]) for name in ORDER]))
    skinned = b.node("skinned", mesh=mesh, skin=skin, translation=(9.0, 9.0, 9.0))  # ignored, as glTF asks
    b.scene([b.node("rig", children=[hips, skinned])])
    path = b.gltf(tmp_path / "rig.gltf")
    if edit is not None:
        document = json.loads(path.read_text())
        edit(document)
        path.write_text(json.dumps(document))
    return path, (positions, joints, weights)


def spawn(path, copies=1):
    world, meshes = World(), []

    def add(mesh):
        meshes.append(mesh)
        return len(meshes) - 1

    scene = load_gltf(path, add, Materials())
    at = np.c_[np.arange(copies) * 4.0, np.zeros(copies), np.zeros(copies)]
    roots = scene.spawn_many(world, copies, at)
    return world, scene, roots, meshes


def settle(world):
    TransformSystem().run(world, 0.0)
    HierarchySystem().run(world, 0.0)
    SkinSystem().run(world, 0.0)


def entity(world, name, copy=0):
    found = sorted(int(e) for e in world.query(Name).entities() if world.get(int(e), Name).value == name)
    return found[copy]


def spec_positions(positions, joints, weights, joint_globals):
    """The specification's skinning, vertex by vertex: sum_i w_i * (global_j_i @ inverseBind_j_i) @ v,
    the weights normalised to sum to 1 (the mesh node's own transform is not applied)."""
    bind = globals_of(BIND)
    out = []
    for v, js, ws in zip(positions.astype(np.float64), joints, weights.astype(np.float64), strict=True):
        total = ws.sum()
        m = np.zeros((4, 4))
        for j, w in zip(js, ws, strict=True):
            name = ORDER[int(j)]
            m += (w / total) * (joint_globals[name] @ np.linalg.inv(bind[name]))
        out.append((m @ np.r_[v, 1.0])[:3])
    return np.array(out)


def test_the_rest_pose_is_the_bind_pose_wherever_a_copy_stands(tmp_path):
    path, (positions, _, _) = skinned_file(tmp_path)
    world, _, _, meshes = spawn(path, copies=3)
    settle(world)
    skin = world.resources.get(Skins)[0]
    mesh = meshes[world.get(entity(world, "skinned", 2), Mesh).handle]
    assert mesh.skin is not None and np.allclose(mesh.skin.weights.sum(1), 1.0, atol=1e-6)
    for copy in range(3):
        moved = skinned_positions(mesh.positions, mesh.skin.joints, mesh.skin.weights, skin.world_matrices(copy))
        assert np.allclose(moved, positions + (4.0 * copy, 0.0, 0.0), atol=1e-5)


@pytest.mark.parametrize("weights_as", [None, "bytes"])
def test_posed_vertices_match_the_specification_s_formula_in_many_poses(tmp_path, weights_as):
    path, (positions, joints, weights) = skinned_file(tmp_path, weights_as=weights_as)
    world, _, _, meshes = spawn(path)
    mesh = meshes[world.get(entity(world, "skinned"), Mesh).handle]
    if weights_as == "bytes":  # the file's weights, as a reader of it sees them
        weights = mesh.skin.weights
        joints = mesh.skin.joints
    rng = np.random.default_rng(11)
    size = float(np.ptp(positions, axis=0).max())
    for _ in range(6):
        pose = {}
        for name in ORDER:  # any rotation, uneven scale, a move
            axis = rng.normal(size=3)
            axis /= np.linalg.norm(axis)
            angle = rng.uniform(-3.0, 3.0)
            rotation = (*(axis * np.sin(angle / 2)), np.cos(angle / 2))
            pose[name] = (rng.uniform(-1, 1, 3), rotation, rng.uniform(0.5, 2.0, 3))
            world.set(entity(world, name), Transform(position=pose[name][0], rotation=rotation, scale=pose[name][2]))
        settle(world)
        skin = world.resources.get(Skins)[0]
        got = skinned_positions(mesh.positions, mesh.skin.joints, mesh.skin.weights, skin.world_matrices(0))
        want = spec_positions(positions, joints, weights, globals_of(pose))
        assert np.abs(got - want).max() <= 1e-4 * size * 4, np.abs(got - want).max()
        # the pose's sphere holds every posed vertex, and the mesh row's model matrix places the
        # mesh's own sphere on it (what the renderer culls and picks by)
        assert (np.linalg.norm(got - skin.centres[0], axis=1) <= skin.radii[0] + 1e-9).all()
        model = world.get(entity(world, "skinned"), ModelMatrix).model.astype(np.float64)
        centre = (model @ np.r_[mesh.center, 1.0])[:3] + render_origin(world)
        radius = mesh.radius * np.linalg.norm(model[:3, :3], axis=0).max()
        assert np.allclose(centre, skin.centres[0], atol=1e-4) and np.isclose(radius, skin.radii[0], rtol=1e-5)


def test_each_copy_follows_its_own_joints_and_a_joint_gone_counts_as_the_identity(tmp_path):
    path, (positions, _, _) = skinned_file(tmp_path)
    world, _, _, meshes = spawn(path, copies=2)
    a, b = entity(world, "skinned", 0), entity(world, "skinned", 1)
    assert [int(world.get(e, Skinned).copy) for e in (a, b)] == [0, 1]
    world.set(entity(world, "hips", 1), Transform(position=(0.0, 5.0, 0.0)))
    settle(world)
    skin = world.resources.get(Skins)[0]
    mesh = meshes[world.get(a, Mesh).handle]
    first = skinned_positions(mesh.positions, mesh.skin.joints, mesh.skin.weights, skin.world_matrices(0))
    second = skinned_positions(mesh.positions, mesh.skin.joints, mesh.skin.weights, skin.world_matrices(1))
    assert np.allclose(first, positions, atol=1e-5)
    assert np.allclose(second, positions + (4.0, 5.0, 0.0), atol=1e-5)
    world.destroy(entity(world, "head", 1))
    settle(world)
    head = world.resources.get(Skins)[0].world_matrices(1)[2]
    assert np.allclose(head, np.linalg.inv(globals_of(BIND)["head"]), atol=1e-6)


def test_skin_weights_are_normalised_padded_and_checked():
    w = SkinWeights.of(np.array([[1, 2], [0, 3]]), np.array([[1.0, 3.0], [0.0, 2.0]]))
    assert w.joints.shape == (2, 8) and w.weights.shape == (2, 8)
    assert np.allclose(w.weights[:, :2], [[0.25, 0.75], [0.0, 1.0]]) and (w.weights[:, 2:] == 0).all()
    assert w.joints[1, 0] == 0 and w.largest_joint() == 3  # an unused influence names joint 0
    with pytest.raises(ValueError, match="vertex 1's weights sum to 0"):
        SkinWeights.of(np.zeros((2, 4), int), np.array([[1.0, 0, 0, 0], [0, 0, 0, 0]]))
    with pytest.raises(ValueError, match="vertex 0 has weights"):
        SkinWeights.of(np.zeros((1, 4), int), np.array([[1.0, -0.5, 0, 0]]))
    with pytest.raises(ValueError, match="at most 8"):
        SkinWeights.of(np.zeros((1, 9), int), np.ones((1, 9)))


def _two_joints(d):
    d["skins"][0]["joints"] = d["skins"][0]["joints"][:2]  # vertices name joint 2: out of range
    d["accessors"][d["skins"][0]["inverseBindMatrices"]]["count"] = 2


def _drop(key):
    return lambda d: d["meshes"][0]["primitives"][0]["attributes"].pop(key)


@pytest.mark.parametrize(
    ("edit", "field", "what"),
    [
        (_two_joints, "nodes[", "has 2 joints, but a vertex of its mesh names joint 2"),
        (lambda d: d["skins"][0].update(joints=[0, 1, 99]), "skins[0].joints[2]", "not a node of the scene"),
        (lambda d: d["skins"][0].update(joints=[0, 1, 1]), "skins[0].joints", "names a node twice"),
        (lambda d: d["nodes"][-2].pop("mesh"), ".skin", "on a node without a mesh"),
        (_drop("JOINTS_0"), ".attributes", "WEIGHTS_0 without JOINTS_0"),
        (lambda d: d["skins"][0].update(inverseBindMatrices=0), "skins[0].inverseBindMatrices", "float MAT4"),
    ],
)
def test_a_broken_skin_is_one_error_naming_the_file_and_the_field(tmp_path, edit, field, what):
    path, _ = skinned_file(tmp_path, edit)
    with pytest.raises(GltfError) as caught:
        spawn(path)
    message = str(caught.value)
    assert str(path) in message and field in message and what in message, message


def test_nan_or_negative_weights_are_one_error_naming_the_file_and_the_accessor(tmp_path):
    def nan(d):
        d["accessors"].append({"componentType": 5126, "count": 24, "type": "VEC4"})  # zeros: no weight at all
        d["meshes"][0]["primitives"][0]["attributes"]["WEIGHTS_1"] = len(d["accessors"]) - 1
        d["meshes"][0]["primitives"][0]["attributes"]["WEIGHTS_0"] = len(d["accessors"]) - 1

    path, _ = skinned_file(tmp_path, nan)
    with pytest.raises(GltfError, match=r"WEIGHTS_0: vertex 0's weights sum to 0"):
        spawn(path)
    for value, what in ((np.nan, "not finite"), (-0.5, "vertex 5 has weights")):
        path, _ = skinned_file(tmp_path, poison=value)
        with pytest.raises(GltfError, match=what) as caught:
            spawn(path)
        assert str(path) in str(caught.value) and ("WEIGHTS" in str(caught.value) or "accessors[" in str(caught.value))


def test_the_pose_kernel_matches_its_numpy_reference():
    from ecs_engine.animation import skin_pose

    rng = np.random.default_rng(4)
    worlds = rng.normal(size=(40, 4, 4))
    worlds[:, 3] = (0, 0, 0, 1)
    rows = rng.integers(-1, 40, (7, 5))  # -1: a joint that is gone
    binds, reach, origin = rng.normal(size=(5, 4, 4)), rng.uniform(0, 2, 5), rng.normal(size=3) * 100
    outs = []
    for kernel in (skin_pose.pose, skin_pose.pose_numpy):
        out, centres, radii = np.zeros((7, 5, 3, 4), np.float32), np.zeros((7, 3)), np.zeros(7)
        kernel(worlds, rows, binds, reach, origin, out, centres, radii, 2, 7)
        outs.append((out, centres, radii))
    for a, b in zip(*outs, strict=True):
        assert np.allclose(a, b, rtol=1e-5, atol=1e-4)
    assert (outs[0][2][2:] > 0).all() and (outs[0][2][:2] == 0).all()  # only copies 2:7 were posed


def test_the_placing_kernel_matches_its_numpy_reference():
    """SkinSystem's ModelMatrix per Skinned row (skin_pose.place): compiled and NumPy agree, rows
    naming no skin or a copy past their skin's are left as they were."""
    from ecs_engine.animation import skin_pose

    rng = np.random.default_rng(6)
    n = 30
    skin = rng.integers(-1, 3, n).astype(np.int32)  # -1: none; skin 2 does not exist
    copy = rng.integers(0, 4, n).astype(np.int32)  # skin 0 has 3 copies, skin 1 has 2
    radius, centre = rng.uniform(0.5, 2.0, n).astype(np.float32), rng.normal(size=(n, 3)).astype(np.float32)
    first = np.array([0, 3, 5], np.int64)
    centres, radii, origin = rng.normal(size=(5, 3)) * 10, rng.uniform(1, 3, 5), rng.normal(size=3)
    outs = []
    for kernel in (skin_pose.place, skin_pose.place_numpy):
        model = np.full((n, 4, 4), 7.0, np.float32)
        kernel(skin, copy, radius, centre, first, centres, radii, origin, model)
        outs.append(model)
    np.testing.assert_allclose(outs[0], outs[1], rtol=1e-5, atol=1e-5)
    known = (skin >= 0) & (skin < 2) & (copy < np.array([3, 2, 0])[np.clip(skin, 0, 2)])
    assert known.any() and (~known).any()
    assert (outs[0][~known] == 7.0).all() and (outs[0][known, 3, 3] == 1.0).all()
