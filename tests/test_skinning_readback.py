"""Skinned and morphed vertices read back from the GPU (render/draw/posed_vertices.py runs the
vertex shaders' own deform functions over a drawn frame's rows) against the glTF specification's
formulas written out here in NumPy: each channel sampled key by key (test_animation_curves.py's
references), the nodes' TRS composed into the joints' globals, the morph targets' deltas added,
then the weighted joint matrices applied, vertex by vertex. Every clip (all STEP, all LINEAR, all
CUBICSPLINE, and one that mixes them, each moving translation, rotation, scale and the morph
weights) at many times inside and outside its keys, within 1e-4 of the model's size; the rest
pose is the bind pose."""

from __future__ import annotations

import math

import numpy as np
from gltf_files import UNSIGNED_SHORT, GltfBuilder
from gpu_context import headless_gpu
from skinned_files import ORDER, PARENT
from test_animation_curves import reference_cubic, reference_linear, reference_slerp, reference_step
from test_skins import BIND, body

from ecs_engine import World
from ecs_engine.animation.player import AnimationSystem
from ecs_engine.app.scenes import default_schedule
from ecs_engine.components import Camera, Name, Transform, render_origin
from ecs_engine.components.animation import AnimationPlayer
from ecs_engine.maths.camera import look_rotation
from ecs_engine.render.assets.gltf.scene import load_gltf
from ecs_engine.render.assets.materials import materials
from ecs_engine.render.draw.posed_vertices import PosedVertices, deformed_rows
from ecs_engine.render.frame.renderer import Renderer

KEYS = np.array([0.0, 0.4, 1.0, 1.6], np.float32).astype(np.float64)  # the times as the file holds them
PROBES = [-0.5, KEYS[0], 0.13, KEYS[1], 0.71, KEYS[2], 1.37, KEYS[3], 2.4]  # before, on and between the keys, after
CLIPS = {  # per clip, the interpolation of each channel, in CHANNELS' order
    "step": ["STEP"] * 10,
    "linear": ["LINEAR"] * 10,
    "cubic": ["CUBICSPLINE"] * 10,
    "mixed": "CUBICSPLINE LINEAR STEP LINEAR CUBICSPLINE STEP STEP CUBICSPLINE LINEAR CUBICSPLINE".split(),
}
CHANNELS = [(name, path) for name in ORDER for path in ("translation", "rotation", "scale")] + [("skinned", "weights")]
TARGETS = 2
SIZE = 2.6  # the model's height: the tolerance is 1e-4 of it


def quaternion_matrix(q):
    x, y, z, w = np.asarray(q, np.float64) / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])  # fmt: skip


def trs(t, r, s):
    m = np.eye(4)
    m[:3, :3] = quaternion_matrix(r) * np.asarray(s, np.float64)[None, :]
    m[:3, 3] = t
    return m


def unit(rows):
    return rows / np.linalg.norm(rows, axis=-1, keepdims=True)


def keys_for(rng, path, interpolation):
    """A channel's key values (and, for CUBICSPLINE, its tangents) near the bind pose."""
    n = len(KEYS)
    if path == "rotation":
        values = unit(rng.normal(size=(n, 4)) * (0.4, 0.4, 0.4, 0.0) + (0.0, 0.0, 0.0, 1.0))
    elif path == "scale":
        values = rng.uniform(0.7, 1.4, (n, 3))
    elif path == "weights":
        values = rng.uniform(0.0, 1.0, (n, TARGETS))
    else:
        values = rng.normal(size=(n, 3)) * 0.3
    if interpolation != "CUBICSPLINE":
        return values, None, None
    a_in, b_out = rng.normal(size=(2, *values.shape)) * 0.5
    return values, a_in, b_out


def sample(interpolation, values, a_in, b_out, path, t):
    """The specification's value at time `t`, written out key by key (Appendix C)."""
    if interpolation == "STEP":
        return np.array(reference_step(KEYS, values.tolist(), t))
    if interpolation == "CUBICSPLINE":
        got = np.array(reference_cubic(KEYS, a_in.tolist(), values.tolist(), b_out.tolist(), t))
        return got / np.linalg.norm(got) if path == "rotation" else got
    if path == "rotation":
        return np.array(reference_slerp(KEYS, values.tolist(), t))
    return np.array(reference_linear(KEYS, values.tolist(), t))


