"""Physics (ecs_engine.physics on culverin/Jolt) tested against physics, not against the
library's own numbers: free fall, a bounce with restitution, momentum in an elastic collision,
a tower standing, friction on a slope, rays against a NumPy ray cast, determinism."""

from __future__ import annotations

import hashlib
import math
import re
import sys
from pathlib import Path

import numpy as np
import pytest
from physics_world import G, ball, floor, physics_plugin, position, simulate

from ecs_engine import App, MinimalPlugins
from ecs_engine.components import Transform, Velocity
from ecs_engine.components.physics import (
    BOX,
    DYNAMIC,
    KINEMATIC,
    SPHERE,
    STATIC,
    Collider,
    RigidBody,
)
from ecs_engine.errors import UsageError

DT = 1.0 / 60.0


def test_a_dropped_ball_falls_as_gravity_says():
    made = {}

    def setup(world, dt):
        made["ball"] = ball(world, 20.0)

    world, _ = simulate(setup, 60)
    fallen = 20.0 - position(world, made["ball"])[1]
    # 1 s of free fall: g/2 (4.905 m); the library's default damping (0.05/s) takes under 2%
    assert fallen == pytest.approx(G / 2, rel=0.03)
    x, _, z = position(world, made["ball"])
    assert x == 0.0 and z == 0.0


def test_a_ball_bounces_to_restitution_squared_of_its_height():
    made, heights = {}, []
    h, e = 5.0, 0.8

    def setup(world, dt):
        floor(world)
        made["ball"] = ball(world, h + 0.5, restitution=e)  # its bottom h above the floor

    def record(world, dt):
        heights.append(float(position(world, made["ball"])[1]) - 0.5)

    from ecs_engine.physics import PhysicsWorld

    app = App(title="bounce").add_plugins(MinimalPlugins, physics_plugin())
    app.add_startup_systems(setup)
    app.add_systems("update", record)
    app.run(frames=180)
    assert app.world.resources[PhysicsWorld].steps == 180
    ground = int(np.argmin(heights[:90]))
    apex = max(heights[ground:])
    assert heights[ground] < 0.05  # it reached the floor
    assert apex == pytest.approx(e * e * h, rel=0.12)


def test_momentum_is_conserved_in_an_elastic_collision():
    made = {}
    m1, m2, v1, v2 = 1.0, 3.0, 2.0, -1.0

    def setup(world, dt):
        made["a"] = world.spawn(
            Transform(position=(-2.0, 0.0, 0.0)), RigidBody(mass=m1), Collider(shape=SPHERE, restitution=1.0),
            Velocity(linear=(v1, 0.0, 0.0)),
        )  # fmt: skip
        made["b"] = world.spawn(
            Transform(position=(2.0, 0.0, 0.0)), RigidBody(mass=m2), Collider(shape=SPHERE, restitution=1.0),
            Velocity(linear=(v2, 0.0, 0.0)),
        )  # fmt: skip

    world, _ = simulate(setup, 120, gravity=(0.0, 0.0, 0.0))
    u1 = world.get(made["a"], Velocity).linear[0]
    u2 = world.get(made["b"], Velocity).linear[0]
    before, after = m1 * v1 + m2 * v2, m1 * u1 + m2 * u2
    damped = math.exp(-0.05 * 2.0)  # the library's default linear damping over the 2 s
    assert after == pytest.approx(before * damped, rel=0.03)
    # the elastic answer: u1 = ((m1 - m2) v1 + 2 m2 v2) / (m1 + m2), u2 likewise
    assert u1 == pytest.approx(((m1 - m2) * v1 + 2 * m2 * v2) / (m1 + m2) * damped, rel=0.08)
    assert u2 == pytest.approx(((m2 - m1) * v2 + 2 * m1 * v1) / (m1 + m2) * damped, rel=0.08)


def test_a_tower_of_ten_boxes_stands_still_for_ten_seconds():
    made = []

    def setup(world, dt):
        floor(world)
        for i in range(10):
            made.append(world.spawn(Transform(position=(0.0, 0.5 + i, 0.0)), RigidBody(), Collider(shape=BOX)))

    settled = {}

    def watch(world, dt):
        from ecs_engine import Time

        if world.resources[Time].steps == 60:  # after the first second's settling
            settled["at"] = np.array([position(world, e) for e in made])

    app = App(title="tower").add_plugins(MinimalPlugins, physics_plugin())
    app.add_startup_systems(setup)
    app.add_systems("update", watch)
    app.run(frames=660)
    end = np.array([position(app.world, e) for e in made])
    drift = np.linalg.norm(end - settled["at"], axis=1)
    assert drift.max() < 1e-3, drift
    assert end[-1, 1] == pytest.approx(9.5, abs=0.25)  # still a tower, its top where it was


