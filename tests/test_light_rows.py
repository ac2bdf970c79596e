"""Light rows: the native kernel and the NumPy reference write the same rows, relative to the
origin and sorted far to near from the eye, across several tables."""

from __future__ import annotations

import numpy as np
import pytest

from ecs_engine.render import light_rows
from ecs_engine.render.light_rows import LIGHT_DTYPE, write_lights, write_lights_numpy


def parts(rng: np.random.Generator, sizes: list[int]) -> list[tuple[np.ndarray, ...]]:
    return [
        (
            rng.normal(scale=50.0, size=(n, 3)) + 1e7,
            rng.uniform(1, 9, n).astype(np.float32),
            rng.uniform(0, 1, (n, 3)).astype(np.float32),
            rng.uniform(0, 5, n).astype(np.float32),
        )
        for n in sizes
    ]


@pytest.mark.parametrize("sizes", [[1], [7], [5, 3, 40]])
def test_rows_are_relative_and_sorted_far_to_near(sizes):
    rng = np.random.default_rng(sum(sizes))
    columns = parts(rng, sizes)
    origin = np.array([1e7, 1e7, 1e7])
    eye = np.array([3.0, -2.0, 1.0])
    total = sum(sizes)
    out = np.zeros((total, 8), np.float32)
    write_lights(columns, origin, eye, out)
    position = np.concatenate([c[0] for c in columns])
    rel = position - origin
    order = np.argsort(-((rel - eye) ** 2).sum(axis=1), kind="stable")
    assert np.array_equal(out[:, :3], rel[order].astype(np.float32))
    assert np.array_equal(out[:, 3], np.concatenate([c[1] for c in columns])[order])
    assert np.array_equal(out[:, 4:7], np.concatenate([c[2] for c in columns])[order])
    assert np.array_equal(out[:, 7], np.concatenate([c[3] for c in columns])[order])
    reference = np.zeros_like(out)
    write_lights_numpy(*[np.concatenate([c[k] for c in columns]) for k in range(4)], origin, eye, reference)
    assert np.array_equal(out, reference)
    assert out.view(LIGHT_DTYPE).shape == (total, 1)


def test_equal_distances_keep_their_order():
    columns = [
        (
            np.array([[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0], [0, 0, 3.0]]),
            np.arange(4, dtype=np.float32),
            np.zeros((4, 3), np.float32),
            np.ones(4, np.float32),
        )
    ]
    out = np.zeros((4, 8), np.float32)
    write_lights(columns, np.zeros(3), np.zeros(3), out)
    assert out[:, 3].tolist() == [3.0, 0.0, 1.0, 2.0]


def test_without_numba_the_reference_runs(monkeypatch):
    monkeypatch.setattr(light_rows, "_write_lights_native", None)
    test_rows_are_relative_and_sorted_far_to_near([5, 3, 40])
