"""Error against run time: spring integrators (explicit Euler, semi-implicit Euler, implicit
Euler, RK4, exact) on a soft and a stiff spring-damper at several time steps, and rendering
precision (pixels of error) against distance from the origin, camera-relative or not.

Integrators: the error is the largest position error after SIM_SECONDS against the analytic
solution (1,000 springs with random starts; the error does not depend on the count); the run
time is the median per step over 1,000,000 springs (STEP_ENTITIES), NumPy on one thread. A
configuration is unstable when a position leaves 1,000x its start or stops being finite.

Rendering precision: the float32 vertex path (model matrix, view, projection) emulated in
NumPy float32 against float64, for a unit cube 3 units in front of the camera at 1280x720:
the worst vertex error in pixels, over 64 camera positions 1 mm apart (the jitter a moving
camera shows). `camera_relative`: the position minus the camera in float64, then the cast (what
the engine does); `world_space`: positions cast to float32 first (RenderOrigin pinned at 0).

Rendered images: the scaling scene through each render mode, with and without culling, against
the most direct path (per-entity draws through the Python recorder, no culling): RMSE and PSNR
of the image against that reference, beside the frame's CPU and GPU time (needs a Vulkan device;
without one the section says {"skipped": why}).

JSON (schema_version 1): {"benchmark": "numerics", "quick", "machine", "config",
"integrators": [{"case", "stiffness", "damping", "integrator", "dt", "k_dt2", "error",
"ms_per_step", "unstable"}], "render_precision": [{"distance", "camera_relative_px",
"world_space_px"}], "render_error": {"skipped"} | {"entities", "size", "reference", "rows": [{"mode",
"recorder", "culling", "rmse", "psnr_db", "cpu_ms", "gpu_ms", "visible"}]}, "findings": [str]};
a plot `numerics-<slug>.png` beside it.
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from ecs_engine.maths.spring import INTEGRATORS, exact_coefficients, step

THREADS = 1
CASES = {"soft": (10.0, 0.5), "stiff": (1e4, 10.0)}  # stiffness, damping (mass 1)
DTS = (1 / 960, 1 / 480, 1 / 240, 1 / 120, 1 / 60, 1 / 30, 1 / 15)
SIM_SECONDS = 2.0
ERROR_ENTITIES = 1_000
STEP_ENTITIES = 1_000_000
DISTANCES = (1.0, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7)
WIDTH, HEIGHT = 1280, 720


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--entities", type=int, help=f"springs timed per step (default {STEP_ENTITIES:,})")


def integrator_error(integrator: str, k: float, c: float, dt: float, seconds: float, n: int) -> tuple[float, bool]:
    rng = np.random.default_rng(1)
    x0 = rng.uniform(-1, 1, (n, 3))
    v0 = rng.uniform(-1, 1, (n, 3))
    anchor = np.zeros((n, 3))
    x, v = x0.copy(), v0.copy()
    steps = max(1, round(seconds / dt))
    limit = 1e3 * np.abs(x0).max()
    unstable = False
    for _ in range(steps):
        step(integrator, x, v, anchor, k, c, 1.0, dt)
        if not np.isfinite(x).all() or np.abs(x).max() > limit:
            unstable = True
            break
    if unstable:
        return math.inf, True
    p00, p01, _, _ = exact_coefficients(k, c, 1.0, steps * dt)
    expected = p00[0] * x0 + p01[0] * v0
    return float(np.abs(x - expected).max()), False


def step_time_ms(integrator: str, k: float, c: float, dt: float, n: int, repeats: int) -> float:
    rng = np.random.default_rng(2)
    x = rng.uniform(-1, 1, (n, 3))
    v = np.zeros((n, 3))
    anchor = np.zeros((n, 3))
    kk, cc, mm = np.full(n, k), np.full(n, c), np.ones(n)  # per-entity columns, as in the ECS
    times = []
    for _ in range(repeats + 1):
        t0 = time.perf_counter()
        step(integrator, x, v, anchor, kk, cc, mm, dt)
        times.append(time.perf_counter() - t0)
        x = np.where(np.isfinite(x), x, 0.0)  # keep unstable runs timing real arithmetic
        v = np.where(np.isfinite(v), v, 0.0)
    return float(np.median(times[1:]) * 1e3)


def _look_at_view(eye: np.ndarray, target: np.ndarray, dtype: Any) -> np.ndarray:
    f = target - eye
    f = f / np.linalg.norm(f)
    r = np.cross(f, [0.0, 1.0, 0.0])
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    view = np.eye(4)
    view[0, :3], view[1, :3], view[2, :3] = r, u, -f
    view[:3, 3] = -view[:3, :3] @ eye
    return view.astype(dtype)


def projected_pixels(vertices: np.ndarray, center: np.ndarray, eye: np.ndarray, mode: str) -> np.ndarray:
    """(8, 2) pixel positions of the cube's corners through the emulated float32 path."""
    from ecs_engine.maths.camera import perspective

    proj = perspective(math.radians(50.0), WIDTH / HEIGHT, 0.05)  # float32, as the GPU gets it
    if mode == "exact":
        world = vertices.astype(np.float64) + center
        clip = proj.astype(np.float64) @ (_look_at_view(eye, center, np.float64) @ np.c_[world, np.ones(8)].T)
    else:
        if mode == "camera_relative":
            origin = eye  # subtract in float64, then cast
        else:
            origin = np.zeros(3)
        model_t = (center - origin).astype(np.float32)
        world = vertices.astype(np.float32) + model_t  # float32 arithmetic, as in the shader
        view = _look_at_view(eye - origin, center - origin, np.float32)  # made in float64, cast
        clip = proj @ (view @ np.c_[world, np.ones(8, np.float32)].T.astype(np.float32))
    ndc = clip[:2] / clip[3]
    return np.stack([(ndc[0] + 1) * 0.5 * WIDTH, (ndc[1] + 1) * 0.5 * HEIGHT], axis=1).astype(np.float64)


