"""The extract stage is the only render code that reads the World: a scan of every
module under ecs_engine/render for what reads a world, which must find nothing outside the extract
modules but the commented allow-list below; and the snapshot it makes (FrameData) carries what the
shadow, ray and environment passes take, following the world from frame to frame.

A read is: importing World (ecs.world) or a run condition over one (ecs.schedule); an attribute of
a name `world`; `.resources`, `.query(...)` or `.change_stamp(...)` on anything; or a call of a
function that reads one (the extract functions, render_origin, active_camera)."""

from __future__ import annotations

import ast
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

import ecs_engine.render
from ecs_engine import World
from ecs_engine.components import Camera, DirectionalLight, Mesh, PointLight, Shadow, SpotLight, Transform
from ecs_engine.components.environment import Environment
from ecs_engine.ecs.errors import AccessError
from ecs_engine.ecs.schedule import Schedule, system
from ecs_engine.maths.camera import look_rotation
from ecs_engine.render.assets.materials import Material, Materials, materials
from ecs_engine.render.extract.frame_data import FrameExtractor
from ecs_engine.render.raytracing.shadows import ray_lights
from ecs_engine.render.shadows.views import shadow_views

RENDER = Path(ecs_engine.render.__file__).parent
# the extract stage: what FrameExtractor is made of
EXTRACT = {
    # temporal culling's masks are decided while extracting (FrameData.masks), from the tables'
    # ModelMatrix and Mesh columns and ticks: the machinery (temporal_culling.py) and its culling
    # method (culling/temporal.py, whose `masks` FrameExtractor.extract calls), reached through
    # extraction alone (checked below)
    "culling/temporal_culling.py",
    "culling/temporal.py",
}
# category (b): modules that take a World outside the frame, per module the scopes ("<module>":
# its imports; else a function or Class.method) allowed to, and why
ALLOWED: dict[str, set[str] | None] = {
    # scene files: the codecs World.save and World.load call with the world being saved or
    # loaded (its Materials, Meshes and Environment resources), never while a frame is drawn
    "assets/scene_assets.py": None,
    "assets/scene_meshes.py": None,  # the meshes' codec, apart from scene_assets.py for size
    # a glTF scene spawned into a world as entities (a prefab) and its clips added to the world's
    # AnimationClips (its skins to its Skins), by a game's set-up or systems, never while a frame is drawn
    "assets/gltf/scene.py": {"GltfScene.spawn_many", "GltfScene._registered", "GltfScene._skins"},
    # the app's and editor's question "which entity is under this pixel", asked between frames
    # with the world in hand (a ray from the active camera against the rows' spheres)
    "picking.py": None,
    # materials(world): the set-up helper apps add materials with, making the resource on first
    # use; frames read the resource through extract/materials.py
    "assets/materials.py": {"<module>", "materials"},
    # Renderer.render(world, ...) takes the world and hands it to the extract stage (its
    # `materials` and `extract` methods) before anything else; the passes get the snapshot
    "frame/renderer.py": {"<module>", "Renderer.materials"},
}
# functions that read a world handed to them (a call of one outside the extract stage is a read)
READERS = {
    "camera_matrices",
    "extract_camera",
    "extract_lights",
    "extract_shadow_casters",
    "extract_environment",
    "extract_materials",
    "render_origin",
    "active_camera",
    "any_with",
}


class _Scan(ast.NodeVisitor):
    def __init__(self) -> None:
        self.scope: list[str] = []
        self.found: list[tuple[str, int, str]] = []  # (scope, line, what)

    def _add(self, node: ast.AST, what: str) -> None:
        self.found.append((".".join(self.scope) or "<module>", getattr(node, "lineno", 0), what))

    def _scoped(self, node: ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef) -> None:
        self.scope.append(node.name)
        self.generic_visit(node)
        self.scope.pop()

    visit_ClassDef = visit_FunctionDef = visit_AsyncFunctionDef = _scoped

    def visit_ImportFrom(self, node: ast.ImportFrom) -> None:
        module = node.module or ""
        if module.endswith(("ecs.world", "ecs.schedule")) or any(a.name == "World" for a in node.names):
            self._add(node, f"imports {module}")
        self.generic_visit(node)

    def visit_Import(self, node: ast.Import) -> None:
        for alias in node.names:
            if alias.name.endswith(("ecs.world", "ecs.schedule")):
                self._add(node, f"imports {alias.name}")

    def visit_Attribute(self, node: ast.Attribute) -> None:
        value = node.value
        if isinstance(value, ast.Name) and value.id == "world":
            self._add(node, f"world.{node.attr}")
        elif node.attr == "resources" and not (isinstance(value, ast.Name) and value.id == "importlib"):
            self._add(node, ".resources")
        self.generic_visit(node)

    def visit_Call(self, node: ast.Call) -> None:
        func = node.func
        if isinstance(func, ast.Attribute) and func.attr in ("query", "change_stamp"):
            self._add(node, f".{func.attr}(...)")
        name = func.id if isinstance(func, ast.Name) else func.attr if isinstance(func, ast.Attribute) else ""
        if name in READERS:
            self._add(node, f"{name}(...)")
        self.generic_visit(node)


