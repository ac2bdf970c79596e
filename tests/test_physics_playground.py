"""`ecs-engine play physics` (demos/physics_playground.py): headless with --autoplay it shoots
balls, the pile falls into a heap and the dominoes topple; without the physics extra it is one
line naming it."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from ecs_engine.app.game_module import find_game, game_defaults, make_app
from ecs_engine.components import Transform, Velocity
from ecs_engine.components.physics import DYNAMIC, HINGE, SPHERE, Collider, Joint, RigidBody


def test_the_playground_plays_itself():
    pytest.importorskip("culverin", reason="the physics extra (CPython 3.12+): make test-physics")
    game = find_game("physics")
    app = make_app(game, game_defaults(game, ["--autoplay", "--pile", "27"]))
    app.run(frames=150, headless=True, width=96, height=64)
    world = app.world
    balls = [
        e
        for b in world.query(Transform, Collider, with_=(Velocity,), write=())
        for e, shape in zip(b.entities, b[Collider].shape)
        if shape == SPHERE
    ]
    assert len(balls) >= 3  # one every half second of the 2.5 s
    bodies = world.query(Transform, RigidBody, Collider, write=())
    moving = np.concatenate([b[RigidBody].kind == DYNAMIC for b in bodies])
    where = np.concatenate([b[Transform].position for b in bodies])[moving]
    sizes = np.concatenate([b[Collider].size for b in bodies])[moving]
    assert where[:, 1].min() > 0.05  # nothing fell through the ground
    # the pile (27 boxes dropped from 3 to 5.8 m, on the +x side) lies in a heap, and dominoes fell
    pile = np.all(sizes == 0.5, axis=1) & (where[:, 0] > 0.0)
    assert pile.sum() == 27 and where[pile, 1].max() < 3.0
    dominoes = [
        b[Transform].rotation[i]
        for b in bodies
        for i in range(len(b))
        if np.allclose(b[Collider].size[i], (0.1, 1.0, 0.5))
    ]
    assert len(dominoes) == 24
    upright = [abs(q[3]) > 0.99 for q in dominoes]
    assert sum(upright) < 24
    # the chain swung, and its links stayed joined: each link's top where the one above ends
    from ecs_engine.demos.physics_playground import CHAIN_LINKS, LINK
    from ecs_engine.demos.physics_ragdoll import PARTS, RAGDOLL
    from ecs_engine.maths.camera import rotation_matrix

    joined = [(e, c) for b in world.query(Joint, Collider, write=()) for e, c in zip(b.entities, b[Collider].category)]
    links = [e for e, category in joined if category == 8]
    assert len(links) == CHAIN_LINKS
    assert sum(category == RAGDOLL for _, category in joined) == 2 * (len(PARTS) - 1)  # two ragdolls
    ends = []
    for e in links:
        t = world.get(e, Transform)
        up = rotation_matrix(t.rotation)[:3, 1] * LINK / 2
        ends.append((t.position + up, t.position - up))
    gaps = [np.linalg.norm(ends[k][0] - ends[k - 1][1]) for k in range(1, CHAIN_LINKS)]
    assert max(gaps) < 0.05
    from ecs_engine.components.physics import CharacterController

    (walker,) = world.query(CharacterController).entities()
    assert np.linalg.norm(world.get(walker, Transform).position[[0, 2]] - (-8.0, 4.0)) > 3.0  # it walked
    bottom = links[-1]  # it swings: away from the middle, or passing through it fast
    assert (
        abs(world.get(bottom, Transform).position[0] - 14.0) > 0.1
        or np.linalg.norm(world.get(bottom, Velocity).linear) > 0.5
    )


def test_without_the_extra_play_physics_is_one_line(monkeypatch, capsys):
    from ecs_engine.app import cli

    monkeypatch.setitem(sys.modules, "culverin", None)
    assert cli.main(["play", "physics", "--headless", "--frames", "2"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "pip install 'ecs_engine[physics]'" in err[0], err


def test_a_ragdoll_falls_in_a_heap_with_its_joints_holding():
    """Dropped from a metre up, a ragdoll collapses on the floor; every joint's pivot, carried by
    each of its two parts, stays where the other part carries it."""
    sys.path.insert(0, str(__import__("pathlib").Path(__file__).parent))
    from physics_world import floor, simulate

    from ecs_engine.components import Mesh
    from ecs_engine.demos.physics_ragdoll import PARTS, spawn_ragdoll
    from ecs_engine.maths.camera import rotation_matrix

    made = {}

    def setup(world, dt):
        floor(world)
        made["parts"] = spawn_ragdoll(world, (0.0, 1.0, 0.0), 0, 0, 0, 0)

    world, _ = simulate(setup, 180)
    parts = made["parts"]
    assert all(world.has(e, Mesh) for e in parts)
    where = {e: world.get(e, Transform) for e in parts}
    for k, part in enumerate(PARTS):
        if part.parent < 0:
            continue
        ends = []
        for index, start in ((k, part.centre), (part.parent, PARTS[part.parent].centre)):
            t = where[parts[index]]
            local = np.asarray(part.pivot) - np.asarray(start)  # (upright and unturned when made)
            ends.append(t.position + rotation_matrix(t.rotation)[:3, :3] @ local)
        assert np.linalg.norm(ends[0] - ends[1]) < 0.03, part.name
    heights = np.array([where[e].position[1] for e in parts])
    assert heights.min() > 0.0 and heights[2] < 1.0  # on the floor, the head come down from 2.65 m
    # each hinge turned its part about x alone (the parts started alike), within its limits:
    # a knee bends one way, an elbow the other
    bent = []
    for k, part in enumerate(PARTS):
        if part.joint != HINGE:
            continue
        (cx, cy, cz, cw), (px, py, pz, pw) = where[parts[k]].rotation, where[parts[part.parent]].rotation
        x = pw * cx - px * cw - py * cz + pz * cy  # the parent's inverse times the child's
        y, z = pw * cy + px * cz - py * cw - pz * cx, pw * cz - px * cy + py * cx - pz * cw
        w = pw * cw + px * cx + py * cy + pz * cz
        assert abs(y) < 0.02 and abs(z) < 0.02, part.name
        angle = 2 * np.arctan2(x * np.sign(w), abs(w))
        assert part.limits[0] - 0.05 <= angle <= part.limits[1] + 0.05, (part.name, angle)
        bent.append(abs(angle) > 0.3)
    assert any(bent)  # it fell in a heap, not stiff
