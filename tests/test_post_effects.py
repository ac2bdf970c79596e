"""Post effects as features (render/post/registry.py, post/effects.py, passes/output_graph.py), on lavapipe
with validation on: the registry and the config's rule; bloom in the renderer against the NumPy
reference applied to the same frame's HDR colour; FXAA in the output's ldr stage against its
NumPy reference; toggling at runtime with frame replay on; the form switch; the plugins and
`--post`."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from bloom_reference import bloom as reference_bloom
from fxaa_reference import fxaa_outcomes, linear_to_srgb, outcome_errors, srgb_to_linear
from gpu_context import headless_gpu
from image_readback import record_copy_out

from ecs_engine import World
from ecs_engine.app.scenes import default_schedule
from ecs_engine.components import Mesh, PointLight, Transform
from ecs_engine.demos.scene_kit import add_camera
from ecs_engine.errors import UsageError
from ecs_engine.render.assets.primitives import cube_mesh
from ecs_engine.render.config import POST_EFFECTS, RenderConfig, validate
from ecs_engine.render.post import registry
from ecs_engine.render.post.bloom_settings import BloomSettings
from ecs_engine.render.post.fxaa import FxaaSettings
from ecs_engine.render.post.ssao import SsaoSettings

# ------------------------------------------------------------------------------ the registry


def test_the_registry_names_the_built_in_effects_and_the_config_reads_it():
    kinds = registry.kinds()
    built_in = {n: (k.stage, k.settings) for n, k in kinds.items() if n in ("bloom", "fxaa", "ssao")}
    assert built_in == {"bloom": ("hdr", BloomSettings), "fxaa": ("ldr", FxaaSettings), "ssao": ("hdr", SsaoSettings)}
    assert POST_EFFECTS == frozenset(kinds)
    assert registry.ordered({"fxaa", "bloom"}) == ("bloom", "fxaa")  # the hdr stage first
    assert registry.ordered({"fxaa", "bloom", "ssao"}) == ("ssao", "bloom", "fxaa")  # ssao before bloom
    assert validate(RenderConfig(post={"bloom", "fxaa"})) == []
    (refusal,) = validate(RenderConfig(post={"bloom", "sparkles"}))
    assert f"unknown post effect in bloom, sparkles; choices: {', '.join(sorted(kinds))}" in refusal
    with pytest.raises(UsageError, match="unknown post effect 'x'"):
        registry.ordered({"x"})
    with pytest.raises(UsageError, match="stage must be one of hdr, ldr"):
        registry.PostEffectKind("glow", "middle", BloomSettings, object)
    with pytest.raises(UsageError, match="bloom settings must be BloomSettings"):
        kinds["bloom"].check_settings(FxaaSettings())


# ------------------------------------------------------------------------------ on the device


def _world(gpu: Any) -> World:
    """A cube, and a point light whose billboard is far brighter than 1 (what bloom spreads)."""
    world = World()
    world.spawn(Transform(), Mesh(handle=gpu.meshes.add(cube_mesh())))
    world.spawn(Transform(position=(1.5, 1.0, 1.0)), PointLight(intensity=40.0))
    add_camera(world, eye=(0.0, 1.0, 4.0), target=(0.0, 0.0, 0.0))
    default_schedule().run(world, 0.0)
    return world


def _renderer(gpu: Any, **settings: Any) -> Any:
    from ecs_engine.render.frame.renderer import Renderer

    renderer = Renderer(gpu.device, gpu.target, gpu.meshes, **settings)
    gpu.owned.append(renderer)
    return renderer


def _pixels(gpu: Any, renderer: Any, world: World) -> np.ndarray:
    renderer.ensure_output()
    renderer.render(world, readback=True)
    return gpu.target.pixels()[..., :3].astype(np.int64)


class HdrSpy:
    """An hdr-stage post effect that copies the HDR colour to a buffer (the HDR image made with
    transfer usage for the test): run first, it sees what the effects after it get."""

    def __init__(self, device: Any, width: int, height: int) -> None:
        from ecs_engine.gpu.memory import Buffer

        vk = self.vk = device.vk
        self.size = (width, height)
        self.buffer = Buffer(device, width * height * 8, vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT)

    def __call__(self, cb: Any, inputs: Any) -> None:
        read_only = self.vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL
        record_copy_out(self.vk, cb, inputs.hdr.handle, self.buffer, self.size, read_only)

    def hdr(self) -> np.ndarray:
        width, height = self.size
        return self.buffer.bytes()[: width * height * 8].view(np.float16).reshape(height, width, 4).copy()

    def destroy(self) -> None:
        self.buffer.destroy()


def test_bloom_in_the_renderer_is_the_reference_bloom_of_the_frames_hdr_colour(monkeypatch):
    """The frame with bloom on is clamp(bloom(hdr)) of that frame's own HDR colour, read just
    before the bloom: the NumPy reference of the whole chain, within a level of 8-bit sRGB
    (it would fail with the bloom left out or run twice); around the bright billboard the
    frame is brighter than without bloom (the energy-conserving composite moves light there)."""
    from ecs_engine.gpu import scene_attachments as render_pass

    usage = render_pass.hdr_read_usage
    monkeypatch.setattr(render_pass, "hdr_read_usage", lambda d: usage(d) | d.vk.VK_IMAGE_USAGE_TRANSFER_SRC_BIT)
    width, height = 64, 48
    with headless_gpu(width, height) as gpu:
        world = _world(gpu)
        renderer = _renderer(gpu, post={"bloom": BloomSettings(intensity=0.3)})
        renderer.replay.enabled = False  # the spy is no part of the frame's key
        spy = HdrSpy(gpu.device, width, height)
        gpu.owned.append(spy)
        assert gpu.target.form == "hdr"
        renderer.output.post.insert(0, spy)
        bloomed = _pixels(gpu, renderer, world)
        hdr = spy.hdr()
        assert hdr[..., :3].max() > 4.0  # the billboard: light to spread
        want = reference_bloom(hdr, BloomSettings(intensity=0.3))[..., :3]
        expected = np.round(linear_to_srgb(np.minimum(want, 1.0)) * 255).astype(np.int64)
        assert np.abs(bloomed - expected).max() <= 2, np.abs(bloomed - expected).max()
        plain = np.round(linear_to_srgb(np.minimum(hdr[..., :3].astype(np.float64), 1.0)) * 255)
        assert np.abs(bloomed - plain).max() > 8  # the bloom shows
        renderer.output.post.remove(spy)
        renderer.set_post_effects(set())
        off = _pixels(gpu, renderer, world)
        assert gpu.target.form == "direct"  # none on: straight into the target again
        bright = hdr[..., :3].max(axis=2) > 2.0
        ring = np.zeros_like(bright)
        for dy in range(-2, 3):  # the pixels around the bright ones, but not those
            for dx in range(-2, 3):
                ring |= np.roll(np.roll(bright, dy, 0), dx, 1)
        ring &= ~bright
        assert ring.any() and (bloomed.sum(axis=2) - off.sum(axis=2))[ring].max() > 8  # lit by the glow


def test_fxaa_in_the_ldr_stage_is_the_reference_fxaa_of_the_tone_mapped_frame():
    """With FXAA on, the tone map writes an intermediate image and FXAA the target: the frame
    is the NumPy FXAA of the frame without it (both tone mapped by ACES, the hdr form), within
    two levels and the hardware filter's precision; only pixels at edges change."""
    with headless_gpu(64, 48) as gpu:
        world = _world(gpu)
        renderer = _renderer(gpu, tone_map="aces")
        off = _pixels(gpu, renderer, world)
        renderer.set_post_effects({"fxaa"})
        on = _pixels(gpu, renderer, world)
        assert renderer.output.graph is not None and "fxaa" in renderer.output.graph.describe()
        linear = srgb_to_linear(np.concatenate([off, np.full(off.shape[:2] + (1,), 255)], axis=2) / 255.0)
        # comparisons within half an 8-bit step of luma may go either way: the intermediate image
        # is 8-bit sRGB, which the GPU decodes with its own precision
        reference = fxaa_outcomes(linear, linear=True, tie=0.5 / 255)

        def to_bytes(colour):
            return np.round(linear_to_srgb(np.asarray(colour)[..., :3]) * 255)

        # a GPU's bilinear weights have subTexelPrecisionBits of precision (the H200's frame
        # differed from the reference by 4 levels): a blend's error is at most a weight step
        # times the local contrast (linear), which the sRGB encode steepens in dark pixels
        step = 2.0 ** -int(gpu.device.limits.subTexelPrecisionBits)
        lin = linear[..., :3]
        pad = np.pad(lin, ((1, 1), (1, 1), (0, 0)), mode="edge")
        near3 = np.stack(
            [
                pad[1 + dy : 1 + dy + lin.shape[0], 1 + dx : 1 + dx + lin.shape[1]]
                for dy in (-1, 0, 1)
                for dx in (-1, 0, 1)
            ]
        )
        contrast = (near3.max(axis=0) - near3.min(axis=0)).max(axis=-1)
        want = np.asarray(reference[0])[..., :3]
        slope = ((linear_to_srgb(np.clip(want + 1e-3, 0, 1)) - linear_to_srgb(want)) / 1e-3).max(axis=-1)
        allowed = 2 + 255 * slope * contrast * step
        assert (outcome_errors(on, reference, to_bytes) <= allowed).all()
        print(f"allowed {allowed.max():.2f} levels at most; FXAA moved pixels by up to {np.abs(on - off).max()}")
        assert allowed.max() < 16  # the allowance stays far below what FXAA changes at an edge
        changed = np.abs(on - off).max(axis=2) > 0
        luma = off @ np.array([0.299, 0.587, 0.114])
        pad = np.pad(luma, 1, mode="edge")
        window = np.stack(
            [
                pad[1 + dy : 1 + dy + luma.shape[0], 1 + dx : 1 + dx + luma.shape[1]]
                for dy, dx in [(0, 0), (-1, 0), (1, 0), (0, -1), (0, 1)]
            ]
        )
        edges = window.max(axis=0) - window.min(axis=0) >= 0.0833 * 255  # FXAA's early exit below
        near = np.zeros_like(edges)
        for dy in (-1, 0, 1):  # the end search and the blend reach a neighbour of an edge pixel
            for dx in (-1, 0, 1):
                near |= np.roll(np.roll(edges, dy, 0), dx, 1)
        assert changed.any() and not (changed & ~near).any()