def render_error_px(distance: float, mode: str, positions: int = 64) -> float:
    corners = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)])
    direction = np.array([1.0, -0.3, 0.7]) / np.linalg.norm([1.0, -0.3, 0.7])
    center = direction * distance
    worst = 0.0
    for i in range(positions):
        eye = center + np.array([0.4, 0.9, 3.0]) + np.array([1e-3 * i, 0.0, 0.0])
        exact = projected_pixels(corners, center, eye, "exact")
        got = projected_pixels(corners, center, eye, mode)
        err = np.abs(got - exact).max()
        worst = max(worst, float(err) if np.isfinite(err) else math.inf)
    return worst


RENDER_CONFIGS = (
    ("per_entity", "python", False),
    ("per_entity", "native", False),
    ("per_entity", "native", True),
    ("instanced", "native", False),
    ("instanced", "native", True),
    ("indirect", "native", False),
    ("indirect", "native", True),
)


def render_error(entities: int, size: tuple[int, int], frames: int, warmup: int) -> dict[str, Any] | None:
    """Each render configuration's image against the first (the direct path), with its times."""
    import tempfile

    from ecs_engine.app.loop import run as run_scene
    from ecs_engine.app.settings import RunOptions
    from ecs_engine.errors import UsageError

    rows = []
    reference = None
    with tempfile.TemporaryDirectory() as tmp:
        for mode, recorder, culling in RENDER_CONFIGS:
            try:
                result = run_scene(
                    RunOptions(
                        scene="scaling",
                        entities=entities,
                        width=size[0],
                        height=size[1],
                        frames=warmup + frames,
                        quiet=True,
                        mode=mode,
                        recorder=recorder,
                        culling=culling,
                        screenshot=str(Path(tmp) / "shot.png"),
                    )
                )
            except UsageError as exc:  # no Vulkan loader or device here
                return {"skipped": str(exc)}
            pixels = result.pixels[..., :3].astype(np.float64)
            if reference is None:
                reference = pixels
            rmse = float(np.sqrt(np.mean((pixels - reference) ** 2)))
            gpu = result.gpu_ms[warmup:] or result.gpu_ms
            rows.append(
                {
                    "mode": mode,
                    "recorder": recorder,
                    "culling": culling,
                    "rmse": rmse,
                    "psnr_db": None if rmse == 0 else float(20 * np.log10(255.0 / rmse)),
                    "cpu_ms": float(np.mean(result.cpu_ms[warmup:])),
                    "gpu_ms": float(np.mean(gpu)) if gpu else None,
                    "visible": result.last_stats.instances,
                }
            )
    return {
        "entities": entities,
        "size": list(size),
        "reference": "per_entity, python recorder, no culling",
        "rows": rows,
    }