def world_reads(source: str) -> list[tuple[str, int, str]]:
    scan = _Scan()
    scan.visit(ast.parse(source))
    return scan.found


# packages that never see a World: they import nothing of the ECS or its components (checked
# below, a stronger rule than the scan, whose `.resources` would also match the graph's own)
WORLDLESS = ("graph",)


def render_modules() -> dict[str, str]:
    """Every module under render/ outside extract/ and the world-less packages, by its path
    relative to render/."""
    return {
        path.relative_to(RENDER).as_posix(): path.read_text()
        for path in sorted(RENDER.rglob("*.py"))
        if path.relative_to(RENDER).parts[0] not in ("extract", *WORLDLESS)
    }


def test_the_frame_graph_imports_nothing_of_the_ecs() -> None:
    for package in WORLDLESS:
        paths = sorted((RENDER / package).rglob("*.py"))
        assert paths, package
        for path in paths:
            for node in ast.walk(ast.parse(path.read_text())):
                if isinstance(node, ast.ImportFrom):
                    module = "." * node.level + (node.module or "")
                    assert not module.lstrip(".").startswith(("ecs", "components", "app")), (path, module)
                    assert "World" not in {a.name for a in node.names}, path


def test_the_scan_finds_each_kind_of_read() -> None:
    """The scan is not blind: each form of a read is found, with its scope."""
    source = """
from ..ecs.world import World
from ..ecs.schedule import any_with
from .camera import camera_matrices
class Pass:
    def plan(self, world, data):
        return world.get(1, Transform)
def sync(env, w):
    return w.resources.get(env), w.query(A, write=()), w.change_stamp(1, A)
def other(w):
    return camera_matrices(w, 1.0)
import importlib.resources
"""
    found = world_reads(source)
    assert {(scope, what) for scope, _, what in found} == {
        ("<module>", "imports ecs.world"),
        ("<module>", "imports ecs.schedule"),
        ("Pass.plan", "world.get"),
        ("sync", ".resources"),
        ("sync", ".query(...)"),
        ("sync", ".change_stamp(...)"),
        ("other", "camera_matrices(...)"),
    }


def test_no_render_module_reads_the_world_outside_the_extract_stage() -> None:
    modules = render_modules()
    wrong = []
    for name, source in modules.items():
        if name in EXTRACT:
            continue
        allowed = ALLOWED.get(name, set())
        for scope, line, what in world_reads(source):
            if allowed is not None and scope not in allowed:
                wrong.append(f"render/{name}:{line} ({scope}): {what}")
    assert not wrong, "read the World outside the extract stage (render/extract/):\n" + "\n".join(wrong)


def test_the_allow_list_and_the_extract_set_are_still_needed() -> None:
    """Every allowed module and scope still reads the world (else it leaves the list), and the
    extract modules do (else the scan no longer sees what they read)."""
    modules = render_modules()
    for name, scopes in ALLOWED.items():
        found = {scope for scope, _, _ in world_reads(modules[name])}
        assert found, f"render/{name} reads no world: take it off ALLOWED"
        assert scopes is None or scopes <= found, f"render/{name}: {scopes - found} read no world"
    for name in EXTRACT:
        assert world_reads(modules[name]), name
    for path in (RENDER / "extract").glob("*.py"):
        if path.name != "__init__.py":
            assert world_reads(path.read_text()), path.name


def test_temporal_culling_is_reached_through_extraction_only() -> None:
    importers = [
        name
        for name, source in render_modules().items()
        if "temporal_culling" in source and name not in ("extract/frame_data.py", *EXTRACT)
        for node in ast.walk(ast.parse(source))
        if isinstance(node, ast.ImportFrom) and (node.module or "").endswith("temporal_culling")
    ]
    assert importers == []
    # a culling method's `masks` (render/culling/) is handed the world: called by the extract stage alone
    callers = [
        name
        for name, source in render_modules().items()
        for node in ast.walk(ast.parse(source))
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "masks"
    ]
    assert callers and set(callers) <= EXTRACT, callers


def _scene() -> tuple[World, dict[str, int]]:
    world = World()
    world.spawn(Camera(), Transform(position=(0.0, 2.0, 8.0), rotation=look_rotation((0.0, -2.0, -8.0))))
    down = look_rotation((0.3, -1.0, -0.2))
    ids = {
        "sun": world.spawn(DirectionalLight(), Transform(rotation=down), Shadow(cascades=2, resolution=256)),
        "spot": world.spawn(
            SpotLight(radius=20.0), Transform(position=(2.0, 5.0, 0.0), rotation=down), Shadow(resolution=128)
        ),
        "lamp": world.spawn(PointLight(radius=10.0), Transform(position=(-2.0, 3.0, 1.0)), Shadow(resolution=64)),
    }
    return world, ids


