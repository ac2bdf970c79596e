"""A procedural character for the animation demo and `bench animation`: a humanoid of 24 joints
and about 1,700 vertices (a tube along each bone, each ring weighted between the joints at its
ends), with three looping clips (idle, walk, run), written as a .glb so that it loads as any
file does (load_gltf: its skin, clips and bounds checked like a user's model).

The engine ships no licensed character; this one is made from numbers, like the test files."""

from __future__ import annotations

import json
import math
import struct
from pathlib import Path
from typing import Any

import numpy as np

# (name, parent, offset from the parent in the bind pose, tube radius of the bone to it)
SKELETON = [
    ("hips", None, (0.0, 0.95, 0.0), 0.0),
    ("spine", "hips", (0.0, 0.12, 0.0), 0.13),
    ("spine1", "spine", (0.0, 0.14, 0.0), 0.14),
    ("chest", "spine1", (0.0, 0.16, 0.0), 0.15),
    ("neck", "chest", (0.0, 0.14, 0.0), 0.06),
    ("head", "neck", (0.0, 0.1, 0.0), 0.06),
    ("clavicle.L", "chest", (0.08, 0.1, 0.0), 0.06),
    ("upper_arm.L", "clavicle.L", (0.14, 0.0, 0.0), 0.06),
    ("forearm.L", "upper_arm.L", (0.0, -0.28, 0.0), 0.05),
    ("hand.L", "forearm.L", (0.0, -0.25, 0.0), 0.04),
    ("finger.L", "hand.L", (0.0, -0.08, 0.0), 0.035),
    ("clavicle.R", "chest", (-0.08, 0.1, 0.0), 0.06),
    ("upper_arm.R", "clavicle.R", (-0.14, 0.0, 0.0), 0.06),
    ("forearm.R", "upper_arm.R", (0.0, -0.28, 0.0), 0.05),
    ("hand.R", "forearm.R", (0.0, -0.25, 0.0), 0.04),
    ("finger.R", "hand.R", (0.0, -0.08, 0.0), 0.035),
    ("thigh.L", "hips", (0.1, -0.05, 0.0), 0.09),
    ("shin.L", "thigh.L", (0.0, -0.42, 0.0), 0.08),
    ("foot.L", "shin.L", (0.0, -0.4, 0.0), 0.06),
    ("toe.L", "foot.L", (0.0, -0.05, 0.14), 0.045),
    ("thigh.R", "hips", (-0.1, -0.05, 0.0), 0.09),
    ("shin.R", "thigh.R", (0.0, -0.42, 0.0), 0.08),
    ("foot.R", "shin.R", (0.0, -0.4, 0.0), 0.06),
    ("toe.R", "foot.R", (0.0, -0.05, 0.14), 0.045),
]
HEAD_TOP, HEAD_RADIUS = 0.24, 0.11  # the head: a tube above the head joint
RINGS, SIDES = 6, 12
CLIPS = {"idle": 2.0, "walk": 1.0, "run": 0.66}  # name -> period (s)


def _quat(axis: tuple[float, float, float], angle: float) -> np.ndarray:
    a = np.asarray(axis, np.float64) / np.linalg.norm(axis)
    return np.r_[a * math.sin(angle / 2), math.cos(angle / 2)]


def _globals() -> dict[str, np.ndarray]:
    out: dict[str, np.ndarray] = {}
    for name, parent, offset, _ in SKELETON:
        out[name] = np.asarray(offset, np.float64) + (0.0 if parent is None else out[parent])
    return out


