"""Deferred lighting (the target's deferred form, render/lighting/deferred.py): the opaque meshes lit in
compute give the forward all-lights loop's image within 1/255 in 8-bit sRGB, with the light grid
and without, for every render path, perspective and orthographic, grid tiles smaller and larger
than the lighting's workgroup, more lights than a workgroup holds at once, and every material
feature the G-buffer carries; `auto` defers with the clusters; MSAA stays forward (a window in
the deferred form: test_window.py). The tone map is aces in every comparison: both sides then blend the
light billboards over HDR colour (in the direct form they blend over the clamped colour)."""

from __future__ import annotations

import logging
import math

import numpy as np
import pytest
from gpu_context import headless_gpu
from test_light_clusters import lit_field

from ecs_engine import World
from ecs_engine.app.scenes import default_schedule
from ecs_engine.components import Camera, DirectionalLight, Mesh, PointLight, Transform
from ecs_engine.maths.camera import look_rotation
from ecs_engine.render.assets.materials import Material, materials
from ecs_engine.render.assets.primitives import cube_mesh, plane_mesh, sphere_mesh
from ecs_engine.render.assets.textures import Texture
from ecs_engine.render.lighting.clusters import CLUSTER_MIN_LIGHTS

W, H = 160, 96


def render(gpu, world: World, culling: str, mode: str = "instanced", frames: int = 1, target=None):
    """(RGB pixels, the target's form, whether the lights were clustered) of the last frame."""
    from ecs_engine.render.frame.renderer import Renderer

    target = target or gpu.target
    renderer = Renderer(gpu.device, target, gpu.meshes, light_culling=culling, mode=mode, tone_map="aces")
    try:
        default_schedule().run(world, 0.0)
        for _ in range(frames):
            renderer.render(world, readback=True)
        return target.pixels()[..., :3].astype(int), target.form, renderer.clustered
    finally:
        renderer.destroy()


def assert_same(a: np.ndarray, b: np.ndarray) -> None:
    diff = np.abs(a - b)
    assert diff.max() <= 1, f"max difference {diff.max()} at {np.unravel_index(diff.argmax(), diff.shape)}"


@pytest.mark.parametrize("ortho", [False, True])
@pytest.mark.parametrize("mode", ["instanced", "indirect"])
@pytest.mark.parametrize("tile", [8, 64])
def test_deferred_lighting_draws_what_the_loop_draws(ortho, mode, tile, monkeypatch):
    """Point, spot, directional and unbounded lights over Lambert and Cook-Torrance surfaces; grid
    tiles of 8 px (four under one 16-px workgroup, their masks ORed) and 64 px."""
    from ecs_engine.render.lighting import clusters as light_clusters

    monkeypatch.setattr(light_clusters, "TILE_PX", tile)
    with headless_gpu(W, H) as gpu:
        world = lit_field(gpu, 300, ortho)
        loop, loop_form, _ = render(gpu, world, "loop", mode)
        deferred, form, clustered = render(gpu, world, "deferred", mode)
        dark, _, _ = render(gpu, lit_field(gpu, 0, ortho), "loop", mode)
    assert loop_form == "hdr" and form == "deferred" and clustered
    assert np.abs(loop - dark).max() > 60  # the small lights make a visible difference
    assert_same(deferred, loop)


def test_per_entity_draws_and_no_light_grid():
    """The per-entity path into the G-buffer; and lights that are all unbounded or directional:
    no grid, the lighting loops over every light."""
    with headless_gpu(W, H) as gpu:
        world = lit_field(gpu, 300)
        loop, _, _ = render(gpu, world, "loop", "per_entity")
        deferred, form, _ = render(gpu, world, "deferred", "per_entity")
        assert form == "deferred"
        assert_same(deferred, loop)
        unbounded = lit_field(gpu, 0)
        for x in (-6.0, 0.0, 6.0):
            unbounded.spawn(Transform(position=(x, 1.5, -3.0)), PointLight(color=(0.9, 0.6, 0.3), radius=0.0))
        loop, _, _ = render(gpu, unbounded, "loop")
        deferred, form, clustered = render(gpu, unbounded, "deferred")
    assert form == "deferred" and not clustered
    assert_same(deferred, loop)


