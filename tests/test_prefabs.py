"""Prefabs (ecs/prefabs.py): a saved scene file read once and spawned many times in bulk, with
overrides on its roots, its entity references pointing into each copy, bad files and bad
overrides refused with one clear error, the world unchanged."""

from __future__ import annotations

import zipfile

import numpy as np
import pytest

from ecs_engine import Component, Field, OnAdd, Prefab, Schedule, World, spawn_prefab, system
from ecs_engine.components import Transform
from ecs_engine.components.hierarchy import Parent
from ecs_engine.ecs.scene_file import SavedResource, SceneFileError
from ecs_engine.jobs import JobPool


class Hull(Component):
    hp = Field(np.float32, default=10.0, finite=True, minimum=0.0)


class Target(Component):
    entity = Field(np.int64, default=-1, entity=True)


class Range(Component):
    near = Field(np.float32, default=1.0)
    far = Field(np.float32, default=2.0)

    @classmethod
    def check(cls, values, who):
        if (np.asarray(values["near"]) >= np.asarray(values["far"])).any():
            raise ValueError("Range.near must be below Range.far")


@pytest.fixture
def ship(tmp_path):
    """A ship (root) with a gun (child) that targets the ship, and a reference outside it."""
    world = World()
    outside = world.spawn(Hull())
    hull = world.spawn(Transform(position=(1.0, 0.0, 0.0)), Hull(hp=50.0), Target(entity=outside))
    world.spawn(Transform(position=(0.0, 1.0, 0.0)), Parent(entity=hull), Target(entity=hull))
    world.destroy(outside)  # saved without it: its id names nothing of the file
    path = tmp_path / "ship.scene"
    world.save(path, resources=())
    return path


def test_copies_get_their_own_entities_with_references_pointing_inside_each_copy(ship):
    world = World()
    prefab = Prefab.load(ship, world, resources=())
    assert len(prefab) == 2 and prefab.roots.tolist() == [True, False]
    ids = prefab.spawn(world, 3)
    assert ids.shape == (3, 2) and len(np.unique(ids)) == 6 and len(world) == 6
    for hull, gun in ids:
        assert world.get(gun, Parent).entity == hull and world.get(gun, Target).entity == hull
        assert world.get(hull, Target).entity == -1  # named an entity the file does not hold
        assert world.get(hull, Hull).hp == 50.0


def test_overrides_go_to_the_roots_one_value_for_all_or_a_row_per_copy(ship):
    world = World()
    prefab = Prefab.load(ship, world, resources=())
    at = np.array([[0.0, 0, 0], [5, 0, 0], [10, 0, 0]])
    ids = prefab.spawn(world, 3, overrides={Transform: {"position": at}, Hull: {"hp": 7.0}})
    np.testing.assert_array_equal([world.get(e, Transform).position for e in ids[:, 0]], at)
    assert [world.get(e, Hull).hp for e in ids[:, 0]] == [7.0] * 3
    assert all((world.get(e, Transform).position == (0, 1, 0)).all() for e in ids[:, 1])  # the gun keeps its own


def test_a_root_s_entity_field_can_be_overridden_to_hang_copies_under_existing_entities(ship):
    world = World()
    carriers = world.spawn_batch(2, Transform())
    ids = Prefab.load(ship, world, resources=()).spawn(world, 2, overrides={Target: {"entity": carriers}})
    assert [world.get(e, Target).entity for e in ids[:, 0]] == carriers.tolist()
    assert [world.get(e, Target).entity for e in ids[:, 1]] == ids[:, 0].tolist()  # the gun still aims inside


def test_spawning_is_one_batch_per_table_and_observers_see_the_copies_once_linked(ship):
    world, seen, batches = World(), [], []
    prefab = Prefab.load(ship, world, resources=())
    world.add_observer(OnAdd(Parent), lambda w, t: seen.append([w.get(e, Parent).entity for e in t.entities]))
    real = world.spawn_batch
    world.spawn_batch = lambda n, *values: batches.append(n) or real(n, *values)
    ids = prefab.spawn(world, 1000)
    assert batches == [1000, 1000]  # the file's two tables, whatever the count
    assert seen == [ids[:, 0].tolist()]  # one call, parents already the copies


def test_inside_a_system_the_spawn_is_deferred_and_needs_no_extra_access(ship):
    world = World()
    prefab = Prefab.load(ship, world, resources=())
    spawned = []

    @system(reads=[Hull])  # declares no write of Parent or Target
    def wave(world, dt):
        spawned.append(prefab.spawn(world, 2))
        assert len(world) == 0  # waits for the sync point

    schedule = Schedule()
    schedule.add(wave)
    schedule.run(world, 0.0)
    (ids,) = spawned
    assert len(world) == 4 and [world.get(g, Parent).entity for g in ids[:, 1]] == ids[:, 0].tolist()


