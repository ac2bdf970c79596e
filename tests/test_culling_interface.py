"""Culling methods are one interface (render/culling/): one factory gives each method
for its name, each method's answers to the extract stage, the chunk jobs and the indirect
path's compute are what the old encodings (names compared, an `occlusion` flag, planes None for
no culling, masks for temporal) decided, switching culling goes through it, and no module outside
the config's table and the culling package compares a culling name."""

from __future__ import annotations

import ast
import importlib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from gpu_context import headless_gpu

import ecs_engine
from ecs_engine import World
from ecs_engine.app.scenes import default_schedule
from ecs_engine.components import Mesh, Transform
from ecs_engine.demos.scene_kit import add_camera
from ecs_engine.errors import UsageError
from ecs_engine.maths.culling import bounding_spheres, frustum_planes, spheres_visible
from ecs_engine.render.assets.primitives import cube_mesh
from ecs_engine.render.config import Culling, Mode, RenderConfig, validate
from ecs_engine.render.culling import (
    METHODS,
    CullingSetting,
    FrustumCulling,
    NoCulling,
    OcclusionCulling,
    TemporalCulling,
    check_culling,
    culling_method,
)
from ecs_engine.render.extract.frame_data import FrameExtractor

EXPECTED = {
    Culling.FRUSTUM: FrustumCulling,
    Culling.TEMPORAL: TemporalCulling,
    Culling.OCCLUSION: OcclusionCulling,
    Culling.NONE: NoCulling,
}


def test_the_factory_gives_each_method_for_its_name() -> None:
    assert set(METHODS) == set(Culling)  # every name the config knows has its method
    for name, kind in EXPECTED.items():
        for given in (name, name.value):
            method = culling_method(given)
            assert type(method) is kind and method.name is name
        assert culling_method(name) is not culling_method(name)  # a new one each time: its own state
    assert type(culling_method(True)) is FrustumCulling and type(culling_method(False)) is NoCulling
    with pytest.raises(UsageError, match="unknown culling 'sideways'; choices: frustum, temporal, occlusion, none"):
        culling_method("sideways")


def test_each_method_answers_the_modes_from_the_config_table() -> None:
    for name in Culling:
        method = culling_method(name)
        for mode in Mode:
            reasons = validate(RenderConfig(mode=mode, culling=name), only=("culling",))
            assert method.supports(mode) is (not reasons)
            assert method.refusal(mode) == ("; ".join(reasons) or None)
            if reasons:
                with pytest.raises(UsageError):
                    check_culling(name.value, mode.value)
            else:
                assert check_culling(name.value, mode.value) == name.value
    assert not culling_method("temporal").supports("indirect")  # the GPU culls there
    assert culling_method("occlusion").supports("indirect") and not culling_method("occlusion").supports("instanced")


