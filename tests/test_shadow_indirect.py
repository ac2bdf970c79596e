"""The indirect mode's shadow views culled and drawn on the GPU (render/shadows/indirect.py): the
maps are the instanced mode's (the same images), the chunks' rows are culled per view by the
compute shaders (no CPU shadow job records them; the GPU counts the instanced mode's draws and
triangles), NotShadowCaster rows and alpha-masked holes are left out of the maps, and the
set-aside casters (blended materials) still cast through the CPU jobs."""

from __future__ import annotations

import numpy as np
import pytest
from gpu_context import headless_gpu
from test_shadows import H, W, render, scene

from ecs_engine import World
from ecs_engine.app.scenes import default_schedule
from ecs_engine.components import Mesh, NotShadowCaster, Transform
from ecs_engine.render.assets.primitives import cube_mesh
from ecs_engine.render.extract.frame_data import NOT_CASTER


def max_difference(a: np.ndarray, b: np.ndarray) -> int:
    return int(np.abs(a - b).max())


@pytest.mark.parametrize("light", ["sun", "spot", "point"])  # 4 cascades, one map, 6 cube faces
def test_indirect_draws_the_instanced_modes_shadows(light):
    with headless_gpu(W, H) as gpu:
        world = scene(gpu, light)
        instanced, _ = render(gpu, world)
        indirect, _ = render(gpu, world, mode="indirect")
        plain, _ = render(gpu, scene(gpu, light, shadow=False), mode="indirect")
    assert max_difference(indirect, instanced) <= 1
    assert max_difference(indirect, plain) > 60  # the shadows are there


class JobSpy:
    """The chunks the shadow pass's CPU jobs record (ShadowPass.record_chunk), in `chunks`."""

    def __init__(self, monkeypatch):
        from ecs_engine.render.shadows.maps_pass import ShadowPass

        self.chunks: list[object] = []
        original = ShadowPass.record_chunk

        def spy(shadows, chunk, camera=None):
            self.chunks.append(chunk)
            return original(shadows, chunk, camera)

        monkeypatch.setattr(ShadowPass, "record_chunk", spy)


def shadow_counts(gpu, world: World, frames: int = 1, readback: bool = True, **settings) -> tuple[int, int, int]:
    """(shadow views, draws, triangles) of the shadow passes as the stats of the last of `frames`
    frames give them."""
    from ecs_engine.render.frame.renderer import Renderer

    renderer = Renderer(gpu.device, gpu.target, gpu.meshes, **settings)
    try:
        default_schedule().run(world, 0.0)
        for _ in range(frames):
            renderer.render(world, readback=readback)
        return len(renderer.shadows.last_views), renderer.shadows.draws, renderer.shadows.triangles
    finally:
        renderer.destroy()


def test_the_indirect_modes_shadow_views_are_culled_on_the_gpu(monkeypatch):
    """No CPU shadow job records the chunks' rows in the indirect mode; what the GPU counted in
    the views is what the instanced mode's CPU culling recorded, view by view in sum."""
    spy = JobSpy(monkeypatch)
    with headless_gpu(W, H) as gpu:
        world = scene(gpu, "sun")
        instanced = shadow_counts(gpu, world)
        assert spy.chunks  # the spy sees the instanced mode's jobs
        spy.chunks.clear()
        indirect = shadow_counts(gpu, world, mode="indirect")
        assert spy.chunks == []
        # one mesh: one draw per view; 12 triangles per cube in a view (the ground in each, the
        # cube in those whose slice of the camera's view reaches it)
        views, draws, triangles = indirect
        assert views == 4 and draws == views and 12 * views < triangles < 24 * views
        assert indirect == instanced
        # a frame not read back reports its slot's previous frame's counts, as the camera's do
        assert shadow_counts(gpu, world, frames=4, readback=False, mode="indirect") == indirect


def test_not_shadow_casters_are_left_out_in_the_indirect_mode():
    with headless_gpu(W, H) as gpu:
        plain, _ = render(gpu, scene(gpu, shadow=False), mode="indirect")
        no_caster, _ = render(gpu, scene(gpu, cube_tags=[NotShadowCaster()]), mode="indirect")
        both, _ = render(gpu, scene(gpu), mode="indirect")
        views, _, triangles = shadow_counts(gpu, scene(gpu, cube_tags=[NotShadowCaster()]), mode="indirect")
    assert max_difference(no_caster, plain) <= 1
    assert max_difference(both, plain) > 60
    assert triangles == 12 * views  # the ground alone


def test_an_alpha_masked_material_cuts_its_holes_in_the_indirect_modes_maps():
    """test_shadows' checkerboard plane: its shadow is the instanced mode's (where the holes are
    checked against a ray cast), not a square."""
    from ecs_engine.render.assets.materials import Material, materials
    from ecs_engine.render.assets.primitives import plane_mesh
    from ecs_engine.render.assets.textures import Texture

    images = {}
    with headless_gpu(W, H) as gpu:
        for alpha_mode in ("mask", "opaque"):
            world = scene(gpu, cube_tags=[NotShadowCaster()])
            library = materials(world)
            px = np.full((64, 64, 4), 200, np.uint8)
            i, j = np.mgrid[0:64, 0:64] // 16
            px[..., 3] = np.where((i + j) % 2 == 0, 255, 0)
            texture = library.textures.add(Texture("checker", px))
            holes = library.add(
                Material("holes", "lambert", alpha_mode=alpha_mode, alpha_cutoff=0.5, base_color_texture=texture)
            )
            plane = gpu.meshes.add(plane_mesh(3.0, 1))
            world.spawn(Transform(position=(0.0, 2.5, 0.0)), Mesh(handle=plane, material=holes))
            for mode in ("instanced", "indirect"):
                images[alpha_mode, mode] = render(gpu, world, mode=mode)[0]
    assert max_difference(images["mask", "indirect"], images["mask", "instanced"]) <= 1
    assert max_difference(images["opaque", "indirect"], images["opaque", "instanced"]) <= 1
    # the holes let light through: the ground under the plane is brighter than under a solid one
    seen_under = images["mask", "indirect"].mean(axis=-1) - images["opaque", "indirect"].mean(axis=-1)
    assert (seen_under > 60).sum() > 20


