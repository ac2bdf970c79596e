"""A glTF scene as a prefab: its node tree read once (meshes uploaded, materials added), then
spawned as entities as many times as wanted, each node an entity with its Transform and a
Parent, so the hierarchy's TransformSystem places it. A node's mesh is a Mesh on it (one
primitive) or on a child entity per primitive; its camera is a Camera, its KHR_lights_punctual
light a PointLight, SpotLight or DirectionalLight (both look down their local -Z, as the
engine's do).

    scene = load_gltf(path, meshes.add, materials(world))
    root = scene.spawn(world, Transform(position=(0, 0, 5)))   # entities: scene.entities(...)
    roots = scene.spawn_many(world, 1000, positions)           # one root a copy, node by node in bulk
"""

from __future__ import annotations

import math
import os
import weakref
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ....animation import AnimationClips, target_id
from ....animation.skins import Skins
from ....components import Camera, DirectionalLight, Mesh, Name, Parent, PointLight, SpotLight, Transform
from ....components.animation import AnimationPlayer, AnimationTarget, MorphWeights, Skinned
from ....components.camera import ORTHOGRAPHIC, PERSPECTIVE
from ....errors import UsageError
from ....maths.decompose import decompose, trs_matrices
from ..materials import Materials
from ..mesh_data import MeshData
from .clips import Clip, animation_clip, read_clips
from .document import GltfDocument
from .meshes import GltfMaterials, primitive_mesh
from .skins import GltfSkin, bind, read_skin

__all__ = ["GltfNode", "GltfScene", "load_gltf"]

LIGHTS = "KHR_lights_punctual"
DEFAULT_RANGE = 100.0  # m: a light without `range` (infinite in glTF) reaches this far here


@dataclass
class GltfNode:
    """One node: its glTF index and name, its parent's place in GltfScene.nodes (-1: a root of the
    scene), its local TRS, its primitives' (mesh, material) handles and its camera or light."""

    index: int
    name: str
    parent: int
    translation: np.ndarray
    rotation: np.ndarray
    scale: np.ndarray
    parts: list[tuple[int, int]] = field(default_factory=list)
    components: list[Any] = field(default_factory=list)  # a Camera or a light
    path: str = ""  # its names from the scene's root node ("Armature/Hips"): what clips bind to
    skin: int = -1  # its mesh's skin: a place in GltfScene.skins (-1: none)
    spheres: list[tuple[np.ndarray, float]] = field(default_factory=list)  # per part, its mesh's (centre, radius)
    morphs: list[np.ndarray | None] = field(default_factory=list)  # per part, its morph weights at rest (or None)


