"""Plugins (app/plugins.py): functions, classes and instances build into an App; groups leave
one out or swap one; the engine's parts are plugins, and the demos' schedule is theirs."""

from __future__ import annotations

import pytest

from ecs_engine import App, DefaultPlugins, MinimalPlugins, Plugin, PluginGroup
from ecs_engine.app import plugins
from ecs_engine.app.plugins import (
    CameraControlPlugin,
    HierarchyPlugin,
    PerfPlugin,
    RenderPlugin,
    ScenePlugin,
    WindowPlugin,
)
from ecs_engine.errors import UsageError


def test_a_plugin_is_a_function_a_class_or_an_instance():
    built = []

    def counter(app):
        built.append(("function", app.name))

    class Spawner(Plugin):
        def __init__(self, n=1):
            self.n = n

        def build(self, app):
            built.append(("class", self.n))

    app = App(title="Plugged").add_plugins(counter, Spawner, PluginGroup(Spawner(3), name="more").without(Spawner))
    app = App(title="Again").add_plugins(PluginGroup(counter, Spawner(3)))
    assert built == [("function", "plugged"), ("class", 1), ("function", "again"), ("class", 3)]
    assert app.has_plugin(Spawner) and app.has_plugin(counter) and not app.has_plugin(RenderPlugin)


def test_groups_leave_out_and_swap_plugins():
    group = DefaultPlugins.without(PerfPlugin, CameraControlPlugin).set(WindowPlugin(title="Big", fullscreen=True))
    names = [plugins.plugin_name(p) for p in group]
    assert "PerfPlugin" not in names and "CameraControlPlugin" not in names
    assert names.index("WindowPlugin") == [plugins.plugin_name(p) for p in DefaultPlugins].index("WindowPlugin")
    app = App().add_plugins(group)
    assert app.title == "Big" and app.window.fullscreen and app.windowed and not app.perf_lines
    assert "fly_camera" not in app.systems() and "transform" in app.systems()
    assert "PerfPlugin" in [plugins.plugin_name(p) for p in DefaultPlugins]  # the group itself is unchanged


def test_a_group_names_what_it_lacks():
    with pytest.raises(UsageError, match=r"MinimalPlugins.without\(RenderPlugin\): it has no such plugin; it has "):
        MinimalPlugins.without(RenderPlugin)
    with pytest.raises(UsageError, match=r"MinimalPlugins.set\(ScenePlugin\): it has no such plugin"):
        MinimalPlugins.set(ScenePlugin(load="a.scene"))


def test_minimal_plugins_have_no_window_and_no_gpu():
    app = App().add_plugins(MinimalPlugins)
    assert not app.renders and not app.windowed
    assert app.systems() == {
        "snapshot": "fixed",
        "orbit": "fixed",
        "motion": "fixed",
        "spring": "fixed",
        "animation": "update",
        "animation_layers": "update",
        "render_origin": "post_update",
        "transform": "post_update",
        "hierarchy": "post_update",
        "skins": "post_update",
    }


def test_the_demo_schedule_is_the_scene_plugins(monkeypatch):
    from ecs_engine.app.scenes import default_schedule

    assert default_schedule().order() == [
        ("fixed", ["snapshot", "orbit", "motion", "spring"]),
        ("update", ["fly_camera"]),
        ("post_update", ["render_origin", "transform", "hierarchy", "skins"]),
    ]
    monkeypatch.setattr(plugins, "SCENE_PLUGINS", plugins.SCENE_PLUGINS.without(HierarchyPlugin))
    assert default_schedule().order()[2] == ("post_update", ["render_origin", "transform"])
