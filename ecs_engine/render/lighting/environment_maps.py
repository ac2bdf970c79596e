"""Environment maps on the CPU: an image of the sky all around becomes the six faces of a cube
map (linear RGB, float32), its box-filtered mip chain (environment_prefilter.py blurs the
specular levels from it), and the nine spherical-harmonic coefficients of its diffuse light,
which the GPU side uploads and samples.

- Cube faces come in Vulkan's layer order (+X, -X, +Y, -Y, +Z, -Z: CUBE_FACE_NAMES) and
  orientation (the spec's cube map face selection, CUBE_FACES in shadow_views.py): on a face with
  forward axis f, s axis a and t axis b, texel (row, column) looks along f + a sc + b tc, where
  sc, tc in [-1, 1] are the column's and row's centres (row 0 at t = 0, the top of the image).
- Equirectangular maps are twice as wide as tall; direction d is at u = 0.5 + atan2(d.x, -d.z) /
  (2 pi), v = acos(d.y) / pi: the centre looks down -Z (the engine's forward), u = 0.75 towards
  +X, the top row straight up (+Y). They are sampled bilinearly, wrapping in u and clamped in v.
- Radiance .hdr files (RGBE, flat or new-style run-length scanlines, "-Y h +X w") are linear
  (an EXPOSURE line is ignored, as most readers do); other images are read with Pillow as 8-bit
  sRGB and decoded to linear.
- `irradiance_sh9` projects the radiance onto the real spherical harmonics up to order 2, each
  texel weighted by its exact solid angle, and convolves them with the clamped cosine
  (Ramamoorthi and Hanrahan 2001) divided by pi: `eval_sh9(c, n)`, the sum the shader does, is the
  radiance a white Lambertian surface facing n reflects.

`load_cube` is the one entry point for user data: every bad input is a UsageError naming the file
(or the array) and what is wrong with it.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Final

import numpy as np

from ...errors import UsageError
from ..assets.textures import ImageError, read_image, srgb_to_linear
from ..shadows.views import CUBE_FACES
from .radiance_hdr import MAX_SOURCE_TEXELS, read_rgbe

__all__ = [
    "CUBE_FACE_NAMES",
    "cube_directions",
    "cube_mips",
    "equirect_to_cube",
    "eval_sh9",
    "irradiance_sh9",
    "load_cube",
    "read_rgbe",
]

CUBE_FACE_NAMES: Final = ("px", "nx", "py", "ny", "pz", "nz")
MIN_DEFAULT_SIZE: Final = 16  # an equirect map's default face size is clamped to these
MAX_DEFAULT_SIZE: Final = 1024
MAX_SIZE: Final = 4096  # the largest face size one may ask for (every Vulkan device has cube maps this large)
#: the SH basis constants, in the shader's order (Y0; Y1..Y3 = y, z, x; Y4..Y8 = order 2)
SH_C0: Final = 0.282095
SH_C1: Final = 0.488603
SH_C2: Final = 1.092548
SH_C3: Final = 0.315392
SH_C4: Final = 0.546274
#: the clamped cosine's SH coefficients A_l (Ramamoorthi and Hanrahan 2001) divided by pi, per basis function
SH_COSINE_OVER_PI: Final = np.array([1.0, 2.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0, 0.25, 0.25, 0.25, 0.25, 0.25])

_FACE_AXES = np.array(CUBE_FACES, dtype=np.float64)  # (6 faces, forward / s / t, xyz)


# --- directions -------------------------------------------------------------------------------


def _texel_centres(size: int) -> np.ndarray:
    """sc (or tc) of each column's (row's) centre, from -1 to 1."""
    return (np.arange(size, dtype=np.float64) + 0.5) * (2.0 / size) - 1.0


def cube_directions(size: int) -> np.ndarray:
    """(6, size, size, 3) float64: the unit direction through every texel's centre."""
    if size < 1:
        raise ValueError(f"a cube face needs at least one texel, got size {size}")
    c = _texel_centres(size)
    sc, tc = np.meshgrid(c, c)  # [row, column]: sc varies along columns, tc along rows
    inverse_length = 1.0 / np.sqrt(1.0 + sc * sc + tc * tc)  # the face's axes are orthonormal
    coordinates = np.stack([sc * inverse_length, tc * inverse_length, inverse_length], axis=-1)
    # (s axis, t axis, forward) rows per face: (sc, tc, 1) @ rows = forward + s axis sc + t axis tc
    rows = _FACE_AXES[:, [1, 2, 0], :]
    return np.matmul(coordinates[None], rows[:, None])


