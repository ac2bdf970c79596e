"""docs/tutorial.md's code blocks run, in order, in one scope, and the game they build works:
stars are caught and scored, the rest missed, and the world saves and loads."""

from __future__ import annotations

import re
from pathlib import Path


def test_the_tutorial_runs_step_by_step(capsys):
    text = (Path(__file__).resolve().parent.parent / "docs" / "tutorial.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, re.S)
    assert len(blocks) == 7, "the tutorial's steps (the eighth is prose)"
    scope: dict = {}
    for k, block in enumerate(blocks, 1):
        exec(compile(block, f"docs/tutorial.md block {k}", "exec"), scope)
    state = scope["state"]
    assert state.points > 0 and state.missed > 0
    assert state.points % 10 == 0
    world, star = scope["world"], scope["Star"]
    assert world.query(star).count() < 200  # caught or missed stars are gone
    assert "caught" in capsys.readouterr().out
