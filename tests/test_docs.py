"""Every ```python block of README.md and docs/*.md runs, so the documentation cannot rot; every
`ecs-engine` line of a ```bash / ```sh block parses; no page but docs/history.md speaks in issue
numbers or the project's private words.

A page's python blocks run in the page's order in one scope, so a block may continue the one
before it. A block that must not run says so visibly: the line before it is
`<!-- not run: why -->`, and the test prints the reason. What a test needs is substituted: fewer
entities, and `app.run()` headless for a few small frames. Some blocks have checks of their
results (CHECKS), run right after the block that contains their marker.
"""

from __future__ import annotations

import re
import shlex
import sys
import types
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
HISTORY = ROOT / "docs" / "history.md"  # the one page that may tell how the engine got here
# pages whose blocks a test of their own runs in order, with checks of what they built: not run twice
TESTS = Path(__file__).resolve().parent  # (not always ROOT / "tests": the GPU host runs a copy)
OWN_TESTS = {
    ROOT / "docs" / "app.md": TESTS / "test_docs_app.py",
    ROOT / "docs" / "game-structure.md": TESTS / "test_game_structure_doc.py",
    ROOT / "docs" / "tutorial.md": TESTS / "test_tutorial.py",
}
FENCE = re.compile(r"^(?P<indent> *)```(?P<lang>[\w-]*)\n(?P<code>.*?)^(?P=indent)```$", re.S | re.M)
NOT_RUN = re.compile(r"<!-- not run: (?P<why>[^>]+?) -->\s*$")
SUBSTITUTIONS = [  # (pattern, replacement): what a block needs to run in a test, quickly
    (re.compile(r"\b1_000_000\b"), "5_000"),
    (re.compile(r"\bapp\.run\(\)"), "app.run(frames=3, headless=True, width=160, height=90)"),
    (re.compile(r"(\bapp\.run\([^)]*?\bframes=)\d+"), r"\g<1>3"),  # a run asked for more frames
]


@dataclass
class Block:
    page: Path
    line: int  # of the opening fence, 1-based
    lang: str
    code: str
    not_run: str | None  # the reason given in the page, if the block is marked not to run

    @property
    def where(self) -> str:
        return f"{self.page.relative_to(ROOT)}:{self.line}"


def blocks(page: Path, lang: tuple[str, ...] = ("python",)) -> list[Block]:
    text = page.read_text()
    found = []
    for m in FENCE.finditer(text):
        if m["lang"] not in lang:
            continue
        line = text.count("\n", 0, m.start()) + 1
        before = text[: m.start()].rstrip("\n").rsplit("\n", 1)[-1]
        why = NOT_RUN.search(before)
        code = "\n".join(row[len(m["indent"]) :] for row in m["code"].split("\n"))
        found.append(Block(page, line, m["lang"], code, why["why"] if why else None))
    return found


# ----------------------------------------------------------------- checks of what blocks made
def _ecs_five_minutes(scope: dict) -> None:
    assert len(scope["world"]) == 5_000  # 1_000_000 in the page


def _games_as_systems(scope: dict) -> None:
    world, health = scope["world"], scope["Health"]
    hp = world.query(health).column(health.hp)
    assert (hp == 6.0).sum() > 0 and (hp == 10.0).sum() > 0  # the ones near the bomb took 4


def _materials(scope: dict) -> None:
    from ecs_engine.components import DirectionalLight, SpotLight
    from ecs_engine.render.assets.materials import materials

    world = scope["world"]
    assert materials(world)[scope["gold"]].roughness == 0.6
    assert materials(world)[scope["floor"]].base_color_texture == scope["tiles"]
    assert world.query(DirectionalLight).count() == 1 and world.query(SpotLight).count() == 1


def _input(scope: dict) -> None:
    import os

    from ecs_engine.app.bindings import bindings_file

    config = Path(os.environ["XDG_CONFIG_HOME"])  # the test's own (conftest)
    assert scope["path"] == bindings_file("mygame") and scope["path"].is_relative_to(config)
    assert scope["actions"].bound("turn") == ["a/d", "gamepad_left_x"]