def scene() -> tuple[World, tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """A row of cubes along x, wider than the view of a camera looking at its middle, and three
    more above it; the bounds of one mesh (a cube's sphere)."""
    world = World()
    world.spawn_batch(41, Transform(position=np.c_[np.arange(41) * 2.0 - 40.0, np.zeros((41, 2))]), Mesh(handle=0))
    world.spawn_batch(3, Transform(position=(0.0, 30.0, 0.0)), Mesh(handle=0))
    add_camera(world, eye=(0.0, 1.0, 10.0), target=(0.0, 0.0, 0.0))
    default_schedule().run(world, 0.0)
    cube = cube_mesh()
    return world, (np.array([cube.center], np.float64), np.array([cube.radius], np.float64), np.array([36]))


def exact(data: Any, bounds: Any, planes: np.ndarray) -> np.ndarray:
    """Per row in chunk order, whether its sphere is inside `planes` (maths/culling.py)."""
    out = []
    for chunk in data.chunks:
        centers, radii = bounding_spheres(chunk.model, bounds[0][chunk.handle], bounds[1][chunk.handle])
        out.append(spheres_visible(centers, radii, planes))
    return np.concatenate(out)


@pytest.mark.parametrize("name", list(Culling))
def test_each_methods_planes_and_masks_are_what_the_old_encodings_decided(name: Culling) -> None:
    """frustum and occlusion: the view's frustum planes for the CPU jobs and no masks; none: no
    planes (every row drawn); temporal: the frustum's planes and masks equal to the exact test."""
    world, bounds = scene()
    method = culling_method(name)
    data = FrameExtractor(lambda: 1, chunk_rows=16).extract(world, 4 / 3, 1, method, dt=1 / 60, bounds=bounds)
    assert data.culling is method  # the snapshot says what decided it
    frustum = frustum_planes(data.camera.lens, data.view)  # the maths, from the snapshot's camera
    inside = exact(data, bounds, frustum)
    assert 0 < inside.sum() < data.candidates  # the scene has rows on both sides
    kept = [method.kept(data, chunk) for chunk in data.chunks]
    if name is Culling.NONE:
        assert data.planes is None and data.masks is None and kept == [None] * len(data.chunks)
        return
    assert np.array_equal(data.planes, frustum)
    if name is Culling.TEMPORAL:
        assert method.decides_ahead and data.masks is not None
        assert np.array_equal(np.concatenate(kept), inside)  # what the chunk jobs write
    else:
        assert not method.decides_ahead and data.masks is None and kept == [None] * len(data.chunks)


def test_temporal_culling_keeps_its_state_between_frames_and_resets() -> None:
    world, bounds = scene()
    method = TemporalCulling()
    extractor = FrameExtractor(lambda: 1)
    first = extractor.extract(world, 4 / 3, 1, method, dt=1 / 60, bounds=bounds)
    assert method.culler.stats.everything and method.culler.stats.tested == first.candidates
    extractor.extract(world, 4 / 3, 1, method, dt=1 / 60, bounds=bounds)
    assert not method.culler.stats.everything and method.culler.stats.tested < first.candidates // 4  # kept
    method.reset()
    extractor.extract(world, 4 / 3, 1, method, dt=1 / 60, bounds=bounds)
    assert method.culler.stats.everything
    # by name, the extractor keeps one method per name (what tests and benches read as .temporal)
    assert extractor.method("temporal") is extractor.method(Culling.TEMPORAL) is not method
    assert extractor.temporal is extractor.method("temporal").culler  # type: ignore[attr-defined]


@dataclass
class _Ctx:
    fill: str


class _Host:
    """The indirect path as the occlusion method sees it (occlusion_passes, made on first use)."""

    def __init__(self, fill: str) -> None:
        self.ctx = _Ctx(fill)
        self.made: list[Any] = []

    def occlusion_passes(self) -> Any:
        if not self.made:
            self.made.append(_Passes())
        return self.made[0]


class _Passes:
    def __init__(self) -> None:
        self.ensured: list[tuple[int, int, int]] = []

    def ensure(self, width: int, height: int, rows: int) -> None:
        self.ensured.append((width, height, rows))


def test_only_occlusion_culling_asks_the_indirect_path_for_its_passes() -> None:
    for name in Culling:
        host = _Host("solid")
        passes = culling_method(name).gpu(host, 64, 48, 10)
        if name is Culling.OCCLUSION:
            assert passes is host.made[0] and passes.ensured == [(64, 48, 10)]
        else:
            assert passes is None and host.made == []
    occlusion = OcclusionCulling()
    for fill in ("wireframe", "points"):  # what is behind the lines shows: the frustum alone
        assert occlusion.gpu(_Host(fill), 64, 48, 10) is None
    assert occlusion.gpu(_Host("solid"), 64, 48, 0) is None  # no rows: nothing to draw early


def test_the_culling_setting_switches_methods_by_name() -> None:
    class Drawer(CullingSetting):
        def __init__(self, culling: Any) -> None:
            self.culling = culling

    drawer = Drawer(True)
    assert drawer.culling == "frustum" and type(drawer.culling_method) is FrustumCulling
    first = drawer.culling_method = TemporalCulling()
    drawer.culling = "temporal"
    assert drawer.culling_method is first  # the same name keeps the method, and its state
    drawer.culling = Culling.OCCLUSION
    assert type(drawer.culling_method) is OcclusionCulling and drawer.culling == "occlusion"
    with pytest.raises(UsageError):
        drawer.culling = "sometimes"
    assert drawer.culling == "occlusion"


def test_switching_the_renderers_culling_at_runtime_goes_through_the_interface() -> None:
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(32, 24) as gpu:
        world = World()
        cube = gpu.meshes.add(cube_mesh())
        for x in (-1.0, 1.0, 60.0):
            world.spawn(Transform(position=(x, 0.0, 0.0)), Mesh(handle=cube))
        add_camera(world, eye=(0.0, 1.0, 4.0), target=(0.0, 0.0, 0.0))
        default_schedule().run(world, 0.0)
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes, culling=False)
        gpu.owned.append(renderer)
        assert isinstance(renderer.culling_method, NoCulling) and renderer.config.culling is Culling.NONE
        assert renderer.render(world, readback=True).instances == 3
        renderer.culling = "temporal"  # as the session and the editor switch it
        method = renderer.culling_method
        assert isinstance(method, TemporalCulling) and renderer.config.culling is Culling.TEMPORAL
        assert renderer.extract(world, 32, 24).culling is method
        assert renderer.render(world, readback=True, dt=1 / 60).instances == 2  # the far cube culled ahead
        assert method.culler.stats.tested == 0  # the render's extraction used the renderer's method
        renderer.culling = "frustum"
        assert isinstance(renderer.culling_method, FrustumCulling)
        assert renderer.render(world, readback=True).instances == 2


