"""The ImGui editor: entity browser, inspector, live render settings, scene switcher and stats.

It only reads the world and writes components through the World API; changes that need new
engine objects (mode, recorder, threads, present mode, another scene) are returned as requests
that the frame loop applies between frames (`Editor.take_requests`).

The entity browser stays fast with millions of entities: the filtered id list is a NumPy array
rebuilt only when the world's structure or the filter changes, and ImGui's list clipper draws
only the visible rows.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from ..components import Camera, Environment, Mesh, PointLight, Transform, active_camera
from ..components.audio import AudioSource
from ..components.name import Name
from ..ecs.world import World
from ..gpu.swapchain import PRESENT_MODES as SWAPCHAIN_PRESENT_MODES
from ..maths.camera import yaw_pitch_roll, yaw_pitch_roll_quat
from ..render.config import CHOICES, RenderConfig, applies
from .editor_animation import AnimationPanel
from .editor_audio import SOURCE_LABELS, AudioPanel, source_section
from .editor_browser import Browser, BrowserPanel
from .editor_dock import DockLayout
from .editor_files import FileMenu
from .editor_gizmo import OPERATIONS, Gizmo
from .editor_history import History
from .editor_layout import button_width, hint, push_label_room, radio_width, same_line_if_fits, wrapped_colored
from .editor_lights import LIGHT_LABELS, LIGHT_SECTIONS, ShadowMapImages
from .editor_materials import MESH_LABELS, MaterialsPanel, mesh_section
from .editor_physics import PhysicsPanel
from .editor_post import post_toggles
from .editor_tree import HierarchyPanel
from .editor_viewport import SceneWindow, scene_input
from .settings import Settings

if TYPE_CHECKING:
    from ..render.frame.renderer import Renderer
    from ..render.ui.imgui_pass import ImGuiRenderer

PRESENT_MODES = tuple(SWAPCHAIN_PRESENT_MODES)
# the labels of each window's fields: the fields leave room for the widest (editor_layout.py)
SETTINGS_LABELS = (
    *("scene", "mode", "recorder", "threads", "culling", "fill", "tone map", "exposure (EV)", "light culling"),
    *("transparency", "shadows", "present", "environment"),
)
ENTITY_LABELS = ("name", "position", "rotation (deg)", "scale", "fov (deg)", "near", "far")


@dataclass
class SceneStats:
    entities: int = 0
    visible: int = 0
    draws: int = 0
    triangles: int = 0


class Editor(BrowserPanel):
    def __init__(
        self, settings: Settings, scenes: tuple[str, ...], max_threads: int, ray_tracing: bool = False
    ) -> None:
        from imgui_bundle import imgui

        self.imgui = imgui
        self.settings = settings
        self.requested = replace(settings)
        self.scenes = scenes
        self.max_threads = max_threads
        self.ray_tracing = ray_tracing  # the device traces rays: ray-traced shadows can be picked
        self.selected: int | None = None
        self.browser = Browser()
        self.materials = MaterialsPanel()
        self.open_tab: str | None = None  # the Inspector's tab to bring forward on the next frame
        self.status = ""  # the last error from an edit, shown in the inspector
        self.settings_status = ""  # the last refused settings request, shown under the settings
        self.status_entity: int | None = None  # the entity it is about
        # screen rectangles (x0, y0, x1, y1) of a few widgets as last drawn: where synthetic
        # input (tests, scripted demos) should click
        self.rects: dict[str, tuple[float, float, float, float]] = {}
        self.shadow_maps: ShadowMapImages | None = None  # show_shadow_maps
        self.meshes: Any = None  # the renderer's MeshRegistry (show_shadow_maps): clicks pick with it
        self.dock = DockLayout(imgui)
        self.history = History()
        self.gizmo = Gizmo()
        self.picked: int | None = None  # what the last click in the scene picked (None: nothing)
        self.tree = HierarchyPanel()
        self.files = FileMenu()
        self.scene = SceneWindow(imgui)  # the scene's window in the dock (editor_viewport.py)
        self.physics = PhysicsPanel()  # while the world has physics (editor_physics.py)
        self.animation = AnimationPanel()  # while a character is selected (editor_animation.py)
        self.audio = AudioPanel()  # while the world has sound (editor_audio.py)
        self.animated: int | None = None  # the player the Animation window showed last
        self.viewport: Any = None  # the renderer's EditorViewport (show_scene), None: no Scene window
        self.viewport_ui: Any = None  # (the ImGuiRenderer, a callable giving the window target)

    def show_scene(self, viewport: Any, ui: ImGuiRenderer, window: Any) -> None:
        """Show the scene in a Scene window: the renderer's `viewport` (render/frame/viewport.py)
        drawn by `ui`; `window()` gives the renderer's window target (its size bounds the image)."""
        self.viewport, self.viewport_ui = viewport, (ui, window)

    def show_shadow_maps(self, renderer: Renderer, overlay: ImGuiRenderer) -> None:
        """Show the shadow maps of `renderer` (render/frame/renderer.py's Renderer) in the light sections,
        drawn by `overlay` (the ImGuiRenderer that draws this editor)."""
        self.shadow_maps = ShadowMapImages(renderer.shadows, overlay)
        self.meshes = renderer.meshes

    # ---------------------------------------------------------------- requests
    def take_requests(self) -> Settings | None:
        """Settings the user changed since the last call (the loop applies them), or None."""
        if self.requested == self.settings:
            return None
        self.settings = replace(self.requested)
        return replace(self.requested)

    def in_force(self, settings: Settings) -> None:
        """What the session runs with after applying the requests (it may have refused some)."""
        self.settings = replace(settings)
        self.requested = replace(settings)

    def refused(self, message: str) -> None:
        self.settings_status = message

    def forget_world(self) -> None:
        """A new scene: its ids name other entities, so nothing stays selected or cached."""
        self.selected = None
        self.status, self.status_entity = "", None
        self.browser.key = None
        self.materials = MaterialsPanel()
        self.history.forget()
        self.tree = HierarchyPanel()

    # -------------------------------------------------------------------- draw
    def draw(self, world: World, stats: SceneStats) -> None:
        """Build this frame's editor windows (between imgui.new_frame() and imgui.render())."""
        imgui = self.imgui
        self.files.draw(imgui, world, self)  # the menu bar first: the dock space fits under it
        self.dock.begin()
        if self.shadow_maps is not None:
            self.shadow_maps.begin_frame()
        self._settings_window(world, stats)
        imgui.set_next_window_pos((10, 330), imgui.Cond_.first_use_ever.value)
        imgui.set_next_window_size((300, 300), imgui.Cond_.first_use_ever.value)
        if imgui.begin("Entities")[0]:
            self._browser(world)
        imgui.end()
        if imgui.begin("Hierarchy")[0]:
            self.tree.draw(imgui, world, self)
        imgui.end()
        imgui.set_next_window_pos((320, 330), imgui.Cond_.first_use_ever.value)
        imgui.set_next_window_size((340, 300), imgui.Cond_.first_use_ever.value)
        if imgui.begin("Inspector")[0] and imgui.begin_tab_bar("inspector tabs"):
            for name, draw in (("Entity", self._inspector), ("Materials", self._materials)):
                flags = imgui.TabItemFlags_.set_selected.value if self.open_tab == name else 0
                if imgui.begin_tab_item(name, None, flags)[0]:
                    draw(world)
                    imgui.end_tab_item()
            self.open_tab = None
            imgui.end_tab_bar()
        imgui.end()
        self.physics.draw(imgui, world)
        self.audio.draw(imgui, world)
        self.animated = self.animation.draw(imgui, world, self.selected)
        self._scene_input(world)

    def _scene_input(self, world: World) -> None:
        scene_input(self, world)  # editor_viewport.py

    def _settings_window(self, world: World, stats: SceneStats) -> None:
        imgui = self.imgui
        req = self.requested
        imgui.set_next_window_pos((10, 10), imgui.Cond_.first_use_ever.value)
        imgui.set_next_window_size((300, 310), imgui.Cond_.first_use_ever.value)
        if imgui.begin("Scene and render")[0]:
            push_label_room(imgui, SETTINGS_LABELS)
            req.scene = _combo(imgui, "scene", req.scene, self.scenes)
            # the lists are the render configuration's names; a control shows where it applies
            req.mode = _combo(imgui, "mode", req.mode, _names("mode"))
            config = RenderConfig.from_strings(mode=req.mode)
            if applies("recorder", config):
                req.recorder = _combo(imgui, "recorder", req.recorder, _names("recorder"))
            _, req.threads = imgui.slider_int("threads", req.threads, 1, max(1, self.max_threads))
            req.culling = _combo(imgui, "culling", req.culling, _names("culling"))
            if applies("lod", config):
                _, req.lod = imgui.checkbox("levels of detail", req.lod)
            req.fill = _combo(imgui, "fill", req.fill, _names("fill"))
            req.tone_map = _combo(imgui, "tone map", req.tone_map, _names("tone_map"))
            _, req.exposure = imgui.slider_float("exposure (EV)", req.exposure, -8.0, 8.0)
            req.light_culling = _combo(imgui, "light culling", req.light_culling, _names("light_culling"))
            req.transparency = _combo(imgui, "transparency", req.transparency, _names("transparency"))
            imgui.begin_disabled(not self.ray_tracing)  # greyed out where the device cannot trace rays
            req.shadow_method = _combo(imgui, "shadows", req.shadow_method, _names("shadows"))
            imgui.end_disabled()
            if not self.ray_tracing and imgui.is_item_hovered(imgui.HoveredFlags_.allow_when_disabled.value):
                imgui.set_tooltip("ray-traced shadows need a GPU with ray-tracing pipelines")
            if applies("shadow_denoise", config.replace(shadows=req.shadow_method)):
                _, req.shadow_denoise = imgui.checkbox("denoise soft shadows", req.shadow_denoise)
            if req.present is not None:
                req.present = _combo(imgui, "present", req.present, PRESENT_MODES)
            req.post = post_toggles(imgui, req.post, self._remember)  # one per registered effect (editor_post.py)
            self._environment(world)
            imgui.pop_item_width()
            imgui.separator()
            imgui.text(f"entities   {stats.entities:,}")
            imgui.text(f"visible    {stats.visible:,}")
            imgui.text(f"draws      {stats.draws:,}")
            imgui.text(f"triangles  {stats.triangles:,}")
            if self.settings_status:
                wrapped_colored(imgui, (1.0, 0.4, 0.3, 1.0), self.settings_status)
        imgui.end()

    def _environment(self, world: World) -> None:
        """The world's Environment, when it has one: its intensity, sky and image-based ambient
        (a new Environment object; the renderer keeps the image, whose source is the same)."""
        env = world.resources.get(Environment)
        if env is None:
            return
        imgui = self.imgui
        imgui.separator()
        changed, intensity = imgui.slider_float("environment", env.intensity, 0.0, 8.0)
        sky_changed, sky = imgui.checkbox("sky", env.sky)
        self._remember("sky")
        ambient_changed, ambient = imgui.checkbox("image-based ambient", env.ambient)
        if changed or sky_changed or ambient_changed:
            world.resources[Environment] = replace(env, intensity=max(intensity, 0.0), sky=sky, ambient=ambient)

    # --------------------------------------------------------------- inspector
    def _inspector(self, world: World) -> None:
        imgui = self.imgui
        eid = self.selected if self.selected is not None and world.is_alive(self.selected) else None
        if imgui.button("add cube"):
            self.selected = self.add_cube(world)
        self._remember("add cube")
        same_line_if_fits(imgui, button_width(imgui, "add light"))
        if imgui.button("add light"):
            self.selected = self.add_light(world)
        if eid is not None:
            same_line_if_fits(imgui, button_width(imgui, "destroy"))
            if imgui.button("destroy"):
                world.destroy(eid)
                self.selected = eid = None
        if imgui.button("undo"):
            self.history.undo(world)
        self._remember("undo")
        imgui.same_line()
        if imgui.button("redo"):
            self.history.redo(world)
        for k, operation in enumerate(OPERATIONS):  # the gizmo's (W, E, R in the scene), a row of their own
            if k:
                same_line_if_fits(imgui, radio_width(imgui, operation))
            if imgui.radio_button(operation, self.gizmo.operation == operation):
                self.gizmo.operation = operation
            self._remember(operation)
        if self.history.status:
            wrapped_colored(imgui, (1.0, 0.7, 0.3, 1.0), self.history.status)
        if eid is None:
            imgui.text("select an entity")
            return
        if self.status_entity != eid:
            self.status = ""  # an error about another entity
        imgui.text(f"entity {eid & 0xFFFFFFFF} (gen {eid >> 32})")
        push_label_room(imgui, ENTITY_LABELS + LIGHT_LABELS + MESH_LABELS + SOURCE_LABELS)
        if Name in world.components(eid):
            changed, name = imgui.input_text("name", str(world.get(eid, Name).value))
            if changed:
                self.set(world, eid, Name, value=name)
        types = world.components(eid)
        imgui.text_wrapped(", ".join(t.__name__ for t in types))
        try:
            if Transform in types:
                self._transform(world, eid)
            if Mesh in types:
                mesh_section(self, world, eid)
            for light, section in LIGHT_SECTIONS.items():
                if light in types:
                    section(self, world, eid)
            if Camera in types:
                self._camera(world, eid)
            if AudioSource in types:
                source_section(self, world, eid)
        except ValueError as exc:  # the world's checks (e.g. near >= far): keep the old value
            self.status, self.status_entity = str(exc), eid
        imgui.pop_item_width()
        if self.status:
            wrapped_colored(imgui, (1.0, 0.4, 0.3, 1.0), self.status)

    def _materials(self, world: World) -> None:
        self.materials.draw(self.imgui, world)

    def show_material(self, handle: int) -> None:
        """Select a material and bring the Materials tab forward."""
        self.materials.selected, self.materials.status = handle, ""
        self.open_tab = "Materials"

    def _transform(self, world: World, eid: int) -> None:
        imgui = self.imgui
        t = world.get(eid, Transform)
        imgui.separator_text("Transform")
        changed, pos = imgui.drag_float3("position", [float(v) for v in t.position], 0.05)
        self._remember("position")
        if changed:
            self.set(world, eid, Transform, position=np.array(pos, dtype=np.float64))
        angles = [math.degrees(a) for a in yaw_pitch_roll(t.rotation)]
        changed, angles = imgui.drag_float3("rotation (deg)", angles, 0.5)
        hint(imgui, "yaw, pitch and roll in degrees")
        if changed:
            q = yaw_pitch_roll_quat(*(math.radians(a) for a in angles))
            self.set(world, eid, Transform, rotation=q)
        changed, scale = imgui.drag_float3("scale", [float(v) for v in t.scale], 0.01)
        if changed:
            self.set(world, eid, Transform, scale=np.array(scale, dtype=np.float64))

    def _camera(self, world: World, eid: int) -> None:
        imgui = self.imgui
        cam = world.get(eid, Camera)
        imgui.separator_text("Camera")
        changed, fov = imgui.slider_float("fov (deg)", math.degrees(float(cam.fov_y)), 5.0, 150.0)
        if changed:
            self.set(world, eid, Camera, fov_y=math.radians(fov))
        changed, near = imgui.drag_float("near", float(cam.near), 0.001, 1e-4, 1e6, "%.4f")
        if changed:
            self.set(world, eid, Camera, near=max(near, 1e-4))
        infinite = math.isinf(float(cam.far))
        changed, infinite_now = imgui.checkbox("infinite far plane", infinite)
        if changed:
            self.set(world, eid, Camera, far=math.inf if infinite_now else max(1000.0, float(cam.near) * 10))
        if not infinite_now:
            changed, far = imgui.drag_float("far", float(cam.far), 1.0, 0.0, 1e9)
            if changed:
                self.set(world, eid, Camera, far=far)

    def _remember(self, name: str) -> None:
        lo, hi = self.imgui.get_item_rect_min(), self.imgui.get_item_rect_max()
        self.rects[name] = (lo.x, lo.y, hi.x, hi.y)

    def set(self, world: World, eid: int, component: type, **fields: Any) -> None:
        """One undoable edit through the World API (a drag of one widget is one step); a rejected
        value leaves the component as it was."""
        imgui = self.imgui
        if imgui.is_item_active():  # a drag or slider held: its edits join one step
            self.history.begin(("widget", imgui.get_item_id(), eid, component), world, eid, component)
        else:
            self.history.end()
        try:
            self.history.set(world, eid, component, **fields)
            self.status = ""
        except ValueError as exc:
            self.status, self.status_entity = str(exc), eid

    # -------------------------------------------------------- add entities
    def _in_front(self, world: World, distance: float = 4.0) -> np.ndarray:
        try:
            cam = world.get(active_camera(world), Transform)
        except Exception:
            return np.zeros(3)
        from ..maths.camera import rotation_matrix

        forward = rotation_matrix(cam.rotation)[:3, :3] @ np.array([0.0, 0.0, -1.0])
        return np.asarray(cam.position, dtype=np.float64) + forward * distance

    def add_cube(self, world: World) -> int:
        handle = 0
        for table in world.tables:  # the mesh most entities use (the scene's first mesh)
            if Mesh in table.type_set and table.count:
                handle = int(table.columns[(Mesh, "handle")][0]) if (Mesh, "handle") in table.columns else 0
                break
        return world.spawn(Transform(position=self._in_front(world)), Mesh(handle=handle))

    def add_light(self, world: World) -> int:
        return world.spawn(
            Transform(position=self._in_front(world, 2.0)), PointLight(color=(1.0, 0.9, 0.7), intensity=5.0, radius=0.0)
        )


def _names(field: str) -> tuple[str, ...]:
    """A render setting's choices (render/config/__init__.py's enum of `field`)."""
    return CHOICES[field][0].names()


def _combo(imgui: Any, label: str, value: str, choices: tuple[str, ...]) -> str:
    index = choices.index(value) if value in choices else 0
    _, index = imgui.combo(label, index, list(choices))
    return choices[index]