def test_blended_casters_still_cast_in_the_indirect_mode(monkeypatch):
    """A blended cube's rows are set aside (not among the indirect path's rows): the CPU shadow
    jobs draw them into the views, next to the GPU-culled chunks, as in the instanced mode."""
    from ecs_engine.render.assets.materials import Material, materials

    spy = JobSpy(monkeypatch)

    def glassy(gpu, world: World, *tags) -> World:
        glass = materials(world).add(Material("glass", "lambert", (0.9, 0.9, 0.9, 0.5), alpha_mode="blend"))
        cube = gpu.meshes.add(cube_mesh())
        world.spawn(
            Transform(position=(1.5, 1.0, 1.5), scale=(0.8, 0.8, 0.8)), Mesh(handle=cube, material=glass), *tags
        )
        return world

    with headless_gpu(W, H) as gpu:
        instanced, _ = render(gpu, glassy(gpu, scene(gpu, "spot")))
        spy.chunks.clear()
        indirect, _ = render(gpu, glassy(gpu, scene(gpu, "spot")), mode="indirect")
        jobs = list(spy.chunks)
        no_glass_shadow, _ = render(gpu, glassy(gpu, scene(gpu, "spot"), NotShadowCaster()), mode="indirect")
    assert max_difference(indirect, instanced) <= 1
    assert len(jobs) == 1 and not jobs[0].flags & NOT_CASTER and len(jobs[0].handle) == 1  # the glass alone
    assert max_difference(indirect, no_glass_shadow) > 30  # the glass cube's shadow


def test_the_views_buffers_follow_new_meshes_rows_and_views():
    """Between frames: a new mesh (more keys: the camera's key table is made anew, the views'
    sets must name the new one) and 3,000 more rows (the views' ids grow); then two point lights
    (4 views become 16: the pool of view sets grows). Each time the frame is a fresh instanced
    renderer's, and the GPU counted its draws and triangles."""
    from ecs_engine.components import PointLight, Shadow
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(W, H) as gpu:
        world = scene(gpu, "sun")
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes, mode="indirect")
        schedule = default_schedule()

        def frames() -> tuple[np.ndarray, tuple[int, int, int]]:
            schedule.run(world, 0.0)
            for _ in range(3):
                renderer.render(world, readback=True)
            shadows = renderer.shadows
            return gpu.target.pixels()[..., :3].astype(int), (len(shadows.last_views), shadows.draws, shadows.triangles)

        results = []
        try:
            frames()
            small = gpu.meshes.add(cube_mesh())
            rng = np.random.default_rng(7)
            for x, z in rng.uniform(-4.0, 4.0, size=(3000, 2)):
                world.spawn(Transform(position=(x, 3.0, z), scale=(0.04, 0.04, 0.04)), Mesh(handle=small))
            results.append((*frames(), render(gpu, world)[0], shadow_counts(gpu, world)))
            for position in ((-3.0, 5.0, 1.0), (3.0, 5.0, -1.0)):
                world.spawn(
                    Transform(position=position), PointLight(intensity=6.0, radius=15.0), Shadow(resolution=256)
                )
            results.append((*frames(), render(gpu, world)[0], shadow_counts(gpu, world)))
        finally:
            renderer.destroy()
    for (image, counts, fresh, instanced), views in zip(results, (4, 16), strict=True):
        assert counts[0] == views
        assert max_difference(image, fresh) <= 1
        assert counts == instanced, (counts, instanced)


def test_the_indirect_mode_gives_the_views_no_copy_of_the_rows():
    """Culled in place on the GPU, the chunks' rows are not written again per view: with a sun's
    4 cascades the instance buffer holds the camera's rows (and the set-aside casters' per view),
    where the instanced mode writes every row again for each view."""
    from ecs_engine.render.frame.renderer import Renderer
    from ecs_engine.render.layouts import INSTANCE

    sizes = {}
    with headless_gpu(W, H) as gpu:
        world = scene(gpu, "sun")
        cube = gpu.meshes.add(cube_mesh())
        for i in range(2000):
            world.spawn(
                Transform(position=(i % 40 - 20.0, 3.0, i // 40 - 25.0), scale=(0.1, 0.1, 0.1)), Mesh(handle=cube)
            )
        rows = 2002
        for mode in ("instanced", "indirect"):
            renderer = Renderer(gpu.device, gpu.target, gpu.meshes, mode=mode)
            try:
                default_schedule().run(world, 0.0)
                renderer.render(world, readback=True)
                sizes[mode] = max(pf.instances.size for pf in renderer.per_frame) // INSTANCE.size
            finally:
                renderer.destroy()
    assert sizes["instanced"] >= 5 * rows  # the camera's and 4 views'
    assert sizes["indirect"] < 2 * rows
