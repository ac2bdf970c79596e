"""The specular mip chain of an environment map: each level below the sharp one holds the sky
blurred by a GGX lobe of a roughness that grows with the level (Karis 2013, "Real shading in
Unreal Engine 4": the split sum's first factor, with n = v = r), so the shader's
`textureLod(environment, reflect(-v, n), roughness * R)` reads the right blur.

- Level k of R roughness levels holds roughness min(k / R, 1) (alpha = roughness^2, as the lights
  use). R = `roughness_levels(levels)`: every level but the last two, so the roughest lobe lands
  on 4 x 4 faces, not on 1 x 1 ones that cannot hold its direction; the levels below it repeat
  roughness 1.
- Each texel sums light directions importance-sampled from the GGX lobe (a Hammersley set),
  weighted by n.l, each read from the box-filtered chain at the level whose texel covers the
  sample's solid angle (Krivanek and Colbert 2008, "filtered importance sampling", without their
  +1 bias, which blurred beyond the lobe): few samples, no fireflies from bright small suns.
  Level k takes SAMPLES * 2^(k-1) (at most MAX_SAMPLES): its faces have a quarter of the texels
  of the level above, so the whole chain costs about twice its first blurred level. Faces of
  SMALL texels or fewer take MAX_SAMPLES (cheap there, and they hold the widest lobes).
- numba compiles the loop (GIL released), run over blocks of texels on the job pool when one is
  given (a 1024 map's chain is about 100M samples: ~12 s on one slow core); without numba the
  same sums run in NumPy, vectorised over the texels of a level (tests compare the two and both
  against a brute-force integral).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any, Final

import numpy as np

from ... import native
from ..shadows.views import CUBE_FACES
from .environment_maps import cube_directions, cube_mips

__all__ = ["MAX_SAMPLES", "SAMPLES", "ggx_prefiltered_mips", "level_roughness", "roughness_levels"]

SAMPLES: Final = 64
MAX_SAMPLES: Final = 1024
SMALL: Final = 16
BLOCK: Final = 8192  # texels per job
_FACE_AXES = np.ascontiguousarray(np.array(CUBE_FACES, dtype=np.float64))  # (face, forward/s/t, xyz)


def roughness_levels(levels: int) -> int:
    """R: the mip level that holds roughness 1 (the shader's GLOBALS.environment.y)."""
    return levels - 1 if levels <= 3 else levels - 3


def level_roughness(level: int, levels: int) -> float:
    r = roughness_levels(levels)
    return 1.0 if r == 0 else min(level / r, 1.0)


def _hammersley(n: int) -> np.ndarray:
    """(n, 2) float64: (i / n, the base-2 radical inverse of i)."""
    i = np.arange(n, dtype=np.int64)
    inverse = np.zeros(n)
    digits, scale = i.copy(), 0.5
    while digits.any():
        inverse += scale * (digits & 1)
        digits >>= 1
        scale *= 0.5
    return np.stack([i / n, inverse], axis=1)


def _lobe(alpha: float, samples: int) -> tuple[np.ndarray, np.ndarray]:
    """The half vectors of the GGX lobe around +z, (samples, 3), and the source level bias of each
    sample: 0.5 log2 of its solid angle 1 / (samples pdf) over a base texel's, pdf(l) = D(h) / 4
    when n = v. Add 0.5 log2(6 S^2 / 4 pi) for a base face of side S."""
    xi = _hammersley(samples)
    a2 = alpha * alpha
    cos_t = np.sqrt((1.0 - xi[:, 1]) / (1.0 + (a2 - 1.0) * xi[:, 1]))
    sin_t = np.sqrt(np.maximum(1.0 - cos_t * cos_t, 0.0))
    phi = 2.0 * math.pi * xi[:, 0]
    h = np.stack([sin_t * np.cos(phi), sin_t * np.sin(phi), cos_t], axis=1)
    d = a2 / (math.pi * np.square(cos_t * cos_t * (a2 - 1.0) + 1.0))
    pdf = d / 4.0
    return h, 0.5 * np.log2(1.0 / (samples * pdf))


def _frames(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Tangent and bitangent of unit normals (..., 3) (the up vector switches near the poles)."""
    up = np.zeros_like(n)
    polar = np.abs(n[..., 2]) > 0.999
    up[..., 0] = polar
    up[..., 2] = ~polar
    t = np.cross(up, n)
    t /= np.linalg.norm(t, axis=-1, keepdims=True)
    return t, np.cross(n, t)


def _flatten(chain: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The chain's levels packed into one float32 array, with each level's offset and side."""
    offsets = np.cumsum([0] + [level.size for level in chain[:-1]]).astype(np.int64)
    sides = np.array([level.shape[1] for level in chain], np.int64)
    return np.concatenate([level.ravel() for level in chain]).astype(np.float32), offsets, sides


def _texel_numpy(
    flat: np.ndarray, offset: int, side: int, face: np.ndarray, row: np.ndarray, col: np.ndarray
) -> np.ndarray:
    index = offset + ((face * side + row) * side + col) * 3
    return flat[index[..., None] + np.arange(3)]


def _fetch_numpy(flat, offsets, sides, d, lod) -> np.ndarray:  # type: ignore[no-untyped-def]
    """Trilinear reads of the packed chain along directions d (M, 3) at levels lod (M,)."""
    axis = np.argmax(np.abs(d), axis=1)
    major = d[np.arange(len(d)), axis]
    face = 2 * axis + (major < 0)
    inverse = 1.0 / np.abs(major)
    sc = np.einsum("ij,ij->i", d, _FACE_AXES[face, 1]) * inverse
    tc = np.einsum("ij,ij->i", d, _FACE_AXES[face, 2]) * inverse
    top = len(sides) - 1
    lod = np.clip(lod, 0.0, float(top))
    low = np.minimum(lod.astype(np.int64), top)
    result = np.zeros((len(d), 3))
    for level in np.unique(np.concatenate([low, np.minimum(low + 1, top)])):
        side, offset = int(sides[level]), int(offsets[level])
        weight = np.where(low == level, 1.0 - (lod - low), 0.0) + np.where(
            np.minimum(low + 1, top) == level, lod - low, 0.0
        )
        pick = weight > 0.0
        if not pick.any():
            continue
        x = (sc[pick] + 1.0) * 0.5 * side - 0.5
        y = (tc[pick] + 1.0) * 0.5 * side - 0.5
        x0 = np.clip(np.floor(x), 0, side - 1).astype(np.int64)
        y0 = np.clip(np.floor(y), 0, side - 1).astype(np.int64)
        x1, y1 = np.minimum(x0 + 1, side - 1), np.minimum(y0 + 1, side - 1)
        fx = np.clip(x - x0, 0.0, 1.0)[:, None]
        fy = np.clip(y - y0, 0.0, 1.0)[:, None]
        f = face[pick]

        def row(y: np.ndarray, f=f, side=side, offset=offset, x0=x0, x1=x1, fx=fx) -> np.ndarray:  # type: ignore[no-untyped-def]
            left, right = _texel_numpy(flat, offset, side, f, y, x0), _texel_numpy(flat, offset, side, f, y, x1)
            return left * (1 - fx) + right * fx

        value = row(y0) * (1 - fy) + row(y1) * fy
        result[pick] += value * weight[pick, None]
    return result


def _prefilter_numpy(flat, offsets, sides, normals, half, bias):
    n = normals.reshape(-1, 3)
    t, b = _frames(n)
    total = np.zeros_like(n)
    weight = np.zeros(len(n))
    for h, level_bias in zip(half, bias):
        hv = t * h[0] + b * h[1] + n * h[2]
        nh = h[2]
        light = 2.0 * nh * hv - n
        nl = np.einsum("ij,ij->i", n, light)
        lit = nl > 0.0
        if not lit.any():
            continue
        lod = np.full(int(lit.sum()), level_bias)
        total[lit] += _fetch_numpy(flat, offsets, sides, light[lit], lod) * nl[lit, None]
        weight[lit] += nl[lit]
    return (total / np.maximum(weight, 1e-12)[:, None]).reshape(normals.shape)


@native.inner
def _fetch_native(flat, offsets, sides, axes, x, y, z, lod, out):  # pragma: no cover - compiled
    ax, ay, az = abs(x), abs(y), abs(z)
    if ax >= ay and ax >= az:
        face = 0 if x >= 0.0 else 1
        inverse = 1.0 / ax
    elif ay >= az:
        face = 2 if y >= 0.0 else 3
        inverse = 1.0 / ay
    else:
        face = 4 if z >= 0.0 else 5
        inverse = 1.0 / az
    sc = (x * axes[face, 1, 0] + y * axes[face, 1, 1] + z * axes[face, 1, 2]) * inverse
    tc = (x * axes[face, 2, 0] + y * axes[face, 2, 1] + z * axes[face, 2, 2]) * inverse
    top = sides.shape[0] - 1
    lod = min(max(lod, 0.0), float(top))
    low = min(int(lod), top)
    frac = lod - low
    out[0] = 0.0
    out[1] = 0.0
    out[2] = 0.0
    for step in range(2):
        level = min(low + step, top)
        w = 1.0 - frac if step == 0 else frac
        if w <= 0.0:
            continue
        side = sides[level]
        base = offsets[level] + face * side * side * 3
        fx_ = (sc + 1.0) * 0.5 * side - 0.5
        fy_ = (tc + 1.0) * 0.5 * side - 0.5
        x0 = min(max(math.floor(fx_), 0), side - 1)
        y0 = min(max(math.floor(fy_), 0), side - 1)
        x1 = min(x0 + 1, side - 1)
        y1 = min(y0 + 1, side - 1)
        fx = min(max(fx_ - x0, 0.0), 1.0)
        fy = min(max(fy_ - y0, 0.0), 1.0)
        for c in range(3):
            top_row = flat[base + (y0 * side + x0) * 3 + c] * (1.0 - fx) + flat[base + (y0 * side + x1) * 3 + c] * fx
            bottom = flat[base + (y1 * side + x0) * 3 + c] * (1.0 - fx) + flat[base + (y1 * side + x1) * 3 + c] * fx
            out[c] += w * (top_row * (1.0 - fy) + bottom * fy)


@native.njit
def _prefilter_native(flat, offsets, sides, axes, normals, half, bias, out):  # pragma: no cover - compiled
    value = np.zeros(3)
    for i in range(normals.shape[0]):
        nx, ny, nz = normals[i, 0], normals[i, 1], normals[i, 2]
        if abs(nz) > 0.999:
            ux, uy, uz = 1.0, 0.0, 0.0
        else:
            ux, uy, uz = 0.0, 0.0, 1.0
        tx, ty, tz = uy * nz - uz * ny, uz * nx - ux * nz, ux * ny - uy * nx
        length = math.sqrt(tx * tx + ty * ty + tz * tz)
        tx, ty, tz = tx / length, ty / length, tz / length
        bx, by, bz = ny * tz - nz * ty, nz * tx - nx * tz, nx * ty - ny * tx
        r = 0.0
        g = 0.0
        b = 0.0
        weight = 0.0
        for k in range(half.shape[0]):
            hx = tx * half[k, 0] + bx * half[k, 1] + nx * half[k, 2]
            hy = ty * half[k, 0] + by * half[k, 1] + ny * half[k, 2]
            hz = tz * half[k, 0] + bz * half[k, 1] + nz * half[k, 2]
            nh2 = 2.0 * half[k, 2]
            lx, ly, lz = nh2 * hx - nx, nh2 * hy - ny, nh2 * hz - nz
            nl = nx * lx + ny * ly + nz * lz
            if nl <= 0.0:
                continue
            _fetch_native(flat, offsets, sides, axes, lx, ly, lz, bias[k], value)
            r += value[0] * nl
            g += value[1] * nl
            b += value[2] * nl
            weight += nl
        weight = max(weight, 1e-12)
        out[i, 0] = r / weight
        out[i, 1] = g / weight
        out[i, 2] = b / weight


Mapper = Callable[[Callable[[Any], Any], Sequence[Any]], list[Any]]


def _serial(fn: Callable[[Any], Any], chunks: Sequence[Any]) -> list[Any]:
    return [fn(chunk) for chunk in chunks]


def ggx_prefiltered_mips(
    faces: np.ndarray, samples: int = SAMPLES, map_blocks: Mapper | None = None
) -> list[np.ndarray]:
    """The cube's mip chain for the shader's specular reads: level 0 the faces themselves, each
    level below it the faces seen through the GGX lobe of `level_roughness` (float32, (6, S, S, 3)
    per level, down to 1 x 1), `samples` at the first blurred level. `map_blocks` (JobPool.map)
    spreads blocks of texels over threads. S must be a power of two (ValueError otherwise, as
    cube_mips)."""
    box = cube_mips(faces)
    flat, offsets, sides = _flatten(box)
    levels = len(box)
    base_bias = 0.5 * math.log2(6.0 * int(sides[0]) ** 2 / (4.0 * math.pi))
    chain = [box[0]]
    for level in range(1, levels):
        roughness = level_roughness(level, levels)
        count = MAX_SAMPLES if sides[level] <= SMALL else min(samples << (level - 1), MAX_SAMPLES)
        half, bias = _lobe(max(roughness * roughness, 1e-4), count)
        bias = bias + base_bias
        normals = cube_directions(int(sides[level])).reshape(-1, 3)
        out = np.empty_like(normals)

        def block(start: int, normals: np.ndarray = normals, out: np.ndarray = out, half=half, bias=bias) -> None:  # type: ignore[no-untyped-def]
            rows = slice(start, start + BLOCK)
            if native.AVAILABLE:
                _prefilter_native(flat, offsets, sides, _FACE_AXES, normals[rows], half, bias, out[rows])  # type: ignore[misc]
            else:
                out[rows] = _prefilter_numpy(flat, offsets, sides, normals[rows], half, bias)

        (map_blocks or _serial)(block, range(0, len(normals), BLOCK))
        chain.append(out.reshape(box[level].shape).astype(np.float32))
    return chain
