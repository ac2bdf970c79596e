"""The inspector's light sections: point, spot and directional lights, picked from a table by
component type. Each edit goes through `Editor.set` (the world's checks; a refused value leaves
the light as it was and shows the message)."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, Protocol

import numpy as np

from ..components import DirectionalLight, PointLight, Shadow, SpotLight
from ..components.shadow import SHADOW_FILTERS
from ..ecs.world import World


class Editor(Protocol):
    """What an inspector section uses of the editor (app/editor.py)."""

    @property
    def imgui(self) -> Any: ...

    def set(self, world: World, eid: int, component: type, **fields: Any) -> None:
        """One edit through the World API; a refused value is shown, not raised."""
        ...

    def show_material(self, handle: int) -> None:
        """Select a material and bring the Materials tab forward."""
        ...


def _color(editor: Editor, world: World, eid: int, component: type, value: Any) -> None:
    changed, color = editor.imgui.color_edit3("colour", [float(c) for c in value])
    if changed:
        editor.set(world, eid, component, color=np.array(color, dtype=np.float32))


def _amount(editor: Editor, world: World, eid: int, component: type, field: str, label: str, value: float) -> None:
    changed, new = editor.imgui.drag_float(label, float(value), 0.1, 0.0, 1e6)
    if changed:
        editor.set(world, eid, component, **{field: max(new, 0.0)})


def point_light(editor: Editor, world: World, eid: int) -> None:
    light = world.get(eid, PointLight)
    editor.imgui.separator_text("PointLight")
    _color(editor, world, eid, PointLight, light.color)
    _amount(editor, world, eid, PointLight, "intensity", "intensity", light.intensity)
    _amount(editor, world, eid, PointLight, "radius", "radius (0: unbounded)", light.radius)
    shadow(editor, world, eid, directional=False)


def spot_light(editor: Editor, world: World, eid: int) -> None:
    imgui = editor.imgui
    light = world.get(eid, SpotLight)
    imgui.separator_text("SpotLight (aim it with the rotation)")
    _color(editor, world, eid, SpotLight, light.color)
    _amount(editor, world, eid, SpotLight, "intensity", "intensity", light.intensity)
    _amount(editor, world, eid, SpotLight, "radius", "range (0: unbounded)", light.radius)
    inner, outer = math.degrees(float(light.inner_angle)), math.degrees(float(light.outer_angle))
    changed, angles = imgui.drag_float2("cone inner, outer (deg)", [inner, outer], 0.2, 0.0, 90.0)
    if changed:
        editor.set(world, eid, SpotLight, inner_angle=math.radians(angles[0]), outer_angle=math.radians(angles[1]))
    shadow(editor, world, eid, directional=False)


def directional_light(editor: Editor, world: World, eid: int) -> None:
    light = world.get(eid, DirectionalLight)
    editor.imgui.separator_text("DirectionalLight (aim it with the rotation)")
    _color(editor, world, eid, DirectionalLight, light.color)
    _amount(editor, world, eid, DirectionalLight, "illuminance", "illuminance", light.illuminance)
    shadow(editor, world, eid, directional=True)


RESOLUTIONS = (256, 512, 1024, 2048, 4096)


def shadow(editor: Editor, world: World, eid: int, directional: bool) -> None:
    """Whether the light casts (adds or removes its Shadow) and, when it does, its settings."""
    imgui = editor.imgui
    casts = world.has(eid, Shadow)
    changed, on = imgui.checkbox("casts shadows", casts)
    if changed:
        if on:
            world.add(eid, Shadow())
        else:
            world.remove(eid, Shadow)
        return
    if not casts:
        return
    s = world.get(eid, Shadow)
    at = RESOLUTIONS.index(int(s.resolution)) if int(s.resolution) in RESOLUTIONS else 3
    changed, pick = imgui.combo("shadow map texels", at, [str(r) for r in RESOLUTIONS])
    if changed:
        editor.set(world, eid, Shadow, resolution=RESOLUTIONS[pick])
    if directional:
        changed, n = imgui.slider_int("cascades", int(s.cascades), 1, 4)
        if changed:
            editor.set(world, eid, Shadow, cascades=n)
        _amount(editor, world, eid, Shadow, "distance", "shadow distance", s.distance)
    _amount(editor, world, eid, Shadow, "bias", "depth bias (texels)", s.bias)
    _amount(editor, world, eid, Shadow, "normal_offset", "normal offset (texels)", s.normal_offset)
    changed, pick = imgui.combo("filter", int(s.filter), list(SHADOW_FILTERS))
    if changed:
        editor.set(world, eid, Shadow, filter=pick)
    _amount(editor, world, eid, Shadow, "softness", "softness (PCF texels)", s.softness)


#: component type -> its inspector section, in the order they are drawn
LIGHT_SECTIONS: dict[type, Callable[[Editor, World, int], None]] = {
    PointLight: point_light,
    SpotLight: spot_light,
    DirectionalLight: directional_light,
}
