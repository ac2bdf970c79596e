"""Saved scenes (ecs/scene_file.py): a round trip keeps every column and archetype and remaps
entity references, into a fresh world or one with entities; a truncated, corrupt, wrong-version
or hostile file is one SceneFileError and changes nothing; a failed save keeps the old file."""

from __future__ import annotations

import json
import zipfile

import numpy as np
import pytest

from ecs_engine import World
from ecs_engine.components import AngularVelocity, Mesh, Name, Parent, Transform, Velocity
from ecs_engine.ecs import scene_file
from ecs_engine.ecs.scene_file import SceneFileError


def sample() -> tuple[World, dict[str, int]]:
    world = World()
    rng = np.random.default_rng(0)
    world.spawn_batch(
        300, Transform(position=rng.normal(size=(300, 3))), Velocity(linear=rng.normal(size=(300, 3))), Mesh(handle=2)
    )
    root = world.spawn(Transform(position=(1.0, 2.0, 3.0)), Name(value="root"), AngularVelocity(angular=(0, 1, 0)))
    child = world.spawn(Transform(), Parent(entity=root), Name(value="child"))
    orphan = world.spawn(Transform(), Parent(entity=123456789))  # names no saved entity
    return world, {"root": root, "child": child, "orphan": orphan}


def columns(world: World) -> dict:
    out = {}
    for table in world.tables:
        key = tuple(sorted(t.__name__ for t in table.types))
        for (ct, name), column in table.columns.items():
            if not ct.__fields__[name].entity:
                out[(key, ct.__name__, name)] = column[: table.count].copy()
    return out


def test_a_round_trip_keeps_columns_and_remaps_references(tmp_path):
    world, named = sample()
    path = tmp_path / "level.scene"
    scene_file.save(world, path)
    loaded, mapping = scene_file.load(path, World())
    assert len(loaded) == len(world)
    before, after = columns(world), columns(loaded)
    assert before.keys() == after.keys()
    for key in before:
        np.testing.assert_array_equal(before[key], after[key])
    root, child, orphan = (mapping[named[k]] for k in ("root", "child", "orphan"))
    assert loaded.get(child, Parent).entity == root
    assert loaded.get(orphan, Parent).entity == -1
    assert loaded.get(root, Name).value == "root"


def test_loading_into_a_world_with_entities_keeps_them(tmp_path):
    world, named = sample()
    path = tmp_path / "level.scene"
    scene_file.save(world, path)
    target = World()
    mine = target.spawn(Transform(position=(9.0, 9.0, 9.0)))
    _, mapping = scene_file.load(path, target)
    assert target.is_alive(mine) and len(target) == len(world) + 1
    assert mine not in mapping.values()
    assert target.get(mapping[named["child"]], Parent).entity == mapping[named["root"]]


def rewrite(path, tmp_path, change) -> object:
    """A copy of the scene at `path` with its header and members passed through `change`."""
    with zipfile.ZipFile(path) as archive:
        members = {name: archive.read(name) for name in archive.namelist()}
    header = json.loads(members["header.json"])
    change(header, members)
    members["header.json"] = json.dumps(header).encode()
    bad = tmp_path / "bad.scene"
    with zipfile.ZipFile(bad, "w") as archive:
        for name, data in members.items():
            archive.writestr(name, data)
    return bad


def nan_positions(header, members):
    for table in header["tables"]:
        for column in table["columns"]:
            if column["field"] == "position" and "Transform" in column["component"]:
                data = bytearray(members[column["member"]])
                data[-8:] = np.array([np.nan]).tobytes()
                members[column["member"]] = bytes(data)
                return


def huge(header, members):
    member = header["tables"][0]["columns"][0]["member"]
    data = members[member]
    members[member] = data.replace(b"(300,", b"(300000000000,", 1)


BAD = {
    "wrong version": (lambda h, m: h.update(version=99), "format version 99"),
    "not a scene": (lambda h, m: h.update(format="zip"), "not a scene file"),
    "unknown component": (lambda h, m: h["tables"][0]["components"].append("nowhere.Thing"), "unknown component"),
    "missing member": (lambda h, m: m.pop(h["tables"][0]["ids"]), "is missing"),
    "shape lie": (lambda h, m: h["tables"][0].update(rows=301), "expected"),
    "absurd size": (huge, "more than it holds"),
    "NaN in a transform": (nan_positions, "Transform.position"),
    "escaping name": (lambda h, m: m.update({"../evil.npy": b"x"}), "leaves the archive"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_a_bad_file_is_one_clear_error_and_changes_nothing(tmp_path, case):
    world, _ = sample()
    path = tmp_path / "level.scene"
    scene_file.save(world, path)
    change, message = BAD[case]
    bad = rewrite(path, tmp_path, change)
    target = World()
    keep = target.spawn(Transform())
    with pytest.raises(SceneFileError, match=message):
        scene_file.load(bad, target)
    assert len(target) == 1 and target.is_alive(keep)


def test_truncated_or_garbage_files_and_a_failed_save(tmp_path):
    world, _ = sample()
    path = tmp_path / "level.scene"
    scene_file.save(world, path)
    data = path.read_bytes()
    for name, content in (("truncated", data[: len(data) // 2]), ("garbage", b"not a zip at all"), ("empty", b"")):
        bad = tmp_path / f"{name}.scene"
        bad.write_bytes(content)
        with pytest.raises(SceneFileError, match="scene file"):
            scene_file.load(bad, World())

    class Thing:
        pass

    world.spawn(Thing())  # an object column: no pickle-free form
    with pytest.raises(SceneFileError, match="Python objects"):
        scene_file.save(world, path)
    assert path.read_bytes() == data  # the old file is untouched
    assert not list(tmp_path.glob(".*.tmp"))


def test_world_save_and_load(tmp_path):
    world, _ = sample()
    world.save(tmp_path / "w.scene")
    loaded = World.load(tmp_path / "w.scene")
    assert len(loaded) == len(world)
    roots = [e for e in loaded.query(Name).entities() if loaded.get(e, Name).value == "root"]
    children = [e for e in loaded.query(Parent).entities() if loaded.get(e, Parent).entity != -1]
    assert len(roots) == 1 and loaded.get(children[0], Parent).entity == roots[0]
