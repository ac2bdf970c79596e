"""Spring integrators against the analytic solution: accuracy order, stability when stiffness
times dt squared is large, and the SpringSystem in a world."""

from __future__ import annotations

import numpy as np
import pytest

from ecs_engine import World
from ecs_engine.components import Spring, Transform, Velocity
from ecs_engine.maths.spring import INTEGRATORS, exact_coefficients, step
from ecs_engine.systems import SpringSystem


def analytic(x0: float, v0: float, k: float, c: float, m: float, t: float) -> float:
    """Closed-form damped oscillator (underdamped): independent of exact_coefficients."""
    w0 = np.sqrt(k / m)
    zeta = c / (2 * np.sqrt(k * m))
    assert zeta < 1
    wd = w0 * np.sqrt(1 - zeta * zeta)
    a = x0
    b = (v0 + zeta * w0 * x0) / wd
    return float(np.exp(-zeta * w0 * t) * (a * np.cos(wd * t) + b * np.sin(wd * t)))


def simulate(integrator: str, k: float, c: float, m: float, dt: float, steps: int, x0=1.0, v0=0.0):
    x = np.array([[x0, 0.0, 0.0]])
    v = np.array([[v0, 0.0, 0.0]])
    anchor = np.zeros((1, 3))
    peak = 0.0
    for _ in range(steps):
        step(integrator, x, v, anchor, k, c, m, dt)
        peak = max(peak, float(np.abs(x).max()) if np.isfinite(x).all() else np.inf)
    return float(x[0, 0]), peak


@pytest.mark.parametrize("integrator, order", [("explicit", 1), ("semi_implicit", 1), ("implicit", 1), ("rk4", 4)])
def test_accuracy_order_on_a_soft_spring(integrator, order):
    k, c, m, t = 10.0, 0.5, 1.0, 2.0
    exact_x = analytic(1.0, 0.0, k, c, m, t)
    errors = []
    for n in (400, 800, 1600):
        x, _ = simulate(integrator, k, c, m, t / n, n)
        errors.append(abs(x - exact_x))
    ratios = [errors[0] / errors[1], errors[1] / errors[2]]
    assert all(2**order * 0.8 < r < 2**order * 1.25 for r in ratios), (errors, ratios)


def test_exact_step_is_exact_for_any_dt():
    k, c, m = 10.0, 0.5, 1.0
    for dt, n in ((0.7, 3), (0.01, 200), (2.0, 1)):
        x, _ = simulate("exact", k, c, m, dt, n, x0=1.0, v0=-0.5)
        assert x == pytest.approx(analytic(1.0, -0.5, k, c, m, dt * n), abs=1e-12)


def test_exact_coefficients_cover_all_damping_regimes():
    # critically damped (c^2 = 4 k m): x(t) = (x0 + (v0 + w x0) t) e^(-w t)
    p00, p01, _, _ = exact_coefficients(4.0, 4.0, 1.0, 1.0)
    assert p00[0] == pytest.approx(3 * np.exp(-2.0)) and p01[0] == pytest.approx(np.exp(-2.0))
    # overdamped with a huge c*dt: no overflow, no NaN, and the spring has barely moved
    coeffs = exact_coefficients(1.0, 1e6, 1.0, 10.0)
    assert all(np.isfinite(p).all() for p in coeffs)
    assert coeffs[0][0] == pytest.approx(np.exp(-1e-5), rel=1e-6)


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_stiff_spring_at_a_long_step(integrator):
    """k dt^2 / m = 11 (omega dt = 3.3): explicit, semi-implicit and RK4 diverge; implicit
    and exact settle."""
    k, c, m, dt = 1e4, 10.0, 1.0, 1 / 30
    assert k * dt * dt / m > 10
    x, peak = simulate(integrator, k, c, m, dt, 300)
    if integrator in ("implicit", "exact"):
        assert peak <= 1.0 + 1e-12 and abs(x) < 1e-3
    else:
        assert not np.isfinite(peak) or peak > 1e6


def test_spring_system_pulls_toward_the_anchor_and_survives_a_hitch():
    world = World()
    eid = world.spawn(
        Transform(position=(5.0, 0.0, 0.0)), Velocity(), Spring(anchor=(0.0, 2.0, 0.0), stiffness=400.0, damping=4.0)
    )
    system = SpringSystem()
    for _ in range(600):
        world.run_system(system, 1 / 60)
    assert world.get(eid, Transform).position == pytest.approx([0.0, 2.0, 0.0], abs=1e-3)
    world.set(eid, Transform, position=np.array([5.0, 0.0, 0.0]))
    world.run_system(system, 5.0)  # a five-second hitch in one step
    p = world.get(eid, Transform).position
    assert np.isfinite(p).all() and np.linalg.norm(p - [0.0, 2.0, 0.0]) < np.linalg.norm([5.0, -2.0, 0.0])


def test_unknown_integrator_is_a_clear_error():
    with pytest.raises(ValueError, match="unknown integrator 'verlet'"):
        SpringSystem("verlet")