@pytest.mark.parametrize(("degrees", "slides"), [(20.0, False), (35.0, True)])
def test_friction_holds_a_box_below_the_friction_angle_only(degrees, slides):
    """Both friction coefficients 0.5: the pair's is their geometric mean, 0.5, whose angle is
    atan(0.5) = 26.6 degrees."""
    made = {}
    a = math.radians(degrees)
    q = (0.0, 0.0, math.sin(a / 2), math.cos(a / 2))  # the slope turned about z
    down = np.array([-math.cos(a), -math.sin(a), 0.0])  # along the slope, downhill (toward -x)
    normal = np.array([-math.sin(a), math.cos(a), 0.0])

    def setup(world, dt):
        world.spawn(Transform(rotation=q), RigidBody(kind=STATIC), Collider(shape=BOX, size=(20.0, 0.5, 5.0)))
        start = normal * 1.0  # resting on the slope's top face
        made["box"] = world.spawn(Transform(position=tuple(start), rotation=q), RigidBody(), Collider(shape=BOX))

    world, _ = simulate(setup, 120)
    moved = float(np.dot(position(world, made["box"]) - normal * 1.0, down))
    if slides:
        assert moved > 1.0
    else:
        assert abs(moved) < 0.02


def test_rays_hit_what_a_numpy_ray_cast_says():
    rng = np.random.default_rng(7)
    centres = np.c_[rng.uniform(-8, 8, 40), rng.uniform(0.5, 3, 40), rng.uniform(-8, 8, 40)]
    half = rng.uniform(0.2, 0.8, (40, 3))
    made = {}

    def setup(world, dt):
        made["boxes"] = [
            world.spawn(Transform(position=tuple(c)), RigidBody(kind=STATIC), Collider(shape=BOX, size=tuple(h)))
            for c, h in zip(centres, half)
        ]

    _, physics = simulate(setup, 1)
    origins = np.c_[rng.uniform(-9, 9, 2000), np.full(2000, 10.0), rng.uniform(-9, 9, 2000)]
    down = np.tile((0.0, -1.0, 0.0), (2000, 1))
    hits = physics.raycast(origins, down, max_distance=50.0)
    # NumPy: a vertical ray hits the highest top face of the boxes over its (x, z)
    inside = (np.abs(origins[:, None, 0] - centres[None, :, 0]) < half[None, :, 0]) & (
        np.abs(origins[:, None, 2] - centres[None, :, 2]) < half[None, :, 2]
    )
    tops = np.where(inside, centres[None, :, 1] + half[None, :, 1], -np.inf)
    expected = np.where(inside.any(axis=1), np.array(made["boxes"])[np.argmax(tops, axis=1)], -1)
    edge = np.min(
        np.abs(np.abs(origins[:, None, [0, 2]] - centres[None, :, [0, 2]]) - half[None, :, [0, 2]]), axis=(1, 2)
    )
    clear = edge > 1e-3  # (rays grazing an edge could go either way in float32)
    assert (hits.entity[clear] == expected[clear]).all()
    hit = hits.entity >= 0
    assert hit.sum() > 100
    assert np.allclose(hits.distance[hit & clear], 10.0 - tops.max(axis=1)[hit & clear], atol=1e-3)
    assert np.allclose(hits.normal[hit & clear], (0.0, 1.0, 0.0), atol=1e-3)
    assert np.isnan(hits.distance[~hit]).all()


def _pile(world, dt):
    floor(world)
    rng = np.random.default_rng(3)
    for i in range(60):
        p = (rng.uniform(-2, 2), 1.0 + i * 0.8, rng.uniform(-2, 2))
        world.spawn(Transform(position=p), RigidBody(), Collider(shape=BOX if i % 2 else SPHERE))


