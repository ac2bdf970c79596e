"""Environment maps on the CPU (render/lighting/environment_maps.py): Radiance .hdr files read back what a
small encoder here wrote, flat and run-length; cube faces are oriented as the Vulkan spec's face
selection table says; an equirectangular map and six face images land on the right faces;
spherical-harmonic irradiance matches constant and half-lit skies; bad inputs get one clear
message naming the file."""

from __future__ import annotations

import itertools
import math
import time

import numpy as np
import pytest
from PIL import Image

from ecs_engine.errors import UsageError
from ecs_engine.render.lighting import environment_maps
from ecs_engine.render.lighting.environment_maps import (
    CUBE_FACE_NAMES,
    cube_directions,
    cube_mips,
    equirect_to_cube,
    eval_sh9,
    irradiance_sh9,
    load_cube,
    read_rgbe,
)

AXES = {"+X": (1, 0, 0), "-X": (-1, 0, 0), "+Y": (0, 1, 0), "-Y": (0, -1, 0), "+Z": (0, 0, 1), "-Z": (0, 0, -1)}


# --- a small Radiance encoder ----------------------------------------------------------------


def to_rgbe(pixels: np.ndarray) -> np.ndarray:
    """(H, W, 4) uint8, as Radiance's setcolr does: mantissas truncated, a shared exponent."""
    brightest = pixels.max(axis=-1)
    mantissa, exponent = np.frexp(brightest)
    scale = np.where(brightest > 1e-32, mantissa * 256.0 / np.maximum(brightest, 1e-32), 0.0)
    rgbe = np.zeros(pixels.shape[:2] + (4,), np.uint8)
    rgbe[..., :3] = np.floor(pixels * scale[..., None]).astype(np.uint8)
    rgbe[..., 3] = np.where(brightest > 1e-32, exponent + 128, 0)
    return rgbe


def rle_channel(values: bytes) -> bytes:
    """One channel of a scanline as runs: repeats of 3 or more as (128 + n, byte), the rest copied
    in pieces of up to 128 bytes."""
    out = bytearray()
    i, n = 0, len(values)
    literal = bytearray()

    def flush() -> None:
        for k in range(0, len(literal), 128):
            piece = literal[k : k + 128]
            out.append(len(piece))
            out.extend(piece)
        literal.clear()

    while i < n:
        j = i
        while j < n and j - i < 127 and values[j] == values[i]:
            j += 1
        if j - i >= 3:
            flush()
            out += bytes([128 + j - i, values[i]])
            i = j
        else:
            literal.append(values[i])
            i += 1
    flush()
    return bytes(out)


def write_hdr(path, pixels: np.ndarray, *, rle: bool, resolution: bytes | None = None) -> None:
    h, w = pixels.shape[:2]
    rgbe = to_rgbe(pixels)
    body = bytearray()
    for row in rgbe:
        if rle:
            body += bytes([2, 2, w >> 8, w & 255])
            for channel in range(4):
                body += rle_channel(row[:, channel].tobytes())
        else:
            body += row.tobytes()
    header = b"#?RADIANCE\n# written by the tests\nFORMAT=32-bit_rle_rgbe\nEXPOSURE=1.0\n\n"
    path.write_bytes(header + (resolution or f"-Y {h} +X {w}".encode()) + b"\n" + bytes(body))