def textured_scene(gpu) -> World:
    """Every material feature the G-buffer pass handles: textures (base colour, metallic-roughness,
    normal, emissive, occlusion), alpha mask, double-sided back faces, unlit and emissive rows,
    each shading model; and the rows drawn forward over the lit scene: glass (blended) and
    wireframe."""
    rng = np.random.default_rng(5)
    world = World()
    library = materials(world)

    def texture(name: str, color: bool, side: int = 32) -> int:
        px = rng.integers(0, 256, (side, side, 4), dtype=np.uint8)
        px[..., 3] = np.where(rng.random((side, side)) < 0.3, 40, 255)
        return library.textures.add(Texture(name, px, color=color))

    looks = [
        Material(
            "textured",
            "cook_torrance",
            base_color_texture=texture("base", True),
            metallic_roughness_texture=texture("mr", False),
            normal_texture=texture("normal", False),
            emissive_texture=texture("glow", True),
            occlusion_texture=texture("ao", False),
            emissive=(0.05, 0.02, 0.0),
        ),
        Material("cutout", "lambert", base_color_texture=texture("holes", True), alpha_mode="mask"),
        Material("leaf", "oren_nayar", (0.3, 0.7, 0.2, 1.0), roughness=0.8, double_sided=True),
        Material("phong", "phong", (0.7, 0.2, 0.2, 1.0), shininess=40.0),
        Material("blinn", "blinn_phong", (0.2, 0.3, 0.8, 1.0), shininess=64.0),
        Material("lamp", "unlit", (1.0, 0.8, 0.3, 1.0)),
        Material("glass", "cook_torrance", (0.6, 0.8, 1.0, 0.4), alpha_mode="blend", roughness=0.1),
        Material("wire", "lambert", (0.9, 0.9, 0.9, 1.0), fill="wireframe"),
    ]
    handles = [library.add(m) for m in looks]
    floor = library.add(Material("floor", "lambert", (0.5, 0.5, 0.5, 1.0)))
    world.spawn(Transform(), Mesh(handle=gpu.meshes.add(plane_mesh(20.0, 10)), material=floor))
    shapes = [gpu.meshes.add(sphere_mesh(20, 10)), gpu.meshes.add(cube_mesh())]
    for i, handle in enumerate(handles):
        x = -5.6 + 1.6 * i
        world.spawn(
            Transform(position=(x, 0.8, -2.0), rotation=look_rotation((0.4, 0.2, -1.0)), scale=(0.7, 0.7, 0.7)),
            Mesh(handle=shapes[i % 2], material=handle),
        )
    leaf = gpu.meshes.add(plane_mesh(1.2, 1))  # seen from below: its back face
    world.spawn(
        Transform(position=(0.0, 2.2, -1.0), rotation=look_rotation((0.0, 1.0, 0.3))),
        Mesh(handle=leaf, material=handles[2]),
    )
    world.spawn_batch(
        40,
        Transform(position=np.c_[rng.uniform(-7, 7, 40), rng.uniform(0.3, 2.5, 40), rng.uniform(-5, 2, 40)]),
        PointLight(color=rng.uniform(0.3, 1.0, (40, 3)).astype(np.float32), intensity=2.0, radius=3.0),
    )
    world.spawn(Transform(rotation=look_rotation((0.2, -1.0, -0.5))), DirectionalLight(illuminance=0.3))
    world.spawn(
        Transform(position=(0.0, 3.5, 5.0), rotation=look_rotation((0.0, -0.45, -1.0))),
        Camera(fov_y=math.radians(60.0), near=0.1),
    )
    return world


def test_every_material_feature_lights_as_forward():
    with headless_gpu(W, H) as gpu:
        world = textured_scene(gpu)
        loop, _, _ = render(gpu, world, "loop")
        clustered, _, _ = render(gpu, world, "clustered")
        deferred, form, _ = render(gpu, world, "deferred")
    assert form == "deferred"
    assert_same(clustered, loop)
    assert_same(deferred, loop)