def world_hash(world):
    digest = hashlib.sha256()
    for batch in world.query(Transform, RigidBody, write=()):
        order = np.argsort(batch.entities)
        digest.update(batch.entities[order].tobytes())
        digest.update(np.ascontiguousarray(batch[Transform].position[order]).tobytes())
        digest.update(np.ascontiguousarray(batch[Transform].rotation[order]).tobytes())
    return digest.hexdigest()


_HASH_SCRIPT = """
import sys
sys.path.insert(0, {tests!r})
from physics_world import simulate
from test_physics import _pile, world_hash
world, _ = simulate(_pile, 240, threads={threads})
print(world_hash(world))
"""


@pytest.mark.parametrize("threads", [1, 4])
def test_the_same_script_gives_the_same_world_in_another_process(threads):
    """Across processes too, and with the library's threads at 1 or 4 (its job system's order
    must not show in the result)."""
    physics_plugin()
    import subprocess

    tests = str(Path(__file__).resolve().parent)
    script = _HASH_SCRIPT.format(tests=tests, threads=threads)
    runs = [
        subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120) for _ in range(2)
    ]
    for run in runs:
        assert run.returncode == 0, run.stderr
    here, _ = simulate(_pile, 240)  # (2 threads)
    assert runs[0].stdout.split()[-1] == runs[1].stdout.split()[-1] == world_hash(here)


def test_the_same_script_gives_the_same_world_twice():
    first, _ = simulate(_pile, 240)
    second, _ = simulate(_pile, 240)
    assert world_hash(first) == world_hash(second)


def test_bodies_come_and_go_with_their_entities():
    made = {}

    def setup(world, dt):
        floor(world)
        made["a"] = ball(world, 3.0)
        made["b"] = ball(world, 6.0)

    def churn(world, dt):
        from ecs_engine import Time

        steps = world.resources[Time].steps
        if steps == 10:
            world.destroy(made["a"])
            made["c"] = ball(world, 9.0, x=3.0)

    from ecs_engine.physics import PhysicsWorld

    app = App(title="churn").add_plugins(MinimalPlugins, physics_plugin())
    app.add_startup_systems(setup)
    app.add_systems("update", churn)
    app.run(frames=240)
    physics = app.world.resources[PhysicsWorld]
    assert set(physics.bodies.entities().tolist()) == {made["b"], made["c"], *app.world.query(RigidBody).entities()}
    assert physics.bodies.handle_of(made["a"]) is None and physics.bodies.handle_of(made["c"]) is not None
    # both balls came to rest on the floor, each at its own body's place
    for e in (made["b"], made["c"]):
        assert position(app.world, e)[1] == pytest.approx(0.5, abs=0.03)


def test_a_body_with_velocity_is_moved_once_by_the_physics_not_by_motion_too():
    made = {}

    def setup(world, dt):
        made["ball"] = ball(world, 50.0, v=Velocity(linear=(3.0, 0.0, 0.0)))

    world, _ = simulate(setup, 60)
    assert position(world, made["ball"])[0] == pytest.approx(3.0, rel=0.03)  # 1 s at 3 m/s, damped a little


def test_bad_bodies_are_refused_naming_the_field():
    world = App(title="bad").world
    with pytest.raises(ValueError, match=re.escape("RigidBody.mass must be > 0")):
        world.spawn(Transform(), RigidBody(mass=-1.0), Collider())
    with pytest.raises(ValueError, match=re.escape("Collider.size must be > 0")):
        world.spawn(Transform(), RigidBody(), Collider(size=(0.0, 1.0, 1.0)))
    with pytest.raises(ValueError, match=re.escape("Collider.shape")):
        world.spawn(Transform(), RigidBody(), Collider(shape=9))
    with pytest.raises(ValueError, match=re.escape("Velocity.linear")):
        world.spawn(Transform(), RigidBody(), Collider(), Velocity(linear=(math.nan, 0.0, 0.0)))


def test_without_the_library_the_plugin_is_one_line_naming_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "culverin", None)  # import culverin: ImportError
    from ecs_engine.physics import PhysicsPlugin

    with pytest.raises(UsageError) as caught:
        App(title="no physics").add_plugins(PhysicsPlugin())
    message = str(caught.value)
    assert "pip install 'ecs_engine[physics]'" in message and "\n" not in message