# --------------------------------------------------------------------- the scan
NAMES = frozenset(Culling.names())
STOCK = ("bench", "demos", "systems", "components")
ROOT = Path(ecs_engine.__file__).parent
# the code scanned, by the name files are reported under: the package and the stock folders it
# installs (top-level folders of a checkout, inside the package when installed from a wheel),
# and the repository's scripts beside the tests
SCANNED = {
    "ecs_engine": ROOT,
    **{name: Path(importlib.import_module(f"ecs_engine.{name}").__file__).parent for name in STOCK},
    "scripts": Path(__file__).resolve().parent.parent / "scripts",
}
# where culling names are compared by right: the config's table and the culling package
OWNERS = ("render/config", "render/culling/")
# comparisons with these words that are not about culling, per file (relative to the repo), and why
ALLOWED: dict[str, int] = {
    "bench/shadows.py": 2,  # `light == "none"`: the bench's light kinds (none, directional, ...)
}


def culling_compares(source: str) -> list[tuple[int, str]]:
    """(line, text) of each comparison with a culling name: a str constant (alone or in a
    tuple, list or set) or a Culling member (`Culling.TEMPORAL`)."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if not isinstance(node, ast.Compare):
            continue
        for operand in (node.left, *node.comparators):
            items = operand.elts if isinstance(operand, (ast.Tuple, ast.List, ast.Set)) else [operand]
            words = {i.value for i in items if isinstance(i, ast.Constant) and isinstance(i.value, str)}
            members = {
                i.attr.lower()
                for i in items
                if isinstance(i, ast.Attribute) and isinstance(i.value, ast.Name) and i.value.id == "Culling"
            }
            if (words | members) & NAMES:
                found.append((node.lineno, ast.unparse(node)))
                break
    return found


def test_the_scan_finds_each_form_of_comparison() -> None:
    source = """
if culling == "temporal": pass
if "none" != c: pass
if name in ("frustum", "occlusion"): pass
if c.culling is Culling.OCCLUSION: pass
if mode == "indirect" or light == 3: pass
"""
    assert [line for line, _ in culling_compares(source)] == [2, 3, 4, 5]


def test_no_module_outside_the_config_and_the_culling_package_compares_a_culling_name() -> None:
    wrong, counts = [], {}
    assert all(top.is_dir() for top in SCANNED.values())
    for key, top in SCANNED.items():
        for path in sorted(top.rglob("*.py")):
            rel = path.relative_to(top)
            if key == "ecs_engine" and rel.parts[0] in STOCK:
                continue  # an installed package holds the stock folders: scanned under their names
            name = f"{key}/{rel.as_posix()}"
            if name.removeprefix("ecs_engine/").startswith(OWNERS):
                continue
            found = culling_compares(path.read_text())
            if name in ALLOWED:
                counts[name] = len(found)
            else:
                wrong += [f"{name}:{line}: {text}" for line, text in found]
    assert not wrong, "a culling name compared outside render/config*.py and render/culling/:\n" + "\n".join(wrong)
    assert counts == ALLOWED  # each allowed comparison is still there (else it leaves the list)