def test_more_lights_than_a_workgroup_holds_at_once():
    """A tile whose depth range reaches 17,000 lights takes two turns through the workgroup's
    shared mask words (DEFERRED_WORDS: 16,384 lights a turn). Lights are sorted far to near, so
    the second turn holds the nearest: a bright group in front of a dim crowd, both over the same
    floor, which the image must show as the loop does."""
    from ecs_engine.render.layouts import DEFERRED_WORDS

    crowd, near = DEFERRED_WORDS * 32 + 16, 600
    with headless_gpu(48, 32) as gpu:

        def scene(bright: bool) -> World:
            world = lit_field(gpu, 0)
            world.spawn_batch(
                crowd,
                Transform(position=np.tile([0.0, 0.8, -2.5], (crowd, 1))),
                PointLight(color=(0.002, 0.0015, 0.001), intensity=1.0, radius=4.0),
            )
            if bright:
                world.spawn_batch(
                    near,
                    Transform(position=np.tile([0.3, 0.8, -1.5], (near, 1))),
                    PointLight(color=(0.004, 0.01, 0.02), intensity=1.0, radius=4.0),
                )
            return world

        world = scene(True)
        loop, _, _ = render(gpu, world, "loop")
        deferred, form, clustered = render(gpu, world, "deferred")
        crowd_only, _, _ = render(gpu, scene(False), "loop")
    assert form == "deferred" and clustered
    assert np.abs(loop - crowd_only).max() > 30  # what the second turn adds shows
    assert_same(deferred, loop)


@pytest.mark.parametrize(("width", "height", "tile"), [(157, 93, 16), (33, 17, 8), (200, 7, 64)])
def test_images_of_any_size_light_their_edges(width, height, tile, monkeypatch):
    """Sizes that are not multiples of the 16-pixel workgroup: the last ones are partial."""
    from ecs_engine.render.lighting import clusters as light_clusters

    monkeypatch.setattr(light_clusters, "TILE_PX", tile)
    with headless_gpu(width, height) as gpu:
        world = lit_field(gpu, 120)
        loop, _, _ = render(gpu, world, "loop")
        deferred, form, _ = render(gpu, world, "deferred")
    assert form == "deferred"
    assert_same(deferred, loop)


def test_auto_defers_with_the_clusters_and_msaa_stays_forward(caplog):
    from ecs_engine.gpu.offscreen import OffscreenTarget

    with headless_gpu(W, H) as gpu:
        _, few, _ = render(gpu, lit_field(gpu, 8), "auto")
        _, many, clustered = render(gpu, lit_field(gpu, CLUSTER_MIN_LIGHTS + 10), "auto")
        assert clustered
        _, asked, _ = render(gpu, lit_field(gpu, 8), "deferred")
        target = OffscreenTarget(gpu.device, W, H, samples=4)
        gpu.owned.append(target)
        with caplog.at_level(logging.WARNING, logger="ecs_engine"):
            _, msaa, msaa_clustered = render(gpu, lit_field(gpu, 40), "deferred", target=target)
    assert (few, many, asked) == ("hdr", "deferred", "deferred")  # aces: hdr, not direct
    assert msaa == "hdr" and msaa_clustered  # forward clustered
    assert sum("deferred lighting draws one sample" in r.message for r in caplog.records) == 1


