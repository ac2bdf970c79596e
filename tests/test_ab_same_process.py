"""scripts/ab_same_process.py, the one-process comparison of two engines (docs/performance.md):
run here with this tree as both, it draws each engine's frames in alternating blocks and prints
their medians and the blocks' ratios as one JSON line."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

SCRIPT = Path(__file__).resolve().parent.parent / "scripts" / "ab_same_process.py"


def test_two_engines_in_one_process_give_their_blocks_and_ratio(tmp_path: Path) -> None:
    args = ["--old", "ecs_engine", "--scene", "cube", "--size", "64x36", "--blocks", "2", "--block", "3"]
    proc = subprocess.run(
        [sys.executable, str(SCRIPT), *args, "--warmup", "2"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr
    result = json.loads(proc.stdout.strip().splitlines()[-1])
    assert result["packages"] == {"old": "ecs_engine", "new": "ecs_engine"}
    assert result["frames_per_engine"] == 6
    for role in ("old", "new"):
        blocks = result["block_medians_ms"][role]
        assert len(blocks) == 2 and all(ms > 0 for ms in blocks)
        assert result["median_ms"][role] > 0
    ratios = [n / o for n, o in zip(result["block_medians_ms"]["new"], result["block_medians_ms"]["old"], strict=True)]
    assert abs(result["median_block_ratio"] - sum(ratios) / 2) < 1e-9  # two blocks: their mean is the median
    assert result["blocks_new_slower"] == sum(r > 1 for r in ratios)


def test_an_engine_that_is_not_importable_is_one_line_and_a_failure(tmp_path: Path) -> None:
    proc = subprocess.run(
        [sys.executable, str(SCRIPT), "--old", "no_such_engine"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert proc.returncode != 0 and "Traceback" not in proc.stderr
    expected = "ab_same_process: cannot import the engine 'no_such_engine': No module named 'no_such_engine'"
    assert proc.stderr.strip() == expected