def test_the_physics_page_example_runs():
    """docs/physics.md's example (which the docs test leaves to this one: it needs the extra),
    headless for 90 frames: the ball fell, bounced and rolled along +x."""
    physics_plugin()
    page = (Path(__file__).resolve().parent.parent / "docs" / "physics.md").read_text()
    code = re.search(r"```python\n(.*?)```", page, re.S)[1]
    assert "app.run()" in code
    scope: dict = {}
    exec(code.replace("app.run()", "app.run(frames=90, headless=True, width=160, height=90)"), scope)
    world = scope["app"].world
    (ball,) = [e for e in world.query(Velocity).entities()]
    x, y, _ = world.get(ball, Transform).position
    assert 0.5 < x < 1.6 and 0.4 < y < 5.0


def test_a_shape_cast_and_overlaps_find_what_geometry_says():
    from ecs_engine.components.physics import CAPSULE

    made = {}

    def setup(world, dt):
        made["low"] = world.spawn(
            Transform(position=(0.0, 1.0, 0.0)), RigidBody(kind=STATIC), Collider(shape=BOX, size=(1.0, 1.0, 1.0))
        )
        made["far"] = world.spawn(
            Transform(position=(10.0, 1.0, 0.0)), RigidBody(kind=STATIC), Collider(shape=BOX, size=(1.0, 1.0, 1.0))
        )

    _, physics = simulate(setup, 1)
    # a sphere of radius 0.5 dropped from y = 6 meets the box's top (y = 2) after 3.5 m
    hit = physics.shapecast(SPHERE, 0.5, (0.0, 6.0, 0.0), (0.0, -10.0, 0.0))
    assert hit is not None and hit.entity == made["low"]
    assert hit.distance == pytest.approx(3.5, abs=0.02)
    assert hit.normal[1] == pytest.approx(1.0, abs=1e-3) and hit.point[1] == pytest.approx(2.0, abs=0.02)
    # a capsule swept sideways at y = 5 passes over both
    assert physics.shapecast(CAPSULE, (0.3, 0.5, 0.3), (-5.0, 5.0, 0.0), (20.0, 0.0, 0.0)) is None
    # ignoring the first box, the sweep along x meets the far one
    along = physics.shapecast(BOX, (0.2, 0.2, 0.2), (-5.0, 1.0, 0.0), (20.0, 0.0, 0.0), ignore=made["low"])
    assert along is not None and along.entity == made["far"] and along.distance == pytest.approx(13.8, abs=0.02)
    assert list(physics.overlap_sphere((1.5, 1.0, 0.0), 0.6)) == [made["low"]]  # 0.5 from its side
    assert list(physics.overlap_sphere((1.5, 3.0, 0.0), 0.6)) == []  # beyond its corner
    assert list(physics.overlap_box((-20.0, 0.0, -1.0), (20.0, 0.5, 1.0))) == sorted([made["low"], made["far"]])
    with pytest.raises(ValueError, match="size must be 3 positive"):
        physics.shapecast(BOX, (0.0, 1.0, 1.0), (0.0, 0.0, 0.0), (1.0, 0.0, 0.0))


def test_bad_settings_are_refused_naming_them():
    physics_plugin()
    from ecs_engine.physics import PhysicsPlugin, PhysicsWorld

    with pytest.raises(ValueError, match="gravity must be 3 finite numbers"):
        PhysicsWorld(gravity=(0.0, math.nan, 0.0))
    with pytest.raises(ValueError, match="contacts must be one of none, triggers, begin_end, all"):
        PhysicsWorld(contacts="some")
    with pytest.raises(TypeError, match="no setting gravitty"):
        PhysicsPlugin(gravitty=(0.0, -1.0, 0.0))


def test_paused_bodies_stay_and_one_step_moves_them_once():
    from ecs_engine import Time
    from ecs_engine.physics import PhysicsWorld

    made, seen = {}, []

    def setup(world, dt):
        made["ball"] = ball(world, 10.0)

    def control(world, dt):  # (update: after the fixed step of this frame)
        physics = world.resources[PhysicsWorld]
        frame = world.resources[Time].steps
        seen.append((frame, physics.steps, float(position(world, made["ball"])[1])))
        physics.paused = frame >= 10
        physics.step_once = frame == 20

    app = App(title="pause").add_plugins(MinimalPlugins, physics_plugin())
    app.add_startup_systems(setup)
    app.add_systems("update", control)
    app.run(frames=30)
    at = {frame: (steps, y) for frame, steps, y in seen}
    assert at[11][0] == at[20][0] == 10 and at[11][1] == at[20][1]  # paused: no step, no motion
    assert at[21][0] == 11 and at[21][1] < at[20][1]  # one step, then paused again
    assert at[30][0] == 11