@dataclass
class GltfScene:
    file: Path
    document: GltfDocument
    nodes: list[GltfNode]  # parents before children
    clips: list[Clip] = field(default_factory=list)  # the file's animations (clips.py)
    skins: list[GltfSkin] = field(default_factory=list)  # the skins its nodes use (skins.py)
    # the clips' handles in each world's AnimationClips they were added to; the skins' in its Skins
    _handles: weakref.WeakKeyDictionary[AnimationClips, list[int]] = field(default_factory=weakref.WeakKeyDictionary)
    _skin_handles: weakref.WeakKeyDictionary[Skins, list[int]] = field(default_factory=weakref.WeakKeyDictionary)

    def spawn(self, world: Any, at: Transform | None = None, play: str | int | None = None) -> int:
        """One copy: a root entity (named after the file, placed `at`) whose children are the
        scene's root nodes; `play`: a clip (name or index) it plays, looping. The root entity."""
        place = at if at is not None else Transform()
        p, r, s = (np.asarray(v, np.float64)[None] for v in (place.position, place.rotation, place.scale))
        return int(self.spawn_many(world, 1, p, r, s, play)[0])

    def spawn_many(
        self, world: Any, count: int, positions: Any, rotations: Any = None, scales: Any = None,
        play: str | int | None = None,
    ) -> np.ndarray:  # fmt: skip
        """`count` copies, their roots at `positions` (and `rotations`, `scales`): each node is
        one spawn_batch over the copies. With clips, each root has an AnimationPlayer (playing
        `play`, or no clip) and each node an AnimationTarget. The roots' entities."""
        position = np.broadcast_to(np.asarray(positions, np.float64), (count, 3))
        rotation = np.broadcast_to(np.asarray((0, 0, 0, 1) if rotations is None else rotations, np.float64), (count, 4))
        scale = np.broadcast_to(np.asarray((1, 1, 1) if scales is None else scales, np.float64), (count, 3))
        place = Transform(position=position, rotation=rotation, scale=scale)
        player: list[Any] = []
        if self.clips:
            player = [AnimationPlayer(clip=self._clip(world, play), playing=play is not None)]
        roots = world.spawn_batch(count, place, Name(value=self.file.stem), *player)
        skins, handles = self._skins(world)
        # each skin's copies made here: numbered from its copies so far (joints added below)
        copies = [np.arange(skins[h].copies, skins[h].copies + count) for h in handles]
        made: list[np.ndarray] = []
        for node in self.nodes:
            parent = roots if node.parent < 0 else made[node.parent]
            here = Transform(position=node.translation, rotation=node.rotation, scale=node.scale)
            values: list[Any] = [here, Parent(entity=parent), Name(value=node.name)]
            values += node.components
            if player:
                values.append(AnimationTarget(player=roots, id=target_id(node.path)))
            skin = [] if node.skin < 0 else [Skinned(skin=handles[node.skin], copy=copies[node.skin])]
            if len(node.parts) == 1:
                values += [Mesh(handle=node.parts[0][0], material=node.parts[0][1]), *_bound(skin, node.spheres[0])]
                values += _morph(node.morphs[0])
            elif any(m is not None for m in node.morphs):  # the weights its channel animates (its parts take them)
                values += _morph(next(m for m in node.morphs if m is not None))
            ids = world.spawn_batch(count, *values)
            made.append(ids)
            if len(node.parts) > 1:
                for (handle, material), sphere, morph in zip(node.parts, node.spheres, node.morphs, strict=True):
                    part = [Transform(), Parent(entity=ids), Mesh(handle=handle, material=material)]
                    world.spawn_batch(count, *part, *_bound(skin, sphere), *_morph(morph))
        for h, s in zip(handles, self.skins, strict=True):
            skins.add_copies(h, np.stack([made[j] for j in s.joints], axis=1))
        return roots

    def _skins(self, world: Any) -> tuple[Skins, list[int]]:
        """The world's Skins, and this scene's skins' handles in it (added once a world)."""
        skins = world.resources.setdefault(Skins, Skins())
        if skins not in self._skin_handles:
            self._skin_handles[skins] = [skins.add(s.name, s.inverse_binds, s.reach) for s in self.skins]
        return skins, self._skin_handles[skins]

    def _clip(self, world: Any, play: str | int | None) -> int:
        """The handle of clip `play` (its name, or its index in the file); -1 for None."""
        handles = self._registered(world)
        names = [clip.name for clip in self.clips]
        if play is None:
            return -1
        if isinstance(play, str) and play in names:
            return handles[names.index(play)]
        if isinstance(play, int) and not isinstance(play, bool) and 0 <= play < len(handles):
            return handles[play]
        raise UsageError(f"{self.file}: has no clip {play!r} (its clips: {', '.join(names) or 'none'})")

    def clip_handles(self, world: Any) -> dict[str, int]:
        """The scene's clips added to the world's AnimationClips (once a world): handle by name."""
        return {clip.name: h for clip, h in zip(self.clips, self._registered(world))}

    def _registered(self, world: Any) -> list[int]:
        clips = world.resources.setdefault(AnimationClips, AnimationClips())
        if clips not in self._handles:
            paths = {node.index: node.path for node in self.nodes}
            self._handles[clips] = [clips.add(animation_clip(clip, paths)) for clip in self.clips]
        return self._handles[clips]


def load_gltf(
    path: str | os.PathLike[str], add_mesh: Callable[[MeshData], int], registry: Materials, scene: int | None = None
) -> GltfScene:
    """The file's scene `scene` (default: the file's `scene`, else its first), its meshes added
    with `add_mesh` (render.Meshes.add) and its materials to `registry` (a primitive without one
    gets material 0). GltfError naming the file and field for anything the specification forbids."""
    document = GltfDocument.read(path)
    scenes = document.items("scenes")
    if scene is None:
        scene = document.json.get("scene", 0) if scenes else None
    roots: list[int]
    if scene is None:  # no scenes: every node that is nobody's child
        children = {c for n in document.items("nodes") if isinstance(n, dict) for c in n.get("children", [])}
        roots = [i for i in range(len(document.items("nodes"))) if i not in children]
    else:
        roots = list(document.item("scenes", scene, "scene").get("nodes", []))
    reader = _Reader(document, add_mesh, registry)
    nodes = reader.tree(roots)
    return GltfScene(document.file, document, nodes, read_clips(document), reader.skins(nodes))