def _readme_game(scope: dict) -> None:
    """Three frames ran headless; the startup system made the scene; the cubes turned."""
    from ecs_engine.components import AngularVelocity, Camera, Mesh, Transform

    app = scope["app"]
    world = app.world
    assert app.started and world.query(Camera).count() == 1
    assert world.query(Mesh).count() == 8 and world.query(Transform, scope["Player"]).count() == 1
    turned = world.query(Transform, with_=[AngularVelocity]).column(Transform.rotation)
    assert len(turned) == 7 and not np.allclose(turned, (0.0, 0.0, 0.0, 1.0))


def _scene_file(scope: dict) -> None:
    from ecs_engine.components import Transform

    loaded, ids = scope["loaded"], scope["ids"]
    assert len(loaded) == 1
    assert np.array_equal(loaded.get(ids[scope["old_id"]], Transform).position, (1.0, 2.0, 3.0))


CHECKS: dict[str, Callable[[dict], None]] = {  # a marker only its block contains -> its check
    "a million entities is one call": _ecs_five_minutes,
    "world.events(Hit)": _games_as_systems,
    'Material("floor", "lambert"': _materials,
    "world.resources[ActionMap] = ActionMap(": _input,
    'app = App(title="Cubes"': _readme_game,
    'save_world(world, "level.scene")': _scene_file,
}


def run_page(page: Path) -> list[str]:
    """Run the page's python blocks in order in one scope; the markers of the checks run."""
    from ecs_engine import World
    from ecs_engine.jobs import JobPool

    module = types.ModuleType("doc_page")  # a real module: dataclasses look their own up
    sys.modules[module.__name__] = module
    scope = module.__dict__
    checked = []
    try:
        for block in blocks(page):
            if block.not_run is not None:
                print(f"{block.where}: not run: {block.not_run}")
                continue
            code = block.code
            for pattern, replacement in SUBSTITUTIONS:
                code = pattern.sub(replacement, code)
            exec(compile(code, block.where, "exec"), scope)
            for marker, check in CHECKS.items():
                if marker in block.code:
                    check(scope)
                    checked.append(marker)
    finally:
        for value in list(scope.values()):  # the pools the blocks started
            if isinstance(value, World) and JobPool in value.resources:
                value.resources[JobPool].close()
        del sys.modules[module.__name__]
    return checked


@pytest.mark.parametrize(
    "page", [p for p in PAGES if blocks(p) and p not in OWN_TESTS], ids=lambda p: str(p.relative_to(ROOT))
)
def test_every_python_block_runs(page, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)  # files a block writes (level.scene, mygame.json) go here
    run_page(page)
    out = capsys.readouterr().out
    for block in blocks(page):
        if block.not_run is not None:
            assert f"{block.where}: not run:" in out


def test_pages_with_their_own_test_are_run_there():
    """Each page left out above has a test that reads that page and runs its python blocks."""
    for page, test in OWN_TESTS.items():
        text = test.read_text()
        assert f'"{page.name}"' in text and "exec(compile(" in text, test.name


def test_every_check_finds_its_block():
    """A check whose block moved or changed would silently check nothing: each marker is in
    exactly one block that runs."""
    found = {m: [b.where for p in PAGES for b in blocks(p) if m in b.code and b.not_run is None] for m in CHECKS}
    assert {m: w for m, w in found.items() if len(w) != 1} == {}


def test_blocks_are_found_with_their_marks(tmp_path):
    """Indented blocks (in a list) are found, a mark is read, and a test's substitutions apply."""
    page = tmp_path / "page.md"
    page.write_text(
        "# A page\n\n```python\nx = 1\n```\n\n- an item:\n\n  <!-- not run: it needs a gamepad -->\n"
        "  ```python\n  y = x\n  ```\n\n```bash\necs-engine demo cube  # a comment\n```\n"
    )
    found = blocks(page)
    assert [(b.code, b.not_run) for b in found] == [("x = 1\n", None), ("y = x\n", "it needs a gamepad")]
    assert [b.code for b in blocks(page, ("bash",))] == ["ecs-engine demo cube  # a comment\n"]
    code = 'app.run()\napp.run(frames=120, headless=True, screenshot="catch.png")'
    for pattern, replacement in SUBSTITUTIONS:
        code = pattern.sub(replacement, code)
    assert code.split("\n") == [
        "app.run(frames=3, headless=True, width=160, height=90)",
        'app.run(frames=3, headless=True, screenshot="catch.png")',
    ]


