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
