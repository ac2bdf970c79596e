"""The README's example runs (with fewer entities), so the documentation cannot rot."""

from __future__ import annotations

import re
from pathlib import Path


def test_readme_example_runs():
    text = (Path(__file__).resolve().parent.parent / "README.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, re.S)
    assert blocks, "README has no python example"
    code = blocks[0].replace("1_000_000", "5_000")
    scope: dict = {}
    exec(compile(code, "README.md", "exec"), scope)
    world = scope["world"]
    assert len(world) == 5_000


def run_block(marker: str, what: str) -> dict:
    """Run the one README python block containing `marker`; its variables."""
    text = (Path(__file__).resolve().parent.parent / "README.md").read_text()
    blocks = [b for b in re.findall(r"```python\n(.*?)```", text, re.S) if marker in b]
    assert len(blocks) == 1, f"README has no {what} example"
    scope: dict = {}
    exec(compile(blocks[0], "README.md", "exec"), scope)
    return scope


def test_readme_materials_example_runs():
    scope = run_block("Material(", "materials")
    from ecs_engine.components import DirectionalLight, SpotLight
    from ecs_engine.render.materials import materials

    world = scope["world"]
    assert materials(world)[scope["gold"]].roughness == 0.6
    assert materials(world)[scope["floor"]].base_color_texture == scope["tiles"]
    assert world.query(DirectionalLight).count() == 1 and world.query(SpotLight).count() == 1


def test_readme_games_example_runs():
    scope = run_block("world.events(Hit)", "games-as-systems")
    from ecs_engine.jobs import JobPool

    world, health = scope["world"], scope["Health"]
    try:
        hp = world.query(health).column(health.hp)
        assert (hp == 6.0).sum() > 0 and (hp == 10.0).sum() > 0  # the ones near the bomb took 4
    finally:
        world.resources[JobPool].close()


def test_readme_input_example_runs(config_home):
    """The action map example: it saves into the config folder (the test's own, conftest)."""
    scope = run_block("ActionMap(", "input")
    from ecs_engine.app.bindings import bindings_file

    assert scope["path"] == bindings_file("mygame") and scope["path"].is_relative_to(config_home)
    assert scope["actions"].bound("turn") == ["a/d", "gamepad_left_x"]
