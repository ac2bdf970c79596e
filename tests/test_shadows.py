"""Shadow maps drawn and read (render/shadows/maps_pass.py): shadows fall where a NumPy ray cast of the
scene says (a directional light's cascades, a spot light's map), open ground stays clean (no
acne), the tags leave meshes out, every render path and the deferred lighting agree, and a scene
without a Shadow pays for none of it."""

from __future__ import annotations

import numpy as np
import pytest
from gpu_context import headless_gpu
from pixel_rays import pixel_rays

from ecs_engine import World
from ecs_engine.app.scenes import default_schedule
from ecs_engine.components import (
    Camera,
    DirectionalLight,
    Mesh,
    NotShadowCaster,
    NotShadowReceiver,
    PointLight,
    Shadow,
    SpotLight,
    Transform,
)
from ecs_engine.demos.scene_kit import add_camera
from ecs_engine.maths.camera import look_rotation
from ecs_engine.render.assets.primitives import cube_mesh
from ecs_engine.render.frame.camera import camera_matrices
from ecs_engine.render.layouts import FEATURE_SHADOWS

W, H = 160, 100
CUBE = (np.array([-0.5, 0.5, -0.5]), np.array([0.5, 1.5, 0.5]))  # the unit cube centred at (0, 1, 0)
POINT = (-1.6, 2.2, 0.9)  # the point light: above, to the side and in front of the cube


def scene(gpu, light: str = "sun", shadow: bool = True, cube_tags=(), ground_tags=()) -> World:
    """The issue's scene: a ground box whose top is y = 0, a unit cube centred at (0, 1, 0),
    the camera at (0, 8, 8) looking at the origin; lit straight down by a directional light or
    by a spot light above and to the side, or by a point light."""
    world = World()
    cube = gpu.meshes.add(cube_mesh())
    world.spawn(Transform(position=(0.0, -0.5, 0.0), scale=(40.0, 1.0, 40.0)), Mesh(handle=cube), *ground_tags)
    world.spawn(Transform(position=(0.0, 1.0, 0.0)), Mesh(handle=cube, material=1), *cube_tags)
    cast = [Shadow(resolution=1024)] if shadow else []
    if light == "sun":
        world.spawn(Transform(rotation=look_rotation((0.0, -1.0, 0.0))), DirectionalLight(illuminance=0.8), *cast)
    elif light == "spot":
        world.spawn(
            Transform(position=(-2.0, 4.0, 0.0), rotation=look_rotation((0.5, -1.0, 0.0))),
            SpotLight(intensity=30.0, radius=20.0, inner_angle=0.9, outer_angle=1.0),
            *cast,
        )
    else:  # a point light's six cube faces: the cube's shadow crosses from one face to another
        world.spawn(Transform(position=POINT), PointLight(intensity=12.0, radius=20.0), *cast)
    add_camera(world, (0.0, 8.0, 8.0), (0.0, 0.0, 0.0))
    return world


def render(gpu, world: World, **settings) -> tuple[np.ndarray, object]:
    from ecs_engine.render.frame.renderer import Renderer

    renderer = Renderer(gpu.device, gpu.target, gpu.meshes, **settings)
    try:
        default_schedule().run(world, 0.0)
        renderer.render(world, readback=True)
        return gpu.target.pixels()[..., :3].astype(int), renderer
    finally:
        renderer.destroy()


def ground_hits(world: World) -> tuple[np.ndarray, np.ndarray]:
    """Per pixel: where its ray meets the ground (y = 0), and whether the cube is in the way."""
    d, eye = pixel_rays(world, W, H)
    t = -eye[1] / d[..., 1]
    hit = eye + d * t[..., None]
    blocked = segment_hits_box(np.broadcast_to(eye, hit.shape), hit, *CUBE)
    return hit, blocked


