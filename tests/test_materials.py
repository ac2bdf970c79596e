"""Materials as shared assets: checks on every field, handles, live updates the renderer uploads,
pipelines specialised again when a new shading model appears, alpha mask, and the default palette
keeping the seed scenes' look (golden images: tests/test_render.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shading_reference as ref
from gpu_context import headless_gpu

from ecs_engine import World
from ecs_engine.app.scenes import default_schedule
from ecs_engine.components import Camera, Mesh, PointLight, Transform
from ecs_engine.render.assets.materials import DEFAULT_PALETTE, SHADING_MODELS, Material, Materials, materials
from ecs_engine.render.assets.primitives import plane_mesh
from ecs_engine.render.layouts import (
    FEATURE_ALPHA_MASK,
    FEATURE_BLEND,
    FEATURE_EMISSIVE,
    MATERIAL,
    MODEL_BLINN_PHONG,
    MODEL_UNLIT,
    NO_TEXTURE,
)

W, H = 64, 48


@pytest.mark.parametrize(
    "changes, message",
    [
        (dict(model="toon"), "unknown shading model 'toon'; models: unlit, lambert"),
        (dict(alpha_mode="see-through"), "alpha_mode must be one of opaque, mask, blend"),
        (dict(base_color=(1, 0, 0)), "base_color must be 4 finite numbers"),
        (dict(base_color=(1, float("nan"), 0, 1)), "base_color must be 4 finite numbers"),
        (dict(base_color=(1, 1, 1, 2)), "alpha must be at most 1"),
        (dict(base_color="red"), "base_color must be 4"),
        (dict(emissive=(-1, 0, 0)), "emissive must be 3 finite numbers of at least 0"),
        (dict(metallic=1.5), r"metallic must be a finite number in \[0.0, 1.0\]"),
        (dict(roughness=float("inf")), "roughness must be a finite number"),
        (dict(shininess=0.5), "shininess must be"),
        (dict(specular=-0.1), "specular must be"),
        (dict(alpha_cutoff="half"), "alpha_cutoff must be"),
    ],
)
def test_bad_material_values_are_refused_naming_the_field(changes, message):
    with pytest.raises(ValueError, match=message):
        Material("m", **changes)


def test_specular_normalisation_is_folded_into_the_row():
    """The shader reads strength * normalisation (not computed per light): (s + 2) / 2 for Phong,
    (s + 8) / 8 for Blinn-Phong, none for the others."""
    for model, factor in (("phong", (40 + 2) / 2), ("blinn_phong", (40 + 8) / 8), ("lambert", 1.0)):
        row = Material("m", model, shininess=40.0, specular=0.3).row()
        assert row["surface"][3] == pytest.approx(0.3 * factor, rel=1e-6)
    # the palette keeps the seed scenes' strengths: pow(n.h, s) * strength, as before materials
    assert DEFAULT_PALETTE[0].row()["surface"][3] == pytest.approx(0.5, rel=1e-6)


def test_registry_handles_rows_and_updates():
    mats = Materials()
    assert len(mats) == 6 and [m.name for m in mats] == [m.name for m in DEFAULT_PALETTE]
    assert mats.features == 1 << MODEL_BLINN_PHONG
    version = mats.version
    handle = mats.add(Material("glow", "unlit", (0.1, 0.2, 0.3, 1.0), emissive=(1.0, 0.5, 0.0)))
    assert handle == 6 and mats.version > version
    assert mats.features == (1 << MODEL_BLINN_PHONG) | (1 << MODEL_UNLIT) | FEATURE_EMISSIVE  # it glows
    row = mats.rows()[handle]
    assert row.dtype == MATERIAL.dtype
    np.testing.assert_allclose(row["base_color"], (0.1, 0.2, 0.3, 1.0), rtol=1e-6)
    np.testing.assert_allclose(row["emissive"], (1.0, 0.5, 0.0, 0.0))
    assert row["kind"].tolist() == [SHADING_MODELS["unlit"], 0, 0, 0]
    assert row["textures"].tolist() == [NO_TEXTURE] * 4
    for i in range(60):  # the table grows
        mats.add(Material(f"m{i}", "lambert"))
    assert len(mats.rows()) == 67 and mats.rows()[handle]["emissive"][0] == 1.0
    version = mats.version
    updated = mats.update(handle, base_color=(1, 1, 1, 1), alpha_mode="mask", alpha_cutoff=0.25)
    assert mats[handle] is updated and mats.version == version + 1
    assert mats.rows()[handle]["params"][0] == 0.25 and mats.features & FEATURE_ALPHA_MASK
    assert not mats.features & FEATURE_BLEND
    with pytest.raises(ValueError, match="roughness"):
        mats.update(handle, roughness=2.0)
    assert mats[handle] is updated  # a refused update changes nothing
    mats.update(handle, alpha_mode="blend")
    assert mats.features & FEATURE_BLEND
    with pytest.raises(TypeError, match="no field"):
        mats.update(handle, colour=(1, 1, 1, 1))
    with pytest.raises(KeyError, match="no material 500"):
        mats[500]
    with pytest.raises(TypeError):
        mats.add("red")  # type: ignore[arg-type]


def test_palette_keeps_the_old_highlights():
    """Normalised Blinn-Phong multiplies by (s + 8) / 8; the palette divides its strengths by it."""
    old = [(0.5, 32.0), (0.6, 48.0), (0.6, 48.0), (0.5, 32.0), (0.7, 64.0), (0.5, 32.0)]
    for material, (strength, shininess) in zip(DEFAULT_PALETTE, old):
        assert material.model == "blinn_phong" and material.shininess == shininess
        assert material.specular * (shininess + 8) / 8 == pytest.approx(strength)


def test_materials_resource_is_made_once_per_world():
    world = World()
    assert materials(world) is materials(world)
    assert materials(World()) is not materials(world)


def flat_scene(gpu, material: Material) -> tuple[World, int]:
    """A plane filling the view, facing the camera, under one point light."""
    world = World()
    handle = materials(world).add(material)
    mesh = gpu.meshes.add(plane_mesh(size=20.0))
    half = math.sqrt(0.5)
    world.spawn(Transform(rotation=(half, 0.0, 0.0, half)), Mesh(handle=mesh, material=handle))  # +Y to +Z
    world.spawn(Transform(position=(0.0, 0.0, 2.0)), Camera(fov_y=math.radians(40.0), near=0.05))
    world.spawn(Transform(position=(0.0, 1.0, 1.5)), PointLight(intensity=4.0, radius=0.0))  # out of view
    return world, handle


def test_edits_show_on_the_next_frame_and_new_models_get_pipelines():
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(W, H) as gpu:
        world, handle = flat_scene(gpu, Material("m", "lambert", (0.8, 0.1, 0.1, 1.0)))
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes, ambient=(1.0, 1.0, 1.0, 0.0))
        try:
            schedule = default_schedule()

            def frame() -> np.ndarray:
                schedule.run(world, 0.0)
                renderer.render(world, readback=True)
                return gpu.target.pixels()[..., :3].astype(int)

            red = frame()
            r, g, _ = red[H // 2, W // 2]
            assert r > 150 and r > 2 * g
            materials(world).update(handle, base_color=(0.1, 0.8, 0.1, 1.0))
            green = frame()
            r, g, _ = green[H // 2, W // 2]
            assert g > 150 and g > 2 * r
            features = renderer.material_features
            path = renderer.path
            materials(world).update(handle, model="unlit", base_color=(0.25, 0.5, 0.75, 1.0))
            flat = frame()
            assert renderer.material_features == features | (1 << MODEL_UNLIT) and renderer.path is not path
            np.testing.assert_allclose(
                flat, np.broadcast_to(ref.srgb8(np.array([0.25, 0.5, 0.75])), flat.shape), atol=1
            )
            path = renderer.path
            materials(world).update(handle, model="lambert")
            frame()
            assert renderer.path is path  # the pipelines already handle it: kept
        finally:
            renderer.destroy()


def test_alpha_mask_drops_fragments_below_the_cutoff():
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(W, H) as gpu:
        material = Material("cut", "unlit", (1.0, 1.0, 1.0, 0.4), alpha_mode="mask", alpha_cutoff=0.5)
        world, handle = flat_scene(gpu, material)
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes, clear_color=(0.0, 0.0, 0.0))
        try:
            default_schedule().run(world, 0.0)
            renderer.render(world, readback=True)
            assert gpu.target.pixels()[..., :3].max() == 0  # all cut: the clear colour
            materials(world).update(handle, alpha_cutoff=0.3)
            renderer.render(world, readback=True)
            assert gpu.target.pixels()[..., :3].min() == 255  # kept: white, unlit
        finally:
            renderer.destroy()


def test_a_mesh_naming_no_material_is_refused_before_drawing():
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(W, H) as gpu:
        world, handle = flat_scene(gpu, Material("m", "lambert"))
        world.spawn(Transform(), Mesh(handle=0, material=handle + 1))
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes)
        try:
            default_schedule().run(world, 0.0)
            with pytest.raises(ValueError, match=f"Mesh.material {handle + 1} does not name a material"):
                renderer.render(world, readback=True)
        finally:
            renderer.destroy()