def test_the_snapshot_follows_the_world_between_frames() -> None:
    """The shadow views, the traced lights, the environment and the materials come from the
    frame's snapshot; a change in the world shows in the next frame's, and only then."""
    world, ids = _scene()
    extractor = FrameExtractor(lambda: 1)

    def frame() -> object:
        return extractor.extract(world, 4 / 3, 1, "frustum")

    first = frame()
    assert first.shadows is not None and frame().shadows is first.shadows  # unchanged: kept
    views = shadow_views(first.shadows, first.camera, first.origin)
    assert [(v.entity, v.kind) for v in views] == [(ids["sun"], "cascade")] * 2 + [(ids["spot"], "spot")] + [
        (ids["lamp"], "cube")
    ] * 6
    lights = ray_lights(first.shadows, first.origin)
    assert [light.entity for light in lights] == [ids["sun"], ids["spot"], ids["lamp"]]

    world.set(ids["lamp"], Transform(position=(4.0, 3.0, 1.0)))
    world.set(ids["spot"], Shadow(resolution=512))
    moved = frame()
    assert moved.shadows is not first.shadows
    np.testing.assert_array_equal(first.shadows.point[0].position[0], (-2.0, 3.0, 1.0))  # a copy: as it was
    after = shadow_views(moved.shadows, moved.camera, moved.origin)
    assert after[2].resolution == 512 and views[2].resolution == 128
    lamp = ray_lights(moved.shadows, moved.origin)[2]
    np.testing.assert_allclose(lamp.position, np.array([4.0, 3.0, 1.0]) - moved.origin)

    world.remove(ids["sun"], Shadow)
    world.remove(ids["spot"], Shadow)
    world.remove(ids["lamp"], Shadow)
    assert frame().shadows is None and shadow_views(None, moved.camera, moved.origin) == []

    assert moved.environment is None
    sky = Environment(source="sky")
    world.resources[Environment] = sky
    assert frame().environment is sky

    default = frame().materials
    assert default is not None and len(default) >= 1  # a world without Materials: a default palette
    assert frame().materials is default
    library = materials(world)
    library.add(Material("red", base_color=(1.0, 0.0, 0.0, 1.0)))
    assert frame().materials is library


@pytest.mark.parametrize("given", [True, False])
def test_the_renderer_s_materials_are_the_snapshot_s(given: bool) -> None:
    """FrameExtractor.extract keeps the Materials it is given (Renderer.extract passes its own)."""
    world, _ = _scene()
    library = materials(world)
    data = FrameExtractor(lambda: 1).extract(world, 1.0, 1, "none", materials=library if given else None)
    assert data.materials is library


def _extract_systems() -> list[tuple[str, tuple[type, ...], Callable[[World], object]]]:
    from ecs_engine.render.extract import camera, chunks, environment, lights, shadows, views
    from ecs_engine.render.extract import materials as materials_extract

    rows = chunks.ChunkExtract(lambda: 1)
    return [
        ("camera", camera.READS, lambda w: camera.camera_matrices(w, 1.5)),
        ("views", views.READS, lambda w: views.extract_views(w, 64, 32)),
        ("lights", lights.READS, lambda w: lights.extract_lights(w, lights.light_kinds())),
        ("shadows", shadows.READS, shadows.ShadowExtract()),
        ("environment", environment.READS, environment.extract_environment),
        ("materials", materials_extract.READS, lambda w: materials_extract.extract_materials(w, Materials())),
        ("chunks", chunks.READS, lambda w: rows.chunks(w, 1)),
    ]


@pytest.mark.parametrize("index", range(7))
def test_each_extract_function_runs_as_a_system_reading_what_it_declares(index: int) -> None:
    """Each extract function run by a system declaring its module's READS (a query or get of
    anything else fails there): what the parallel schedule needs to run them side by side."""
    name, reads, extract = _extract_systems()[index]
    world, _ = _scene()
    world.spawn(Transform(), Mesh(handle=0))
    world.resources[Environment] = Environment(source="sky")
    materials(world)
    out: list[object] = []
    schedule = Schedule()
    schedule.add(system(reads=reads, name=f"extract_{name}")(lambda w, dt: out.append(extract(w))))
    schedule.run(world, 0.0)
    assert out and out[0] is not None

    if len(reads) > 1:  # the check holds: without one of the components, the system fails
        narrow = Schedule()
        narrow.add(system(reads=reads[1:], name=f"narrow_{name}")(lambda w, dt: extract(w)))
        with pytest.raises(AccessError, match="does not declare"):
            narrow.run(world, 0.0)