def test_a_body_a_system_moves_is_put_there_and_goes_on_from_there():
    """Writing a dynamic body's Transform teleports it (a game wrapping a field, a respawn):
    it falls on from where it was put, its velocity kept."""
    from ecs_engine import Time

    made, seen = {}, {}

    def setup(world, dt):
        made["ball"] = ball(world, 50.0, v=Velocity(linear=(2.0, 0.0, 0.0)))

    def wrap(world, dt):  # (update: after the step)
        frame = world.resources[Time].steps
        if frame == 30:
            seen["before"] = world.get(made["ball"], Velocity).linear.copy()
            world.set(made["ball"], Transform(position=(-20.0, 40.0, 5.0)))
        if frame == 31:
            seen["after"] = position(world, made["ball"]).copy(), world.get(made["ball"], Velocity).linear.copy()

    app = App(title="teleport").add_plugins(MinimalPlugins, physics_plugin())
    app.add_startup_systems(setup)
    app.add_systems("update", wrap)
    app.run(frames=40)
    where, velocity = seen["after"]
    step = 1 / 60
    assert where[0] == pytest.approx(-20.0 + 2.0 * step, abs=0.01)  # one step from where it was put
    assert where[1] == pytest.approx(40.0 + seen["before"][1] * step, abs=0.02)
    assert where[2] == pytest.approx(5.0, abs=1e-6)
    assert velocity[1] == pytest.approx(seen["before"][1] - G * step, abs=0.05)  # still falling as fast


def test_a_body_with_a_parent_is_one_error_and_a_body_s_children_follow_it(capsys):
    from ecs_engine.components import Parent, WorldMatrix

    made = {}

    def setup(world, dt):
        made["ball"] = ball(world, 5.0)
        made["badge"] = world.spawn(Transform(position=(0.0, 1.0, 0.0)), Parent(entity=made["ball"]))

    world, _ = simulate(setup, 30)
    fallen = position(world, made["ball"])
    assert fallen[1] < 5.0
    # the child is drawn 1 m above wherever its body went (its world matrix, from the hierarchy)
    matrix = world.get(made["badge"], WorldMatrix).matrix
    assert matrix[1, 3] == pytest.approx(fallen[1] + 1.0, abs=0.05)

    def orphan(world, dt):
        root = world.spawn(Transform())
        world.spawn(Transform(), RigidBody(), Collider(), Parent(entity=root))

    with pytest.raises(SystemExit) as stop:
        simulate(orphan, 2)
    assert stop.value.code == 2
    assert "cannot have a Parent" in capsys.readouterr().err


def test_a_collider_a_system_changes_remakes_the_body():
    """A ball shrunk mid-run (Collider.size) settles lower; one made bouncy bounces."""
    from ecs_engine import Time

    made, seen = {}, {}

    def setup(world, dt):
        made["other"] = ball(world, 8.0, x=8.0, v=Velocity())  # a table of its own, planned first
        floor(world)
        made["shrunk"] = ball(world, 0.5, x=-2.0)
        made["bouncy"] = ball(world, 0.5, x=2.0)

    def change(world, dt):
        frame = world.resources[Time].steps
        if frame == 30:
            world.set(made["shrunk"], Collider, size=(0.2, 0.2, 0.2))
            world.set(made["bouncy"], Collider, restitution=0.9)
            world.set(made["bouncy"], Transform(position=(2.0, 3.0, 0.0)))
        seen.setdefault("bouncy", []).append(float(position(world, made["bouncy"])[1]))

    app = App(title="remake").add_plugins(MinimalPlugins, physics_plugin())
    app.add_startup_systems(setup)
    app.add_systems("update", change)
    app.run(frames=150)
    assert position(app.world, made["shrunk"])[1] == pytest.approx(0.2, abs=0.02)  # resting on its new radius
    assert position(app.world, made["other"])[1] == pytest.approx(0.5, abs=0.03)  # its rows followed too
    heights = seen["bouncy"][31:]
    bottom = int(np.argmin(heights[:60]))
    assert max(heights[bottom:]) > 0.5 + 0.5 * 2.5  # bounced back up most of its 2.5 m drop