class _Reader:
    def __init__(self, document: GltfDocument, add_mesh: Callable[[MeshData], int], registry: Materials) -> None:
        self.d, self.add_mesh = document, add_mesh
        self.materials = GltfMaterials(document, registry)
        self.meshes: dict[int, list[tuple[int, int]]] = {}
        self.data: dict[int, MeshData] = {}  # by mesh handle: what a skin checks its vertices against
        self.lights = document.json.get("extensions", {}).get(LIGHTS, {}).get("lights", [])

    def tree(self, roots: list[int]) -> list[GltfNode]:
        out: list[GltfNode] = []
        seen: set[int] = set()
        stack = [(r, -1, "scene.nodes") for r in reversed(roots)]
        while stack:
            index, parent, where = stack.pop()
            entry = self.d.item("nodes", index, where)
            if index in seen:
                raise self.d.error(where, f"names node {index} a second time (a node has one parent, no cycles)")
            seen.add(index)
            node = self._node(index, entry, parent)
            node.path = node.name if parent < 0 else f"{out[parent].path}/{node.name}"
            out.append(node)
            children = entry.get("children", [])
            if not isinstance(children, list):
                raise self.d.error(f"nodes[{index}].children", "is not an array")
            here = len(out) - 1
            stack += [(c, here, f"nodes[{index}].children") for c in reversed(children)]
        return out

    def _node(self, index: int, entry: dict[str, Any], parent: int) -> GltfNode:
        here = f"nodes[{index}]"
        if "matrix" in entry:
            if any(k in entry for k in ("translation", "rotation", "scale")):
                raise self.d.error(here, "has both a matrix and translation, rotation or scale")
            t, r, s = node_trs(self.d.floats(entry, "matrix", here, 16, None).reshape(4, 4).T, self.d, f"{here}.matrix")
        else:
            t = self.d.floats(entry, "translation", here, 3, [0, 0, 0])
            r = self.d.floats(entry, "rotation", here, 4, [0, 0, 0, 1])
            s = self.d.floats(entry, "scale", here, 3, [1, 1, 1])
            length = float(np.linalg.norm(r))
            if abs(length - 1.0) > 1e-3:
                raise self.d.error(f"{here}.rotation", f"is {r.tolist()}, not a unit quaternion")
            r = r / length
        node = GltfNode(index, str(entry.get("name", f"node{index}")), parent, t, r, s)
        if "mesh" in entry:
            node.parts = self._mesh(self.d.number(entry, "mesh", here), f"{here}.mesh")
            node.spheres = [(self.data[h].center, self.data[h].radius) for h, _ in node.parts]
            node.morphs = [self._morph_weights(entry, self.data[h], here) for h, _ in node.parts]
        if "skin" in entry:
            if "mesh" not in entry:
                raise self.d.error(f"{here}.skin", "is on a node without a mesh")
            node.skin = self.d.number(entry, "skin", here)  # the file's index, until skins() reads it
        if "camera" in entry:
            node.components.append(self._camera(self.d.number(entry, "camera", here), f"{here}.camera"))
        light = entry.get("extensions", {}).get(LIGHTS) if isinstance(entry.get("extensions"), dict) else None
        if isinstance(light, dict):
            node.components.append(self._light(light.get("light"), f"{here}.extensions.{LIGHTS}.light"))
        return node

    def _morph_weights(self, entry: dict[str, Any], data: MeshData, here: str) -> np.ndarray | None:
        """A part's morph weights at rest: the node's `weights`, else its mesh's (None: no targets)."""
        if data.morph is None:
            return None
        count = data.morph.count
        if "weights" in entry:
            return self.d.floats(entry, "weights", here, count, None)
        return data.morph.weights

    def skins(self, nodes: list[GltfNode]) -> list[GltfSkin]:
        """The skins `nodes` use, read and checked against their meshes; each node's `skin`
        then names its place in the list."""
        places = {node.index: k for k, node in enumerate(nodes)}
        read: dict[int, int] = {}
        out: list[GltfSkin] = []
        for node in nodes:
            if node.skin < 0:
                continue
            here = f"nodes[{node.index}].skin"
            if node.skin not in read:
                read[node.skin] = len(out)
                out.append(read_skin(self.d, node.skin, places, here))
            node.skin = read[node.skin]
            for handle, _ in node.parts:
                bind(self.d, out[node.skin], self.data[handle], here)
        return out

    def _mesh(self, mesh: int, where: str) -> list[tuple[int, int]]:
        if mesh not in self.meshes:
            primitives = self.d.item("meshes", mesh, where).get("primitives")
            if not isinstance(primitives, list) or not primitives:
                raise self.d.error(f"meshes[{mesh}].primitives", "is not a non-empty array")
            parts = []
            for p, primitive in enumerate(primitives):
                if not isinstance(primitive, dict):
                    raise self.d.error(f"meshes[{mesh}].primitives[{p}]", "is not an object")
                data = primitive_mesh(self.d, mesh, p)
                if data is None:
                    continue
                material = self.materials.handle(primitive.get("material"), f"meshes[{mesh}].primitives[{p}].material")
                handle = self.add_mesh(data)
                self.data[handle] = data
                parts.append((handle, 0 if material is None else material))
            self.meshes[mesh] = parts
        return self.meshes[mesh]

    def _camera(self, index: int, where: str) -> Camera:
        c = self.d.item("cameras", index, where)
        here = f"cameras[{index}]"
        kind = c.get("type")
        if kind == "perspective" and isinstance(c.get("perspective"), dict):
            p, at = c["perspective"], f"{here}.perspective"
            fov = self.d.floats(p, "yfov", at, 1, None)[0]
            near = self.d.floats(p, "znear", at, 1, None)[0]
            far = self.d.floats(p, "zfar", at, 1, [math.inf])[0] if "zfar" in p else math.inf
            aspect = self.d.floats(p, "aspectRatio", at, 1, [0.0])[0]
            return Camera(projection=PERSPECTIVE, fov_y=fov, near=near, far=far, aspect=aspect)
        if kind == "orthographic" and isinstance(c.get("orthographic"), dict):
            o, at = c["orthographic"], f"{here}.orthographic"
            ymag = self.d.floats(o, "ymag", at, 1, None)[0]
            near, far = self.d.floats(o, "znear", at, 1, None)[0], self.d.floats(o, "zfar", at, 1, None)[0]
            return Camera(projection=ORTHOGRAPHIC, height=2.0 * abs(ymag), near=max(near, 1e-4), far=far)
        raise self.d.error(f"{here}.type", f"is {kind!r} (with no matching object), not perspective or orthographic")

    def _light(self, index: Any, where: str) -> Any:
        if isinstance(index, bool) or not isinstance(index, int) or not 0 <= index < len(self.lights):
            raise self.d.error(where, f"is {index!r}, not one of the file's {len(self.lights)} lights")
        light, here = self.lights[index], f"extensions.{LIGHTS}.lights[{index}]"
        color = np.clip(self.d.floats(light, "color", here, 3, [1, 1, 1]), 0.0, None)
        intensity = max(float(self.d.floats(light, "intensity", here, 1, [1.0])[0]), 0.0)
        reach = float(self.d.floats(light, "range", here, 1, [DEFAULT_RANGE])[0])
        kind = light.get("type")
        if kind == "directional":
            return DirectionalLight(color=color, illuminance=intensity)
        if kind == "point":
            return PointLight(color=color, intensity=intensity, radius=reach)
        if kind == "spot":
            spot = light.get("spot", {})
            inner = float(self.d.floats(spot, "innerConeAngle", f"{here}.spot", 1, [0.0])[0])
            outer = float(self.d.floats(spot, "outerConeAngle", f"{here}.spot", 1, [math.pi / 4])[0])
            return SpotLight(color=color, intensity=intensity, radius=reach, inner_angle=inner, outer_angle=outer)
        raise self.d.error(f"{here}.type", f"is {kind!r}, not directional, point or spot")


