"""Shapes for scenes and games, made in code: cube, sphere, plane, cylinder, cone, torus.

Each is centred on the origin, fits the unit box (largest extent 1, like the cube), winds
counter-clockwise seen from outside, and has texture coordinates ((0, 0) at the image's top-left,
glTF's convention) and tangents along +u. Seams are split (the first column of vertices is
repeated with u = 1) so a texture wraps once around without a smeared column, and hard edges (the
cube's, a cylinder's rims) have their own vertices so normals stay flat there.
"""

from __future__ import annotations

import inspect
from typing import Any, Final

import numpy as np

from .mesh_data import MeshData

__all__ = [
    "MAX_LENGTH",
    "PRIMITIVES",
    "cone_mesh",
    "cube_mesh",
    "cylinder_mesh",
    "plane_mesh",
    "primitive_vertices",
    "sphere_mesh",
    "torus_mesh",
]

#: The largest radius, height or size a primitive takes: past it float32 positions lose the
#: shape's detail (and 1e300 would overflow to inf).
MAX_LENGTH: Final = 1e6


def _grid_indices(rows: int, cols: int, first: int = 0) -> np.ndarray:
    """Two triangles per cell of a (rows + 1) x (cols + 1) vertex grid laid out row by row, counter-
    clockwise when the rows run along -v and the columns along +u seen from the front."""
    r, c = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
    a = first + r * (cols + 1) + c  # (row, col)
    b = a + 1  # (row, col + 1)
    d = a + cols + 1  # (row + 1, col)
    e = d + 1
    return np.stack([a, d, b, b, d, e], axis=-1).reshape(-1)


def _source(name: str, **args: Any) -> dict[str, Any]:
    """The recipe a saved scene keeps instead of the arrays (MeshData.source): maker and arguments."""
    return {"primitive": name, "args": {k: v.item() if isinstance(v, np.generic) else v for k, v in args.items()}}


def _checked(count: Any, name: str, least: int, shape: str = "") -> int:
    """`count` as an int of at least `least`; one ValueError naming the shape and argument else
    (a bool, a float, a string, None)."""
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < least:
        raise ValueError(f"{shape + ': ' if shape else ''}{name} must be an integer of at least {least}, got {count!r}")
    return int(count)


