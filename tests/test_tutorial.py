"""docs/tutorial.md's code blocks run, in order, in one scope, and the game they build works:
stars are caught and scored, the rest missed, the world saves and loads, and step 8's App draws
it (headless, a picture of gold stars and the blue paddle)."""

from __future__ import annotations

import os
import re
import sys
import types
from pathlib import Path

import numpy as np
import pytest
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


@pytest.mark.skipif(not os.environ.get("DISPLAY"), reason="needs a display (make test runs under Xvfb)")
def test_the_tutorial_s_game_opens_in_a_window(capsys, tmp_path, monkeypatch):
    """Step 8's `app.run()` without headless=True: a window (Xvfb here), the same game drawn."""
    monkeypatch.chdir(tmp_path)
    text = (Path(__file__).resolve().parent.parent / "docs" / "tutorial.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, re.S)
    last = blocks[-1].replace(
        'app.run(frames=60, headless=True, screenshot="catch.png")', 'app.run(frames=20, screenshot="w.png")'
    )
    assert last != blocks[-1], "step 8 runs its App as this test expects"
    module = types.ModuleType("tutorial_in_a_window")  # its Star is not the other test's; dataclasses look it up
    monkeypatch.setitem(sys.modules, module.__name__, module)
    for k, block in enumerate([*blocks[:-1], last], 1):
        exec(compile(block, f"docs/tutorial.md block {k}", "exec"), module.__dict__)
    out = capsys.readouterr().out
    assert "catch: window 320x180" in out and "20 frames drawn" in out
    pixels = np.asarray(Image.open(tmp_path / "w.png"))
    gold = (pixels[..., 0] > 200) & (pixels[..., 1] > 150) & (pixels[..., 2] < 150)
    blue = (pixels[..., 2] > 180) & (pixels[..., 0] < 150)
    assert gold.sum() > 50 and blue.sum() > 50