def test_toggling_at_runtime_never_replays_a_stale_frame():
    """With frame replay on, each change of the effects or their settings shows in the next
    frame (never a kept recording of the old ones), replayed frames draw what recorded ones
    did, and turning an effect on switches the direct form to hdr (off: back)."""
    with headless_gpu(48, 32) as gpu:
        world = _world(gpu)
        renderer = _renderer(gpu)
        replay = renderer.replay

        def settle() -> np.ndarray:
            """Frames until one is replayed: its image (a recorded frame's)."""
            first = _pixels(gpu, renderer, world)
            for _ in range(6):
                before = replay.replayed
                again = _pixels(gpu, renderer, world)
                if replay.replayed > before:
                    assert np.array_equal(again, first)
                    return again
            raise AssertionError("no frame was replayed")

        plain = settle()
        assert gpu.target.form == "direct"
        renderer.set_post_effects({"bloom"})
        assert gpu.target.form == "hdr"
        bloom = settle()
        renderer.post_settings["bloom"] = BloomSettings(intensity=0.6)  # made again with these
        stronger = settle()
        renderer.set_post_effects({"bloom", "fxaa"})
        both = settle()
        renderer.set_post_effects(set())
        assert gpu.target.form == "direct"
        back = settle()
        assert np.array_equal(back, plain)
        for a, b in ((plain, bloom), (bloom, stronger), (stronger, both)):
            assert np.abs(a - b).max() > 2
        assert renderer.post_settings["bloom"] == BloomSettings(intensity=0.6)  # kept while off
        assert renderer.config.post == frozenset()
        with pytest.raises(UsageError, match="unknown post effect 'glow'"):
            renderer.set_post_effects({"bloom", "glow"})
        with pytest.raises(UsageError, match="fxaa settings must be FxaaSettings"):
            renderer.post_settings["fxaa"] = BloomSettings()
        assert renderer.post_effects == () and gpu.target.form == "direct"  # nothing changed