def segment_hits_box(a: np.ndarray, b: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Whether the segments a -> b cross the box [lo, hi] (slab test)."""
    d = b - a
    with np.errstate(divide="ignore", invalid="ignore"):
        t0, t1 = (lo - a) / d, (hi - a) / d
    near = np.nanmax(np.minimum(t0, t1), axis=-1)
    far = np.nanmin(np.maximum(t0, t1), axis=-1)
    return (near <= far) & (far > 1e-6) & (near < 1 - 1e-6)


def compare(image: np.ndarray, shadowed: np.ndarray, lit: np.ndarray) -> tuple[float, float]:
    brightness = image.mean(axis=-1)
    return float(brightness[shadowed].mean()), float(brightness[lit].mean())


@pytest.mark.parametrize("light", ["sun", "spot", "point"])
def test_shadows_fall_where_a_ray_cast_says(light):
    with headless_gpu(W, H) as gpu:
        world = scene(gpu, light)
        image, _ = render(gpu, world)
        plain, _ = render(gpu, scene(gpu, light, shadow=False))
    hit, blocked = ground_hits(world)
    if light == "sun":  # straight down: the shadow is the cube's footprint, x and z in [-0.5, 0.5]
        inside = (np.abs(hit[..., 0]) < 0.4) & (np.abs(hit[..., 2]) < 0.4)
        outside = (np.abs(hit[..., 0]) > 0.6) | (np.abs(hit[..., 2]) > 0.6)
    else:  # from the light past the cube to the ground point, the cube shrunk and grown a little
        apex = np.array([-2.0, 4.0, 0.0]) if light == "spot" else np.array(POINT)
        inside = segment_hits_box(np.broadcast_to(apex, hit.shape), hit, CUBE[0] + 0.1, CUBE[1] - 0.1)
        outside = ~segment_hits_box(np.broadcast_to(apex, hit.shape), hit, CUBE[0] - 0.1, CUBE[1] + 0.1)
        outside &= np.linalg.norm(hit - np.array([0.0, 0.0, 0.0]), axis=-1) < 3.0  # within the spot's pool
    shadowed, lit = inside & ~blocked, outside & ~blocked & (np.linalg.norm(hit, axis=-1) < 6.0)
    assert shadowed.sum() > 20 and lit.sum() > 200  # the ray cast sees both
    dark, bright = compare(image, shadowed, lit)
    assert dark < 0.5 * bright, (dark, bright)
    # the same scene without a Shadow: no darkening anywhere the ray cast says is shadowed
    plain_dark, _ = compare(plain, shadowed, lit)
    assert plain_dark > dark + 40
    # and the rest of the image is the shadowless one's: lit ground is not darkened (no acne)
    away = lit
    assert np.abs(image[away] - plain[away]).max() <= 2


@pytest.mark.parametrize("light", ["sun", "point"])
def test_open_ground_has_no_acne_and_no_seams(light):
    """Ground lit by a casting light, nothing above it: the image is the shadowless one. Under
    the point light the ground is seen through five of its cube's faces: a face's edge that
    filtered past its map, or a bias that fails at grazing angles, would show."""
    with headless_gpu(W, H) as gpu:
        world = scene(gpu, light, cube_tags=[NotShadowCaster()])
        image, _ = render(gpu, world)
        plain, _ = render(gpu, scene(gpu, light, shadow=False))
    assert np.abs(image - plain).max() <= 1


@pytest.mark.parametrize("lighting", ["loop", "deferred"])  # deferred: the flag rides in the G-buffer
def test_tags_leave_meshes_out_of_shadows(lighting):
    with headless_gpu(W, H) as gpu:
        plain, _ = render(gpu, scene(gpu, shadow=False), light_culling=lighting)
        no_caster, _ = render(gpu, scene(gpu, cube_tags=[NotShadowCaster()]), light_culling=lighting)
        no_receiver, _ = render(gpu, scene(gpu, ground_tags=[NotShadowReceiver()]), light_culling=lighting)
        both, _ = render(gpu, scene(gpu), light_culling=lighting)
    assert np.abs(no_caster - plain).max() <= 1
    assert np.abs(no_receiver - plain).max() <= 1
    assert np.abs(both - plain).max() > 60


@pytest.mark.parametrize(
    "settings",
    [dict(mode="per_entity"), dict(mode="indirect"), dict(light_culling="deferred"), dict(recorder="python")],
)
def test_every_path_and_the_deferred_lighting_draw_the_same_shadows(settings):
    with headless_gpu(W, H) as gpu:
        world = scene(gpu, "spot")
        reference, _ = render(gpu, world, tone_map="aces")
        image, _ = render(gpu, world, tone_map="aces", **settings)
    difference = np.abs(image - reference).max(axis=-1)
    # the paths draw the same maps; the deferred lighting runs the same shading in a compute
    # shader, where the NVIDIA driver rounds differently: up to 2/255 there, on 0.1% of pixels
    assert difference.max() <= 2 and (difference > 1).mean() < 0.001


def test_a_scene_without_shadows_pays_for_none():
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(W, H) as gpu:
        world = scene(gpu, shadow=False)
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes)
        try:
            default_schedule().run(world, 0.0)
            stats = renderer.render(world, readback=True)
            assert renderer.shadows.maps.resolution == 1 and renderer.shadows.path is None
            assert not renderer.material_features & FEATURE_SHADOWS
            assert stats.draws == 1  # the two cubes in one instanced draw, nothing for shadows
            world.spawn(Transform(rotation=look_rotation((0.2, -1.0, 0.1))), DirectionalLight(), Shadow(cascades=2))
            stats = renderer.render(world, readback=True)
            assert renderer.material_features & FEATURE_SHADOWS
            assert renderer.shadows.maps.resolution == 2048 and renderer.shadows.maps.layers == 2
            assert stats.draws > 1  # the shadow views drew
        finally:
            renderer.destroy()


def test_cascades_cover_the_shadow_distance_and_stop_there():
    """A cube far beyond Shadow.distance casts nothing; one within it does."""
    with headless_gpu(W, H) as gpu:
        cube = gpu.meshes.add(cube_mesh())
        images = []
        for distance in (5.0, 60.0):
            world = World()
            world.spawn(Transform(position=(0.0, -0.5, -20.0), scale=(80.0, 1.0, 80.0)), Mesh(handle=cube))
            world.spawn(Transform(position=(0.0, 2.0, -20.0), scale=(2.0, 2.0, 2.0)), Mesh(handle=cube, material=1))
            world.spawn(
                Transform(rotation=look_rotation((1.0, -1.0, 0.0))),  # slanted: the shadow falls to the side
                DirectionalLight(),
                Shadow(cascades=3, distance=distance),
            )
            add_camera(world, (0.0, 18.0, 0.0), (0.0, 0.0, -20.0))  # looking down steeply: the shadow shows
            images.append(render(gpu, world)[0])
        near_only, far_enough = images
    # the cube stands ~27 units from the camera, in the last of three cascades of a 60-unit
    # shadow distance, beyond a 5-unit one
    assert (far_enough.mean(axis=-1) < near_only.mean(axis=-1) - 60).sum() > 20


CELLS = 4  # the cutout plane's checkerboard: CELLS x CELLS cells, every other one cut away


def cutout_scene(gpu) -> World:
    """The issue's scene with a 3-unit plane at y = 2.5 under the straight-down sun, alpha-masked
    by a checkerboard texture; the cube casts nothing."""
    from ecs_engine.render.assets.materials import Material, materials
    from ecs_engine.render.assets.primitives import plane_mesh
    from ecs_engine.render.assets.textures import Texture

    world = scene(gpu, cube_tags=[NotShadowCaster()])
    library = materials(world)
    px = np.full((64, 64, 4), 200, np.uint8)
    i, j = np.mgrid[0:64, 0:64] // (64 // CELLS)
    px[..., 3] = np.where((i + j) % 2 == 0, 255, 0)
    mask = library.add(
        Material(
            "holes",
            "lambert",
            alpha_mode="mask",
            alpha_cutoff=0.5,
            base_color_texture=library.textures.add(Texture("checker", px)),
        )
    )
    world.spawn(Transform(position=(0.0, 2.5, 0.0)), Mesh(handle=gpu.meshes.add(plane_mesh(3.0, 1)), material=mask))
    return world


def assert_checkerboard_shadow(world: World, image: np.ndarray) -> None:
    """The cutout plane's shadow on the ground is its checkerboard (a ray cast through the
    texture says where), not a square."""
    hit, blocked = ground_hits(world)
    # where the ray meets the ground, and whether the plane above it is solid there; the plane
    # and the cube hide parts of the ground from the camera: rays through them are left out
    u, v = hit[..., 0] / 3.0 + 0.5, hit[..., 2] / 3.0 + 0.5
    under = (u > 0.02) & (u < 0.98) & (v > 0.02) & (v < 0.98)
    eye = camera_matrices(world, W / H).position
    t = (2.5 - eye[1]) / (hit[..., 1] - eye[1])
    through = eye + (hit - eye) * t[..., None]
    seen = (np.abs(through[..., 0]) > 1.5) | (np.abs(through[..., 2]) > 1.5)
    cu, cv = np.floor(u * CELLS), np.floor(v * CELLS)
    fu, fv = u * CELLS - cu, v * CELLS - cv
    inner = (fu > 0.2) & (fu < 0.8) & (fv > 0.2) & (fv < 0.8)  # away from the cells' edges
    solid = (cu + cv) % 2 == 0  # texture rows follow v, columns u (a row-major image)
    bright = image.mean(axis=-1)
    seen &= ~blocked
    shadowed, lit = under & seen & inner & solid, under & seen & inner & ~solid
    assert shadowed.sum() > 10 and lit.sum() > 10
    assert bright[shadowed].max() < bright[lit].min() - 40


def test_alpha_cutouts_cut_holes_in_the_shadow():
    """A plane above the ground under the straight-down sun, alpha-masked by a 4 x 4 checkerboard:
    its shadow on the ground is the checkerboard, not a square."""
    with headless_gpu(W, H) as gpu:
        world = cutout_scene(gpu)
        image, _ = render(gpu, world)
    assert_checkerboard_shadow(world, image)


FINE = np.arange(0.0, 1.2, 0.005)  # the penumbra profiles' samples (world units across the edge)


def penumbra_widths(gpu, filter_: int) -> tuple[float, float, float]:
    """A 4-unit wall (0.8 wide) under a sun 45 degrees from straight down, seen from straight
    above (orthographic): the width (world units) of its shadow's side edge near its foot and
    near the shadow's far end, and the share of flat steps (bands) across the far edge."""
    from ecs_engine.components import ORTHOGRAPHIC, Camera

    world = World()
    cube = gpu.meshes.add(cube_mesh())
    world.spawn(Transform(position=(0.0, -0.5, 0.0), scale=(40.0, 1.0, 40.0)), Mesh(handle=cube))
    world.spawn(Transform(position=(0.0, 2.0, 0.0), scale=(0.3, 4.0, 0.8)), Mesh(handle=cube, material=1))
    world.spawn(
        Transform(rotation=look_rotation((1.0, -1.0, 0.0))),
        DirectionalLight(illuminance=0.8),
        Shadow(resolution=1024, cascades=1, distance=20.0, filter=filter_, softness=0.05 if filter_ == 2 else 1.5),
    )
    world.spawn(
        Transform(position=(2.0, 10.0, 0.0), rotation=look_rotation((0.0, -1.0, -1e-3))),
        Camera(projection=ORTHOGRAPHIC, height=3.0, near=0.1, far=30.0),
    )
    image, _ = render(gpu, world)
    cam = camera_matrices(world, W / H)
    vp = cam.projection.astype(np.float64) @ cam.view.astype(np.float64)
    brightness = image.mean(axis=-1)

    def profile(x: float, z: np.ndarray = FINE) -> np.ndarray:
        p = np.c_[np.full_like(z, x), np.zeros_like(z), z] - cam.position
        c = np.c_[p, np.ones(len(z))] @ vp.T
        px = np.clip(((c[:, 0] / c[:, 3]) * 0.5 + 0.5) * W, 0, W - 1).astype(int)
        py = np.clip(((c[:, 1] / c[:, 3]) * 0.5 + 0.5) * H, 0, H - 1).astype(int)
        return brightness[py, px]

    widths = []
    for x in (0.6, 3.4):
        b = profile(x)
        dark, lit = b[0], b[-20:].mean()
        assert lit - dark > 60, (x, dark, lit)  # the shadow is there, its edge inside the profile
        between = (b > dark + 0.1 * (lit - dark)) & (b < lit - 0.1 * (lit - dark))
        widths.append(between.sum() * 0.005)
    # bands: across the far edge, one pixel to the next, averaged over a stretch of the edge (the
    # pixels from x = 2.9 to 3.9), steps under 2% of the contrast inside the penumbra
    z = np.arange(0.0, 1.2, 3.0 / H)  # a pixel apart
    ramp = np.mean([profile(x, z) for x in np.arange(2.9, 3.9, 3.0 / H)], axis=0)
    steps = np.diff(ramp)
    dark, lit = ramp[0], ramp[-5:].mean()
    inside = (ramp[1:] > dark + 0.1 * (lit - dark)) & (ramp[:-1] < lit - 0.1 * (lit - dark))
    flat = np.abs(steps[inside]) < 0.02 * (lit - dark)
    return widths[0], widths[1], float(flat.mean())


