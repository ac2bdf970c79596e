"""docs/app.md's code blocks run, in order, in one scope (in a scratch folder): an App that draws
and steers a cube headless, a MinimalPlugins simulation with a run condition, plugins and
groups, states and an observer, a game module played with its own option and an input script
that saves a scene with F5, which the editor reopens."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
from PIL import Image
from test_app import drawn

DOC = Path(__file__).resolve().parent.parent / "docs" / "app.md"


def test_the_app_page_runs_block_by_block(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    blocks = re.findall(r"```python\n(.*?)```", DOC.read_text(), re.S)
    assert len(blocks) == 7
    scope: dict = {}
    for k, block in enumerate(blocks, 1):
        exec(compile(block, f"docs/app.md block {k}", "exec"), scope)
    assert drawn(np.asarray(Image.open(tmp_path / "mover.png"))) > 0.02  # the red cube
    assert scope["app"].window.title == "Mover at 0.3 s"  # set by its system: 20 steps of 1/60 s
    assert (tmp_path / "saved.scene").is_file()  # F5 at frame 2
    out = capsys.readouterr().out
    assert "balls: headless 64x48, 5 frames" in out and "2 of 2 entities drawn" in out
    editor = out[out.index("saved.scene: headless 480x320, 1 frames") :]  # the editor on the saved file
    assert "2 of 2 entities drawn" in editor  # its balls, their meshes made again from the recipes