def test_the_replay_key_holds_the_effects():
    """The frame's replay key changes with an effect on or off and with its settings: the output
    graph's passes' keys hold them (fxaa's pass; render/frame/replay.py frame_key)."""
    from ecs_engine.render.frame.replay import frame_key

    with headless_gpu(32, 24) as gpu:
        world = _world(gpu)
        renderer = _renderer(gpu, tone_map="aces")

        def key() -> Any:
            renderer.render(world, readback=True)  # the output graph of these effects is made
            state = renderer.output._last[1]
            frame = frame_key(renderer, state, 0, (0, None, 0, True), ([], [], False))
            assert frame is not None
            return frame[-1][:-2]  # the graph's passes' (name, key) in order

        keys = [key()]
        renderer.set_post_effects({"fxaa"})
        keys.append(key())
        renderer.post_settings["fxaa"] = FxaaSettings(subpix=0.25)
        keys.append(key())
        renderer.set_post_effects(set())
        keys.append(key())
        assert keys[0] == keys[3] and len({repr(k) for k in keys}) == 3
        assert "fxaa" not in dict(keys[0]) and dict(keys[1])["fxaa"] != dict(keys[2])["fxaa"]


# ------------------------------------------------------------------------------ the one line


def test_the_plugin_line_turns_an_effect_on():
    from ecs_engine import App, BloomPlugin, DefaultPlugins, FxaaPlugin

    app = App(title="glow", size=(32, 24))
    app.add_plugins(DefaultPlugins, BloomPlugin(BloomSettings(intensity=0.2)), FxaaPlugin())
    seen = {}

    def look(world: Any, session: Any) -> None:
        seen["post"] = session.renderer.post_effects
        seen["bloom"] = session.renderer.post_settings["bloom"]
        seen["form"] = session.renderer.target.form

    app.on_open(look)
    app.add_startup_systems(lambda world, dt: add_camera(world, eye=(0.0, 1.0, 4.0), target=(0.0, 0.0, 0.0)))
    app.run(frames=1, headless=True)
    assert seen == {"post": ("bloom", "fxaa"), "bloom": BloomSettings(intensity=0.2), "form": "hdr"}
    with pytest.raises(UsageError, match="bloom settings must be BloomSettings"):
        App().add_plugins(BloomPlugin(FxaaSettings()))


