"""A post effect is a plugin: a game's own, wholly outside ecs_engine/ (this module; its GLSL and
SPIR-V in tests/shaders/), registered (render/post/registry.py) and turned on as a user would
(RenderConfig, `set_post_effects`, `PostEffectPlugin`, `--post`), against NumPy on lavapipe:
"vignette" (ldr stage) darkens the tone-mapped image towards the corners, in linear colour;
"exposure_scale" (hdr stage) scales the HDR colour in place before the tone map. The `external`
fixture registers them for a test and unregisters them after it."""

from __future__ import annotations

import json
import math
import shutil
import subprocess
from collections.abc import Hashable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from fxaa_reference import linear_to_srgb, srgb_to_linear
from gpu_context import headless_gpu

from ecs_engine import World
from ecs_engine.app.scenes import default_schedule
from ecs_engine.components import Mesh, Transform
from ecs_engine.demos.scene_kit import add_camera
from ecs_engine.errors import UsageError
from ecs_engine.gpu.array_image import clamped_sampler
from ecs_engine.gpu.descriptors import DescriptorPool, DescriptorSetLayout, write_set
from ecs_engine.gpu.owned import Owned
from ecs_engine.gpu.pipeline import compute_pipeline, pipeline_layout
from ecs_engine.render.assets.primitives import cube_mesh
from ecs_engine.render.config import RenderConfig, validate
from ecs_engine.render.graph import Access, ImageDesc, Pass
from ecs_engine.render.post import registry
from ecs_engine.render.post.bloom_settings import BloomSettings
from ecs_engine.render.post.fxaa import fullscreen_pipeline  # the engine's full-screen triangle pipeline

SHADERS = Path(__file__).resolve().parent / "shaders"
SOURCES = ("vignette.frag", "exposure_scale.comp")


def shader(name: str) -> str:
    """A game's own SPIR-V, by path (gpu/pipeline.py shader_path)."""
    return str(SHADERS / f"{name}.spv")


# ------------------------------------------------------------------------------ the effects


def _check(what: str, value: Any, low: float, high: float) -> None:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not low <= value <= high:  # NaN: refused
        raise UsageError(f"{what} must be a number in [{low}, {high}], got {value!r}")


@dataclass(frozen=True)
class VignetteSettings:
    strength: float = 0.8  # the darkening at an edge's middle; a corner gets twice it

    def __post_init__(self) -> None:
        _check("vignette strength", self.strength, 0.0, 1.0)


@dataclass(frozen=True)
class ExposureScaleSettings:
    scale: float = 0.5

    def __post_init__(self) -> None:
        _check("exposure scale", self.scale, 0.0, math.inf)


