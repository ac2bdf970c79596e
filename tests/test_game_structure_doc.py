"""docs/game-structure.md's code blocks run, in order, in one scope (each ends with asserts on
what it built), so the page cannot drift from the API."""

from __future__ import annotations

import re
from pathlib import Path


def test_the_game_structure_page_runs_block_by_block():
    text = (Path(__file__).resolve().parent.parent / "docs" / "game-structure.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, re.S)
    assert len(blocks) == 5, "states, observers, removals, one-shot systems, prefabs"
    scope: dict = {"__name__": "game_structure_doc"}
    for k, block in enumerate(blocks):
        exec(compile(block, f"docs/game-structure.md block {k}", "exec"), scope)
    assert scope["world"].query(scope["Health"]).count() == 10  # the prefab block's copies


def test_a_removal_reader_its_run_condition_skips_falls_behind():
    """What the page says of a skipped reader: removals it did not read for two frames are lost,
    so a reader that must see every removal runs every frame."""
    import numpy as np

    from ecs_engine import Component, Field, Schedule, World, system

    class Rock(Component):
        size = Field(np.float32, default=1.0)

    world = World()
    world.removed(Rock)
    seen = {"skipped": [], "every frame": []}
    awake = {"on": False}

    @system(reads=[Rock])
    def sometimes(world, dt):
        seen["skipped"].extend(world.removed(Rock).read().tolist())

    @system(reads=[Rock])
    def always(world, dt):
        seen["every frame"].extend(world.removed(Rock).read().tolist())

    schedule = Schedule()
    schedule.add(sometimes, run_if=lambda world: awake["on"])
    schedule.add(always)
    rock = world.spawn(Rock())
    world.destroy(rock)
    for _ in range(3):
        schedule.run(world, 1 / 60)
    awake["on"] = True
    schedule.run(world, 1 / 60)
    assert seen == {"skipped": [], "every frame": [rock]}