def test_the_cli_flag_turns_effects_on_and_refuses_an_unknown_one(capsys, monkeypatch):
    from ecs_engine.app.cli import main
    from ecs_engine.app.settings import RunOptions
    from ecs_engine.render.post.bloom import BloomDownsample
    from ecs_engine.render.post.fxaa import FxaaPass

    ran: list[str] = []  # the effects' passes recorded (bloom's in the output graph)
    for cls, name, method in ((BloomDownsample, "bloom", "record"), (FxaaPass, "fxaa", "record")):
        real = getattr(cls, method)

        def logged(self, *args, _real=real, _name=name):
            ran.append(_name)
            return _real(self, *args)

        monkeypatch.setattr(cls, method, logged)
    assert RunOptions(post=frozenset({"bloom"})).settings().post == {"bloom"}
    assert (
        main(["demo", "cube", "--headless", "--frames", "1", "--width", "32", "--height", "24", "--post", "bloom,fxaa"])
        == 0
    )
    assert "bloom" in ran and "fxaa" in ran
    capsys.readouterr()
    with pytest.raises(SystemExit) as exit_info:
        main(["demo", "cube", "--headless", "--post", "bogus"])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    choices = ", ".join(sorted(registry.kinds()))
    assert err.count("\n") == 1 and f"unknown post effect 'bogus'; choices: {choices}" in err


def test_the_editor_has_a_toggle_per_effect_that_goes_through_the_renderer(scene):
    """Clicking the "bloom" checkbox of the "Scene and render" window turns bloom on through
    the session's apply (Renderer.set_post_effects): the form becomes hdr; again turns it off."""
    from test_editor import centre

    scene.frame()
    scene.frame()  # the dock layout settles
    editor = scene.session.editor
    assert {"post bloom", "post fxaa", "post ssao"} <= set(editor.rects)  # one per registered effect
    renderer = scene.state.renderer

    def click(name: str) -> None:
        scene.frame(mouse=centre(editor.rects[name]))
        scene.frame(down=True)
        scene.frame(down=False)
        scene.frame()

    click("post bloom")
    assert renderer.post_effects == ("bloom",) and scene.gpu.target.form == "hdr"
    assert scene.state.settings.post == {"bloom"}
    click("post bloom")
    assert renderer.post_effects == ()


@pytest.mark.parametrize("settings", [{"light_culling": "deferred"}, {"samples": 4}], ids=["deferred", "msaa4"])
def test_effects_run_in_the_deferred_form_and_over_msaa(settings):
    """Both stages run after the G-buffer's lighting (the deferred form, the light culling's
    choice here) and after the MSAA resolve, validation-clean, and change the frame."""
    from ecs_engine.gpu.offscreen import OffscreenTarget
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(48, 32) as gpu:
        target = OffscreenTarget(gpu.device, 48, 32, samples=settings.get("samples", 1))
        gpu.owned.append(target)
        world = _world(gpu)
        renderer = Renderer(gpu.device, target, gpu.meshes, light_culling=settings.get("light_culling", "auto"))
        gpu.owned.append(renderer)
        renderer.render(world, readback=True)
        off = target.pixels()[..., :3].astype(np.int64)
        renderer.set_post_effects({"bloom", "fxaa"})
        renderer.render(world, readback=True)
        on = target.pixels()[..., :3].astype(np.int64)
        assert target.form == ("deferred" if "light_culling" in settings else "hdr")
        assert np.abs(on - off).max() > 8