def _length(value: Any, name: str, shape: str) -> float:
    """`value` as a finite float in (0, MAX_LENGTH]: zero or negative lengths made degenerate
    shapes (and divisions by zero: a cone's slope, a cap's rim), NaN and inf non-finite ones."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"{shape}: {name} must be a number, got {value!r}")
    if not 0.0 < float(value) <= MAX_LENGTH:  # NaN fails this too
        raise ValueError(f"{shape}: {name} must be a finite number above 0 and at most {MAX_LENGTH:g}, got {value!r}")
    return float(value)


def _flag(value: Any, name: str, shape: str) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{shape}: {name} must be true or false, got {value!r}")
    return bool(value)


def cube_mesh() -> MeshData:
    """Unit cube centred at the origin: 24 vertices (4 per face, so normals stay flat), 36 indices,
    counter-clockwise from outside; each face maps the whole texture. The fallback model."""
    positions: list[np.ndarray] = []
    normals: list[np.ndarray] = []
    uvs: list[tuple[float, float]] = []
    indices: list[int] = []
    for axis in range(3):
        for sign in (1.0, -1.0):
            n = np.zeros(3)
            n[axis] = sign
            u = np.zeros(3)
            u[(axis + 1) % 3] = 1.0
            v = np.cross(n, u)  # u x v == n, so corners in (u, v) order wind counter-clockwise around n
            base = len(positions)
            for du, dv in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                positions.append((n + du * u + dv * v) / 2)
                normals.append(n)
                uvs.append(((du + 1) / 2, (1 - dv) / 2))  # +v in space is up the image
            indices += [base, base + 1, base + 2, base, base + 2, base + 3]
    return MeshData.from_arrays(
        np.array(positions), np.array(normals), np.array(indices), "cube", np.array(uvs), source=_source("cube")
    )


def sphere_mesh(segments: int = 32, rings: int = 16, radius: float = 0.5) -> MeshData:
    """A UV sphere: `segments` around the Y axis, `rings` from pole to pole; u runs around (from +X
    towards -Z, counter-clockwise seen from above), v from the north pole (0) to the south (1)."""
    segments, rings = _checked(segments, "segments", 3, "sphere"), _checked(rings, "rings", 2, "sphere")
    radius = _length(radius, "radius", "sphere")
    theta = np.linspace(0.0, np.pi, rings + 1)[:, None]  # from +Y
    phi = np.linspace(0.0, 2 * np.pi, segments + 1)[None, :]
    normals = np.stack(
        np.broadcast_arrays(np.sin(theta) * np.cos(phi), np.cos(theta), -np.sin(theta) * np.sin(phi)), -1
    ).reshape(-1, 3)
    u, v = np.meshgrid(np.linspace(0, 1, segments + 1), np.linspace(0, 1, rings + 1))
    tris = _grid_indices(rings, segments).reshape(-1, 3)
    # the cells touching a pole have two vertices at the pole: keep their one real triangle
    p = normals[tris]
    area = np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    return MeshData.from_arrays(
        normals * radius,
        normals,
        tris[area > 1e-12],
        "sphere",
        np.stack([u.ravel(), v.ravel()], -1),
        source=_source("sphere", segments=segments, rings=rings, radius=radius),
    )


def plane_mesh(size: float = 1.0, subdivisions: int = 1) -> MeshData:
    """A square in the XZ plane facing +Y, `size` on a side, cut into `subdivisions`^2 cells (more
    cells give per-vertex lighting and spot lights something to work with). u along +X, v along +Z."""
    n = _checked(subdivisions, "subdivisions", 1, "plane")
    size = _length(size, "size", "plane")
    s = np.linspace(0.0, 1.0, n + 1)
    u, v = np.meshgrid(s, s)  # rows along +v (+Z), columns along +u (+X)
    positions = np.stack([(u - 0.5) * size, np.zeros_like(u), (v - 0.5) * size], -1).reshape(-1, 3)
    normals = np.tile([0.0, 1.0, 0.0], (len(positions), 1))
    tris = _grid_indices(n, n).reshape(-1, 3)  # seen from +Y: +X right, +Z down the image
    uvs = np.stack([u.ravel(), v.ravel()], -1)
    return MeshData.from_arrays(
        positions, normals, tris, "plane", uvs, source=_source("plane", size=size, subdivisions=subdivisions)
    )


def _cap(y: float, radius: float, segments: int, first: int) -> tuple[np.ndarray, ...]:
    """A disc at height y facing up (y > 0) or down: a centre and a rim of its own vertices."""
    up = 1.0 if y > 0 else -1.0
    phi = np.linspace(0.0, 2 * np.pi, segments + 1)[:-1]
    rim = np.stack([np.cos(phi), np.full_like(phi, y / radius), -np.sin(phi)], -1) * radius
    positions = np.concatenate([[[0.0, y, 0.0]], rim])
    normals = np.tile([0.0, up, 0.0], (segments + 1, 1))
    uvs = np.concatenate([[[0.5, 0.5]], np.stack([0.5 + 0.5 * np.cos(phi), 0.5 - 0.5 * up * np.sin(phi)], -1)])
    k = np.arange(segments)
    a, b = first + 1 + k, first + 1 + (k + 1) % segments
    tris = np.stack([np.full(segments, first), a, b] if up > 0 else [np.full(segments, first), b, a], -1)
    return positions, normals, uvs, tris


def _solid_of_revolution(
    source: dict[str, Any],
    radius_at: np.ndarray,
    heights: np.ndarray,
    slope: float,
    segments: int,
    caps: list[tuple[float, float]],
) -> MeshData:
    """A side surface through rings of radius `radius_at[i]` at `heights[i]` (top first), its normals
    tilted by `slope` (d radius / d height), plus flat caps (height, radius)."""
    phi = np.linspace(0.0, 2 * np.pi, segments + 1)
    rings = len(heights)
    r = radius_at[:, None]
    positions = np.stack(np.broadcast_arrays(r * np.cos(phi), heights[:, None], -r * np.sin(phi)), -1).reshape(-1, 3)
    normal = np.stack(np.broadcast_arrays(np.cos(phi), -slope + 0 * heights[:, None], -np.sin(phi)), -1)
    normals = (normal / np.linalg.norm(normal, axis=-1, keepdims=True)).reshape(-1, 3)
    u, v = np.meshgrid(np.linspace(0, 1, segments + 1), np.linspace(0, 1, rings))
    parts_p, parts_n, parts_uv = [positions], [normals], [np.stack([u.ravel(), v.ravel()], -1)]
    tris = _grid_indices(rings - 1, segments).reshape(-1, 3)
    p = positions[tris]
    parts_t = [tris[np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1) > 1e-12]]
    first = len(positions)
    for y, radius in caps:
        cp, cn, cuv, ct = _cap(y, radius, segments, first)
        parts_p.append(cp)
        parts_n.append(cn)
        parts_uv.append(cuv)
        parts_t.append(ct)
        first += len(cp)
    return MeshData.from_arrays(
        np.concatenate(parts_p),
        np.concatenate(parts_n),
        np.concatenate(parts_t),
        source["primitive"],
        np.concatenate(parts_uv),
        source=source,
    )


def cylinder_mesh(segments: int = 32, radius: float = 0.5, height: float = 1.0, caps: bool = True) -> MeshData:
    """A cylinder along Y; u runs around the side, v from the top rim (0) to the bottom (1); the
    caps map a disc of the texture."""
    segments = _checked(segments, "segments", 3, "cylinder")
    radius, height = _length(radius, "radius", "cylinder"), _length(height, "height", "cylinder")
    caps = _flag(caps, "caps", "cylinder")
    h = height / 2
    return _solid_of_revolution(
        _source("cylinder", segments=segments, radius=radius, height=height, caps=caps),
        np.array([radius, radius]),
        np.array([h, -h]),
        0.0,
        segments,
        [(h, radius), (-h, radius)] if caps else [],
    )


def cone_mesh(segments: int = 32, radius: float = 0.5, height: float = 1.0, rings: int = 8) -> MeshData:
    """A cone along Y with its apex up and a base cap; the side has `rings` bands so its normals
    (tilted by radius / height) interpolate smoothly towards the apex."""
    segments, rings = _checked(segments, "segments", 3, "cone"), _checked(rings, "rings", 1, "cone")
    radius, height = _length(radius, "radius", "cone"), _length(height, "height", "cone")
    t = np.linspace(0.0, 1.0, rings + 1)
    h = height / 2
    source = _source("cone", segments=segments, radius=radius, height=height, rings=rings)
    return _solid_of_revolution(source, radius * t, h - height * t, -radius / height, segments, [(-h, radius)])


def torus_mesh(segments: int = 48, sides: int = 24, major: float = 0.35, minor: float = 0.15) -> MeshData:
    """A torus around Y: `segments` around the ring (u), `sides` around the tube (v, from the
    outer equator down and under)."""
    segments, sides = _checked(segments, "segments", 3, "torus"), _checked(sides, "sides", 3, "torus")
    major, minor = _length(major, "major", "torus"), _length(minor, "minor", "torus")
    if not minor < major:
        raise ValueError(f"torus: the tube radius (minor) must be below the ring's (major), got {minor} and {major}")
    phi = np.linspace(0.0, 2 * np.pi, segments + 1)[None, :]
    psi = np.linspace(0.0, 2 * np.pi, sides + 1)[:, None]
    ring = np.stack(np.broadcast_arrays(np.cos(phi), 0 * psi, -np.sin(phi)), -1)
    normals = (ring * np.cos(psi)[..., None] + np.array([0.0, 1.0, 0.0]) * np.sin(psi)[..., None]).reshape(-1, 3)
    positions = (ring * major).reshape(-1, 3) + normals * minor
    u, v = np.meshgrid(np.linspace(0, 1, segments + 1), np.linspace(1, 0, sides + 1))  # rows run over the top
    tris = _grid_indices(sides, segments).reshape(-1, 3)[:, ::-1]
    uvs = np.stack([u.ravel(), v.ravel()], -1)
    source = _source("torus", segments=segments, sides=sides, major=major, minor=minor)
    return MeshData.from_arrays(positions, normals, tris, "torus", uvs, source=source)


_COUNTS: Final = frozenset({"segments", "rings", "subdivisions", "sides"})

#: name -> maker with its defaults, for scenes and the editor
PRIMITIVES = {
    "cube": cube_mesh,
    "sphere": sphere_mesh,
    "plane": plane_mesh,
    "cylinder": cylinder_mesh,
    "cone": cone_mesh,
    "torus": torus_mesh,
}


def primitive_vertices(name: str, args: dict[str, Any]) -> int:
    """The vertices PRIMITIVES[name](**args) would make, worked out without making them, so a scene
    file's recipe can be refused before it allocates anything (scene_assets.py). Counts only: the
    maker checks the rest. Unknown names or arguments, or a count that is not an integer, raise
    ValueError naming them."""
    maker = PRIMITIVES.get(name)
    if maker is None:
        raise ValueError(f"unknown primitive {str(name)[:40]!r}; known: {', '.join(PRIMITIVES)}")
    defaults = {k: p.default for k, p in inspect.signature(maker).parameters.items()}
    unknown = sorted(set(args) - set(defaults))
    if unknown:
        known = ", ".join(defaults) or "none"
        raise ValueError(f"{name}: unknown argument {str(unknown[0])[:40]!r} (its arguments: {known})")
    count = {k: _checked(v, k, 1, name) for k, v in {**defaults, **args}.items() if k in _COUNTS}
    if name == "cube":
        return 24
    if name == "sphere":
        return (count["segments"] + 1) * (count["rings"] + 1)
    if name == "plane":
        return (count["subdivisions"] + 1) ** 2
    if name == "cylinder":
        return 2 * (count["segments"] + 1) + (2 * (count["segments"] + 1) if args.get("caps", True) else 0)
    if name == "cone":
        return (count["segments"] + 1) * (count["rings"] + 1) + count["segments"] + 1
    return (count["segments"] + 1) * (count["sides"] + 1)  # torus
