"""A small skinned glTF character for the tests that draw one: a tube up a chain of three joints
(hips, spine with uneven scale, head), its rings weighted between the joints around them, every
vertex with eight influences (the last ones small and spread over every joint)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from gltf_files import ARRAY_BUFFER, UNSIGNED_SHORT, GltfBuilder

from ecs_engine.maths.decompose import trs_matrices

BIND = {
    "hips": ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0), (1.0, 1.0, 1.0)),
    "spine": ((0.0, 1.0, 0.0), (0.0, 0.0, np.sin(0.1), np.cos(0.1)), (1.0, 1.3, 0.9)),
    "head": ((0.0, 1.0, 0.0), (0.0, 0.0, 0.0, 1.0), (1.0, 1.0, 1.0)),
}
PARENT = {"hips": None, "spine": "hips", "head": "spine"}
ORDER = ["hips", "spine", "head"]


def local(trs):
    t, r, s = (np.asarray(v, np.float64)[None] for v in trs)
    return trs_matrices(t, r, s)[0]


def globals_of(pose):
    out = {}
    for name in ORDER:
        parent = PARENT[name]
        out[name] = (np.eye(4) if parent is None else out[parent]) @ local(pose[name])
    return out


def tube(rings=14, sides=10, radius=0.25, height=2.6):
    """(positions, normals, indices, joints (V, 8), weights (V, 8)) of an open tube along +Y."""
    y = np.linspace(0.0, height, rings)
    angle = np.linspace(0.0, 2 * np.pi, sides, endpoint=False)
    ring = np.c_[np.cos(angle), np.zeros(sides), np.sin(angle)]
    positions = (ring[None] * radius + np.c_[np.zeros(rings), y, np.zeros(rings)][:, None]).reshape(-1, 3)
    normals = np.tile(ring, (rings, 1))
    quads = [(r * sides + s, r * sides + (s + 1) % sides) for r in range(rings - 1) for s in range(sides)]
    indices = np.array([[a, a + sides, b, b, a + sides, b + sides] for a, b in quads]).reshape(-1)
    # each ring between the two joints nearest its height, then four small influences on every joint
    along = np.clip(np.repeat(y, sides), 0.0, 2.0)
    lower = np.minimum(np.floor(along).astype(int), 1)
    t = along - lower
    joints = np.zeros((len(positions), 8), np.uint16)
    weights = np.zeros((len(positions), 8), np.float32)
    joints[:, 0], joints[:, 1] = lower, lower + 1
    weights[:, 0], weights[:, 1] = 1.0 - t, t
    rng = np.random.default_rng(5)
    joints[:, 2:] = rng.integers(0, 3, (len(positions), 6))
    weights[:, 2:] = rng.uniform(0.0, 0.02, (len(positions), 6))
    weights[:, 0] += 0.01  # no vertex without weight
    return positions.astype(np.float32), normals.astype(np.float32), indices, joints, weights


def tube_file(path: Path, material_color=(0.8, 0.5, 0.2, 1.0), rings=14, sides=10) -> Path:
    b = GltfBuilder()
    positions, normals, indices, joints, weights = tube(rings=rings, sides=sides)
    joints_1 = b.accessor(joints[:, 4:], UNSIGNED_SHORT, target=ARRAY_BUFFER)
    primitive = b.primitive(
        positions, indices, normals=normals, material=b.material("skin", base_color=material_color, metallic=0.0),
        joints=joints[:, :4], weights=weights[:, :4], JOINTS_1=joints_1, WEIGHTS_1=weights[:, 4:],
    )  # fmt: skip
    head = b.node("head", translation=BIND["head"][0])
    spine = b.node(
        "spine", translation=BIND["spine"][0], rotation=BIND["spine"][1], scale=BIND["spine"][2], children=[head]
    )
    hips = b.node("hips", children=[spine])
    bind = globals_of(BIND)
    skin = b.skin([hips, spine, head], np.stack([np.linalg.inv(bind[name]) for name in ORDER]))
    body = b.node("body", mesh=b.mesh([primitive], name="tube"), skin=skin)
    b.scene([b.node("character", children=[hips, body])])
    return b.gltf(path)
