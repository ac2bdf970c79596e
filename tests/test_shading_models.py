"""Each shading model as the GPU draws it (lavapipe, validation on) against an independent NumPy
evaluation of its formula (tests/shading_reference.py) on a flat surface and a sphere, under a
point, a spot and a directional light: RMSE at most 1/255 in 8-bit sRGB. And Cook-Torrance
reflects no more than it receives: a white-furnace check with light from the whole hemisphere."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shading_reference as ref
from gpu_context import headless_gpu

from ecs_engine import World
from ecs_engine.app.scenes import default_schedule
from ecs_engine.components import Camera, DirectionalLight, Mesh, PointLight, SpotLight, Transform
from ecs_engine.maths.camera import look_rotation
from ecs_engine.render.assets.materials import Material, materials
from ecs_engine.render.assets.primitives import plane_mesh, sphere_mesh

W, H = 160, 120
EYE = np.array([0.0, 0.0, 3.0])
AMBIENT = (1.0, 1.0, 1.0, 0.05)
LIGHTS = [
    ref.Light("point", (1.0, 0.9, 0.8), 9.0, position=(2.5, 2.5, 2.0), radius=20.0),
    ref.Light("directional", (0.7, 0.8, 1.0), 0.5, direction=(0.5, -0.6, -0.62)),
    ref.Light(
        "spot",
        (1.0, 1.0, 1.0),
        8.0,
        position=(0.0, 3.0, 2.0),
        direction=(0.1, -3.0, -2.0),
        radius=30.0,
        inner=0.25,
        outer=0.55,
    ),
]
MATERIALS = {
    "unlit": dict(base_color=(0.2, 0.6, 0.3, 1.0), emissive=(0.1, 0.0, 0.0)),
    "lambert": dict(base_color=(0.8, 0.5, 0.3, 1.0)),
    "oren_nayar": dict(base_color=(0.7, 0.7, 0.6, 1.0), roughness=0.9),
    "phong": dict(base_color=(0.3, 0.4, 0.8, 1.0), shininess=24.0, specular=0.6),
    "blinn_phong": dict(base_color=(0.6, 0.3, 0.5, 1.0), shininess=40.0, specular=0.5),
    "cook_torrance": dict(base_color=(0.9, 0.6, 0.2, 1.0), metallic=0.3, roughness=0.4),
    "cook_torrance_metal": dict(base_color=(0.95, 0.8, 0.5, 1.0), metallic=1.0, roughness=0.25),
}


def add_lights(world: World, lights: list[ref.Light]) -> None:
    for light in lights:
        if light.kind == "point":
            world.spawn(
                Transform(position=light.position),
                PointLight(color=light.color, intensity=light.intensity, radius=light.radius),
            )
        elif light.kind == "spot":
            world.spawn(
                Transform(position=light.position, rotation=look_rotation(light.direction)),
                SpotLight(
                    color=light.color,
                    intensity=light.intensity,
                    radius=light.radius,
                    inner_angle=light.inner,
                    outer_angle=light.outer,
                ),
            )
        else:
            world.spawn(
                Transform(rotation=look_rotation(light.direction)),
                DirectionalLight(color=light.color, illuminance=light.intensity),
            )


def turning_y_to(normal) -> np.ndarray:
    """The rotation (x, y, z, w) taking +Y (the plane's normal) to `normal`."""
    n = np.asarray(normal, float) / np.linalg.norm(normal)
    axis = np.cross([0.0, 1.0, 0.0], n)
    angle = math.acos(np.clip(n[1], -1, 1))
    axis = axis / np.linalg.norm(axis) if np.linalg.norm(axis) > 0 else np.array([1.0, 0, 0])
    return np.array([*(axis * math.sin(angle / 2)), math.cos(angle / 2)])


def render(gpu, world: World) -> np.ndarray:
    from ecs_engine.render.frame.renderer import Renderer

    renderer = Renderer(gpu.device, gpu.target, gpu.meshes, ambient=AMBIENT)
    try:
        default_schedule().run(world, 0.0)
        renderer.render(world, readback=True)
        return gpu.target.pixels()[..., :3].astype(np.float64)
    finally:
        renderer.destroy()


def scene(gpu, shape: str, material: Material, lights: list[ref.Light]) -> World:
    world = World()
    handle = materials(world).add(material)
    if shape == "plane":  # facing +Z (the camera), tilted a little about Y
        mesh = gpu.meshes.add(plane_mesh(size=8.0))
        world.spawn(Transform(rotation=turning_y_to((0.3, 0.2, 1.0))), Mesh(handle=mesh, material=handle))
    else:
        mesh = gpu.meshes.add(sphere_mesh(256, 128, radius=1.0))
        world.spawn(Transform(), Mesh(handle=mesh, material=handle))
    world.spawn(Transform(position=EYE), Camera(fov_y=math.radians(50.0), near=0.05))
    add_lights(world, lights)
    return world


def expected(
    world: World, shape: str, model: str, params: dict, lights: list[ref.Light]
) -> tuple[np.ndarray, np.ndarray]:
    """The reference image (h, w, 3) in 8-bit sRGB, and the pixels to compare (away from edges)."""
    from ecs_engine.render.frame.camera import camera_matrices

    cam = camera_matrices(world, W / H)
    rays = ref.pixel_rays(cam.projection, cam.inverse_view, EYE, W, H)
    if shape == "plane":
        entity = world.query(Mesh, Transform).entities()[0]
        q = world.get(entity, Transform).rotation
        from ecs_engine.maths.transform import quat_to_mat3

        normal = quat_to_mat3(np.asarray(q)[None])[0] @ [0.0, 1.0, 0.0]
        t, p = ref.hit_plane(EYE, rays, np.zeros(3), normal)
        n = np.broadcast_to(normal, p.shape)
        inside = (t > 0) & (np.abs(p).max(-1) < 3.5)  # well within the 8 x 8 plane
    else:
        t, p = ref.hit_sphere(EYE, rays, np.zeros(3), 1.0)
        n = p / np.linalg.norm(p, axis=-1, keepdims=True)
        inside = np.isfinite(t) & ((n * -rays).sum(-1) > 0.2)  # off the silhouette
    m = {**dict(metallic=0.0, roughness=0.5, shininess=32.0, specular=0.5, emissive=(0.0, 0.0, 0.0)), **params}
    color = ref.shade(model, m, np.where(inside[..., None], p, 0.0), n, EYE, lights, AMBIENT)
    return ref.srgb8(color), inside


@pytest.mark.parametrize("shape", ["plane", "sphere"])
@pytest.mark.parametrize("name", list(MATERIALS))
def test_shading_model_matches_the_numpy_formula(name, shape):
    model = name.removesuffix("_metal")
    params = MATERIALS[name]
    with headless_gpu(W, H) as gpu:
        world = scene(gpu, shape, Material(name, model, **params), LIGHTS)
        got = render(gpu, world)
    want, inside = expected(world, shape, model, params, LIGHTS)
    assert inside.sum() > 2000
    lit = want[inside].max(-1)
    assert lit.max() - lit.min() > 30 or model == "unlit"  # the lights make a difference to compare
    error = got[inside] - want[inside]
    rmse = float(np.sqrt((error**2).mean()))
    assert rmse <= 1.0, f"{name} on the {shape}: RMSE {rmse:.2f} of 255, worst {np.abs(error).max():.0f}"


def test_the_comparison_fails_for_another_model():
    """A model drawn with another's formula is caught (the check is not too loose)."""
    params = MATERIALS["blinn_phong"]
    with headless_gpu(W, H) as gpu:
        world = scene(gpu, "sphere", Material("b", "blinn_phong", **params), LIGHTS)
        got = render(gpu, world)
    for other in ("phong", "lambert"):
        want, inside = expected(world, "sphere", other, params, LIGHTS)
        assert np.sqrt(((got[inside] - want[inside]) ** 2).mean()) > 2.0


def hemisphere_lights(count: int, total: float) -> list[ref.Light]:
    """Directional lights from every direction above a +Z-facing surface (a Fibonacci spiral of
    equal solid angles), each of illuminance total * omega / pi: with them, a surface's radiance
    is total * its directional albedo, the integral of f cos over the hemisphere."""
    k = np.arange(count) + 0.5
    z = 1 - k / count  # uniform in z on the hemisphere: equal solid angles 2 pi / count
    r = np.sqrt(1 - z * z)
    phi = k * math.pi * (3 - math.sqrt(5))
    toward = np.stack([r * np.cos(phi), r * np.sin(phi), z], -1)
    e = total * (2 * math.pi / count) / math.pi
    return [ref.Light("directional", (1.0, 1.0, 1.0), e, direction=tuple(-d)) for d in toward]


@pytest.mark.parametrize("metallic, roughness", [(1.0, 0.5), (1.0, 1.0), (0.0, 0.5), (0.0, 1.0)])
def test_cook_torrance_reflects_no_more_than_it_receives(metallic, roughness):
    """White furnace on the GPU: a white surface lit from the whole hemisphere (2,048 directional
    lights) with total irradiance 0.5 sends back at most 0.5 (its albedo is at most 1) at every
    angle the camera sees it from (and what the formula gives: a NaN from rounding showed here).
    Discrete lights cannot integrate the narrow lobes of smooth
    surfaces; the reference formula (which the GPU matches, above) is integrated for those below."""
    total = 0.5
    lights = hemisphere_lights(2048, total)
    with headless_gpu(W, H) as gpu:
        world = World()
        white = Material("white", "cook_torrance", (1, 1, 1, 1), metallic=metallic, roughness=roughness)
        handle = materials(world).add(white)
        mesh = gpu.meshes.add(plane_mesh(size=8.0))
        world.spawn(Transform(rotation=turning_y_to((0.0, 0.0, 1.0))), Mesh(handle=mesh, material=handle))
        world.spawn(Transform(position=EYE), Camera(fov_y=math.radians(50.0), near=0.05))
        add_lights(world, lights)
        from ecs_engine.render.frame.renderer import Renderer

        renderer = Renderer(gpu.device, gpu.target, gpu.meshes, ambient=(0.0, 0.0, 0.0, 0.0))
        try:
            default_schedule().run(world, 0.0)
            renderer.render(world, readback=True)
            got = gpu.target.pixels()[..., :3].astype(np.float64)
        finally:
            renderer.destroy()
    ceiling = ref.srgb8(np.array(total))  # an albedo of exactly 1
    assert got.max() <= ceiling + 1, f"reflects {got.max():.0f} > {ceiling:.0f}: more than it receives"
    # and it is the albedo the formula gives (rough metal keeps only about a third: single scattering)
    from ecs_engine.render.frame.camera import camera_matrices

    cam = camera_matrices(world, W / H)
    rays = ref.pixel_rays(cam.projection, cam.inverse_view, EYE, W, H)
    _, p = ref.hit_plane(EYE, rays, np.zeros(3), np.array([0.0, 0.0, 1.0]))
    m = dict(base_color=(1.0, 1.0, 1.0, 1.0), metallic=metallic, roughness=roughness, emissive=(0.0, 0.0, 0.0))
    want = ref.srgb8(
        ref.shade("cook_torrance", m, p, np.broadcast_to([0.0, 0.0, 1.0], p.shape), EYE, lights, (0, 0, 0, 0))
    )
    assert np.abs(got - want).max() <= 1


@pytest.mark.parametrize("roughness", [0.045, 0.1, 0.3, 0.6, 1.0])
@pytest.mark.parametrize("metallic", [0.0, 1.0])
def test_cook_torrance_albedo_is_at_most_one(metallic, roughness):
    """The reference formula's directional albedo (the furnace test's integral), by importance
    sampling that follows even the narrowest lobe: at most 1 at every view angle, and close to 1
    for smooth metal (single-scattering GGX loses energy only when rough)."""
    rng = np.random.default_rng(1)
    m = dict(base_color=(1.0, 1.0, 1.0, 1.0), metallic=metallic, roughness=roughness)
    alpha = max(roughness, 0.045) ** 2
    n = np.array([0.0, 0.0, 1.0])
    for theta_v in np.radians([0.0, 30.0, 60.0, 85.0]):
        v = np.array([math.sin(theta_v), 0.0, math.cos(theta_v)])
        albedo = directional_albedo(m, n, v, rng, 200_000, alpha)
        assert albedo <= 1.0 + 0.01, f"albedo {albedo:.3f} at {math.degrees(theta_v):.0f} degrees"
        if metallic == 1.0 and roughness <= 0.1 and theta_v < math.radians(80):
            assert albedo >= 0.95


def directional_albedo(m: dict, n, v, rng, samples: int, alpha: float) -> float:
    """The integral of f (n.wi) over the hemisphere by multiple importance sampling: cosine-
    weighted directions (the diffuse lobe) and GGX half vectors (the specular one), balance
    heuristic (Veach 1997)."""
    a2 = alpha**2

    def pdf_cos(wi):
        return np.maximum(wi @ n, 0) / math.pi

    def pdf_ggx(wi):
        h = wi + v
        h /= np.linalg.norm(h, axis=-1, keepdims=True)
        nh, vh = h @ n, h @ v
        d = a2 / (math.pi * (nh**2 * (a2 - 1) + 1) ** 2)
        return np.where(vh > 0, d * nh / (4 * np.maximum(vh, 1e-12)), 0.0)

    u1, u2 = rng.random(samples), rng.random(samples)
    r, phi = np.sqrt(u1), 2 * math.pi * u2
    l_cos = np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(1 - u1)], -1)
    u1, u2 = rng.random(samples), rng.random(samples)
    cos_h = np.sqrt((1 - u1) / (1 + (a2 - 1) * u1))
    sin_h = np.sqrt(1 - cos_h**2)
    h = np.stack([sin_h * np.cos(2 * math.pi * u2), sin_h * np.sin(2 * math.pi * u2), cos_h], -1)
    l_ggx = 2 * (h @ v)[:, None] * h - v
    total = 0.0
    for wi in (l_cos, l_ggx):
        nl = wi @ n
        ok = nl > 1e-6
        wi = wi[ok]
        f = ref.brdf_pi("cook_torrance", m, n[None], wi, np.broadcast_to(v, wi.shape)).mean(-1) / math.pi
        weight = pdf_cos(wi) + pdf_ggx(wi)
        total += (f * nl[ok] / weight).sum() / samples
    return float(total)