def mesh_arrays() -> tuple[np.ndarray, ...]:
    """(positions, normals, indices, joints (V, 4), weights (V, 4)) of the body in its bind pose."""
    at = _globals()
    index = {name: k for k, (name, *_) in enumerate(SKELETON)}
    bones: list[tuple[str, str | None, float]] = [
        (parent, name, radius) for name, parent, _, radius in SKELETON if parent is not None
    ]
    bones.append(("head", None, HEAD_RADIUS))
    positions, normals, joints, weights, indices = [], [], [], [], []
    for parent, child, radius in bones:
        start = at[parent]
        end = at[child] if child is not None else start + (0.0, HEAD_TOP, 0.0)
        axis = (end - start) / np.linalg.norm(end - start)
        side = np.cross(axis, (0.0, 0.0, 1.0) if abs(axis[2]) < 0.9 else (1.0, 0.0, 0.0))
        side /= np.linalg.norm(side)
        up = np.cross(axis, side)
        grand = SKELETON[index[parent]][1]
        for r in range(RINGS):
            t = r / (RINGS - 1)
            for s in range(SIDES):
                a = 2 * math.pi * s / SIDES
                n = math.cos(a) * side + math.sin(a) * up
                positions.append(start + t * (end - start) + radius * n)
                normals.append(n)
                # the bone's own joint, blending to the child's near its end, the parent's near its start
                w = {parent: 1.0}
                if child is not None and t > 0.6:
                    w[child] = (t - 0.6) / 0.4 * 0.5
                if grand is not None and t < 0.4:
                    w[grand] = (0.4 - t) / 0.4 * 0.5
                js = [index[j] for j in w] + [0] * (4 - len(w))
                joints.append(js)
                weights.append(list(w.values()) + [0.0] * (4 - len(w)))
        base = len(positions) - RINGS * SIDES
        for r in range(RINGS - 1):
            for s in range(SIDES):
                a, b = base + r * SIDES + s, base + r * SIDES + (s + 1) % SIDES
                indices += [a, b, a + SIDES, b, b + SIDES, a + SIDES]
    return (
        np.array(positions, np.float32),
        np.array(normals, np.float32),
        np.array(indices, np.uint32),
        np.array(joints, np.uint16),
        np.array(weights, np.float32),
    )


def _pose(clip: str, phase: float) -> dict[str, np.ndarray]:
    """Local rotations (x, y, z, w) of the joints a clip moves, at `phase` (0 to 1) of its period."""
    swing = math.sin(2 * math.pi * phase)
    lift = max(0.0, -math.sin(2 * math.pi * phase))
    lift2 = max(0.0, math.sin(2 * math.pi * phase))
    if clip == "idle":
        return {
            "spine": _quat((0, 0, 1), 0.04 * swing),
            "chest": _quat((1, 0, 0), 0.03 * swing),
            "upper_arm.L": _quat((0, 0, 1), 0.08 + 0.03 * swing),
            "upper_arm.R": _quat((0, 0, 1), -0.08 - 0.03 * swing),
        }
    leg, knee, arm, lean = (0.45, 0.7, 0.35, 0.05) if clip == "walk" else (0.85, 1.3, 0.8, 0.25)
    return {
        "spine": _quat((1, 0, 0), lean),
        "thigh.L": _quat((1, 0, 0), -leg * swing),
        "thigh.R": _quat((1, 0, 0), leg * swing),
        "shin.L": _quat((1, 0, 0), knee * lift),
        "shin.R": _quat((1, 0, 0), knee * lift2),
        "upper_arm.L": _quat((1, 0, 0), arm * swing),
        "upper_arm.R": _quat((1, 0, 0), -arm * swing),
        "forearm.L": _quat((1, 0, 0), -0.3 - 0.3 * lift2),
        "forearm.R": _quat((1, 0, 0), -0.3 - 0.3 * lift),
    }