def test_blocks_marked_not_run_say_why():
    for page in PAGES:
        for block in blocks(page):
            assert block.not_run is None or len(block.not_run.strip()) >= 10, block.where


# ------------------------------------------------------------------------------ shell blocks
def commands(page: Path) -> list[tuple[str, list[str]]]:
    """The `ecs-engine ...` lines of a page's bash and sh blocks: (where, its arguments)."""
    found = []
    for block in blocks(page, ("bash", "sh")):
        for k, row in enumerate(block.code.split("\n"), block.line + 1):
            words = shlex.split(row, comments=True)
            if words[:1] == ["ecs-engine"]:
                found.append((f"{block.page.relative_to(ROOT)}:{k}", words[1:]))
    return found


def parse(words: list[str]) -> None:
    """Read a command line as `ecs-engine` does (the game first, then its own options)."""
    from ecs_engine.app.cli import FirstReading, build_parser, game_of

    args, _ = build_parser(parser_class=FirstReading).parse_known_args(words)
    build_parser(game_of(args)).parse_args(words)


@pytest.mark.parametrize("page", [p for p in PAGES if commands(p)], ids=lambda p: str(p.relative_to(ROOT)))
def test_every_shell_command_parses(page, tmp_path, monkeypatch):
    """Its flags are the CLI's. `ecs-engine new NAME` runs (it writes a folder, in a temporary
    one), so that the lines after it find the game it made; the repository's paths are given as
    they are in it."""
    from ecs_engine.app.cli import main

    monkeypatch.chdir(tmp_path)
    for where, words in commands(page):
        words = [str(ROOT / w) if "/" in w and (ROOT / w).exists() else w for w in words]
        try:
            if words[:1] == ["new"]:
                assert main(words) == 0
            else:
                parse(words)
        except SystemExit as exc:
            pytest.fail(f"{where}: ecs-engine {shlex.join(words)} does not parse (exit {exc.code})")


# ------------------------------------------------------------------------- private vocabulary
PRIVATE = {  # a newcomer cannot know these; docs/history.md tells them
    "an issue number": re.compile(r"\bissues? #?\d+|\b(?:the|this|that) issue\b", re.I),
    "the seed (the thesis the engine started from)": re.compile(
        r"\bthe seed\b|\bseed's\b|\bseed (?:scene|thesis)", re.I
    ),
    "a table number of the thesis": re.compile(r"\bTables? \d+\.\d+"),
    "talk of work sessions": re.compile(
        r"\b(?:this|that|one|an earlier|a later|each|every|the) sessions?\b|\bsessions? \d+"
    ),
    "talk of reviews and stops": re.compile(r"\b(?:the|a) review\b|\blast stop\b", re.I),
}


def private_words(text: str) -> list[str]:
    found = []
    for k, row in enumerate(text.split("\n"), 1):
        for what, pattern in PRIVATE.items():
            for m in pattern.finditer(row):
                found.append(f"{k}: {what}: {m.group(0)!r}")
    return found


@pytest.mark.parametrize("page", [p for p in PAGES if p != HISTORY], ids=lambda p: str(p.relative_to(ROOT)))
def test_no_private_vocabulary(page):
    assert private_words(page.read_text()) == [], f"{page.relative_to(ROOT)}: move these to docs/history.md"


def test_private_vocabulary_is_found():
    """The patterns find what they are for (and the history page exists to take it)."""
    assert HISTORY.exists()
    text = "Shadows (issue 15)\nthe seed's key map (Table 7.1)\nin this session\nafter the review's mends"
    assert len(private_words(text)) == 5
    assert private_words("`Session.apply` and tests/test_scene_file.py, `--seed 1`") == []


def test_readme_is_short():
    """The README is a newcomer's first screen and a map to docs/: at most 12 KB."""
    size = len((ROOT / "README.md").read_bytes())
    assert size <= 12 * 1024, f"README.md is {size} bytes"