def test_bad_overrides_and_counts_are_one_clear_error_and_change_nothing(ship):
    world = World()
    prefab = Prefab.load(ship, world, resources=())
    bad = [
        ({Parent: {"entity": 1}}, ValueError, "no root entity has Parent to override"),
        ({Transform: {"pos": 1}}, TypeError, "Transform has no field\\(s\\) \\['pos'\\]"),
        ({Hull: {"hp": np.nan}}, ValueError, "copy 0 of prefab ship.scene: Hull.hp must be finite"),
        ({Hull: {"hp": [1.0, -1.0]}}, ValueError, "copy 1 of prefab ship.scene: Hull.hp"),
        ({Transform: {"position": np.zeros((3, 3))}}, ValueError, "expects \\(3,\\) per entity, or shape \\(2, 3\\)"),
        ({"Hull": {"hp": 1}}, TypeError, "keyed by component types, got 'Hull'"),
        ([1], TypeError, "prefab overrides are"),
    ]
    for overrides, kind, message in bad:
        with pytest.raises(kind, match=message):
            prefab.spawn(world, 2, overrides=overrides)
    for count in (-1, 1.5, True, "3"):
        with pytest.raises(ValueError, match="count is a whole number >= 0"):
            prefab.spawn(world, count)
    assert len(world) == 0
    assert prefab.spawn(world, 0).shape == (0, 2)


def test_a_failed_cross_field_check_spawns_nothing(tmp_path):
    source = World()
    source.spawn(Range())
    path = tmp_path / "range.scene"
    source.save(path, resources=())
    world = World()
    prefab = Prefab.load(path, world, resources=())
    with pytest.raises(ValueError, match=r"Range.near must be below Range.far"):
        prefab.spawn(world, 3, overrides={Range: {"near": 5.0}})
    assert len(world) == 0


def test_bad_files_are_refused_as_scene_files_are(tmp_path, ship):
    world = World()
    broken = tmp_path / "broken.scene"
    broken.write_bytes(ship.read_bytes()[:100])
    empty = tmp_path / "empty.scene"
    World().save(empty, resources=())
    cases = [
        (broken, "broken.scene: unreadable"),
        (tmp_path / "missing.scene", "missing.scene"),
        (tmp_path, "not a regular file|directory"),
        (empty, "it holds no entities: nothing to spawn as a prefab"),
    ]
    for path, message in cases:
        with pytest.raises(SceneFileError, match=message):
            Prefab.load(path, world, resources=())
    source = World()
    source.spawn(Hull(hp=1.0))
    nan = tmp_path / "nan.scene"
    source.save(nan, resources=())
    with zipfile.ZipFile(nan) as archive:
        members = {name: archive.read(name) for name in archive.namelist()}
    with zipfile.ZipFile(nan, "w") as archive:  # the hp column's one value made NaN, the CRCs right
        for name, data in members.items():
            if name.endswith("0.npy") and data.endswith(np.float32(1.0).tobytes()):
                data = data[:-4] + np.float32(np.nan).tobytes()
            archive.writestr(name, data)
    with pytest.raises(SceneFileError, match=r"nan.scene: table 0, row 0: Hull.hp must be finite"):
        Prefab.load(nan, world, resources=())
    assert len(world) == 0


class Skin(Component):
    handle = Field(np.int32, default=0)


class Palette(list):
    """A resource: the colours a Skin.handle indexes."""


class PaletteCodec:
    name = "palette"
    resource_types = (Palette,)

    def save(self, world):
        return SavedResource(list(world.resources[Palette]))

    def read(self, saved, world):
        target = world.resources.setdefault(Palette, Palette())
        lookup = np.arange(len(saved.doc)) + len(target)

        class Ready:
            def remaps(self):
                return {(Skin, "handle"): lookup}

            def commit(self, world):
                target.extend(saved.doc)

        return Ready()


def test_the_file_s_resources_go_into_the_world_once_and_its_handles_follow(tmp_path):
    source = World()
    source.resources[Palette] = Palette(["red", "green"])
    source.spawn(Skin(handle=1))
    path = tmp_path / "skin.scene"
    source.save(path, resources=[PaletteCodec()])
    world = World()
    world.resources[Palette] = Palette(["blue"])
    ids = spawn_prefab(world, path, 2, resources=[PaletteCodec()])
    assert world.resources[Palette] == ["blue", "red", "green"]
    assert [world.get(e, Skin).handle for e in ids[:, 0]] == [2, 2]  # "green" in the world's palette
    prefab = Prefab.load(path, world, resources=[PaletteCodec()])
    prefab.spawn(world, 5)
    prefab.spawn(world, 5)
    assert len(world.resources[Palette]) == 5  # once per load, not per spawn


def _waves(ship, parallel: bool) -> tuple[list, list]:
    """Two systems of one stage spawn copies each frame; what the world holds after."""
    world = World()
    pool = world.resources[JobPool] = JobPool(4)
    try:
        prefab = Prefab.load(ship, world, resources=())
        spawned: list = []

        @system(reads=[Hull])
        def left(world, dt):
            spawned.append(("left", prefab.spawn(world, 3, overrides={Hull: {"hp": 1.0}}).tolist()))

        @system(reads=[Target])
        def right(world, dt):
            spawned.append(("right", prefab.spawn(world, 2).tolist()))

        schedule = Schedule(parallel=parallel)
        schedule.add(left)
        schedule.add(right)
        for _ in range(3):
            schedule.run(world, 0.0)
        links = sorted((int(e), int(world.get(int(e), Parent).entity)) for b in world.query(Parent) for e in b.entities)
        return sorted(spawned), links
    finally:
        pool.close()


def test_a_parallel_schedule_spawns_the_same_copies_with_the_same_ids(ship):
    sequential = _waves(ship, parallel=False)
    assert len(sequential[0]) == 6 and len(sequential[1]) == 15
    guns_to_hulls = {gun: hull for _, copies in sequential[0] for hull, gun in copies}
    assert dict(sequential[1]) == guns_to_hulls  # each gun hangs on its own copy's hull
    assert _waves(ship, parallel=True) == sequential