def plot(doc: dict[str, Any], path: Path) -> None:
    import matplotlib.ticker

    from . import pyplot, save_figure

    plt = pyplot()

    fig, axes = plt.subplots(1, 4, figsize=(21, 4.4))
    markers = dict(zip(INTEGRATORS, "osD^*"))
    for ax, case in zip(axes[:2], CASES):
        rows = [r for r in doc["integrators"] if r["case"] == case]
        finite = [r["error"] for r in rows if not r["unstable"] and r["error"] > 0]
        top = max(finite) * 10 if finite else 1.0
        for integ in INTEGRATORS:
            rr = sorted((r for r in rows if r["integrator"] == integ), key=lambda r: r["dt"])
            xs = [r["ms_per_step"] for r in rr]
            ys = [max(r["error"], 1e-16) if not r["unstable"] else top for r in rr]
            ax.plot(xs, ys, marker=markers[integ], label=integ, alpha=0.85)
            for r, x in zip(rr, xs):
                if r["unstable"]:
                    ax.plot([x], [top], marker="x", color="red", markersize=10)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.xaxis.set_major_formatter(matplotlib.ticker.FormatStrFormatter("%g"))
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.set_xlabel(f"ms per step, {doc['config']['step_entities']:,} springs")
        ax.set_ylabel(f"max position error after {SIM_SECONDS:g} s")
        k, c = CASES[case]
        ax.set_title(f"{case} spring (k={k:g}, c={c:g}); red x: unstable")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    ax = axes[2]
    rp = doc["render_precision"]
    ax.plot(
        [r["distance"] for r in rp],
        [max(r["camera_relative_px"], 1e-6) for r in rp],
        marker="o",
        label="camera-relative (the engine)",
    )
    ax.plot(
        [r["distance"] for r in rp],
        [max(r["world_space_px"], 1e-6) for r in rp],
        marker="s",
        label="float32 world space",
    )
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("distance from the world origin")
    ax.set_ylabel(f"worst vertex error, pixels at {WIDTH}x{HEIGHT}")
    ax.set_title("rendering precision")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    ax = axes[3]
    render = doc.get("render_error") or {}
    for r in render.get("rows", []):
        t = r["cpu_ms"] + (r["gpu_ms"] or 0.0)
        ax.plot([t], [r["rmse"]], marker="o")
        ax.annotate(
            f"{r['mode']} {r['recorder']}{' cull' if r['culling'] else ''}",
            (t, r["rmse"]),
            fontsize=7,
            rotation=30,
            xytext=(3, 3),
            textcoords="offset points",
        )
    ax.set_xscale("log")
    ax.set_xlabel("CPU + GPU ms per frame")
    ax.set_ylabel("image RMSE against the direct path (0-255)")
    ax.set_title(f"render paths, scaling scene ({render.get('entities', 0):,} entities)")
    ax.grid(True, which="both", alpha=0.3)
    save_figure(fig, path)


def findings(doc: dict[str, Any]) -> list[str]:
    out = []
    for case in CASES:
        rows = [r for r in doc["integrators"] if r["case"] == case]
        for integ in INTEGRATORS:
            rr = [r for r in rows if r["integrator"] == integ]
            bad = [r["dt"] for r in rr if r["unstable"]]
            if bad:
                out.append(
                    f"{case}: {integ} unstable from dt = 1/{round(1 / min(bad))} "
                    f"(k dt^2 = {CASES[case][0] * min(bad) ** 2:.3g})"
                )
            else:
                out.append(f"{case}: {integ} stable at every dt tried")
    render = doc.get("render_error") or {}
    if render.get("rows"):
        worst = max(render["rows"], key=lambda r: r["rmse"])
        fastest = min(render["rows"], key=lambda r: r["cpu_ms"] + (r["gpu_ms"] or 0.0))
        out.append(
            f"render paths: largest image RMSE against the direct path {worst['rmse']:.3g} "
            f"({worst['mode']}, culling {'on' if worst['culling'] else 'off'}); fastest: "
            f"{fastest['mode']} {fastest['recorder']}, culling {'on' if fastest['culling'] else 'off'}"
        )
    far = doc["render_precision"][-1]
    out.append(
        f"at {far['distance']:g} units from the origin: {far['camera_relative_px']:.2g} px camera-relative, "
        f"{far['world_space_px']:.3g} px in float32 world space"
    )
    return out