def rig_file(tmp_path):
    """test_skins.py's three-joint rig (uneven scale, 8 influences a vertex) with two morph
    targets on its mesh and the clips of CLIPS; returns the path, the mesh's arrays and the keys."""
    rng = np.random.default_rng(11)
    b = GltfBuilder()
    positions, indices, joints, weights = body()
    normals = unit(rng.normal(size=(len(positions), 3)))
    deltas = rng.normal(size=(TARGETS, 2, len(positions), 3)) * np.array([0.2, 0.3])[None, :, None, None]
    targets = [{"POSITION": d[0].astype(np.float32), "NORMAL": d[1].astype(np.float32)} for d in deltas]
    primitive = b.primitive(
        positions, indices, normals=normals.astype(np.float32), joints=joints[:, :4], weights=weights[:, :4],
        JOINTS_1=b.accessor(joints[:, 4:], UNSIGNED_SHORT), WEIGHTS_1=weights[:, 4:], targets=targets,
    )  # fmt: skip
    mesh = b.mesh([primitive], name="body", weights=[0.0] * TARGETS)
    node = {}
    node["head"] = b.node("head", translation=BIND["head"][0], rotation=BIND["head"][1], scale=BIND["head"][2])
    spine = BIND["spine"]
    node["spine"] = b.node("spine", translation=spine[0], rotation=spine[1], scale=spine[2], children=[node["head"]])
    node["hips"] = b.node("hips", children=[node["spine"]])
    inverse_bind = np.stack([np.linalg.inv(m) for m in bind_globals().values()])
    skin = b.skin([node[name] for name in ORDER], inverse_bind)
    node["skinned"] = b.node("skinned", mesh=mesh, skin=skin, translation=(9.0, 9.0, 9.0))  # ignored, as glTF asks
    b.scene([b.node("rig", children=[node["hips"], node["skinned"]])])
    keys = {}
    for clip, kinds in CLIPS.items():
        channels = []
        for (name, path), kind in zip(CHANNELS, kinds, strict=True):
            values, a_in, b_out = keys_for(rng, path, kind)
            keys[clip, name, path] = (kind, values, a_in, b_out)
            out = values if kind != "CUBICSPLINE" else np.stack([a_in, values, b_out], axis=1)
            channels.append((node[name], path, KEYS, out, kind))
        b.animation(channels, name=clip)
    mesh_arrays = (positions, normals, joints, weights, deltas)
    return b.gltf(tmp_path / "rig.gltf"), mesh_arrays, keys


def bind_globals(pose=None):
    """The joints' global matrices, composed from the nodes' TRS here (not by the engine)."""
    pose = pose or BIND
    out = {}
    for name in ORDER:
        parent = PARENT[name]
        out[name] = (np.eye(4) if parent is None else out[parent]) @ trs(*pose[name])
    return out


def spec_vertices(mesh_arrays, pose, morph):
    """Positions and unit normals by the specification: the morph targets' deltas weighted by
    `morph`, then sum_i w_i * (global_j_i @ inverseBind_j_i), the weights normalised."""
    positions, normals, joints, weights, deltas = mesh_arrays
    p = positions.astype(np.float64) + np.einsum("t,tvc->vc", morph, deltas[:, 0])
    n = normals + np.einsum("t,tvc->vc", morph, deltas[:, 1])
    joint_globals, bind = bind_globals(pose), bind_globals()
    out_p, out_n = [], []
    for v in range(len(p)):
        ws = weights[v].astype(np.float64)
        skin = [joint_globals[ORDER[j]] @ np.linalg.inv(bind[ORDER[j]]) for j in joints[v]]
        m = sum((w / ws.sum()) * joint for joint, w in zip(skin, ws, strict=True))
        out_p.append((m @ np.r_[p[v], 1.0])[:3])
        out_n.append(np.linalg.inv(m[:3, :3]).T @ n[v])
    return np.array(out_p), unit(np.array(out_n))


def spec_pose(keys, clip, t):
    pose = {name: list(BIND[name]) for name in ORDER}
    morph = np.zeros(TARGETS)
    for name, path in CHANNELS:
        kind, values, a_in, b_out = keys[clip, name, path]
        value = sample(kind, values, a_in, b_out, path, t)
        if path == "weights":
            morph = value
        else:
            pose[name][("translation", "rotation", "scale").index(path)] = value
    return pose, morph