def _texel_solid_angles(size: int) -> np.ndarray:
    """(size, size) float64: the solid angle of each texel of a face (the same on every face), from
    the area element's integral atan(x y / sqrt(x^2 + y^2 + 1)) over the texel's corners."""
    edges = np.linspace(-1.0, 1.0, size + 1)
    x, y = np.meshgrid(edges, edges, indexing="ij")
    a = np.arctan2(x * y, np.sqrt(x * x + y * y + 1.0))
    return a[1:, 1:] - a[:-1, 1:] - a[1:, :-1] + a[:-1, :-1]


# --- resampling -------------------------------------------------------------------------------


def _resample_axis(a: np.ndarray, n: int, axis: int) -> np.ndarray:
    """`a` with `n` samples along `axis`: each the mean of the input it covers when shrinking
    (exact area weights, fractional at the ends), bilinear between texel centres (clamped) when
    growing."""
    m = a.shape[axis]
    if n == m:
        return a
    a = np.moveaxis(a, axis, 0)
    if n < m and m % n == 0:  # whole texels: a plain box filter
        out = a.reshape((n, m // n) + a.shape[1:]).mean(axis=1, dtype=np.float64).astype(a.dtype)
    elif n < m:  # area average: differences of the running sum, interpolated within a texel
        total = np.concatenate([np.zeros_like(a[:1], np.float64), np.cumsum(a, axis=0, dtype=np.float64)])
        edges = np.arange(n + 1, dtype=np.float64) * (m / n)
        k = np.minimum(np.floor(edges).astype(np.intp), m - 1)
        frac = (edges - k).reshape((-1,) + (1,) * (a.ndim - 1))
        at_edge = total[k] + frac * a[k]
        out = ((at_edge[1:] - at_edge[:-1]) * (n / m)).astype(a.dtype)
    else:
        x = np.clip((np.arange(n) + 0.5) * (m / n) - 0.5, 0.0, m - 1)
        k0 = np.minimum(np.floor(x).astype(np.intp), max(m - 2, 0))
        k1 = np.minimum(k0 + 1, m - 1)
        frac = (x - k0).reshape((-1,) + (1,) * (a.ndim - 1)).astype(a.dtype)
        out = a[k0] * (1 - frac) + a[k1] * frac
    return np.moveaxis(out, 0, axis)


def equirect_to_cube(pixels: np.ndarray, size: int) -> np.ndarray:
    """(6, size, size, 3) float32 faces of an (H, 2H, 3) equirectangular map, sampled bilinearly
    (wrapping in u, clamped in v) at each texel's centre direction; a map finer than the faces
    (more than 2 * size rows) is first area-averaged to 2 * size rows, so that it does not alias."""
    pixels = np.asarray(pixels)
    if pixels.ndim != 3 or pixels.shape[2] != 3 or pixels.shape[1] != 2 * pixels.shape[0] or pixels.shape[0] < 1:
        raise ValueError(f"an equirectangular map is (H, 2H, 3), got {pixels.shape}")
    image = pixels.astype(np.float32, copy=False)
    if image.shape[0] > 2 * size:
        image = _resample_axis(_resample_axis(image, 2 * size, 0), 4 * size, 1)
    h, w = image.shape[:2]
    d = cube_directions(size).astype(np.float32)
    u = np.arctan2(d[..., 0], -d[..., 2]) * np.float32(1.0 / (2.0 * math.pi)) + np.float32(0.5)
    v = np.arccos(np.clip(d[..., 1], -1.0, 1.0)) * np.float32(1.0 / math.pi)
    x = u * np.float32(w) - np.float32(0.5)
    y = np.clip(v * np.float32(h) - np.float32(0.5), 0.0, h - 1)
    x0 = np.floor(x)
    y0 = np.minimum(np.floor(y), max(h - 2, 0))
    fx = (x - x0)[..., None]
    fy = (y - y0)[..., None]
    c0 = x0.astype(np.intp) % w
    c1 = (c0 + 1) % w
    r0 = y0.astype(np.intp) * w
    r1 = np.minimum(y0.astype(np.intp) + 1, h - 1) * w
    flat = image.reshape(-1, 3)
    top, bottom = (_lerp(np.take(flat, r + c0, axis=0), np.take(flat, r + c1, axis=0), fx) for r in (r0, r1))
    return _lerp(top, bottom, fy).astype(np.float32, copy=False)


def _lerp(a: np.ndarray, b: np.ndarray, t: np.ndarray) -> np.ndarray:
    """a + (b - a) t, in place in b."""
    b -= a
    b *= t
    b += a
    return b


# --- loading ----------------------------------------------------------------------------------


def _nearest_power_of_two(x: float) -> int:
    return 1 << max(round(math.log2(max(x, 1.0))), 0)


def _read_linear(file: Path, max_texels: int) -> np.ndarray:
    """(H, W, 3) float32 linear RGB of an image file: .hdr as is, others decoded from 8-bit sRGB."""
    if file.suffix.lower() == ".hdr":
        return read_rgbe(file, max_texels)
    try:
        rgba = read_image(file, max_texels)
    except ImageError as exc:
        raise UsageError(f"environment map {file}: {exc}") from None
    return srgb_to_linear(rgba[..., :3].astype(np.float32) / np.float32(255.0)).astype(np.float32)


def _check_values(pixels: np.ndarray, name: str) -> None:
    if not np.all(np.isfinite(pixels)):
        raise UsageError(f"environment map {name}: has NaN or infinite values")
    if np.any(pixels < 0.0):
        raise UsageError(f"environment map {name}: has negative values (radiance is never negative)")


def environment_texels(shape: tuple[int, ...], name: str) -> None:
    """UsageError for a source of more than MAX_SOURCE_TEXELS texels (its shape: (..., channels))."""
    texels = math.prod(shape[:-1])
    if texels > MAX_SOURCE_TEXELS:
        raise UsageError(
            f"environment map {name}: shape {tuple(shape)} holds more than the {MAX_SOURCE_TEXELS:,} texels an "
            "environment map may have (an 8192 x 4096 map, or six faces of 2364 x 2364)"
        )


def check_cube_size(size: int | None) -> None:
    if size is None:
        return
    if isinstance(size, bool) or not isinstance(size, int | np.integer):
        raise UsageError(f"environment map size {size!r}: must be a whole number")
    if size < 1 or size > MAX_SIZE or size & (size - 1):
        raise UsageError(f"environment map size {size}: must be a power of two from 1 to {MAX_SIZE}")


def _cube_from_equirect(pixels: np.ndarray, size: int | None, name: str) -> np.ndarray:
    h, w = pixels.shape[:2]
    if w != 2 * h:
        raise UsageError(f"environment map {name}: is {w} x {h}; an equirectangular map is twice as wide as tall")
    _check_values(pixels, name)
    if size is None:
        size = min(max(_nearest_power_of_two(h / 2), MIN_DEFAULT_SIZE), MAX_DEFAULT_SIZE)
    return equirect_to_cube(pixels, size)


def _cube_from_faces(faces: np.ndarray, size: int | None, name: str) -> np.ndarray:
    _check_values(faces, name)
    if size is None:
        size = min(_nearest_power_of_two(faces.shape[1]), MAX_DEFAULT_SIZE)
    faces = _resample_axis(_resample_axis(faces.astype(np.float32, copy=False), size, 1), size, 2)
    return np.ascontiguousarray(faces, dtype=np.float32)


def load_cube(
    source: str | os.PathLike[str] | Sequence[str | os.PathLike[str]] | np.ndarray, size: int | None = None
) -> np.ndarray:
    """(6, S, S, 3) float32 linear RGB cube faces in CUBE_FACE_NAMES order, S a power of two, from:

    - a path to an equirectangular image (.hdr linear, others 8-bit sRGB); S defaults to the power
      of two nearest half its height, from 16 to 1024;
    - six paths, one square image per face in CUBE_FACE_NAMES order, all the same size; S defaults
      to their size rounded to a power of two, at most 1024 (faces are area-averaged when shrunk,
      bilinear when grown);
    - an array: (6, S, S, 3) faces, or an (H, 2H, 3) equirectangular map, linear.

    Any bad input is a UsageError naming the file (or the array) and what is wrong with it."""
    check_cube_size(size)
    if isinstance(source, np.ndarray):
        pixels = source
        if not np.issubdtype(pixels.dtype, np.number) or np.iscomplexobj(pixels):
            raise UsageError(f"environment map array: must hold real numbers, not {pixels.dtype}")
        environment_texels(pixels.shape, "array")
        if pixels.ndim == 4 and pixels.shape[0] == 6 and pixels.shape[3] == 3:
            if pixels.shape[1] != pixels.shape[2] or pixels.shape[1] < 1:
                raise UsageError(f"environment map array: cube faces must be square, got {pixels.shape}")
            return _cube_from_faces(pixels, size, "array")
        if pixels.ndim == 3 and pixels.shape[2] == 3 and pixels.shape[0] >= 1:
            return _cube_from_equirect(pixels.astype(np.float32, copy=False), size, "array")
        raise UsageError(
            f"environment map array: shape {pixels.shape} is neither (6, S, S, 3) faces nor an (H, 2H, 3) map"
        )
    if isinstance(source, str | os.PathLike):
        file = Path(source)
        return _cube_from_equirect(_read_linear(file, MAX_SOURCE_TEXELS), size, str(file))
    if not isinstance(source, Sequence):
        raise UsageError(f"environment map {source!r}: not a path, six paths or an array")
    if not all(isinstance(p, str | os.PathLike) for p in source):
        raise UsageError(f"environment map faces {source!r}: each face must be a path")
    files = [Path(p) for p in source]
    if len(files) != 6:
        raise UsageError(f"environment map faces: {len(files)} given, a cube needs 6 ({', '.join(CUBE_FACE_NAMES)})")
    faces = [_read_linear(f, MAX_SOURCE_TEXELS // 6) for f in files]
    for file, face in zip(files, faces):
        if face.shape[0] != face.shape[1]:
            raise UsageError(f"environment map {file}: cube face is {face.shape[1]} x {face.shape[0]}, not square")
        if face.shape != faces[0].shape:
            raise UsageError(
                f"environment map {file}: cube face is {face.shape[1]} x {face.shape[0]}, "
                f"but {files[0]} is {faces[0].shape[1]} x {faces[0].shape[0]}"
            )
    return _cube_from_faces(np.stack(faces), size, ", ".join(map(str, files)))


# --- mips and irradiance ----------------------------------------------------------------------


def cube_mips(faces: np.ndarray) -> list[np.ndarray]:
    """Level 0 (the faces, float32) and each half-size level down to 1 x 1, every texel the mean of
    the 2 x 2 above it on its own face. S must be a power of two (ValueError otherwise)."""
    faces = np.asarray(faces)
    if faces.ndim != 4 or faces.shape[0] != 6 or faces.shape[1] != faces.shape[2]:
        raise ValueError(f"cube_mips needs (6, S, S, C) faces, got {faces.shape}")
    side = faces.shape[1]
    if side < 1 or side & (side - 1):
        raise ValueError(f"cube_mips needs a power-of-two face size, got {side}")
    levels = [faces.astype(np.float32)]
    values = faces.astype(np.float64)
    while values.shape[1] > 1:
        h = values.shape[1] // 2
        values = values.reshape(6, h, 2, h, 2, -1).mean(axis=(2, 4))
        levels.append(values.astype(np.float32))
    return levels


def _sh9_basis(x: np.ndarray, y: np.ndarray, z: np.ndarray) -> list[np.ndarray]:
    """The nine basis functions at unit directions (x, y, z), in the shader's order."""
    return [
        np.full_like(x, SH_C0),
        SH_C1 * y,
        SH_C1 * z,
        SH_C1 * x,
        SH_C2 * x * y,
        SH_C2 * y * z,
        SH_C3 * (3.0 * z * z - 1.0),
        SH_C2 * x * z,
        SH_C4 * (x * x - y * y),
    ]


def irradiance_sh9(faces: np.ndarray) -> np.ndarray:
    """(9, 3) float32: the faces' radiance projected onto the SH basis (each texel weighted by its
    solid angle) and convolved with the clamped cosine over pi, for `eval_sh9`."""
    faces = np.asarray(faces)
    if faces.ndim != 4 or faces.shape[0] != 6 or faces.shape[1] != faces.shape[2] or faces.shape[3] != 3:
        raise ValueError(f"irradiance_sh9 needs (6, S, S, 3) faces, got {faces.shape}")
    size = faces.shape[1]
    solid_angles = _texel_solid_angles(size)[:, :, None]
    coefficients = np.zeros((9, 3))
    for face, directions in zip(faces, cube_directions(size)):  # a face at a time: (9, S^2) stays small
        d = directions.reshape(-1, 3).T.copy()  # x, y, z each contiguous
        coefficients += np.stack(_sh9_basis(d[0], d[1], d[2])) @ (face * solid_angles).reshape(-1, 3)
    return (coefficients * SH_COSINE_OVER_PI[:, None]).astype(np.float32)


def eval_sh9(coefficients: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """(..., 3) float32: sum_i coefficients[i] * Y_i(n) for unit normals n (..., 3), clamped at 0:
    the radiance a white Lambertian surface facing n reflects (the shader's sum)."""
    c = np.asarray(coefficients, dtype=np.float64)
    if c.shape != (9, 3):
        raise ValueError(f"eval_sh9 needs (9, 3) coefficients, got {c.shape}")
    n = np.asarray(normals, dtype=np.float64)
    if n.shape[-1:] != (3,):
        raise ValueError(f"eval_sh9 needs (..., 3) normals, got {n.shape}")
    total = np.zeros(n.shape, np.float64)
    for basis, coefficient in zip(_sh9_basis(n[..., 0], n[..., 1], n[..., 2]), c):
        total += basis[..., None] * coefficient
    return np.maximum(total, 0.0).astype(np.float32)
