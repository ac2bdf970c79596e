"""The editor's Materials window: the world's materials listed by handle and name, the selected one
edited live (the renderer uploads the table on the next frame), and the inspector's Mesh section
that picks an entity's material. Edits go through `Materials.update`, which checks them: a refused
value leaves the material as it was and the window shows why."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from ..components import Mesh
from ..ecs.world import World
from ..render.assets.materials import ALPHA_MODES, FILLS, SHADING_MODELS, TEXTURE_FIELDS, Material, Materials, materials
from .editor_layout import button_width, hint, push_label_room, same_line_if_fits, wrapped_colored
from .editor_lights import Editor

_ALPHA_EDITABLE = ("opaque", "mask", "blend")
# the fields' labels (the fields leave room for the widest: editor_layout.py); the texture slots
# are named by their field, "metallic roughness" the longest
MATERIAL_LABELS = (
    *("shading model", "base colour", "metallic", "roughness", "shininess", "specular", "emissive"),
    *("alpha mode", "alpha cutoff", "fill"),
)
TEXTURE_LABELS = (*(f.removesuffix("_texture").replace("_", " ") for f in TEXTURE_FIELDS), "normal scale", "occlusion")
MESH_LABELS = ("material",)
assert set(_ALPHA_EDITABLE) <= set(ALPHA_MODES)


@dataclass
class MaterialsPanel:
    selected: int = 0
    status: str = ""
    # screen rectangles of widgets as last drawn (where synthetic input should click)
    rects: dict[str, tuple[float, float, float, float]] = field(default_factory=dict)

    def draw(self, imgui: Any, world: World) -> None:
        library = materials(world)
        if imgui.begin_child("list", (0, 120)):
            for handle, material in enumerate(library):
                clicked, _ = imgui.selectable(f"{handle}: {material.name} ({material.model})", handle == self.selected)
                if clicked:
                    self.selected, self.status = handle, ""
        imgui.end_child()
        if not 0 <= self.selected < len(library):
            self.selected = 0
        push_label_room(imgui, MATERIAL_LABELS)
        self.edit(imgui, library, self.selected)
        imgui.pop_item_width()
        if self.status:
            wrapped_colored(imgui, (1.0, 0.4, 0.3, 1.0), self.status)

    def edit(self, imgui: Any, library: Materials, handle: int) -> None:
        m = library[handle]
        imgui.separator_text(m.name)
        changes: dict[str, Any] = {}
        models = tuple(SHADING_MODELS)
        changed, index = imgui.combo("shading model", models.index(m.model), list(models))
        if changed:
            changes["model"] = models[index]
        changed, color = imgui.color_edit4("base colour", list(m.base_color))
        if changed:
            changes["base_color"] = tuple(color)
        if m.model == "cook_torrance":
            changed, value = imgui.slider_float("metallic", m.metallic, 0.0, 1.0)
            self.rects["metallic"] = _rect(imgui)
            if changed:
                changes["metallic"] = value
        if m.model in ("cook_torrance", "oren_nayar"):
            changed, value = imgui.slider_float("roughness", m.roughness, 0.0, 1.0)
            if changed:
                changes["roughness"] = value
        if m.model in ("phong", "blinn_phong"):
            changed, value = imgui.slider_float(
                "shininess", m.shininess, 1.0, 1024.0, "%.1f", imgui.SliderFlags_.logarithmic.value
            )
            if changed:
                changes["shininess"] = value
            changed, value = imgui.slider_float("specular", m.specular, 0.0, 2.0)
            if changed:
                changes["specular"] = value
        changed, emissive = imgui.color_edit3("emissive", list(m.emissive))
        if changed:
            changes["emissive"] = tuple(emissive)
        alpha = _ALPHA_EDITABLE.index(m.alpha_mode) if m.alpha_mode in _ALPHA_EDITABLE else 0
        changed, alpha = imgui.combo("alpha mode", alpha, list(_ALPHA_EDITABLE))
        if changed:
            changes["alpha_mode"] = _ALPHA_EDITABLE[alpha]
        if m.alpha_mode == "mask":
            changed, value = imgui.slider_float("alpha cutoff", m.alpha_cutoff, 0.0, 1.0)
            if changed:
                changes["alpha_cutoff"] = value
        changed, index = imgui.combo("fill", FILLS.index(m.fill), list(FILLS))
        if changed:
            changes["fill"] = FILLS[index]
        changed, value = imgui.checkbox("double-sided", m.double_sided)
        if changed:
            changes["double_sided"] = value
        changes.update(texture_slots(imgui, library, m))
        if changes:
            self.apply(library, handle, changes)

    def apply(self, library: Materials, handle: int, changes: dict[str, Any]) -> Material | None:
        try:
            material = library.update(handle, **changes)
        except (ValueError, TypeError) as exc:
            self.status = str(exc)
            return None
        self.status = ""
        return material


def texture_slots(imgui: Any, library: Materials, m: Material) -> dict[str, Any]:
    """A combo per texture field (none, or one of the registry's textures by handle and name),
    and the normal scale and occlusion strength where those maps are set."""
    changes: dict[str, Any] = {}
    textures = library.textures
    names = ["none"] + [f"{h}: {textures[h].name}" for h in range(len(textures))]
    used = sum(getattr(m, f) is not None for f in TEXTURE_FIELDS)
    if imgui.tree_node_ex(f"textures ({used})###textures", imgui.TreeNodeFlags_.default_open.value):
        push_label_room(imgui, TEXTURE_LABELS)  # indented: less room than the fields above
        for name in TEXTURE_FIELDS:
            current = getattr(m, name)
            changed, index = imgui.combo(
                name.removesuffix("_texture").replace("_", " "),
                0 if current is None else current + 1,
                names,
            )
            if changed:
                changes[name] = None if index == 0 else index - 1
        if m.normal_texture is not None:
            changed, value = imgui.slider_float("normal scale", m.normal_scale, 0.0, 2.0)
            if changed:
                changes["normal_scale"] = value
        if m.occlusion_texture is not None:
            changed, value = imgui.slider_float("occlusion", m.occlusion_strength, 0.0, 1.0)
            hint(imgui, "the occlusion map's strength")
            if changed:
                changes["occlusion_strength"] = value
        imgui.pop_item_width()
        imgui.tree_pop()
    return changes


def mesh_section(editor: Editor, world: World, eid: int) -> None:
    """The inspector's Mesh section: which material the entity is drawn with."""
    imgui = editor.imgui
    mesh = world.get(eid, Mesh)
    library = materials(world)
    imgui.separator_text("Mesh")
    imgui.text(f"mesh {int(mesh.handle)}")
    names = [f"{h}: {m.name}" for h, m in enumerate(library)]
    current = int(mesh.material) if int(mesh.material) < len(names) else 0
    changed, index = imgui.combo("material", current, names)
    if changed:
        editor.set(world, eid, Mesh, material=index)
    same_line_if_fits(imgui, button_width(imgui, "edit"))
    if imgui.button("edit"):
        editor.show_material(current)


def _rect(imgui: Any) -> tuple[float, float, float, float]:
    lo, hi = imgui.get_item_rect_min(), imgui.get_item_rect_max()
    return (lo.x, lo.y, hi.x, hi.y)