class _OneSetPass(Pass):
    """A pass with one descriptor set of one image binding, kept per (graph compile, view): a
    compile makes new transients whose handles may reuse old values, so the sets go with it."""

    descriptor: str = ""  # the binding's VkDescriptorType name
    stage: str = ""  # the VkShaderStageFlagBits name of its shader
    knob: str = ""  # the settings' field pushed as the one float push constant

    def __init__(self, graph: Any, settings: Any) -> None:
        self.graph, self.settings = graph, settings
        self.push = np.array([getattr(settings, self.knob)], np.float32)
        self.owned: Owned | None = None
        self.pool: DescriptorPool | None = None
        self.sets: dict[tuple[int, int], Any] = {}  # (graph compile, view) -> VkDescriptorSet[1]
        self.pipelines: dict[int, Any] = {}  # target format -> pipeline

    def make(self, device: Any) -> None:
        vk = device.vk
        self.owned = owned = Owned(device)
        stage = getattr(vk, f"VK_SHADER_STAGE_{self.stage}_BIT")
        kind = getattr(vk, f"VK_DESCRIPTOR_TYPE_{self.descriptor}")
        self.set_layout = owned.add(DescriptorSetLayout(device, [(0, kind, stage)]))
        layout = pipeline_layout(device, [self.set_layout.handle], [(stage, 0, 4)])
        self.layout = owned.add(layout, lambda: vk.vkDestroyPipelineLayout(device.handle, layout, None))
        sampler = clamped_sampler(device, max_lod=0.0)
        self.sampler = owned.add(sampler, lambda: vk.vkDestroySampler(device.handle, sampler, None))

    def set_for(self, device: Any, image: Any) -> Any:
        vk = device.vk
        key = (self.graph.compiles, int(vk.ffi.cast("uintptr_t", image.view)))
        if key in self.sets:
            return self.sets[key]
        assert self.owned is not None
        if self.pool is None or len(self.sets) >= 8 or any(k[0] != key[0] for k in self.sets):
            if self.pool is not None:
                device.wait_idle()  # frames in flight may still bind the old sets
                self.owned.release(self.pool)
            self.sets.clear()
            kind = getattr(vk, f"VK_DESCRIPTOR_TYPE_{self.descriptor}")
            self.pool = self.owned.add(DescriptorPool(device, 8, {kind: 8}))
        descriptor_set = self.pool.allocate(self.set_layout)
        if self.descriptor == "STORAGE_IMAGE":
            write_set(device, descriptor_set, storage_images=[(0, image.view)])
        else:
            read_only = vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL
            write_set(device, descriptor_set, samplers=[(0, self.sampler, image.view, read_only)])
        self.sets[key] = vk.ffi.new("VkDescriptorSet[1]", [descriptor_set])
        return self.sets[key]

    def key(self) -> Hashable:
        return self.settings

    def bind(self, cb: Any, ctx: Any, point: int, fmt: int, image: Any) -> None:
        """Its pipeline (for a target format; made, with the rest, on the first record), set
        and push constants bound."""
        vk, lib = ctx.vk, ctx.vk.lib
        if self.owned is None:
            self.make(ctx.device)
        if fmt not in self.pipelines:
            made, handle = self.pipeline(ctx.device, fmt), ctx.device.handle
            assert self.owned is not None
            self.pipelines[fmt] = self.owned.add(made, lambda: vk.vkDestroyPipeline(handle, made, None))
        lib.vkCmdBindPipeline(cb, point, self.pipelines[fmt])
        lib.vkCmdBindDescriptorSets(cb, point, self.layout, 0, 1, self.set_for(ctx.device, image), 0, vk.ffi.NULL)
        stage = getattr(vk, f"VK_SHADER_STAGE_{self.stage}_BIT")
        lib.vkCmdPushConstants(cb, self.layout, stage, 0, 4, vk.ffi.from_buffer(self.push))

    def destroy(self) -> None:
        if self.owned is not None:
            self.owned.destroy()
        self.owned, self.pool, self.sets, self.pipelines = None, None, {}, {}


class VignettePass(_OneSetPass):
    name = "vignette"
    descriptor, stage, knob = "COMBINED_IMAGE_SAMPLER", "FRAGMENT", "strength"

    def __init__(self, graph: Any, settings: VignetteSettings, source: str, target: str, create: Any) -> None:
        super().__init__(graph, settings)
        self.source, self.target, self.create = source, target, create

    def setup(self, builder: Any) -> None:
        if self.create is not None:
            builder.create(self.target, self.create)
        builder.read(self.source, Access.FRAGMENT_SAMPLED)
        builder.write(self.target, Access.COLOR_WRITE)

    def pipeline(self, device: Any, fmt: int) -> Any:
        return fullscreen_pipeline(device, self.layout, shader("vignette.frag"), fmt, None)

    def record(self, cb: Any, ctx: Any) -> None:
        ctx.begin_rendering(colors=(self.target,))
        fmt = int(ctx.image(self.target).format)
        self.bind(cb, ctx, ctx.vk.VK_PIPELINE_BIND_POINT_GRAPHICS, fmt, ctx.image(self.source))
        ctx.vk.lib.vkCmdDraw(cb, 3, 1, 0, 0)
        ctx.end_rendering()


