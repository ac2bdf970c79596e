"""The inspector's light sections: point, spot and directional lights, picked from a table by
component type. Each edit goes through `Editor.set` (the world's checks; a refused value leaves
the light as it was and shows the message).

A light that casts shadows shows its shadow maps (ShadowMapImages): a thumbnail per layer (a
directional light's cascades, a spot light's map, a point light's six cube faces), grey, near
white and far black (reverse-Z depth), as the last frame drew them: texel (0, 0) at the top left,
so each shows what a camera at the light sees (render/shadows/views.py draws the cube faces so,
not as the spec's mirror images)."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from ..components import DirectionalLight, PointLight, Shadow, SpotLight
from ..components.shadow import SHADOW_FILTERS
from ..ecs.world import World
from .editor_layout import hint

if TYPE_CHECKING:
    from ..gpu.shadow_maps import ShadowMaps
    from ..render.shadows.maps_pass import ShadowPass
    from ..render.shadows.views import ShadowView
    from ..render.ui.imgui_pass import ImGuiRenderer

CUBE_FACE_NAMES = ("+X", "-X", "+Y", "-Y", "+Z", "-Z")  # shadow_views.py's face order
THUMBNAIL = 128  # a shadow map thumbnail's largest side in pixels (64 at least: smaller fit a row)


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

    @property
    def shadow_maps(self) -> ShadowMapImages | None:
        """The shadow map thumbnails (None: the editor has no renderer to show them from)."""
        ...


class ShadowMapImages:
    """The renderer's shadow map layers as ImGui images: per layer a grey view of it
    (ShadowMaps.preview_view) registered with the overlay (imgui_pass.ImGuiRenderer's
    register_image) the first time it is shown. When the maps are made anew (larger: render/
    shadow_pass.py's ensure), the old ids are dropped (the overlay drops them itself when it draws
    after the maps went, before the next UI is built) and the new layers registered as shown.
    Which layers are a light's comes from the renderer's last planned views (ShadowPass.last_views)."""

    def __init__(self, shadows: ShadowPass, overlay: ImGuiRenderer) -> None:
        self.shadows, self.overlay = shadows, overlay
        self._maps: ShadowMaps | None = None  # the maps the ids below show
        self._ids: dict[int, int] = {}  # layer -> ImGui texture id
        self.drawn: dict[int, int] = {}  # the last UI's thumbnails: layer -> texture id
        self.rects: dict[int, tuple[float, float, float, float]] = {}  # layer -> its thumbnail on screen

    def begin_frame(self) -> None:
        self.drawn, self.rects = {}, {}

    def views(self, eid: int) -> list[ShadowView]:
        """The light's views (ShadowView) as last planned, in layer order (none before it was drawn)."""
        maps = self.shadows.maps
        if maps is None:
            return []
        return [v for v in self.shadows.last_views if v.entity == eid and v.layer < maps.layers]

    def texture(self, layer: int) -> int:
        """The ImGui texture id of the current maps' `layer`."""
        maps = self.shadows.maps
        assert maps is not None
        if maps is not self._maps:
            for tex_id in self._ids.values():
                self.overlay.unregister_image(tex_id)
            self._maps, self._ids = maps, {}
        known = self._ids.get(layer)
        if known is not None:
            return known
        view = maps.preview_view(layer)
        alive = lambda: not maps.destroyed  # the maps may go before the overlay draws
        tex_id = self._ids[layer] = self.overlay.register_image(view, maps.plain_sampler, maps.read_layout, alive)
        return tex_id

    def draw(self, imgui: Any, eid: int) -> None:
        """The light's thumbnails, as many to a row as fit; hovering one shows it larger."""
        views = self.views(eid)
        if not views:
            return
        imgui.text_wrapped("shadow maps (near white, far black)")
        spacing = float(imgui.get_style().item_spacing.x)
        avail = float(imgui.get_content_region_avail().x)
        columns = 3 if views[0].kind == "cube" else len(views)
        side = max(64.0, min(float(THUMBNAIL), (avail - (columns - 1) * spacing) / columns))
        per_row = max(1, int((avail + spacing) // (side + spacing)))
        maps = self.shadows.maps
        assert maps is not None
        for k, v in enumerate(views):
            if k % per_row:
                imgui.same_line()
            tex_id = self.texture(v.layer)
            corner = (min(v.resolution, maps.resolution) / maps.resolution,) * 2  # its map: the layer's corner
            imgui.image(imgui.ImTextureRef(tex_id), (side, side), (0.0, 0.0), corner)
            lo, hi = imgui.get_item_rect_min(), imgui.get_item_rect_max()
            self.drawn[v.layer], self.rects[v.layer] = tex_id, (lo.x, lo.y, hi.x, hi.y)
            if imgui.is_item_hovered():
                imgui.begin_tooltip()
                imgui.text(f"{_view_name(v)}: layer {v.layer}, {v.resolution} texels")
                imgui.image(imgui.ImTextureRef(tex_id), (2 * THUMBNAIL, 2 * THUMBNAIL), (0.0, 0.0), corner)
                imgui.end_tooltip()


def _view_name(view: ShadowView) -> str:
    if view.kind == "cascade":
        return f"cascade {view.index} (to {view.far:.3g})"
    if view.kind == "cube":
        return f"cube face {CUBE_FACE_NAMES[view.index]}"
    return "spot light"


def _color(editor: Editor, world: World, eid: int, component: type, value: Any) -> None:
    changed, color = editor.imgui.color_edit3("colour", [float(c) for c in value])
    if changed:
        editor.set(world, eid, component, color=np.array(color, dtype=np.float32))


def _amount(
    editor: Editor, world: World, eid: int, component: type, field: str, label: str, value: float, more: str = ""
) -> None:
    """A drag for a field of at least 0; `more`: a tooltip saying what the short label leaves out."""
    changed, new = editor.imgui.drag_float(label, float(value), 0.1, 0.0, 1e6)
    if more:
        hint(editor.imgui, more)
    if changed:
        editor.set(world, eid, component, **{field: max(new, 0.0)})


def point_light(editor: Editor, world: World, eid: int) -> None:
    light = world.get(eid, PointLight)
    editor.imgui.separator_text("PointLight")
    _color(editor, world, eid, PointLight, light.color)
    _amount(editor, world, eid, PointLight, "intensity", "intensity", light.intensity)
    _amount(editor, world, eid, PointLight, "radius", "radius", light.radius, "0: unbounded")
    shadow(editor, world, eid, directional=False)


def spot_light(editor: Editor, world: World, eid: int) -> None:
    imgui = editor.imgui
    light = world.get(eid, SpotLight)
    imgui.separator_text("SpotLight")
    hint(imgui, "aim it with the rotation")
    _color(editor, world, eid, SpotLight, light.color)
    _amount(editor, world, eid, SpotLight, "intensity", "intensity", light.intensity)
    _amount(editor, world, eid, SpotLight, "radius", "range", light.radius, "0: unbounded")
    inner, outer = math.degrees(float(light.inner_angle)), math.degrees(float(light.outer_angle))
    changed, angles = imgui.drag_float2("cone (deg)", [inner, outer], 0.2, 0.0, 90.0)
    hint(imgui, "the cone's inner and outer angles in degrees")
    if changed:
        editor.set(world, eid, SpotLight, inner_angle=math.radians(angles[0]), outer_angle=math.radians(angles[1]))
    shadow(editor, world, eid, directional=False)


def directional_light(editor: Editor, world: World, eid: int) -> None:
    light = world.get(eid, DirectionalLight)
    editor.imgui.separator_text("DirectionalLight")
    hint(editor.imgui, "aim it with the rotation")
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
    changed, pick = imgui.combo("map texels", at, [str(r) for r in RESOLUTIONS])
    hint(imgui, "the shadow map's side in texels")
    if changed:
        editor.set(world, eid, Shadow, resolution=RESOLUTIONS[pick])
    if directional:
        changed, n = imgui.slider_int("cascades", int(s.cascades), 1, 4)
        if changed:
            editor.set(world, eid, Shadow, cascades=n)
        _amount(editor, world, eid, Shadow, "distance", "shadow distance", s.distance)
    _amount(editor, world, eid, Shadow, "bias", "depth bias", s.bias, "in texels")
    _amount(editor, world, eid, Shadow, "normal_offset", "normal offset", s.normal_offset, "in texels")
    changed, pick = imgui.combo("filter", int(s.filter), list(SHADOW_FILTERS))
    if changed:
        editor.set(world, eid, Shadow, filter=pick)
    _amount(editor, world, eid, Shadow, "softness", "softness", s.softness, "the PCF filter's radius in texels")
    if editor.shadow_maps is not None:
        editor.shadow_maps.draw(imgui, eid)


# the sections' field labels (the inspector leaves room for the widest: editor_layout.py)
LIGHT_LABELS = (
    *("colour", "intensity", "radius", "range", "cone (deg)", "illuminance", "map texels", "cascades"),
    *("shadow distance", "depth bias", "normal offset", "filter", "softness"),
)

#: component type -> its inspector section, in the order they are drawn
LIGHT_SECTIONS: dict[type, Callable[[Editor, World, int], None]] = {
    PointLight: point_light,
    SpotLight: spot_light,
    DirectionalLight: directional_light,
}