def sample_pixels(h: int = 12, w: int = 40) -> np.ndarray:
    """Flat patches (long runs), noise (literal runs), a black column and values over a wide range."""
    rng = np.random.default_rng(7)
    pixels = np.ones((h, w, 3)) * np.array([0.25, 1.5, 3.0])
    pixels[:, w // 2 :] = rng.uniform(0.0, 1.0, (h, w - w // 2, 3)) * 10.0 ** rng.uniform(-3, 3, (h, w - w // 2, 1))
    pixels[2, :8] = (1000.0, 20.0, 0.001)
    pixels[:, 3] = 0.0
    return pixels


@pytest.mark.parametrize("rle", [False, True])
def test_read_rgbe_gives_back_what_was_written_within_rgbe_precision(tmp_path, rle):
    pixels = sample_pixels()
    path = tmp_path / "sky.hdr"
    write_hdr(path, pixels, rle=rle)
    read = read_rgbe(path)
    assert read.shape == pixels.shape and read.dtype == np.float32
    # the shared exponent leaves the brightest channel at least 128 steps: each off by at most one step
    step = pixels.max(axis=-1, keepdims=True) / 128.0
    assert np.all(np.abs(read - pixels) <= step + 1e-30)
    assert np.all(read[:, 3] == 0.0)


def test_flat_and_run_length_files_read_the_same(tmp_path):
    pixels = sample_pixels()
    write_hdr(tmp_path / "flat.hdr", pixels, rle=False)
    write_hdr(tmp_path / "rle.hdr", pixels, rle=True)
    assert (tmp_path / "rle.hdr").stat().st_size < (tmp_path / "flat.hdr").stat().st_size  # runs were used
    np.testing.assert_array_equal(read_rgbe(tmp_path / "flat.hdr"), read_rgbe(tmp_path / "rle.hdr"))


@pytest.mark.parametrize("rle", [False, True])
def test_truncated_hdr_is_a_usage_error_naming_the_file(tmp_path, rle):
    path = tmp_path / "cut.hdr"
    write_hdr(path, sample_pixels(), rle=rle)
    path.write_bytes(path.read_bytes()[:-7])
    with pytest.raises(UsageError, match=r"cut\.hdr.*truncated"):
        read_rgbe(path)


@pytest.mark.parametrize(
    ("content", "why"),
    [
        (b"P6\n4 4\n255\n" + bytes(48), "not a Radiance"),
        (b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n", "header"),
        (b"#?RADIANCE\nFORMAT=32-bit_rle_xyze\n\n-Y 1 +X 1\n\0\0\0\0", "format"),
        (b"#?RADIANCE\n\n-Y four +X 1\n\0\0\0\0", "resolution"),
        (b"#?RADIANCE\n\n+Y 1 +X 1\n\0\0\0\0", "orientation"),
    ],
)
def test_bad_hdr_header_is_a_usage_error_naming_the_file(tmp_path, content, why):
    path = tmp_path / "bad.hdr"
    path.write_bytes(content)
    with pytest.raises(UsageError, match=rf"bad\.hdr.*{why}"):
        read_rgbe(path)


def test_missing_hdr_is_a_usage_error():
    with pytest.raises(UsageError, match=r"nowhere\.hdr: no such file"):
        read_rgbe("/nonexistent/nowhere.hdr")


# --- orientation -----------------------------------------------------------------------------


def spec_face_selection(r: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Face index, s and t of directions (..., 3): the Vulkan spec's "cube map face selection"
    table, written out here independently of the engine's CUBE_FACES."""
    rx, ry, rz = r[..., 0], r[..., 1], r[..., 2]
    ax, ay, az = np.abs(rx), np.abs(ry), np.abs(rz)
    x_major = (ax >= ay) & (ax >= az)
    y_major = ~x_major & (ay >= az)
    face = np.where(x_major, np.where(rx > 0, 0, 1), np.where(y_major, np.where(ry > 0, 2, 3), np.where(rz > 0, 4, 5)))
    table = [  # (ma, sc, tc) per face
        (rx, -rz, -ry),
        (rx, rz, -ry),
        (ry, rx, rz),
        (ry, rx, -rz),
        (rz, rx, -ry),
        (rz, -rx, -ry),
    ]
    ma = np.choose(face, [t[0] for t in table])
    sc = np.choose(face, [t[1] for t in table])
    tc = np.choose(face, [t[2] for t in table])
    return face, (sc / np.abs(ma) + 1) / 2, (tc / np.abs(ma) + 1) / 2


def test_cube_directions_follow_the_spec_face_selection_for_every_texel():
    size = 8
    d = cube_directions(size)
    assert d.shape == (6, size, size, 3) and d.dtype == np.float64
    face, s, t = spec_face_selection(d)
    centres = (np.arange(size) + 0.5) / size
    np.testing.assert_array_equal(face, np.arange(6)[:, None, None] * np.ones((1, size, size), int))
    np.testing.assert_allclose(s, np.broadcast_to(centres[None, None, :], s.shape), atol=1e-12)  # column = s
    np.testing.assert_allclose(t, np.broadcast_to(centres[None, :, None], t.shape), atol=1e-12)  # row = t


def test_cube_directions_named_examples_and_unit_length():
    d = cube_directions(3)
    for index, axis in enumerate(["+X", "-X", "+Y", "-Y", "+Z", "-Z"]):
        np.testing.assert_allclose(d[index, 1, 1], AXES[axis], atol=1e-12)  # each face's centre
    assert CUBE_FACE_NAMES == ("px", "nx", "py", "ny", "pz", "nz")
    d = cube_directions(16)
    assert np.all(d[0, :, 0, 2] > 0)  # +X: column 0 (s near 0) looks towards +Z
    assert np.all(d[0, 0, :, 1] > 0)  # +X: row 0 (t near 0) looks up
    assert np.all(d[4, 0, :, 1] > 0)  # +Z: row 0 looks up
    assert np.all(d[4, :, -1, 0] > 0)  # +Z: the last column looks towards +X
    assert np.all(d[2, -1, :, 2] > 0)  # +Y: the last row looks towards +Z
    assert np.all(d[3, -1, :, 2] < 0)  # -Y: the last row looks towards -Z
    assert np.all(d[5, :, 0, 0] > 0)  # -Z: column 0 looks towards +X
    np.testing.assert_allclose(np.linalg.norm(d, axis=-1), 1.0, atol=1e-12)


def direction_equirect(h: int) -> np.ndarray:
    """An (h, 2h, 3) map whose colour at each pixel centre is its direction * 0.5 + 0.5."""
    u = (np.arange(2 * h) + 0.5) / (2 * h)
    v = (np.arange(h) + 0.5) / h
    phi = (u - 0.5) * 2 * math.pi
    theta = v * math.pi
    d = np.stack(
        [
            np.sin(theta)[:, None] * np.sin(phi)[None, :],
            np.cos(theta)[:, None] * np.ones_like(phi)[None, :],
            -np.sin(theta)[:, None] * np.cos(phi)[None, :],
        ],
        axis=-1,
    )
    return d * 0.5 + 0.5


@pytest.mark.parametrize("h", [64, 256])  # as fine as the faces, and finer (averaged first)
def test_equirect_to_cube_puts_each_direction_on_its_texel(h):
    faces = equirect_to_cube(direction_equirect(h), 32)
    assert faces.shape == (6, 32, 32, 3) and faces.dtype == np.float32
    error = np.abs(faces * 2 - 1 - cube_directions(32))
    assert error.max() < 0.05 and error.mean() < 0.005


def test_equirect_centre_looks_down_minus_z_and_three_quarters_towards_plus_x():
    equirect = np.zeros((16, 32, 3))
    equirect[:, 23:25, 0] = 1.0  # u = 0.75: +X, red
    equirect[:, 15:17, 2] = 1.0  # u = 0.5: -Z, blue
    equirect[0, :, 1] = 1.0  # the top row: +Y, green
    faces = equirect_to_cube(equirect, 8)
    assert faces[0, 3:5, 3:5, 0].min() > 0.4 and faces[0, ..., 2].max() == 0.0
    assert faces[5, 3:5, 3:5, 2].min() > 0.4 and faces[5, ..., 0].max() == 0.0
    assert faces[2, 3:5, 3:5, 1].min() > 0.5 and faces[3, ..., 1].max() == 0.0


# --- loading ---------------------------------------------------------------------------------


def srgb_decoded(c: int) -> float:
    c /= 255.0
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


FACE_COLOURS = [(255, 0, 0), (0, 255, 0), (0, 0, 255), (128, 128, 0), (0, 64, 200), (10, 30, 250)]


def write_faces(folder, size: int = 8, sizes=None) -> list:
    paths = []
    for name, colour, side in zip(CUBE_FACE_NAMES, FACE_COLOURS, sizes or [size] * 6):
        path = folder / f"{name}.png"
        Image.new("RGB", side if isinstance(side, tuple) else (side, side), colour).save(path)
        paths.append(path)
    return paths


@pytest.mark.parametrize(("size", "expected"), [(None, 8), (4, 4), (16, 16)])
def test_six_face_images_land_on_their_faces_srgb_decoded(tmp_path, size, expected):
    faces = load_cube(write_faces(tmp_path), size)
    assert faces.shape == (6, expected, expected, 3) and faces.dtype == np.float32
    for face, colour in zip(faces, FACE_COLOURS):
        np.testing.assert_allclose(face, np.broadcast_to([srgb_decoded(c) for c in colour], face.shape), atol=1e-6)


def test_face_images_of_a_size_not_a_power_of_two_are_rounded_to_one(tmp_path):
    faces = load_cube([str(p) for p in write_faces(tmp_path, 12)])
    assert faces.shape == (6, 16, 16, 3)
    np.testing.assert_allclose(faces[2], np.broadcast_to([0.0, 0.0, 1.0], (16, 16, 3)), atol=1e-6)


def test_bad_face_sets_are_usage_errors_naming_the_problem(tmp_path):
    paths = write_faces(tmp_path)
    with pytest.raises(UsageError, match="5 given, a cube needs 6"):
        load_cube(paths[:5])
    with pytest.raises(UsageError, match=r"nowhere\.png: no such file"):
        load_cube(paths[:5] + [tmp_path / "nowhere.png"])
    (tmp_path / "text.png").write_text("not pixels")
    with pytest.raises(UsageError, match=r"text\.png: not an image"):
        load_cube(paths[:5] + [tmp_path / "text.png"])
    (tmp_path / "odd").mkdir()
    uneven = write_faces(tmp_path / "odd", sizes=[8, 8, 8, 8, 8, 4])
    with pytest.raises(UsageError, match=r"nz\.png.*4 x 4, but .*px\.png is 8 x 8"):
        load_cube(uneven)
    (tmp_path / "flat").mkdir()
    oblong = write_faces(tmp_path / "flat", sizes=[8, 8, (8, 4), 8, 8, 8])
    with pytest.raises(UsageError, match=r"py\.png.*not square"):
        load_cube(oblong)
    with pytest.raises(UsageError, match="power of two"):
        load_cube(paths, 12)
    with pytest.raises(UsageError, match="must be a path"):
        load_cube([*paths[:5], 7])


def test_equirect_files_load_hdr_linear_and_png_srgb(tmp_path):
    left, right = (0.5, 2.0, 8.0), (4.0, 0.25, 1.0)
    pixels = np.empty((32, 64, 3))
    pixels[:, :32], pixels[:, 32:] = left, right  # u < 0.5 towards -X, u > 0.5 towards +X
    write_hdr(tmp_path / "sky.hdr", pixels, rle=True)
    faces = load_cube(tmp_path / "sky.hdr")
    assert faces.shape == (6, 16, 16, 3)  # half the height is 16, the smallest default
    # RGBE keeps 1/128 of a pixel's brightest channel
    np.testing.assert_allclose(faces[0], np.broadcast_to(right, faces[0].shape), atol=max(right) / 128)
    np.testing.assert_allclose(faces[1], np.broadcast_to(left, faces[1].shape), atol=max(left) / 128)
    png = np.zeros((32, 64, 3), np.uint8)
    png[:, 32:] = (200, 100, 50)
    Image.fromarray(png).save(tmp_path / "sky.png")
    faces = load_cube(str(tmp_path / "sky.png"), 8)
    np.testing.assert_allclose(faces[0], np.broadcast_to([srgb_decoded(c) for c in (200, 100, 50)], (8, 8, 3)), 1e-6)
    assert faces[1].max() == 0.0


def test_default_equirect_size_is_the_power_of_two_nearest_half_the_height_within_16_to_1024(monkeypatch):
    assert load_cube(np.zeros((8, 16, 3), np.float32)).shape == (6, 16, 16, 3)
    asked = []  # the sizes load_cube asks for, without making (large) faces
    monkeypatch.setattr(environment_maps, "equirect_to_cube", lambda pixels, size: asked.append(size))
    for h in (8, 100, 190, 512, 2900):
        load_cube(np.broadcast_to(np.float32(1.0), (h, 2 * h, 3)))  # a view: no memory for 2900 x 5800
    assert asked == [16, 64, 128, 256, 1024]  # 2900 / 2 is nearest 2048, above the largest default


@pytest.mark.parametrize(
    ("array", "why"),
    [
        (np.ones((16, 30, 3)), "twice as wide as tall"),
        (np.ones((5, 8, 8, 3)), "neither"),
        (np.ones((6, 8, 4, 3)), "square"),
        (np.full((6, 8, 8, 3), np.nan), "NaN"),
        (np.full((8, 16, 3), np.inf), "infinite"),
        (-np.ones((6, 8, 8, 3)), "negative"),
    ],
)
def test_bad_arrays_are_usage_errors(array, why):
    with pytest.raises(UsageError, match=why):
        load_cube(array)


def test_equirect_that_is_not_two_to_one_names_the_file(tmp_path):
    Image.new("RGB", (30, 20)).save(tmp_path / "square.jpg")
    with pytest.raises(UsageError, match=r"square\.jpg: is 30 x 20"):
        load_cube(tmp_path / "square.jpg")


def test_loading_a_1024_equirect_and_its_irradiance_is_fast():
    equirect = np.random.default_rng(1).uniform(0.0, 4.0, (512, 1024, 3)).astype(np.float32)
    start = time.perf_counter()
    faces = load_cube(equirect)
    irradiance_sh9(faces)
    elapsed = time.perf_counter() - start
    assert faces.shape == (6, 256, 256, 3)
    assert elapsed < 1.0, f"{elapsed:.2f} s"  # ~0.1 s on a laptop: a per-texel Python loop would take minutes


# --- mips and irradiance ---------------------------------------------------------------------


def test_cube_mips_halve_down_to_one_texel_keeping_the_mean():
    faces = np.random.default_rng(3).uniform(0.0, 5.0, (6, 16, 16, 3)).astype(np.float32)
    levels = cube_mips(faces)
    assert [level.shape[1] for level in levels] == [16, 8, 4, 2, 1]
    assert all(level.shape == (6, level.shape[1], level.shape[1], 3) and level.dtype == np.float32 for level in levels)
    np.testing.assert_array_equal(levels[0], faces)
    for above, below in itertools.pairwise(levels):
        np.testing.assert_allclose(below.mean(axis=(1, 2)), above.mean(axis=(1, 2)), rtol=1e-5)  # per face
    np.testing.assert_allclose(levels[1][4, 2, 3], faces[4, 4:6, 6:8].mean(axis=(0, 1)), rtol=1e-6)
    with pytest.raises(ValueError, match="power-of-two"):
        cube_mips(np.zeros((6, 12, 12, 3)))


def sky(size: int, radiance) -> np.ndarray:
    """(6, size, size, 3) faces whose radiance is radiance(directions), grey."""
    return np.repeat(radiance(cube_directions(size))[..., None], 3, axis=-1).astype(np.float32)


def normals() -> np.ndarray:
    n = np.random.default_rng(5).normal(size=(200, 3))
    return n / np.linalg.norm(n, axis=-1, keepdims=True)


@pytest.mark.parametrize("size", [4, 32])
def test_constant_sky_lights_every_normal_the_same(size):
    colour = np.array([0.5, 1.0, 2.0], np.float32)
    c = irradiance_sh9(np.broadcast_to(colour, (6, size, size, 3)))
    assert c.shape == (9, 3) and c.dtype == np.float32
    np.testing.assert_allclose(eval_sh9(c, normals()), np.broadcast_to(colour, (200, 3)), rtol=0.01)
    np.testing.assert_allclose(c[1:], 0.0, atol=1e-5)  # no direction is favoured


def test_sky_lit_from_above_matches_the_analytic_irradiance():
    # L(w) = max(0, w.y): exactly, E(n)/pi is 2/3 at n = +Y and 0 at -Y. Its order-2 SH
    # approximation (zonal: (A_l/pi) (2l+1)/2 P_l(n.y) int_0^1 t P_l(t) dt, l = 0..2) gives
    # 1/4 + 1/3 + 5/64 = 127/192 at +Y (1/192 = 0.0052 short), -1/192 at -Y (clamped to 0) and
    # 1/4 - 5/128 = 27/128 at +X; the cube's discretization adds well under 0.001 at 64 texels a side.
    c = irradiance_sh9(sky(64, lambda d: np.maximum(d[..., 1], 0.0)))
    up, down, side = eval_sh9(c, np.array([[0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [1.0, 0.0, 0.0]]))[:, 0]
    assert abs(up - 2 / 3) < 0.01 and abs(up - 127 / 192) < 0.002
    assert 0.0 <= down < 0.01
    assert abs(side - 27 / 128) < 0.002 and up > side


@pytest.mark.parametrize("axis", list(AXES))
def test_sky_lit_from_one_axis_is_brightest_facing_it(axis):
    a = np.array(AXES[axis], float)
    c = irradiance_sh9(sky(16, lambda d: np.maximum(d @ a, 0.0)))
    lit = {name: eval_sh9(c, np.array(v, float))[0] for name, v in AXES.items()}
    assert max(lit, key=lit.get) == axis
    opposite = {"+": "-", "-": "+"}[axis[0]] + axis[1]
    assert lit[opposite] < 0.01 * lit[axis]


def test_eval_sh9_is_the_shaders_sum_clamped_at_zero():
    n = np.array([0.36, 0.48, 0.8])
    x, y, z = n
    basis = [
        0.282095,
        0.488603 * y,
        0.488603 * z,
        0.488603 * x,
        1.092548 * x * y,
        1.092548 * y * z,
        0.315392 * (3 * z * z - 1),
        1.092548 * x * z,
        0.546274 * (x * x - y * y),
    ]
    for i, value in enumerate(basis):
        c = np.zeros((9, 3))
        c[i] = (1.0, 2.0, 3.0)
        np.testing.assert_allclose(eval_sh9(c, n), np.maximum(value * np.array([1.0, 2.0, 3.0]), 0.0), rtol=1e-6)
        np.testing.assert_allclose(eval_sh9(-c, n), np.maximum(-value * np.array([1.0, 2.0, 3.0]), 0.0), rtol=1e-6)
    assert eval_sh9(np.zeros((9, 3)), np.zeros((4, 5, 3))).shape == (4, 5, 3)
