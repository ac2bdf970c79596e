"""Several cameras: which draw, where, in which order (components/camera_views.py), and the
extract stage's views with their pixel rectangles and matrices (render/extract/views.py)."""

from __future__ import annotations

import numpy as np
import pytest

from ecs_engine import World
from ecs_engine.components import (
    ActiveCamera,
    Camera,
    RenderLayers,
    RenderTexture,
    Transform,
    Viewport,
    active_camera,
    camera_views,
)
from ecs_engine.errors import UsageError
from ecs_engine.render.extract.views import extract_views


def _camera(world: World, *extra: object, x: float = 0.0) -> int:
    return world.spawn(Camera(), Transform(position=(x, 0.0, 5.0)), *extra)


def test_one_camera_draws_the_whole_window_as_before() -> None:
    w = World()
    eid = _camera(w)
    (view,) = camera_views(w)
    assert (view.entity, view.rect, view.texture, view.layers, view.order) == (eid, (0.0, 0.0, 1.0, 1.0), None, 1, 0)
    (data,) = extract_views(w, 640, 360)
    assert data.rect == (0, 0, 640, 360) and data.target_size == (640, 360) and data.texture is None
    assert data.camera.entity == eid


def test_split_screen_views_share_their_edge_and_draw_in_order() -> None:
    w = World()
    right = _camera(w, Viewport(x=0.5, width=0.5, order=1), x=3.0)
    left = _camera(w, Viewport(width=0.5), x=-3.0)
    views = extract_views(w, 641, 360)  # an odd width: the edge pixel belongs to one side only
    assert [v.view.entity for v in views] == [left, right]
    (x0, _, w0, _), (x1, _, w1, _) = (v.rect for v in views)
    assert x0 == 0 and x0 + w0 == x1 and x1 + w1 == 641
    # each projection is made for its own half's aspect (Camera.aspect 0: the viewport's)
    for v in views:
        aspect = v.rect[2] / v.rect[3]
        assert abs(v.camera.projection[1, 1] / v.camera.projection[0, 0]) == pytest.approx(aspect, rel=1e-6)
    assert not np.array_equal(views[0].camera.position, views[1].camera.position)
    assert active_camera(w) == left  # the first by order: the player's, for the render origin


def test_render_textures_draw_first_and_the_main_camera_is_the_window_s() -> None:
    w = World()
    main = _camera(w)
    monitor = _camera(w, RenderTexture(name="monitor", width=128, height=64), RenderLayers(mask=0b10))
    views = extract_views(w, 320, 200)
    assert [v.view.entity for v in views] == [monitor, main]
    tex = views[0]
    assert tex.texture == "monitor" and tex.rect == (0, 0, 128, 64) and tex.target_size == (128, 64)
    assert tex.layers == 0b10 and views[1].layers == 1
    assert active_camera(w) == main  # the monitor's camera never is the player's


def test_a_picture_in_picture_draws_over_the_main_view() -> None:
    w = World()
    main = _camera(w)
    mirror = _camera(w, Viewport(x=0.75, y=0.0, width=0.25, height=0.25, order=1))
    views = camera_views(w)
    assert [v.entity for v in views] == [main, mirror]
    assert views[1].pixels(400, 400) == (300, 0, 100, 100)


def test_views_follow_component_writes() -> None:
    w = World()
    eid = _camera(w, Viewport(width=0.5))
    _camera(w, Viewport(x=0.5, width=0.5, order=1))
    first = camera_views(w)
    assert camera_views(w) is first  # kept while nothing changed
    w.set(eid, Viewport(width=0.5, order=5))
    again = camera_views(w)
    assert again is not first and again[-1].entity == eid


def test_ambiguous_or_missing_window_cameras_are_refused() -> None:
    w = World()
    _camera(w, RenderTexture(name="only"))
    with pytest.raises(UsageError, match="no camera draws into the window"):
        camera_views(w)
    with pytest.raises(UsageError, match="every camera has a RenderTexture"):
        active_camera(w)
    w = World()
    _camera(w)
    _camera(w)
    with pytest.raises(UsageError, match="ActiveCamera"):
        camera_views(w)
    w = World()
    _camera(w, RenderTexture(name="same"))
    _camera(w, RenderTexture(name="same"))
    _camera(w)
    with pytest.raises(UsageError, match="named 'same'"):
        camera_views(w)


def test_spare_cameras_do_not_draw_beside_viewports_unless_tagged() -> None:
    w = World()
    a = _camera(w, Viewport(width=0.5))
    b = _camera(w, Viewport(x=0.5, width=0.5))
    _camera(w)
    _camera(w)  # two cameras without a viewport: spares (an editor's, a controller's)
    assert [v.entity for v in camera_views(w)] == [a, b]
    tagged = _camera(w, ActiveCamera())
    views = camera_views(w)
    assert [v.entity for v in views] == [tagged, a, b]  # the full-window one first: the backdrop
    assert active_camera(w) == tagged


@pytest.mark.parametrize(
    "bad, match",
    [
        (lambda: Viewport(x=0.6, width=0.5), "right edge"),
        (lambda: Viewport(y=0.5, height=0.75), "bottom edge"),
        (lambda: Viewport(width=0.0), "width"),
        (lambda: Viewport(x=float("nan")), "x"),
        (lambda: RenderTexture(name="", width=4, height=4), "name is empty"),
        (lambda: RenderTexture(name="t", width=0, height=4), "width"),
    ],
)
def test_bad_view_components_are_refused_where_they_enter(bad, match) -> None:
    w = World()
    with pytest.raises(ValueError, match=match):
        _camera(w, bad())


def test_the_split_screen_scene_gives_each_player_half_and_a_picture_in_picture_on_top() -> None:
    """demos/split_screen.py (drawn by the renderer's views once it draws several cameras)."""
    from ecs_engine.demos.split_screen import build

    w = World()
    build(w, lambda mesh: 0)
    left, right, inset = extract_views(w, 1280, 720)
    assert (left.rect, right.rect) == ((0, 0, 640, 720), (640, 0, 640, 720))
    x, y, width, height = inset.rect
    assert inset.view.order == 1 and x >= 640 and x + width <= 1280 and y + height <= 720
