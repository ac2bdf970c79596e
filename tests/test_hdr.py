"""HDR: the scene lit in 16-bit float, then exposure and a tone map (clamp, ACES filmic, Reinhard)
into the sRGB target, each against its formula in NumPy; MSAA smooths edges; bad settings get one
clear message."""

from __future__ import annotations

import math
import subprocess
import sys
from dataclasses import replace

import numpy as np
import pytest
from gpu_context import headless_gpu, render_world

from ecs_engine import World
from ecs_engine.components import Camera, Mesh, Transform
from ecs_engine.errors import UsageError
from ecs_engine.render.assets.materials import Material, materials
from ecs_engine.render.assets.primitives import plane_mesh
from ecs_engine.render.assets.textures import linear_to_srgb

W, H = 64, 48
FACING_Z = (math.sin(math.pi / 4), 0.0, 0.0, math.cos(math.pi / 4))
RADIANCE = np.array([2.0, 0.5, 0.125])  # exact in half floats


def aces(x):
    return np.clip((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0)


CURVES = {"clamp": lambda x: np.minimum(x, 1.0), "aces": aces, "reinhard": lambda x: x / (1.0 + x)}


def glowing_plane(gpu, size: float = 4.0, rotation=FACING_Z) -> World:
    world = World()
    m = materials(world).add(Material("glow", "unlit", (0.0, 0.0, 0.0, 1.0), emissive=tuple(RADIANCE)))
    world.spawn(Transform(rotation=rotation), Mesh(handle=gpu.meshes.add(plane_mesh(size)), material=m))
    world.spawn(Transform(position=(0.0, 0.0, 1.0)), Camera(fov_y=math.radians(60.0), near=0.05))
    return world


def draw(gpu, world: World, target=None, **settings) -> np.ndarray:
    return render_world(gpu, world, target, **settings)


@pytest.mark.parametrize("name", list(CURVES))
@pytest.mark.parametrize("exposure", [0.0, -1.5, 1.0])
def test_tone_maps_match_their_formulas(name, exposure):
    with headless_gpu(W, H) as gpu:
        got = draw(gpu, glowing_plane(gpu), tone_map=name, exposure=exposure)[H // 2, W // 2]
    want = np.round(linear_to_srgb(CURVES[name](RADIANCE * 2.0**exposure)) * 255)
    assert np.abs(got - want).max() <= 1, (name, exposure, got, want)


def test_clamp_keeps_the_old_look_and_aces_keeps_highlights_apart():
    """Two radiances above 1 come out the same under clamp (both 255) and different under ACES."""
    with headless_gpu(W, H) as gpu:
        world = glowing_plane(gpu)
        clamp = draw(gpu, world)[H // 2, W // 2]
        filmic = draw(gpu, world, tone_map="aces", exposure=-1.0)[H // 2, W // 2]
    assert clamp[0] == 255 and clamp[1] < 255
    assert filmic[0] < 255 and filmic[0] > filmic[1]


def edge_pixels(img: np.ndarray) -> int:
    """Pixels part way between the black background and the plane's red (its centre's value)."""
    red = img[..., 0]
    inside = red[H // 2, W // 2]
    return int(((red > 0.1 * inside) & (red < 0.9 * inside)).sum())


def test_msaa_smooths_the_edges():
    from ecs_engine.gpu.offscreen import OffscreenTarget

    tilted = (0.0, 0.0, math.sin(0.2), math.cos(0.2))  # about Z: edges across pixel rows
    with headless_gpu(W, H) as gpu:
        rotation = tuple(np.array(FACING_Z))  # facing the camera, then turned in its plane
        world = glowing_plane(gpu, size=0.8, rotation=_compose(tilted, rotation))
        plain = draw(gpu, world, tone_map="reinhard", clear_color=(0.0, 0.0, 0.0))
        target = OffscreenTarget(gpu.device, W, H, samples=4)
        try:
            smooth = draw(gpu, world, target=target, tone_map="reinhard", clear_color=(0.0, 0.0, 0.0))
        finally:
            target.destroy()
    assert edge_pixels(plain) <= 2  # without MSAA a pixel is in or out
    assert edge_pixels(smooth) > 20
    half = plain[H // 2, W // 2, 0] / 2
    covered = int((plain[..., 0] > half).sum())
    # the same shape (edge pixels count a little more often as covered with MSAA: the resolve
    # averages linear HDR colour, and the curve and sRGB encoding lift half-covered pixels)
    assert abs(covered - int((smooth[..., 0] > half).sum())) < 0.1 * covered


def _compose(a, b):
    """Quaternion product a * b (x, y, z, w): b first, then a."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    )


def test_bad_settings_are_refused():
    from ecs_engine.gpu.scene_attachments import supported_samples
    from ecs_engine.render.config import check_samples
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(W, H) as gpu:
        assert 1 in supported_samples(gpu.device)
        with pytest.raises(UsageError, match="--msaa 3"):
            check_samples(gpu.device, 3)
        with pytest.raises(UsageError, match="tone map"):
            Renderer(gpu.device, gpu.target, gpu.meshes, tone_map="filmic-ish")
        with pytest.raises(UsageError, match="exposure"):
            Renderer(gpu.device, gpu.target, gpu.meshes, exposure=float("nan"))


def test_session_changes_tone_map_and_exposure_live():
    from ecs_engine.app.offscreen import OffscreenSource
    from ecs_engine.app.session import Session
    from ecs_engine.app.settings import RunOptions

    source = OffscreenSource()
    with Session(RunOptions(scene="cube", width=W, height=H, validate=True, threads=1), source) as session:
        session.apply(replace(session.settings, tone_map="aces", exposure=2.0))
        assert (session.renderer.tone_map, session.renderer.exposure) == ("aces", 2.0)
        with pytest.raises(UsageError, match="exposure"):
            session.apply(replace(session.settings, exposure=99.0, scene="grid100"))
        assert session.settings.exposure == 2.0 and session.settings.scene == "cube"
    assert source.validation_messages() == []
    with pytest.raises(UsageError, match="tone map"):
        RunOptions(tone_map="nope")


def test_cli_hdr_flags(tmp_path):
    shot = tmp_path / "hdr.png"
    base = [sys.executable, "-m", "ecs_engine", "demo", "grid100", "--headless", "--frames", "2"]
    proc = subprocess.run(
        [*base, "--width", "64", "--height", "48", "--tone-map", "aces", "--exposure", "0.5", "--msaa", "4"]
        + ["--validate", "--screenshot", str(shot)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    assert shot.exists() and "validation" not in proc.stderr.lower()
    bad = subprocess.run([*base, "--exposure", "nan"], capture_output=True, text=True, timeout=300)
    assert bad.returncode == 2 and "exposure" in bad.stderr and "Traceback" not in bad.stderr


def test_the_target_takes_the_scene_straight_unless_the_tone_map_needs_hdr():
    """clamp at exposure 0 without MSAA needs no HDR colour: the scene goes straight into the sRGB
    target (no tone map pass). Another tone map or exposure switches the target to HDR between
    frames, and back; the pipelines follow, and the clamp image is the same either way."""
    from ecs_engine.app.scenes import default_schedule
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(W, H) as gpu:
        world = glowing_plane(gpu)
        default_schedule().run(world, 0.0)
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes)
        waits = []
        real_wait = gpu.device.wait_idle
        try:
            shots, pipelines = [], []
            for tone_map, exposure in [("clamp", 0.0), ("aces", 0.0), ("clamp", 1e-6), ("clamp", 0.0)]:
                renderer.tone_map, renderer.exposure = tone_map, exposure
                renderer.render(world, readback=True)
                shots.append((gpu.target.hdr, gpu.target.pixels()[..., :3].astype(int)))
                pipelines.append(renderer.path.pipelines)
                gpu.device.wait_idle = lambda: waits.append(1)  # type: ignore[method-assign]
        finally:
            gpu.device.wait_idle = real_wait  # type: ignore[method-assign]
            renderer.destroy()
    assert [hdr for hdr, _ in shots] == [False, True, True, False]
    # a change of form neither waits for the device nor remakes what was made for the old one:
    # back in the direct form, the mesh pipelines are those of the first frame
    assert waits == [] and pipelines[0] == pipelines[3] and pipelines[1] == pipelines[2] != pipelines[0]
    direct, filmic, hdr_clamp, direct_again = (image for _, image in shots)
    assert np.array_equal(direct, direct_again)
    assert np.abs(direct - hdr_clamp).max() <= 1  # the same picture, through HDR or not
    assert np.abs(direct - filmic).max() > 8  # aces(0.5) is 0.62, not 0.5


def test_msaa_always_renders_through_hdr():
    from ecs_engine.gpu.offscreen import OffscreenTarget

    with headless_gpu(W, H) as gpu:
        target = OffscreenTarget(gpu.device, W, H, samples=4)
        try:
            assert target.hdr and target.hdr_view is not None
            target.set_form("direct")  # the resolve needs the HDR colour: refused quietly
            assert target.hdr and target.form == "hdr"
        finally:
            target.destroy()


def test_blended_materials_are_drawn_through_hdr_colour():
    """An 8-bit target clamps a blended colour before blending: glass lit to 3.0 at alpha 0.5
    over a dark background would come out at 0.5. With a blended material in the world the
    target takes the HDR form even at clamp and exposure 0, and the glass is white."""
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(W, H) as gpu:
        world = World()
        glass = materials(world).add(
            Material("glass", "unlit", (0.0, 0.0, 0.0, 0.5), emissive=(3.0, 3.0, 3.0), alpha_mode="blend")
        )
        world.spawn(Transform(rotation=FACING_Z), Mesh(handle=gpu.meshes.add(plane_mesh(4.0)), material=glass))
        world.spawn(Transform(position=(0.0, 0.0, 1.0)), Camera(fov_y=math.radians(60.0), near=0.05))
        image = render_world(gpu, world)
        assert gpu.target.hdr
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes)  # a world without: straight again
        try:
            renderer.render(glowing_plane(gpu))
            assert not gpu.target.hdr
        finally:
            renderer.destroy()
    assert image[H // 2, W // 2].min() >= 254
