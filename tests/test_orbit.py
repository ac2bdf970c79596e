"""Orbit animation: positions after a few steps against the closed-form circle, over several
tables, with phase kept wrapped."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ecs_engine import Schedule, World
from ecs_engine.components.light import PointLight
from ecs_engine.components.orbit import Orbit
from ecs_engine.components.transform import Transform
from ecs_engine.systems.orbit import OrbitSystem


def expected(center, radius, height, phase):
    return np.stack(
        [center[:, 0] + radius * np.cos(phase), center[:, 1] + height, center[:, 2] + radius * np.sin(phase)], axis=1
    )


def test_positions_follow_the_formula_over_several_steps_and_tables():
    rng = np.random.default_rng(11)
    n = 64
    center = rng.normal(scale=100.0, size=(n, 3))
    radius = rng.uniform(0.0, 10.0, n)
    speed = rng.uniform(-3.0, 3.0, n)
    phase0 = rng.uniform(-10.0, 10.0, n)
    height = rng.uniform(-2.0, 5.0, n)
    w = World()
    ids = w.spawn_batch(n, Orbit(center=center, radius=radius, angular_speed=speed, phase=phase0, height=height))
    lights = w.spawn_batch(3, Orbit(radius=2.0, angular_speed=0.5, height=1.0), PointLight())
    schedule = Schedule()
    schedule.add(OrbitSystem())
    dts = [1 / 60, 0.1, 0.5, 2.0]
    for dt in dts:
        schedule.run(w, dt)
    phase = phase0 + speed * sum(dts)
    got = np.stack([w.get(e, Transform).position for e in ids])
    assert np.allclose(got, expected(center, radius, height, phase), rtol=0, atol=1e-9)
    stored = np.array([w.get(e, Orbit).phase for e in ids])
    assert ((stored >= 0) & (stored < 2 * math.pi)).all()
    assert np.allclose(np.cos(stored), np.cos(phase), atol=1e-12)
    assert np.allclose(np.sin(stored), np.sin(phase), atol=1e-12)
    p = w.get(lights[0], Transform).position
    t = 0.5 * sum(dts)
    assert np.allclose(p, [2.0 * math.cos(t), 1.0, 2.0 * math.sin(t)], atol=1e-12)


def test_quarter_turn_goes_from_plus_x_to_plus_z():
    w = World()
    e = w.spawn(Orbit(center=(1.0, 2.0, 3.0), radius=4.0, angular_speed=math.pi / 2, height=0.5))
    schedule = Schedule()
    schedule.add(OrbitSystem())
    schedule.run(w, 0.0)
    assert np.allclose(w.get(e, Transform).position, [5.0, 2.5, 3.0])
    schedule.run(w, 1.0)
    assert np.allclose(w.get(e, Transform).position, [1.0, 2.5, 7.0])


def test_orbit_only_moves_position_and_validates_values():
    w = World()
    q = np.array([0.0, 0.6, 0.0, 0.8])
    e = w.spawn(Orbit(radius=1.0), Transform(rotation=q, scale=(2.0, 2.0, 2.0)))
    s = OrbitSystem()
    assert s.writes == frozenset({Orbit, Transform})
    w.run_system(s, 0.1)
    t = w.get(e, Transform)
    assert np.allclose(t.rotation, q) and t.scale.tolist() == [2.0, 2.0, 2.0]
    for bad in (dict(radius=-1.0), dict(angular_speed=math.inf), dict(center=(0.0, math.nan, 0.0))):
        with pytest.raises(ValueError):
            w.spawn(Orbit(**bad))


def test_native_step_matches_the_numpy_reference():
    from ecs_engine.systems.orbit import orbit_step, orbit_step_numpy

    rng = np.random.default_rng(3)
    n = 40
    args = [rng.normal(size=(n, 3)), rng.uniform(0, 5, n), rng.uniform(-4, 4, n)]
    height = rng.normal(size=n)
    phases = [rng.uniform(-20, 20, n) for _ in range(2)]
    positions = [np.zeros((n, 3)) for _ in range(2)]
    phases[1][:] = phases[0]
    orbit_step(*args, phases[0], height, positions[0], 0.37)
    orbit_step_numpy(*args, phases[1], height, positions[1], 0.37)
    assert np.allclose(phases[0], phases[1], atol=1e-12)
    assert np.allclose(positions[0], positions[1], atol=1e-12)