class ExposureScalePass(_OneSetPass):
    name = "exposure_scale"
    descriptor, stage, knob = "STORAGE_IMAGE", "COMPUTE", "scale"

    def setup(self, builder: Any) -> None:
        builder.write("hdr", Access.COMPUTE_READ_WRITE)  # in place, as the bloom's composite

    def pipeline(self, device: Any, fmt: int) -> Any:
        return compute_pipeline(device, shader("exposure_scale.comp"), self.layout)

    def record(self, cb: Any, ctx: Any) -> None:
        hdr = ctx.image("hdr")
        self.bind(cb, ctx, ctx.vk.VK_PIPELINE_BIND_POINT_COMPUTE, 0, hdr)
        ctx.vk.lib.vkCmdDispatch(cb, (hdr.extent[0] + 7) // 8, (hdr.extent[1] + 7) // 8, 1)


class _Effect:
    """The effect object registry.py's `make(device, settings)` gives; its passes are the graphs'."""

    def __init__(self, device: Any, settings: Any) -> None:
        self.settings = settings

    def key(self, inputs: Any = None) -> Hashable:
        return (type(self).__name__, self.settings)

    def destroy(self) -> None:
        pass


class VignetteEffect(_Effect):
    def add(self, graph: Any, source: str, target: str, create: ImageDesc | None = None) -> None:
        """The ldr stage: its pass from `source` into `target` in the output's graph."""
        graph.add_pass(VignettePass(graph, self.settings, source, target, create))


class ExposureScaleEffect(_Effect):
    def add_hdr(self, graph: Any, extent: tuple[int, int]) -> None:
        """The hdr stage: its pass over the graph's "hdr", before the tone map."""
        graph.add_pass(ExposureScalePass(graph, self.settings))


VIGNETTE = registry.PostEffectKind("vignette", "ldr", VignetteSettings, VignetteEffect, "a test's vignette")
EXPOSURE = registry.PostEffectKind("exposure_scale", "hdr", ExposureScaleSettings, ExposureScaleEffect, "scale")


@pytest.fixture
def external() -> Iterator[None]:
    assert validate(RenderConfig(post={"vignette"}))  # unknown before it is registered
    registry.register(VIGNETTE)
    registry.register(EXPOSURE)
    try:
        yield
    finally:
        for name in {"vignette", "exposure_scale"} & registry.names():
            registry.unregister(name)
    assert not {"vignette", "exposure_scale"} & registry.names()
    assert validate(RenderConfig(post={"vignette"}))  # refused again


# ------------------------------------------------------------------------------ the registry


def test_a_registered_effect_is_a_name_like_the_built_in_ones(external):
    from ecs_engine.render.config.flags import post_list

    assert registry.kind("vignette") is VIGNETTE
    assert validate(RenderConfig(post={"vignette", "exposure_scale", "fxaa"})) == []
    assert post_list("vignette,bloom") == {"vignette", "bloom"}  # what --post parses
    # the hdr stage first, each in registration order (the built-in ones first)
    order = ("bloom", "exposure_scale", "fxaa", "vignette")
    assert registry.ordered(set(order)) == order
    with pytest.raises(UsageError, match="vignette settings must be VignetteSettings"):
        VIGNETTE.check_settings(BloomSettings())
    # a bad kind, an unknown name, bad settings: one UsageError each
    with pytest.raises(UsageError, match=r"post effect 'vignette': stage must be one of hdr, ldr, got 'post'") as e:
        registry.PostEffectKind("vignette", "post", VignetteSettings, VignetteEffect)
    assert "\n" not in str(e.value)
    with pytest.raises(UsageError, match="post effect name 'Vignette!'"):
        registry.PostEffectKind("Vignette!", "ldr", VignetteSettings, VignetteEffect)
    with pytest.raises(UsageError, match="unknown post effect 'sparkles'"):
        registry.unregister("sparkles")
    with pytest.raises(UsageError, match=r"vignette strength must be a number in \[0.0, 1.0\], got 2.0"):
        VignetteSettings(2.0)


def test_a_name_another_module_registered_is_refused_and_a_reload_replaces(external):
    """Not a built-in's name; the same module again (hot reload) replaces its own."""
    before = registry.kind("bloom")
    with pytest.raises(UsageError, match=r"'bloom' is taken \(by ecs_engine\.render\.post\.bloom_effect\)"):
        registry.register(registry.PostEffectKind("bloom", "ldr", VignetteSettings, VignetteEffect))
    assert registry.kind("bloom") is before
    again = registry.PostEffectKind("vignette", "ldr", VignetteSettings, VignetteEffect, "reloaded")
    try:
        assert registry.register(again) is again and registry.kind("vignette") is again
    finally:
        registry.register(VIGNETTE)  # the fixture's, whatever happened


def test_the_committed_spirv_is_its_source_compiled(tmp_path):
    """As tests/test_shaders.py does for the engine's shaders: byte for byte with the glslc the
    engine's manifest records; with another one, that the sources still compile."""
    for name in SOURCES:
        assert (SHADERS / f"{name}.spv").read_bytes()[:4] == b"\x03\x02\x23\x07"
    if shutil.which("glslc") is None:
        pytest.skip("glslc not installed")
    version = subprocess.run(["glslc", "--version"], capture_output=True, text=True).stdout.splitlines()[0]
    recorded = json.loads((SHADERS.parent.parent / "shaders" / "manifest.json").read_text())["glslc"]
    for name in SOURCES:
        out = tmp_path / f"{name}.spv"
        subprocess.run(["glslc", "--target-env=vulkan1.2", "-O", str(SHADERS / name), "-o", str(out)], check=True)
        if version == recorded:
            assert out.read_bytes() == (SHADERS / f"{name}.spv").read_bytes(), f"{name}.spv is stale"


# ------------------------------------------------------------------------------ on the device

W, H = 48, 32


def _world(gpu: Any) -> World:
    world = World()
    world.spawn(Transform(), Mesh(handle=gpu.meshes.add(cube_mesh())))
    add_camera(world, eye=(0.0, 1.0, 4.0), target=(0.0, 0.0, 0.0))
    default_schedule().run(world, 0.0)
    return world


def _frame(gpu: Any, renderer: Any, world: World) -> np.ndarray:
    renderer.render(world, readback=True)
    return gpu.target.pixels()[..., :3].astype(np.int64)


def _renderer(gpu: Any, **settings: Any) -> Any:
    from ecs_engine.render.frame.renderer import Renderer

    # a grey background: the corners have light for the vignette to take
    renderer = Renderer(gpu.device, gpu.target, gpu.meshes, clear_color=(0.3, 0.3, 0.3), **settings)
    gpu.owned.append(renderer)
    return renderer


def vignette(image: np.ndarray, strength: float) -> np.ndarray:
    """NumPy's vignette of 8-bit sRGB `image` (h, w, 3): as tests/shaders/vignette.frag."""
    h, w = image.shape[:2]
    y, x = np.mgrid[0:h, 0:w]
    r2 = ((x + 0.5) / w * 2 - 1) ** 2 + ((y + 0.5) / h * 2 - 1) ** 2
    factor = np.maximum(1.0 - strength * r2, 0.0)[..., None]
    return np.round(linear_to_srgb(srgb_to_linear(image / 255.0) * factor) * 255).astype(np.int64)


def test_the_vignette_is_numpys_of_the_frame_without_it(external):
    """On through `set_post_effects` (after FXAA, the ldr stage's order), then alone through the
    renderer's `post=`: the frame is NumPy's vignette of the frame without it, within 2 levels;
    the corners are far darker, so a pass that did not run fails."""
    with headless_gpu(W, H) as gpu:
        world = _world(gpu)
        renderer = _renderer(gpu, tone_map="aces")
        off = _frame(gpu, renderer, world)
        renderer.set_post_effects({"vignette"}, {"vignette": VignetteSettings(0.6)})
        on = _frame(gpu, renderer, world)
        assert renderer.post_effects == ("vignette",) and "vignette" in renderer.output.graph.describe()
        want = vignette(off, 0.6)
        assert np.abs(on - want).max() <= 2, np.abs(on - want).max()
        assert (off[0, 0] - on[0, 0]).min() > 40  # a corner, darkened
        renderer.set_post_effects({"vignette", "fxaa"})  # the settings kept
        assert renderer.post_effects == ("fxaa", "vignette")
        _frame(gpu, renderer, world)  # both run, validation-clean
        renderer.set_post_effects(set())
        assert np.array_equal(_frame(gpu, renderer, world), off)
    with headless_gpu(W, H) as gpu:
        world = _world(gpu)
        renderer = _renderer(gpu, tone_map="aces", post={"vignette": VignetteSettings(1.0)})
        assert np.abs(_frame(gpu, renderer, world) - vignette(off, 1.0)).max() <= 2


def test_the_exposure_scale_is_numpys_of_the_hdr_colour(external):
    """The clamp tone map: the frame is encode(min(scale x hdr, 1)); without the effect
    encode(min(hdr, 1)): where that frame is below white (nothing clamped), the effect's frame
    is NumPy's decode, scale and encode of it, within 2 levels (an effect that did not run, or
    ran after the tone map on clamped values, fails)."""
    with headless_gpu(W, H) as gpu:
        world = _world(gpu)
        renderer = _renderer(gpu)
        off = _frame(gpu, renderer, world)
        renderer.set_post_effects({"exposure_scale"}, {"exposure_scale": ExposureScaleSettings(0.4)})
        on = _frame(gpu, renderer, world)
        assert gpu.target.form == "hdr" and "exposure_scale" in renderer.output.graph.describe()
        unclamped = (off < 255).all(axis=2)
        assert unclamped.mean() > 0.9
        want = np.round(linear_to_srgb(srgb_to_linear(off / 255.0) * 0.4) * 255).astype(np.int64)
        assert np.abs(on - want)[unclamped].max() <= 2, np.abs(on - want)[unclamped].max()
        assert np.abs(on - off).max() > 40
        renderer.set_post_effects({"exposure_scale", "vignette"})  # both stages at once
        both = _frame(gpu, renderer, world)
        assert np.abs(both - vignette(on, VignetteSettings().strength))[unclamped].max() <= 3


def test_the_plugin_line_and_the_cli_turn_it_on(external, capsys, monkeypatch):
    from ecs_engine import App, DefaultPlugins, PostEffectPlugin
    from ecs_engine.app.cli import main

    ran: list[str] = []
    for cls in (VignettePass, ExposureScalePass):
        real = cls.record

        def logged(self: Any, *args: Any, _real: Any = real) -> None:
            ran.append(self.name)
            _real(self, *args)

        monkeypatch.setattr(cls, "record", logged)
    app = App(title="vignette", size=(32, 24))
    app.add_plugins(DefaultPlugins, PostEffectPlugin("vignette", VignetteSettings(0.3)))
    seen: dict[str, Any] = {}
    app.on_open(lambda world, session: seen.update(renderer=session.renderer))
    app.add_startup_systems(lambda world, dt: add_camera(world, eye=(0.0, 1.0, 4.0), target=(0.0, 0.0, 0.0)))
    app.run(frames=1, headless=True)
    assert seen["renderer"].post_effects == ("vignette",) and ran == ["vignette"]
    assert seen["renderer"].post_settings["vignette"] == VignetteSettings(0.3)
    with pytest.raises(UsageError, match="vignette settings must be VignetteSettings"):
        App().add_plugins(PostEffectPlugin("vignette", BloomSettings()))
    args = ["demo", "cube", "--headless", "--frames", "1", "--width", "32", "--height", "24"]
    assert main([*args, "--post", "exposure_scale,vignette"]) == 0
    assert ran[1:] == ["exposure_scale", "vignette"]
    capsys.readouterr()
    registry.unregister("vignette")  # gone: the flag refuses it, one line, exit 2
    with pytest.raises(SystemExit) as exit_info:
        main([*args, "--post", "vignette"])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "unknown post effect 'vignette'" in err