class _Glb:
    """The few glTF objects this file needs, and its one binary buffer."""

    def __init__(self) -> None:
        self.json: dict = {"asset": {"version": "2.0", "generator": "ecs_engine demos/character.py"}}
        self.data = bytearray()

    def add(self, kind: str, entry: dict) -> int:
        self.json.setdefault(kind, []).append(entry)
        return len(self.json[kind]) - 1

    def accessor(self, values: np.ndarray, kind: str, target: int | None = None, bounds: bool = False) -> int:
        component = {np.dtype("float32"): 5126, np.dtype("uint16"): 5123, np.dtype("uint32"): 5125}[values.dtype]
        self.data += b"\0" * (-len(self.data) % 4)
        view: dict[str, int] = {"buffer": 0, "byteOffset": len(self.data), "byteLength": values.nbytes}
        if target is not None:
            view["target"] = target
        raw = np.ascontiguousarray(values.transpose(0, 2, 1) if values.ndim == 3 else values)
        self.data += raw.astype(values.dtype.newbyteorder("<")).tobytes()
        entry: dict[str, Any] = {"bufferView": self.add("bufferViews", view), "componentType": component}
        entry.update(count=len(values), type=kind)
        if bounds:
            entry["min"], entry["max"] = values.min(0).tolist(), values.max(0).tolist()
        return self.add("accessors", entry)

    def bytes(self) -> bytes:
        self.data += b"\0" * (-len(self.data) % 4)
        self.json["buffers"] = [{"byteLength": len(self.data)}]
        text = json.dumps(self.json).encode()
        text += b" " * (-len(text) % 4)
        chunks = struct.pack("<II", len(text), 0x4E4F534A) + text
        chunks += struct.pack("<II", len(self.data), 0x004E4942) + bytes(self.data)
        return struct.pack("<III", 0x46546C67, 2, 12 + len(chunks)) + chunks


def character_glb() -> bytes:
    """The character as a .glb file's bytes."""
    g = _Glb()
    positions, normals, indices, joints, weights = mesh_arrays()
    attributes = {
        "POSITION": g.accessor(positions, "VEC3", 34962, bounds=True),
        "NORMAL": g.accessor(normals, "VEC3", 34962),
        "JOINTS_0": g.accessor(joints, "VEC4", 34962),
        "WEIGHTS_0": g.accessor(weights, "VEC4", 34962),
    }
    primitive = {"attributes": attributes, "indices": g.accessor(indices, "SCALAR", 34963), "material": 0}
    pbr = {"baseColorFactor": [0.8, 0.55, 0.4, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.7}
    g.add("materials", {"name": "skin", "pbrMetallicRoughness": pbr})
    mesh = g.add("meshes", {"name": "body", "primitives": [primitive]})
    nodes = {}
    for name, parent, offset, _ in SKELETON:
        nodes[name] = g.add("nodes", {"name": name, "translation": list(offset), "children": []})
        if parent is not None:
            g.json["nodes"][nodes[parent]]["children"].append(nodes[name])
    at = _globals()
    binds = np.stack([np.eye(4) for _ in SKELETON]).astype(np.float32)
    binds[:, :3, 3] = -np.stack([at[name] for name, *_ in SKELETON])
    joint_nodes = [nodes[n] for n, *_ in SKELETON]
    skin = g.add("skins", {"joints": joint_nodes, "inverseBindMatrices": g.accessor(binds, "MAT4")})
    body = g.add("nodes", {"name": "body", "mesh": mesh, "skin": skin})
    g.add("scenes", {"nodes": [nodes["hips"], body]})
    g.json["scene"] = 0
    for clip, period in CLIPS.items():
        keys = 9
        times = np.linspace(0.0, period, keys).astype(np.float32)
        poses = [_pose(clip, k / (keys - 1)) for k in range(keys)]
        input_ = g.accessor(times, "SCALAR")
        g.json["accessors"][input_].update(min=[0.0], max=[float(period)])
        channels, samplers = [], []
        for joint in poses[0]:
            values = np.stack([p[joint] for p in poses]).astype(np.float32)
            samplers.append({"input": input_, "output": g.accessor(values, "VEC4"), "interpolation": "LINEAR"})
            channels.append({"sampler": len(samplers) - 1, "target": {"node": nodes[joint], "path": "rotation"}})
        g.add("animations", {"name": clip, "channels": channels, "samplers": samplers})
    return g.bytes()


def character_file(folder: Path) -> Path:
    """The character written into `folder` (once: kept while its bytes are the same)."""
    data = character_glb()
    path = Path(folder) / "character.glb"
    if not path.exists() or path.read_bytes() != data:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)
    return path