def test_pcss_hardens_at_contact_and_softens_away_from_it():
    """...and its wide penumbra is a smooth ramp: its taps (a disc turned by a noise per texel)
    leave no bands of flat steps (a fixed 5 x 5 grid left 47% of the steps flat)."""
    with headless_gpu(W, H) as gpu:
        pcf_near, pcf_far, _ = penumbra_widths(gpu, 1)
        pcss_near, pcss_far, bands = penumbra_widths(gpu, 2)
    assert bands < 0.1, bands
    assert pcss_far > 2.0 * max(pcss_near, 0.03), (pcss_near, pcss_far)
    assert pcss_far > 3.0 * pcf_far, (pcf_far, pcss_far)
    assert pcf_far < 2.0 * max(pcf_near, 0.03)  # PCF's edge is as wide everywhere


def test_cascades_do_not_shimmer_when_the_camera_moves():
    """An orthographic camera looking straight down moves by whole pixels: the image moves with
    it and nothing else changes, shadow edges included (the cascades' texel grid stays put in
    the world). Without the snap the edges' pixels change as the map's texels slide."""
    from ecs_engine.components import ORTHOGRAPHIC, Camera
    from ecs_engine.render.assets.materials import Material, materials

    pixel = 3.0 / H  # world units per pixel of a 3-unit-high orthographic view
    shots = []
    with headless_gpu(W, H) as gpu:
        cube = gpu.meshes.add(cube_mesh())
        for step in (0, 7):
            world = World()
            world.spawn(Transform(position=(0.0, -0.5, 0.0), scale=(40.0, 1.0, 40.0)), Mesh(handle=cube))
            matte = materials(world).add(Material("matte", "lambert", (0.8, 0.4, 0.3, 1.0)))  # no view-dependent light
            world.spawn(Transform(position=(0.0, 0.75, 0.0), scale=(0.6, 1.5, 0.6)), Mesh(handle=cube, material=matte))
            world.spawn(
                Transform(rotation=look_rotation((0.7, -1.0, 0.35))),
                DirectionalLight(illuminance=0.8),
                Shadow(resolution=512, cascades=2, distance=15.0, filter=0),  # hard: every texel shows
            )
            world.spawn(
                Transform(position=(0.6 + step * pixel, 10.0, 0.0), rotation=look_rotation((0.0, -1.0, -1e-6))),
                Camera(projection=ORTHOGRAPHIC, height=3.0, near=0.1, far=30.0),
            )
            shots.append(render(gpu, world)[0])
    # the camera moved 7 pixels towards +x: the world moved 7 pixels left in the image
    before, after = shots[0][:, 7:], shots[1][:, :-7]
    dark = before.mean(axis=-1) < 120
    assert dark.sum() > 100  # the shadow is in the compared part
    assert np.abs(before.astype(int) - after).max() <= 2