def test_a_body_a_system_makes_static_dynamic_or_kinematic_takes_its_new_motion():
    """RigidBody.kind changed mid-run: a static box made dynamic falls, a falling one made
    static stops where it is, one made kinematic stays at its Transform (the game moves it). A
    change to or from static makes the body again: the library crashed when asked to move a
    static one."""
    from ecs_engine import Time

    made, at = {}, {}

    def setup(world, dt):
        floor(world)
        made["freed"] = world.spawn(Transform(position=(-3.0, 4.0, 0.0)), RigidBody(kind=STATIC), Collider(shape=BOX))
        made["held"] = world.spawn(Transform(position=(0.0, 8.0, 0.0)), RigidBody(), Collider(shape=BOX))
        made["driven"] = world.spawn(Transform(position=(3.0, 8.0, 0.0)), RigidBody(), Collider(shape=BOX))

    def change(world, dt):
        if world.resources[Time].steps == 30:
            for name, kind in (("freed", DYNAMIC), ("held", STATIC), ("driven", KINEMATIC)):
                world.set(made[name], RigidBody, kind=kind)
                at[name] = float(position(world, made[name])[1])

    app = App(title="kinds").add_plugins(MinimalPlugins, physics_plugin())
    app.add_startup_systems(setup)
    app.add_systems("update", change)
    app.run(frames=120)
    assert position(app.world, made["freed"])[1] == pytest.approx(0.5, abs=0.03)  # fell onto the floor
    assert position(app.world, made["held"])[1] == pytest.approx(at["held"], abs=1e-6)  # stayed in mid-air
    assert position(app.world, made["driven"])[1] == pytest.approx(at["driven"], abs=1e-6)  # where its Transform is


def test_a_static_body_a_system_moves_is_put_there():
    """A static ledge a system moves (its Transform written) is where a ball then lands; the
    Transform is not written back over."""
    from ecs_engine import Time

    made = {}

    def setup(world, dt):
        floor(world)
        made["ledge"] = world.spawn(
            Transform(position=(0.0, 1.0, 0.0)), RigidBody(kind=STATIC), Collider(shape=BOX, size=(1.0, 0.25, 1.0))
        )

    def move(world, dt):
        if world.resources[Time].steps == 10:
            world.set(made["ledge"], Transform(position=(5.0, 3.0, 0.0)))
            made["ball"] = ball(world, 6.0, x=5.0)

    app = App(title="ledge").add_plugins(MinimalPlugins, physics_plugin())
    app.add_startup_systems(setup)
    app.add_systems("update", move)
    app.run(frames=150)
    assert position(app.world, made["ledge"]) == pytest.approx((5.0, 3.0, 0.0))
    assert position(app.world, made["ball"])[1] == pytest.approx(3.25 + 0.5, abs=0.03)  # on the ledge, not the floor


def test_gravity_scale_and_damping_per_body():
    made = {}

    def setup(world, dt):
        made["half"] = world.spawn(
            Transform(position=(0.0, 50.0, 0.0)), RigidBody(gravity_scale=0.5), Collider(shape=SPHERE)
        )
        made["float"] = world.spawn(
            Transform(position=(3.0, 50.0, 0.0)), RigidBody(gravity_scale=0.0), Collider(shape=SPHERE)
        )
        made["drag"] = world.spawn(
            Transform(position=(-30.0, 50.0, 9.0)), RigidBody(gravity_scale=0.0, linear_damping=2.0),
            Collider(shape=SPHERE), Velocity(linear=(10.0, 0.0, 0.0)),
        )  # fmt: skip

    world, _ = simulate(setup, 60)
    assert 50.0 - position(world, made["half"])[1] == pytest.approx(0.5 * G / 2, rel=0.03)  # half of g/2 in 1 s
    assert position(world, made["float"])[1] == pytest.approx(50.0, abs=1e-6)
    # velocity times (1 - 2/60) a step, with the library's 0.05 beside it: about e^-2.05 after 1 s
    speed = world.get(made["drag"], Velocity).linear[0]
    assert speed == pytest.approx(10.0 * ((1 - 2.0 / 60) * (1 - 0.05 / 60)) ** 60, rel=0.02)
