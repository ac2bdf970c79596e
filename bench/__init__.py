"""Benchmarks for ecs_engine: `ecs-engine bench NAME [--quick] [--out DIR] [--machine SLUG]` (or
`python -m ecs_engine.bench ...`; `ecs-engine bench --help` lists them).

Each benchmark is a module registered in `bench.__main__.REGISTRY`. It provides
`add_arguments(parser)` (optional, for its own options), `preflight(args)` (optional: raises
ecs_engine.errors.UsageError, reported as one line and exit 2 before anything is printed, when
the benchmark cannot run here, e.g. an optional extra is missing), `THREADS` (the thread count it uses,
recorded in the machine description) and `run(args, machine, progress) -> dict` returning the JSON
document that `bench.__main__` writes to `<out>/<name>-<slug>.json`. Anything else it writes (a
plot) goes under `args.out` too, never beside the code.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Iterator
from contextlib import ExitStack, contextmanager
from typing import Any, TextIO


class Progress:
    """Progress lines on stderr: one line when a step starts, one with its elapsed time; with
    `total` steps set (a benchmark that knows them sets it), a bar of the steps done."""

    def __init__(self, name: str, stream: TextIO | None = None, enabled: bool = True) -> None:
        self.name = name
        self.stream = stream
        self.enabled = enabled
        self.start = time.perf_counter()
        self.steps = 0
        self.total: int | None = None
        self.done = 0

    def _write(self, text: str) -> None:
        if self.enabled:
            stream = self.stream if self.stream is not None else sys.stderr
            bar = ""
            if self.total:
                filled = round(20 * min(self.done, self.total) / self.total)
                bar = f" [{'#' * filled}{'.' * (20 - filled)}] {self.done}/{self.total}"
            print(f"[{self.name} {time.perf_counter() - self.start:7.1f}s{bar}] {text}", file=stream, flush=True)

    def note(self, text: str) -> None:
        self._write(text)

    @contextmanager
    def step(self, what: str) -> Iterator[None]:
        self.steps += 1
        self._write(f"{what} ...")
        t0 = time.perf_counter()
        yield
        self.done += 1
        self._write(f"{what}: {time.perf_counter() - t0:.2f} s")


def pyplot() -> Any:
    """matplotlib's pyplot on the Agg backend: plots are written as PNG, no display needed."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save_figure(fig: Any, path: Any) -> None:
    """Lay out, write the PNG beside the benchmark's JSON, and free the figure."""
    import matplotlib.pyplot as plt

    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


@contextmanager
def headless_gpu(width: int, height: int) -> Iterator[tuple[Any, Any, Any]]:
    """(device, offscreen target, mesh registry) for a Vulkan benchmark, destroyed in reverse
    order however the benchmark ends, including when one of them fails to be made."""
    from ecs_engine.gpu.device import Device
    from ecs_engine.gpu.instance import Instance
    from ecs_engine.gpu.offscreen import OffscreenTarget
    from ecs_engine.render.assets.mesh_registry import MeshRegistry

    with ExitStack() as made:
        instance = Instance()
        made.callback(instance.destroy)
        device = Device(instance)
        made.callback(device.destroy)
        target = OffscreenTarget(device, width, height)
        made.callback(target.destroy)
        meshes = MeshRegistry(device)
        made.callback(meshes.destroy)
        yield device, target, meshes


def ratio_verdict(measured: float | None, baseline: float | None, limit: float) -> dict[str, Any]:
    """A ratio target's entries: measured / baseline (None without both), the limit, whether met."""
    ratio = measured / baseline if measured is not None and baseline else None
    return {"ratio": ratio, "limit": limit, "met": None if ratio is None else ratio <= limit}


def timed_frames(
    world: Any, schedule: Any, renderer: Any, warmup: int, frames: int, warm: Any = None
) -> dict[str, float | None]:
    """`warmup` then `frames` frames of 1/60 s: the medians of the CPU frame (the schedule and
    the render, minus waits for the GPU) and of the GPU frame (timestamps, a frame late; None
    when the device gave none), after the device has finished. `warm()`: called once, when the
    warm-up frames are done."""
    import statistics

    cpu: list[float] = []
    gpu: list[float] = []
    for i in range(warmup + frames):
        if i == warmup and warm is not None:
            warm()
        t0 = time.perf_counter()
        schedule.run(world, 1.0 / 60.0)
        stats = renderer.render(world)
        if i >= warmup:
            cpu.append((time.perf_counter() - t0) * 1e3 - stats.wait_ms)
            if stats.gpu_ms is not None:
                gpu.append(stats.gpu_ms)
    renderer.device.wait_idle()
    return {"cpu_ms": statistics.median(cpu), "gpu_ms": statistics.median(gpu) if gpu else None}
