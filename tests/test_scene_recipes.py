"""What a scene file may ask a primitive recipe to make (issue 34): every argument checked, one
SceneFileError naming the recipe and argument, and a cap on the vertices all of a file's recipes
make together, checked before anything is made (render/assets/scene_assets.py, docs/scene-format.md)."""

from __future__ import annotations

import json
import time
import tracemalloc
import zipfile

import pytest

from ecs_engine import World
from ecs_engine.components import Mesh, Transform
from ecs_engine.ecs.scene_file import SceneFileError, load_world, save_world
from ecs_engine.render.assets.mesh_data import MeshData
from ecs_engine.render.assets.primitives import sphere_mesh
from ecs_engine.render.assets.scene_assets import MAX_RECIPE_VERTICES, mesh_from_source, scene_codecs


class Registry(list):
    """MeshRegistry as the mesh codec sees it, without the GPU."""

    def add(self, mesh: MeshData) -> int:
        self.append(mesh)
        return len(self) - 1


def scene_with(tmp_path, entries: list[dict]) -> str:
    """A saved scene (one entity drawing a small sphere) whose meshes resource is `entries`."""
    world = World()
    world.spawn(Transform(), Mesh(handle=0))
    path = tmp_path / "x.scene"
    save_world(world, path, resources=scene_codecs(Registry([sphere_mesh(8, 4)])))
    with zipfile.ZipFile(path) as archive:
        members = {name: archive.read(name) for name in archive.namelist()}
    header = json.loads(members.pop("header.json"))
    meshes = next(r for r in header["resources"] if r["name"] == "meshes")
    meshes["doc"]["meshes"] += entries
    hostile = tmp_path / "hostile.scene"
    with zipfile.ZipFile(hostile, "w") as archive:
        archive.writestr("header.json", json.dumps(header))
        for name, data in members.items():
            archive.writestr(name, data)
    return str(hostile)


def sphere_entry(handle: int, n: int) -> dict:
    args = {"segments": n, "rings": n}
    return {"handle": handle, "vertices": (n + 1) ** 2, "source": {"primitive": "sphere", "args": args}}


def test_the_issues_million_vertex_recipe_is_refused_before_it_is_made(tmp_path):
    """The issue's entry: no entity uses it, and it once cost the editor 175 s and 17.8 GB."""
    path = scene_with(tmp_path, [sphere_entry(1, 1024)])
    tracemalloc.start()
    start = time.perf_counter()
    try:
        with pytest.raises(SceneFileError, match=r"sphere recipe .* would make 1,050,625 vertices.* at most 262,144"):
            load_world(path, World(), resources=scene_codecs(Registry()))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert time.perf_counter() - start < 2.0 and peak < 20e6  # refused before a vertex is made


def test_the_cap_counts_every_recipe_of_the_file(tmp_path):
    """Eight recipes under the cap alone but over it together (distinct, so none is reused)."""
    entries = [sphere_entry(1 + k, 200 - k) for k in range(8)]
    with pytest.raises(SceneFileError, match="made already"):
        load_world(scene_with(tmp_path, entries), World(), resources=scene_codecs(Registry()))
    same = [sphere_entry(1 + k, 200) for k in range(8)]  # the same recipe eight times: made once
    loaded, _ = load_world(scene_with(tmp_path, same), World(), resources=scene_codecs(Registry()))
    assert len(loaded) == 1


@pytest.mark.parametrize(
    ("source", "message"),
    [
        ({"primitive": "cylinder", "args": {"radius": 0}}, "cylinder: radius must be a finite number above 0"),
        ({"primitive": "cone", "args": {"height": 0}}, "cone: height must be a finite number above 0"),
        ({"primitive": "cone", "args": {"radius": 0}}, "cone: radius must be a finite number above 0"),
        ({"primitive": "sphere", "args": {"segs": 8}}, "sphere: unknown argument 'segs'"),
        ({"primitive": "sphere", "args": {"segments": "8"}}, "sphere: segments must be an integer"),
        ({"primitive": 7, "args": {}}, "a primitive's name must be a str"),
        ({"normalized": 2.0, "of": {"primitive": "cone", "args": {"height": -1}}}, "cone: height"),
    ],
)
def test_a_bad_recipe_argument_is_one_scene_error_naming_it(tmp_path, source, message):
    path = scene_with(tmp_path, [{"handle": 1, "vertices": 0, "source": source}])
    with pytest.raises(SceneFileError, match=message):
        load_world(path, World(), resources=scene_codecs(Registry()))


def test_a_recipe_at_the_cap_is_made():
    n = 511  # 512 x 512 = 262,144 vertices: exactly the cap
    assert (n + 1) ** 2 == MAX_RECIPE_VERTICES
    assert mesh_from_source({"primitive": "plane", "args": {"subdivisions": n}}).vertex_count == MAX_RECIPE_VERTICES