def run(args: argparse.Namespace, machine: dict[str, Any], progress: Any) -> dict[str, Any]:
    quick = bool(args.quick)
    step_entities = args.entities or (10_000 if quick else STEP_ENTITIES)
    dts = DTS[::3] if quick else DTS
    seconds = 0.5 if quick else SIM_SECONDS
    error_entities = 100 if quick else ERROR_ENTITIES
    repeats = 2 if quick else 5
    rows = []
    progress.total = len(CASES) + 2
    for case, (k, c) in CASES.items():
        with progress.step(f"{case} spring: {len(INTEGRATORS)} integrators x {len(dts)} steps"):
            for integ in INTEGRATORS:
                for dt in dts:
                    error, unstable = integrator_error(integ, k, c, dt, seconds, error_entities)
                    rows.append(
                        {
                            "case": case,
                            "stiffness": k,
                            "damping": c,
                            "integrator": integ,
                            "dt": dt,
                            "k_dt2": k * dt * dt,
                            "error": None if unstable else error,
                            "ms_per_step": step_time_ms(integ, k, c, dt, step_entities, repeats),
                            "unstable": unstable,
                        }
                    )
    precision = []
    with progress.step("rendering precision against distance"):
        for d in DISTANCES[::2] if quick else DISTANCES:
            precision.append(
                {
                    "distance": d,
                    "camera_relative_px": render_error_px(d, "camera_relative"),
                    "world_space_px": render_error_px(d, "world_space"),
                }
            )
    with progress.step("rendered images: each render path against the direct one"):
        render = render_error(
            300 if quick else 20_000, (160, 120) if quick else (1280, 720), 3 if quick else 12, 1 if quick else 4
        )
    doc = {
        "benchmark": "numerics",
        "schema_version": 1,
        "quick": quick,
        "machine": machine,
        "config": {
            "sim_seconds": seconds,
            "error_entities": error_entities,
            "step_entities": step_entities,
            "repeats": repeats,
            "dts": list(dts),
            "size": [WIDTH, HEIGHT],
        },
        "integrators": rows,
        "render_precision": precision,
        "render_error": render,
    }
    plot_doc = dict(doc, integrators=[dict(r, error=r["error"] if r["error"] is not None else 0.0) for r in rows])
    doc["findings"] = findings(plot_doc)
    out = Path(args.out) / f"numerics-{machine['slug']}.png"
    out.parent.mkdir(parents=True, exist_ok=True)
    plot(plot_doc, out)
    print(f"{'case':6} {'integrator':14} {'dt':>9} {'k dt^2':>9} {'error':>10} {'ms/step':>9}")
    for r in rows:
        err = "unstable" if r["unstable"] else f"{r['error']:.2e}"
        print(
            f"{r['case']:6} {r['integrator']:14} 1/{round(1 / r['dt']):<7} {r['k_dt2']:9.3g} {err:>10} "
            f"{r['ms_per_step']:9.3f}"
        )
    for p in precision:
        print(
            f"distance {p['distance']:9.0e}: camera-relative {p['camera_relative_px']:.3g} px, "
            f"world space {p['world_space_px']:.3g} px"
        )
    for r in (render or {}).get("rows", []):
        gpu = "n/a" if r["gpu_ms"] is None else f"{r['gpu_ms']:.2f}"
        print(
            f"{r['mode']:10} {r['recorder']:6} culling {'on ' if r['culling'] else 'off'}: RMSE {r['rmse']:.3g}, "
            f"cpu {r['cpu_ms']:.2f} ms, gpu {gpu} ms, {r['visible']} drawn"
        )
    for line in doc["findings"]:
        print(line)
    return doc
