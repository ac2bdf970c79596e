"""Golden-image helpers shared by the rendering tests (tolerance: see golden/README.md)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from PIL import Image

GOLDEN = Path(__file__).resolve().parent / "golden"
SIZE = (160, 120)


def image_difference(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    diff = np.abs(a.astype(np.int16) - b.astype(np.int16))[..., :3]
    return float(diff.mean()), float((diff.max(axis=-1) > 24).mean())


def assert_close_to_golden(pixels: np.ndarray, name: str) -> None:
    path = GOLDEN / f"{name}.png"
    if os.environ.get("ECS_ENGINE_UPDATE_GOLDEN") == "1":
        Image.fromarray(pixels[..., :3]).save(path)
    reference = np.asarray(Image.open(path).convert("RGB"))
    mean, outliers = image_difference(pixels[..., :3], reference)
    assert mean <= 1.5 and outliers <= 0.005, f"{name}: mean diff {mean:.2f}, {outliers:.2%} pixels off"