class Probe:
    """A renderer drawing every row (no culling: each row is in the frame's buffer) and the
    read-back of its last frame's deformed rows."""

    def __init__(self, gpu):
        self.gpu = gpu
        self.renderer = Renderer(gpu.device, gpu.target, gpu.meshes, culling="none")
        self.posed = PosedVertices(gpu.device, self.renderer.set_layout.handle)

    def draw(self, world):
        world.run_system(AnimationSystem(), 0.0)  # (not a scene plugin's: the default schedule poses)
        default_schedule().run(world, 0.0)
        stats = self.renderer.render(world)
        self.gpu.device.wait_idle()
        frames = self.renderer.frames
        frame = self.renderer.per_frame[(frames.index - 1) % len(frames.frames)]
        rows = deformed_rows(frame, stats.candidates)
        assert len(rows) == 1, rows  # the body, and not the ground
        (posed,) = self.posed.read(frame, self.gpu.meshes, rows.tolist())
        origin = render_origin(world)
        return posed[:, 0, :3] + origin, unit(posed[:, 1, :3].astype(np.float64))

    def destroy(self):
        self.posed.destroy()
        self.renderer.destroy()


def world_with(scene, play=None):
    world = World()
    eye = np.array([0.0, 1.2, 6.0])
    world.spawn(Transform(position=eye, rotation=look_rotation((0.0, 1.2, 0.0) - eye)), Camera(fov_y=0.9))
    root = scene.spawn(world, play=play)
    return world, root


def test_read_back_skinned_and_morphed_vertices_match_the_specification_for_every_clip_at_many_times(tmp_path):
    path, mesh_arrays, keys = rig_file(tmp_path)
    with headless_gpu(32, 32) as gpu:
        scene = load_gltf(path, gpu.meshes.add, materials(World()))
        probe = Probe(gpu)
        try:
            world, _ = world_with(scene)
            positions, normals = probe.draw(world)  # no clip: the rest pose
            want_p, want_n = spec_vertices(mesh_arrays, None, np.zeros(TARGETS))
            np.testing.assert_allclose(positions, mesh_arrays[0], atol=1e-4 * SIZE)  # the bind pose
            np.testing.assert_allclose(positions, want_p, atol=1e-4 * SIZE)
            np.testing.assert_allclose(normals, want_n, atol=1e-4)
            for clip in CLIPS:
                world, root = world_with(scene, play=clip)
                for t in PROBES:
                    world.set(root, AnimationPlayer, time=t, playing=False)
                    positions, normals = probe.draw(world)
                    want_p, want_n = spec_vertices(mesh_arrays, *spec_pose(keys, clip, t))
                    error = np.abs(positions - want_p).max()
                    assert error <= 1e-4 * SIZE, (clip, t, error)
                    assert np.abs(normals - want_n).max() <= 1e-3, (clip, t)
                    moved = np.abs(want_p - mesh_arrays[0]).max()
                    assert moved > 0.05, (clip, t, moved)  # the pose shows: the test can fail
        finally:
            probe.destroy()


def test_the_probe_sees_the_shader_s_deform_not_the_row_s_model_matrix(tmp_path):
    """With the joints moved, the read-back follows them (it is the shader's skinning, not a
    copy of the rest vertices placed by the row's model matrix)."""
    path, mesh_arrays, _ = rig_file(tmp_path)
    with headless_gpu(32, 32) as gpu:
        scene = load_gltf(path, gpu.meshes.add, materials(World()))
        probe = Probe(gpu)
        try:
            world, _ = world_with(scene)
            spine = next(int(e) for e in world.query(Name).entities() if world.get(int(e), Name).value == "spine")
            t = world.get(spine, Transform)
            turned = (0.0, 0.0, math.sin(0.6), math.cos(0.6))
            world.set(spine, Transform(position=t.position, rotation=turned, scale=t.scale))
            positions, _ = probe.draw(world)
        finally:
            probe.destroy()
    pose = {name: list(BIND[name]) for name in ORDER}
    pose["spine"][1] = np.array(turned)
    want, _ = spec_vertices(mesh_arrays, pose, np.zeros(TARGETS))
    np.testing.assert_allclose(positions, want, atol=1e-4 * SIZE)
    assert np.abs(positions - mesh_arrays[0]).max() > 0.3