def _morph(weights: np.ndarray | None) -> list[MorphWeights]:
    """A part's MorphWeights (none or one): its weights at rest, padded to eight."""
    if weights is None:
        return []
    return [MorphWeights(weights=np.pad(np.asarray(weights, np.float32), (0, 8 - len(weights))))]


def _bound(skin: list[Skinned], sphere: tuple[np.ndarray, float]) -> list[Skinned]:
    """A part's Skinned (none or one) with its mesh's bind-pose sphere."""
    return [Skinned(skin=s.skin, copy=s.copy, centre=sphere[0], radius=sphere[1]) for s in skin]


def node_trs(matrix: np.ndarray, document: GltfDocument, where: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A node matrix (row-major here) as translation, rotation (x, y, z, w) and scale; GltfError
    when it is not one (a shear, a projection), which a Transform cannot hold."""
    basis = matrix[:3, :3]
    if abs(np.linalg.det(basis)) < 1e-18 or not np.allclose(matrix[3], (0, 0, 0, 1)):
        raise document.error(where, "is not a translation, rotation and scale")
    t, r, s = decompose(matrix)
    if not np.allclose(trs_matrices(t[None], r[None], s[None])[0], matrix, atol=1e-5 * max(1.0, np.abs(matrix).max())):
        raise document.error(where, "has a shear, which a Transform (translation, rotation, scale) cannot hold")
    return t, r, s