def test_shadow_views_follow_the_frame_set_when_its_buffers_grow():
    """A shadow view's set 0 is a copy of the frame's, made again only when the frame's set is
    written (shadow_pass.view_inputs). When the instance buffer grows (far more casters), the
    views must read the new one: the frame then matches a fresh renderer's; and while nothing
    changes, the copies are not made again."""
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(W, H) as gpu:
        world = scene(gpu, "sun")
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes)
        try:
            schedule = default_schedule()
            schedule.run(world, 0.0)
            for _ in range(3):
                renderer.render(world, readback=True)
            sets = [list(slot) for slot in renderer.shadows.view_sets._sets]
            copied = [[s.copied for s in slot] for slot in sets]
            for _ in range(2):
                renderer.render(world, readback=True)
            assert [[s.copied for s in slot] for slot in renderer.shadows.view_sets._sets] == copied
            # 3,000 small cubes floating over the ground (the instance buffer held a few rows)
            cube = gpu.meshes.add(cube_mesh())
            rng = np.random.default_rng(5)
            for x, z in rng.uniform(-6.0, 6.0, size=(3000, 2)):
                world.spawn(Transform(position=(x, 3.0, z), scale=(0.05, 0.05, 0.05)), Mesh(handle=cube))
            schedule.run(world, 0.0)
            versions = [pf.set_version for pf in renderer.per_frame]
            for _ in range(3):
                renderer.render(world, readback=True)
            assert [pf.set_version for pf in renderer.per_frame] != versions  # the buffers grew
            grown = gpu.target.pixels()[..., :3].astype(int)
        finally:
            renderer.destroy()
        fresh, _ = render(gpu, world)
    assert np.abs(grown - fresh).max() <= 1


