"""docs/tutorial.md's code blocks run, in order, in one scope, and the game they build works:
stars are caught and scored, the rest missed, the world saves and loads, and step 8's App draws
it (headless, a picture of gold stars and the blue paddle)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
from PIL import Image


def test_the_tutorial_runs_step_by_step(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # step 8 writes catch.png
    text = (Path(__file__).resolve().parent.parent / "docs" / "tutorial.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, re.S)
    assert len(blocks) == 8, "the tutorial's steps"
    scope: dict = {}
    for k, block in enumerate(blocks, 1):
        exec(compile(block, f"docs/tutorial.md block {k}", "exec"), scope)
    state = scope["state"]
    assert state.points > 0 and state.missed > 0
    assert state.points % 10 == 0
    world, star = scope["world"], scope["Star"]
    assert world.query(star).count() < 200  # caught or missed stars are gone
    out = capsys.readouterr().out
    assert "caught" in out and "60 frames drawn; caught" in out
    app = scope["app"]
    assert scope["result"].frames == 60 and app.world.query(star).count() > 0
    pixels = np.asarray(Image.open(tmp_path / "catch.png"))
    gold = (pixels[..., 0] > 200) & (pixels[..., 1] > 150) & (pixels[..., 2] < 150)
    blue = (pixels[..., 2] > 180) & (pixels[..., 0] < 150)
    assert gold.sum() > 50 and blue.sum() > 50
