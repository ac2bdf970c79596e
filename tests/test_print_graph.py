"""`ecs-engine demo ... --print-graph` (app/cli_graph.py): one frame drawn headless, then the
frame graph it built printed (render/graph/describe.py) and exit 0; the passes follow the
render configuration. Bad input is still one line and exit 2."""

from __future__ import annotations

import re
import subprocess
import sys

PASS_LINE = re.compile(r"^  (\d+) (\S+)", re.M)  # "  0 forward": a pass that runs, in order


def demo(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "ecs_engine", "demo", *args],
        capture_output=True,
        text=True,
        timeout=300,
    )


def printed(*args: str) -> tuple[str, list[str]]:
    proc = demo("cube", "--print-graph", "--validate", "--width", "64", "--height", "48", *args)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert proc.stderr == ""  # no validation message, nothing else said
    text = proc.stdout
    assert text.startswith("frame graph 64x48: ")
    names = [m.group(2) for m in PASS_LINE.finditer(text)]
    assert [int(m.group(1)) for m in PASS_LINE.finditer(text)] == list(range(len(names)))
    return text, names


def test_the_default_config_draws_the_scene_straight_into_the_target():
    text, names = printed()
    assert names[0] == "forward"
    assert "imgui" not in names  # no UI headless: the pass is culled, with its barrier
    assert re.search(r"culled: .*imgui", text.splitlines()[0])
    assert "tone_map" not in names and "post" not in names  # no HDR colour: nothing to tone map
    assert "writes target COLOR_WRITE clear" in text  # the scene's rendering clears the target
    assert "  depth: D32_SFLOAT 64x48" in text  # its depth is the graph's transient
    assert "hdr" not in text


def test_aces_with_msaa_and_bloom_renders_hdr_resolves_blooms_and_tone_maps():
    text, names = printed("--tone-map", "aces", "--msaa", "4", "--post", "bloom")
    assert {"forward", "bloom_downsample_0", "bloom_composite", "tone_map"} <= set(names)
    order = [names.index(n) for n in ("forward", "bloom_downsample_0", "bloom_composite", "tone_map")]
    assert order == sorted(order)
    assert "writes hdr_msaa COLOR_WRITE clear store dont_care, hdr COLOR_WRITE" in text  # hdr: the resolve target
    assert "  hdr_msaa: R16G16B16A16_SFLOAT 64x48, 4x MSAA" in text  # the multisampled colour: a transient
    assert "reads  hdr FRAGMENT_SAMPLED" in text  # the tone map samples the resolved colour


def test_bad_input_is_one_line_and_exit_2():
    for args, fragment in (
        (("motion", "--print-graph"), "--print-graph does not apply"),
        (("cube", "--print-graph", "--msaa", "3"), "--msaa"),
        (("cube", "--print-graph=yes"), "--print-graph"),
    ):
        proc = demo(*args)
        assert proc.returncode == 2, proc.stdout + proc.stderr
        lines = [line for line in proc.stderr.splitlines() if line.strip()]
        assert len(lines) == 1 and "Traceback" not in proc.stderr and fragment in lines[0], proc.stderr