def test_the_kept_plan_follows_every_change_of_the_lights_and_camera():
    """The views are planned again only when the camera, the origin or a casting light's columns
    changed (ShadowPass.plan): while nothing does, the frame reuses the last list (and the slots
    their rows); after each change the views equal a fresh plan's and the image a fresh
    renderer's."""
    from ecs_engine.render.extract.shadows import extract_shadow_casters
    from ecs_engine.render.frame.renderer import Renderer
    from ecs_engine.render.shadows.views import shadow_views

    with headless_gpu(W, H) as gpu:
        world = scene(gpu, "spot")
        world.spawn(Transform(position=POINT), PointLight(intensity=6.0, radius=20.0), Shadow(resolution=512))
        sun = world.spawn(
            Transform(rotation=look_rotation((0.3, -1.0, 0.2))), DirectionalLight(illuminance=0.3), Shadow()
        )
        spot = world.query(SpotLight).entities()[0]
        camera = world.query(Camera).entities()[0]
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes)
        schedule = default_schedule()

        def frames() -> list:
            schedule.run(world, 0.0)
            for _ in range(2):  # both slots
                renderer.render(world, readback=True)
            return renderer.shadows.last_views

        def same_as_fresh(views: list) -> None:
            cam = camera_matrices(world, W / H)
            fresh = shadow_views(extract_shadow_casters(world), cam, world.get(camera, Transform).position)
            assert len(views) == len(fresh)
            for a, b in zip(views, fresh, strict=True):
                assert (a.entity, a.kind, a.index, a.layer, a.resolution, a.bias) == (
                    b.entity,
                    b.kind,
                    b.index,
                    b.layer,
                    b.resolution,
                    b.bias,
                )
                assert np.allclose(a.view, b.view) and np.allclose(a.projection, b.projection)

        try:
            first = frames()
            assert frames() is first  # nothing changed: the same plan
            changes = [
                lambda: world.set(spot, Transform, position=(-1.0, 5.0, 1.0)),  # a light moves
                lambda: world.set(spot, SpotLight, inner_angle=0.6, outer_angle=0.8),  # its cone
                lambda: world.set(sun, Shadow, bias=2.0),  # a Shadow setting
                lambda: world.set(camera, Transform, position=(1.0, 7.0, 8.0)),  # the camera: the cascades
                lambda: world.remove(sun, Shadow),  # a light stops casting
            ]
            last = first
            for change in changes:
                change()
                views = frames()
                assert views is not last
                same_as_fresh(views)
                assert frames() is views  # and kept again
                last = views
            image = gpu.target.pixels()[..., :3].astype(int)
        finally:
            renderer.destroy()
        fresh, _ = render(gpu, world)
    assert np.abs(image - fresh).max() <= 1


@pytest.mark.parametrize("light", ["spot", "point"])
def test_a_map_is_drawn_at_its_lights_resolution_whatever_another_asks(light):
    """Each view is drawn at its own light's resolution, in the corner of a layer as large as
    the largest any light asks (render/shadows/maps_pass.py's target_state): the light's shadow is the
    same beside an unlit caster asking for 256 texels or for 1024 (drawn at the largest, its
    edges came out sharper)."""
    with headless_gpu(W, H) as gpu:
        images = []
        for other in (256, 1024):
            world = scene(gpu, light)
            lit = world.query(Shadow).entities()[0]
            world.set(lit, Shadow, resolution=256)
            world.spawn(
                Transform(rotation=look_rotation((0.3, -1.0, 0.2))),
                DirectionalLight(illuminance=0.0),
                Shadow(resolution=other),
            )
            images.append(render(gpu, world)[0])
        assert np.abs(images[0] - images[1]).max() <= 1