@pytest.mark.parametrize(("tone_map", "forward"), [("clamp", "direct"), ("aces", "hdr")])
def test_one_renderer_switches_form_as_the_light_count_changes(tone_map, forward):
    """auto: many lights defer, few go forward again (straight into the target with clamp); the
    image each time is what a new renderer draws. Going deferred builds the G-buffer pipelines
    once, not the forward clustered ones first."""
    from ecs_engine.render.draw import chunk_paths
    from ecs_engine.render.frame.renderer import Renderer

    made: list[str] = []
    real = chunk_paths.graphics_pipeline

    def counting(device, spec):
        made.append(spec.fragment_shader)
        return real(device, spec)

    with headless_gpu(W, H) as gpu:
        worlds = [lit_field(gpu, 4), lit_field(gpu, 200), lit_field(gpu, 4)]
        fresh = []
        for world in worlds:
            r = Renderer(gpu.device, gpu.target, gpu.meshes, tone_map=tone_map)
            try:
                default_schedule().run(world, 0.0)
                r.render(world, readback=True)
                fresh.append(gpu.target.pixels()[..., :3].astype(int))
            finally:
                r.destroy()
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes, tone_map=tone_map)
        forms = []
        try:
            for world, want in zip(worlds, fresh, strict=True):
                default_schedule().run(world, 0.0)
                chunk_paths.graphics_pipeline = counting
                try:
                    renderer.render(world, readback=True)
                finally:
                    chunk_paths.graphics_pipeline = real
                forms.append(gpu.target.form)
                assert_same(gpu.target.pixels()[..., :3].astype(int), want)
        finally:
            renderer.destroy()
    assert forms == [forward, "deferred", forward]
    assert not any("clustered" in name for name in made), made
    assert sum("gbuffer" in name for name in made) == 2  # plain and mirrored, once


def test_a_renderer_that_cannot_make_its_form_leaves_nothing(monkeypatch):
    """The deferred form's attachments fail to be made (its depth and HDR colour; the G-buffer
    is the output graph's): the error comes out, the target keeps its old form, and whatever
    the renderer had made is destroyed."""
    from ecs_engine.gpu import scene_attachments as render_pass
    from ecs_engine.gpu.frames import FrameRing
    from ecs_engine.gpu.secondary import SecondaryBuffers
    from ecs_engine.render.frame import renderer as renderer_module
    from ecs_engine.render.lighting.clusters import LightCulling

    def refuse(*args):
        raise RuntimeError("no G-buffer today")

    destroyed: list[str] = []
    for cls in (FrameRing, SecondaryBuffers, LightCulling):
        real = cls.destroy

        def spy(self, real=real, name=cls.__name__):
            destroyed.append(name)
            real(self)

        monkeypatch.setattr(cls, "destroy", spy)
    monkeypatch.setattr(render_pass, "Image", refuse)
    with headless_gpu(W, H) as gpu:
        used = gpu.device.allocator.stats()["used_bytes"]
        with pytest.raises(RuntimeError, match="no G-buffer"):
            renderer_module.Renderer(gpu.device, gpu.target, gpu.meshes, light_culling="deferred")
        assert gpu.target.form == "direct"  # the old form stays whole
        assert gpu.device.allocator.stats()["used_bytes"] == used
    assert sorted(destroyed) == ["FrameRing", "LightCulling", "SecondaryBuffers"]


@pytest.mark.parametrize("culling", ["auto", "deferred"])
def test_a_device_without_fragment_subgroups_still_walks_the_grid_in_compute(culling, caplog):
    """The forward `_clustered` shaders need subgroup arithmetic in fragment shaders; the lighting
    pass does not: such a device still builds the grid and defers, and the rows drawn forward
    (glass, wireframe) loop over every light. No warning: nothing asked for is missing."""
    from ecs_engine.render.draw import chunk_paths

    made: list[str] = []
    real = chunk_paths.graphics_pipeline

    def counting(device, spec):
        made.append(spec.fragment_shader)
        return real(device, spec)

    with headless_gpu(W, H) as gpu, caplog.at_level(logging.WARNING, logger="ecs_engine"):
        world = textured_scene(gpu)
        loop, _, _ = render(gpu, world, "loop")
        gpu.device.features["fragmentSubgroupArithmetic"] = False
        chunk_paths.graphics_pipeline = counting
        try:
            image, form, clustered = render(gpu, world, culling, frames=2)
        finally:
            chunk_paths.graphics_pipeline = real
            gpu.device.features["fragmentSubgroupArithmetic"] = True
    assert form == "deferred" and clustered
    assert_same(image, loop)
    assert made and not any("clustered" in name for name in made), made
    assert not caplog.records
