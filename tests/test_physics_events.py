"""Physics events: Contact rows for bodies that touch (asked for) and Trigger rows for bodies
entering and leaving sensors (on by default)."""

from __future__ import annotations

import math

import pytest
from physics_world import G, ball, floor, physics_plugin

from ecs_engine import App, MinimalPlugins
from ecs_engine.components import Transform, Velocity
from ecs_engine.components.physics import BEGIN, END, SPHERE, STATIC, STAY, Collider, Contact, RigidBody, Trigger


def _events(setup, frames, more=(), **kw):
    """Every Contact and Trigger event of a run, as (step, rows) lists (`more`: systems run
    beside the listener, each frame)."""
    from ecs_engine import Time

    seen: dict = {"contacts": [], "triggers": []}

    def listen(world, dt):
        step = world.resources[Time].steps
        c, t = world.events(Contact).read(), world.events(Trigger).read()
        if len(c):
            seen["contacts"].append((step, c))
        if len(t):
            seen["triggers"].append((step, t))

    app = App(title="events").add_plugins(MinimalPlugins, physics_plugin(**kw))
    app.add_startup_systems(setup)
    app.add_systems("update", listen, *more)
    app.run(frames=frames)
    return seen


def test_a_bounce_is_a_contact_that_begins_and_ends_with_the_speed_it_met_at():
    made = {}
    h, e, m = 2.0, 0.5, 2.0

    def setup(world, dt):
        made["floor"] = floor(world)
        made["ball"] = world.spawn(
            Transform(position=(0.0, h + 0.5, 0.0)), RigidBody(mass=m), Collider(shape=SPHERE, restitution=e)
        )

    seen = _events(setup, 60, contacts="begin_end")
    first = seen["contacts"][0][1]
    assert set(first.phase) == {BEGIN}
    assert {int(first.a[0]), int(first.b[0])} == {made["floor"], made["ball"]}
    assert abs(first.point[0, 1]) < 0.1  # where the ball meets the floor's top
    assert abs(first.normal[0, 1]) == pytest.approx(1.0, abs=1e-3)
    # it met the floor at the speed of a fall from h: sqrt(2 g h), give or take a step's gravity
    assert first.speed[0] == pytest.approx(math.sqrt(2 * G * h), rel=0.05)
    phases = [int(p) for _, c in seen["contacts"] for p in c.phase]
    assert STAY not in phases and END in phases  # begin and end only, by default


@pytest.mark.parametrize(("m_a", "m_b", "e", "floor_under"), [(2.0, None, 0.5, True), (1.0, 3.0, 1.0, False)])
def test_a_contacts_impulse_is_the_momentum_the_collision_gives_a_body(m_a, m_b, e, floor_under):
    """Measured from the body's own velocity across the contact, not from the library: a ball
    bouncing on a floor (the impulse m (1 + e) v), and two balls meeting head on in space (the
    impulse (1 + e) v m_a m_b / (m_a + m_b))."""
    from ecs_engine import Time

    made, velocity = {}, {}

    def setup(world, dt):
        if floor_under:
            floor(world)
            made["a"] = world.spawn(
                Transform(position=(0.0, 2.5, 0.0)), RigidBody(mass=m_a), Collider(shape=SPHERE, restitution=e),
                Velocity(),
            )  # fmt: skip
        else:
            made["a"] = world.spawn(
                Transform(position=(-2.0, 0.0, 0.0)), RigidBody(mass=m_a), Collider(shape=SPHERE, restitution=e),
                Velocity(linear=(3.0, 0.0, 0.0)),
            )  # fmt: skip
            world.spawn(
                Transform(position=(2.0, 0.0, 0.0)), RigidBody(mass=m_b), Collider(shape=SPHERE, restitution=e),
                Velocity(),
            )  # fmt: skip

    def track(world, dt):
        velocity[world.resources[Time].steps] = world.get(made["a"], Velocity).linear.copy()

    seen = _events(setup, 90, contacts="begin_end", gravity=(0.0, -G if floor_under else 0.0, 0.0), more=[track])
    step, rows = seen["contacts"][0]
    assert rows.phase[0] == BEGIN and rows.impulse[0] > 1.0
    axis = 1 if floor_under else 0
    # its velocity along the normal a step before the contact was reported and two steps after,
    # less what gravity gave it over those three steps
    fell = -G * 3 / 60 if floor_under else 0.0
    change = m_a * abs(velocity[step + 2][axis] - velocity[step - 1][axis] - fell)
    assert rows.impulse[0] == pytest.approx(change, rel=0.03)
    ended = [c for _, c in seen["contacts"] if END in c.phase]
    assert ended and all((c.impulse[c.phase == END] == 0.0).all() for c in ended)


