"""Shadow views (render/shadows/views.py): which lights get views (only those with a Shadow), in
what order and layers; cascades holding their slices of the camera's view; spot views holding
their cone; cube faces in Vulkan's cube-map orientation. And the Shadow component's checks."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ecs_engine import World
from ecs_engine.components import Camera, DirectionalLight, PointLight, Shadow, SpotLight, Transform
from ecs_engine.maths.camera import look_rotation
from ecs_engine.maths.shadow_cascades import cascade_splits
from ecs_engine.render.extract.shadows import extract_shadow_casters
from ecs_engine.render.frame.camera import camera_matrices
from ecs_engine.render.shadows.views import cube_face_scale, shadow_views

ASPECT = 16 / 9


def scene(origin=(0.0, 0.0, 0.0)) -> World:
    world = World()
    world.spawn(
        Transform(position=origin, rotation=look_rotation((0.3, -0.4, -1.0))),
        Camera(fov_y=math.radians(60.0), near=0.5, far=400.0),
    )
    world.spawn(
        Transform(rotation=look_rotation((0.2, -1.0, 0.3))), DirectionalLight(), Shadow(cascades=3, distance=30.0)
    )
    world.spawn(Transform(rotation=look_rotation((0.0, -1.0, 0.0))), DirectionalLight())  # casts none
    world.spawn(
        Transform(position=(4.0, 3.0, -2.0), rotation=look_rotation((0.1, -1.0, 0.2))),
        SpotLight(radius=12.0, outer_angle=0.7, inner_angle=0.5),
        Shadow(resolution=1024),
    )
    world.spawn(Transform(position=(-3.0, 2.0, -5.0)), PointLight(radius=8.0), Shadow(resolution=512))
    world.spawn(Transform(position=(1.0, 1.0, 1.0)), PointLight(radius=8.0))  # casts none
    return world


def clip(view, points):
    p = np.c_[points, np.ones(len(points))] @ view.view_projection.astype(np.float64).T
    return p


def test_only_lights_with_a_shadow_get_views_in_layer_order():
    world = scene()
    cam = camera_matrices(world, ASPECT)
    views = shadow_views(extract_shadow_casters(world), cam, cam.position)
    assert [(v.kind, v.index) for v in views] == [
        ("cascade", 0),
        ("cascade", 1),
        ("cascade", 2),
        ("spot", 0),
        *[("cube", f) for f in range(6)],
    ]
    assert [v.layer for v in views] == list(range(10))
    assert [v.resolution for v in views] == [2048] * 3 + [1024] + [512] * 6
    assert [v.far for v in views[:3]] == pytest.approx(cascade_splits(0.5, 30.0, 3)[1:].tolist())
    assert shadow_views(extract_shadow_casters(World()), cam, cam.position) == []


@pytest.mark.parametrize("origin", [(0.0, 0.0, 0.0), (1.0e5, 20.0, -3.0e5)])
def test_each_cascade_holds_its_slice_of_the_view(origin):
    world = scene(origin)
    cam = camera_matrices(world, ASPECT)
    views = shadow_views(extract_shadow_casters(world), cam, cam.position)
    inv = np.linalg.inv(cam.projection.astype(np.float64))
    rot = cam.inverse_view[:3, :3].astype(np.float64)
    for v in views[:3]:
        d0 = cam.near if v.index == 0 else views[v.index - 1].far
        corners = []
        for d in (d0, v.far):
            for x in (-1, 1):
                for y in (-1, 1):
                    p = inv @ np.array([x, y, 0.5, 1.0])
                    p = p[:3] / p[3]
                    corners.append(rot @ (p * (d / -p[2])))  # render-relative: the camera is the origin
        c = clip(v, np.array(corners))
        ndc = c[:, :3] / c[:, 3:]
        assert (np.abs(ndc[:, :2]) <= 1 + 1e-4).all() and (ndc[:, 2] >= -1e-4).all() and (ndc[:, 2] <= 1 + 1e-4).all()


def test_a_spot_view_holds_its_cone_and_range():
    world = scene()
    cam = camera_matrices(world, ASPECT)
    spot = shadow_views(extract_shadow_casters(world), cam, cam.position)[3]
    rng = np.random.default_rng(2)
    axis = np.array([0.1, -1.0, 0.2]) / np.linalg.norm([0.1, -1.0, 0.2])
    apex = np.array([4.0, 3.0, -2.0]) - cam.position
    inside = []
    while len(inside) < 200:
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
        if math.acos(np.clip(d @ axis, -1, 1)) < 0.7:
            inside.append(apex + d * rng.uniform(0.2, 11.9))
    dist = np.array(inside) @ spot.planes[:, :3].T + spot.planes[:, 3]
    assert (dist >= -1e-5).all()
    behind = apex - axis * 1.0
    assert (behind @ spot.planes[:, :3].T + spot.planes[:, 3] < 0).any()


def test_cube_faces_follow_vulkans_cube_map_face_selection():
    """The face a direction's major axis picks draws it, at the spec's (s, t) with s negated (a
    camera's view, not the spec's mirror image) shrunk by the margin; another face holds it only
    in its margin; depth runs from the near plane (1) to the light's range along the face's axis
    (0)."""
    world = scene()
    cam = camera_matrices(world, ASPECT)
    faces = shadow_views(extract_shadow_casters(world), cam, cam.position)[4:]
    light = np.array([-3.0, 2.0, -5.0]) - cam.position
    rng = np.random.default_rng(5)
    for _ in range(300):
        r = rng.normal(size=3)
        distance = rng.uniform(0.2, 7.9)
        r *= distance / np.linalg.norm(r)
        axis = int(np.argmax(np.abs(r)))
        face = 2 * axis + (r[axis] < 0)
        rx, ry, rz = r
        ma = abs(r[axis])
        sc, tc = {
            0: (-rz, -ry),
            1: (rz, -ry),
            2: (rx, rz),
            3: (rx, -rz),
            4: (rx, -ry),
            5: (-rx, -ry),
        }[face]
        scale = cube_face_scale(512)
        for v in faces:
            c = clip(v, (light + r)[None])[0]
            holds = c[3] > 0 and abs(c[0]) <= c[3] and abs(c[1]) <= c[3]
            if v.index == face:
                assert holds
                assert (c[0] / c[3], c[1] / c[3]) == pytest.approx((-sc / ma * scale, tc / ma * scale), abs=1e-5)
                assert 0.0 <= c[2] / c[3] <= 1.0
            elif holds:  # another face holds it only within its margin, past its own edge
                assert max(abs(c[0]), abs(c[1])) / c[3] > scale - 1e-6
        beyond = clip(faces[face], (light + r * (8.5 / ma))[None])[0]
        assert beyond[2] / beyond[3] < 0  # past the range along the face's axis: behind its far plane


def front_facing(view_projection: np.ndarray, inverse: np.ndarray) -> bool:
    """Whether a triangle facing the view (wound counter-clockwise around its normal, as every
    mesh's outside) is front-facing to a pipeline with VK_FRONT_FACE_COUNTER_CLOCKWISE: the
    spec's polygon area a = -1/2 sum(x_i y_(i+1) - x_(i+1) y_i) in framebuffer coordinates
    (y down) is positive. Its centre is the view's middle at mid depth, its normal towards the
    view (the middle nearer it)."""

    def unproject(ndc):
        p = inverse @ np.array([*ndc, 1.0])
        return p[:3] / p[3]

    centre, nearer = unproject((0.0, 0.0, 0.5)), unproject((0.0, 0.0, 0.9))  # reverse-Z: 0.9 is nearer
    n = (nearer - centre) / np.linalg.norm(nearer - centre)
    u = np.cross(n, [0.3, 0.5, 0.7])
    u *= 0.01 * np.linalg.norm(centre - nearer) / np.linalg.norm(u)
    v = np.cross(n, u)  # u x v = n: counter-clockwise around n
    corners = np.array([centre, centre + u, centre + v])
    c = np.c_[corners, np.ones(3)] @ view_projection.T
    xy = (c[:, :2] / c[:, 3:] * 0.5 + 0.5) * 100.0  # framebuffer: x right, y down (Vulkan's NDC)
    x, y = xy[:, 0], xy[:, 1]
    area = -0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)
    return bool(area > 0)


def test_no_view_is_mirrored():
    """A caster's side facing the light is front-facing in every shadow view, as a surface
    facing the camera is in the camera's view: the shadow pipelines cull back faces with one
    winding for all. The spec's cube faces are mirror images (sc x tc = -forward): point lights
    drew their casters' far sides, so a single-sided plane facing one cast nothing."""
    world = scene()
    cam = camera_matrices(world, ASPECT)
    camera = cam.projection.astype(np.float64) @ cam.view.astype(np.float64)
    assert front_facing(camera, np.linalg.inv(camera))  # the rule holds for the camera's own view
    views = shadow_views(extract_shadow_casters(world), cam, cam.position)
    assert {v.kind for v in views} == {"cascade", "spot", "cube"}
    for v in views:
        vp = v.view_projection.astype(np.float64)
        assert front_facing(vp, np.linalg.inv(vp)), (v.kind, v.index)


def test_cube_faces_are_seen_as_from_a_camera_at_the_light():
    """Each face's map (and so its editor thumbnail, texel (0, 0) at the top left) shows what a
    camera at the light looking along the face sees: the side faces upright (world +Y up the
    image) and right = forward x up, not the spec's mirror image."""
    world = scene()
    cam = camera_matrices(world, ASPECT)
    faces = shadow_views(extract_shadow_casters(world), cam, cam.position)[4:]
    light = np.array([-3.0, 2.0, -5.0]) - cam.position
    forwards = np.array([(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)], np.float64)
    for v, forward in zip(faces, forwards, strict=True):
        up = np.array([0.0, 1.0, 0.0]) if forward[1] == 0 else np.array([0.0, 0.0, -forward[1]])
        right = np.cross(forward, up)
        for offset, expect in ((right, (1, 0)), (-right, (-1, 0)), (up, (0, -1)), (-up, (0, 1))):
            c = clip(v, (light + 2.0 * forward + 0.5 * offset)[None])[0]
            ndc = c[:2] / c[3]
            assert np.sign(np.round(ndc, 6)).tolist() == list(expect), (v.index, offset, ndc)


@pytest.mark.parametrize(
    ("field", "value"),
    [("resolution", 8), ("resolution", 9000), ("cascades", 0), ("cascades", 5), ("distance", 0.0), ("filter", 3),
     ("bias", -1.0), ("softness", float("nan"))],
)  # fmt: skip
def test_bad_shadow_settings_are_refused_naming_the_field(field, value):
    world = World()
    with pytest.raises((ValueError, OverflowError), match=field):
        world.spawn(Transform(), DirectionalLight(), Shadow(**{field: value}))
