"""Rewrite torus_knot.obj, the default demo model: a (2,3) torus knot as a smooth tube, centred, largest
extent 2.0. Plain numpy and fixed formatting, so the output is byte-for-byte reproducible.

    python demos/assets/make_torus_knot.py
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

OUT = Path(__file__).with_name("torus_knot.obj")


def torus_knot(
    p: int = 2, q: int = 3, segments: int = 256, sides: int = 24, tube: float = 0.4, size: float = 2.0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Positions (segments*sides, 3), unit normals and counter-clockwise triangles (0-based) of the tube."""
    t = np.arange(segments) * (2 * np.pi / segments)
    r = 2 + np.cos(q * t)
    curve = np.stack([r * np.cos(p * t), r * np.sin(p * t), -np.sin(q * t)], 1)
    tangent = np.stack(
        [
            -q * np.sin(q * t) * np.cos(p * t) - p * r * np.sin(p * t),
            -q * np.sin(q * t) * np.sin(p * t) + p * r * np.cos(p * t),
            -q * np.cos(q * t),
        ],
        1,
    )
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    # Frame by parallel transport (project the previous normal), so the tube does not twist ...
    normal = np.empty_like(curve)
    n = np.cross(tangent[0], [0.0, 0.0, 1.0])
    for i in range(segments):
        n = n - (n @ tangent[i]) * tangent[i]
        normal[i] = n = n / np.linalg.norm(n)
    # ... then spread the mismatch left where the loop closes evenly along it, so the seam is invisible.
    end = n - (n @ tangent[0]) * tangent[0]
    gap = np.arctan2(np.cross(normal[0], end) @ tangent[0], normal[0] @ end)
    angle = -gap * np.arange(segments) / segments
    binormal = np.cross(tangent, normal)
    normal, binormal = (
        np.cos(angle)[:, None] * normal + np.sin(angle)[:, None] * binormal,
        -np.sin(angle)[:, None] * normal + np.cos(angle)[:, None] * binormal,
    )
    theta = np.arange(sides) * (2 * np.pi / sides)
    normals = np.cos(theta)[None, :, None] * normal[:, None] + np.sin(theta)[None, :, None] * binormal[:, None]
    positions = (curve[:, None] + tube * normals).reshape(-1, 3)
    normals = normals.reshape(-1, 3)
    lo, hi = positions.min(0), positions.max(0)
    positions = (positions - (lo + hi) / 2) * (size / (hi - lo).max())
    i, j = np.meshgrid(np.arange(segments), np.arange(sides), indexing="ij")
    a, b = i * sides + j, i * sides + (j + 1) % sides
    c, d = (i + 1) % segments * sides + (j + 1) % sides, (i + 1) % segments * sides + j
    # Around the tube (j) then along it (i): (around) x (along) points outwards, so this winds CCW.
    faces = np.stack([a, b, c, a, c, d], -1).reshape(-1, 3)
    return positions, normals, faces


def obj_text(positions: np.ndarray, normals: np.ndarray, faces: np.ndarray) -> str:
    """OBJ with 6 decimals; vertex k uses normal k, so faces are written `f k//k ...`."""

    def fmt(values: np.ndarray) -> np.ndarray:
        return np.round(values, 6) + 0.0  # + 0.0 turns -0.0 into 0.0

    lines = ["# (2,3) torus knot tube, 256 x 24, written by make_torus_knot.py", "o torus_knot"]
    lines += [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in fmt(positions).tolist()]
    lines += [f"vn {x:.6f} {y:.6f} {z:.6f}" for x, y, z in fmt(normals).tolist()]
    lines += [f"f {a}//{a} {b}//{b} {c}//{c}" for a, b, c in (faces + 1).tolist()]
    return "\n".join(lines) + "\n"


def main(out: Path = OUT) -> Path:
    out.write_text(obj_text(*torus_knot()), encoding="ascii", newline="\n")
    return out


if __name__ == "__main__":
    print(f"wrote {main()}")