def test_stays_are_reported_when_asked():
    def setup(world, dt):
        floor(world)
        ball(world, 0.5)

    seen = _events(setup, 30, contacts="all")
    phases = [int(p) for _, c in seen["contacts"] for p in c.phase]
    assert phases[0] == BEGIN and phases.count(STAY) > 20


def test_a_body_entering_and_leaving_a_sensor_is_a_pair_of_triggers():
    made = {}

    def setup(world, dt):
        floor(world)
        made["zone"] = world.spawn(
            Transform(position=(0.0, 3.0, 0.0)), RigidBody(kind=STATIC), Collider(size=(1.0, 0.5, 1.0), sensor=True)
        )
        made["ball"] = ball(world, 6.0)

    seen = _events(setup, 120)  # (triggers only, by default)
    rows = [
        (step, int(t.sensor[i]), int(t.other[i]), bool(t.entered[i]))
        for step, t in seen["triggers"]
        for i in range(len(t))
    ]
    assert [(s, o, e) for _, s, o, e in rows] == [
        (made["zone"], made["ball"], True),
        (made["zone"], made["ball"], False),
    ]
    assert rows[0][0] < rows[1][0]
    assert seen["contacts"] == []  # contacts are asked for
    seen = _events(setup, 120, contacts="begin_end")
    touched = {(int(c.a[i]), int(c.b[i])) for _, c in seen["contacts"] for i in range(len(c))}
    assert touched and not any(made["zone"] in pair for pair in touched)  # the sensor pushed nothing


@pytest.mark.parametrize("stays", [False, True])
def test_the_compiled_pass_over_the_records_sorts_them_as_numpy_does(stays):
    """The records of balls falling through a sensor onto a floor (begin, stay and end rows,
    triggers among them), sorted by the compiled pass and by its NumPy twin: the same
    entities, phases, points, normals, speeds, impulses and triggers."""
    import numpy as np

    from ecs_engine.physics import contacts

    if contacts._sort is None:
        pytest.skip("the compiled pass needs numba")

    def setup(world, dt):
        floor(world)
        world.spawn(
            Transform(position=(0.0, 2.0, 0.0)), RigidBody(kind=STATIC), Collider(size=(3.0, 0.5, 3.0), sensor=True)
        )
        for k in range(6):
            ball(world, 3.0 + k, x=0.3 * k - 0.8)

    from physics_world import simulate

    _, physics = simulate(setup, 1, contacts="all")
    seen = {BEGIN: 0, STAY: 0, END: 0, "triggers": 0}
    impulses = 0
    for _ in range(150):
        physics.step(1 / 60)
        records = np.frombuffer(physics.native.get_contact_events_raw(), physics.contact_dtype)
        ours = contacts.sorted_records(records, physics, stays)
        theirs = contacts._sort_numpy(records, physics, stays)
        for x, y in zip(ours[0] + ours[1], theirs[0] + theirs[1]):
            assert x.dtype == y.dtype and np.array_equal(x, y)
        for p in ours[0][2]:
            seen[int(p)] += 1
        seen["triggers"] += len(ours[1][0])
        impulses += int((ours[0][6] > 0).sum())
    assert seen[BEGIN] >= 6 and seen[END] >= 1 and seen["triggers"] >= 6 and (seen[STAY] > 0) == stays
    assert impulses >= 6  # (the balls' impacts on the floor)
