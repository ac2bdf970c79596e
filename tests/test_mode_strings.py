"""No mode string is compared outside the render configuration: a setting's or target form's name
(a value of a config enum or of `Form`) compared as a literal string is a decision made in a
second place, which a renamed or added value leaves behind. The comparisons name the enums'
members instead (`form == Form.DEFERRED`); render/config/ (the table itself) is left out."""

from __future__ import annotations

import ast
from pathlib import Path

import ecs_engine
import ecs_engine.components
import ecs_engine.demos
import ecs_engine.systems
from ecs_engine.render.config.choices import Choice, Form

PACKAGE = Path(ecs_engine.__file__).parent  # the package the tests import (installed or not)
# the folders installed inside the package but kept beside it in a checkout (pyproject's
# package-dir), scanned from wherever they are so an install and a checkout see the same files;
# bench/ is left out: a benchmark compares the values of its own command-line options
OUTSIDE = {"components": ecs_engine.components, "systems": ecs_engine.systems, "demos": ecs_engine.demos}
VALUES = frozenset({str(v) for enum in Choice.__subclasses__() for v in enum} | {str(f) for f in Form})


def _constants(node: ast.expr) -> list[ast.expr]:
    """The literal strings a comparison's operand is or lists (`x in ("a", "b")`)."""
    if isinstance(node, (ast.Tuple, ast.Set, ast.List)):
        return list(node.elts)
    return [node]


def compared_names(source: str) -> list[tuple[int, str]]:
    """(line, value) of each literal string among VALUES that `source` compares or matches on."""
    found = []
    for node in ast.walk(ast.parse(source)):
        operands: list[ast.expr] = []
        if isinstance(node, ast.Compare):
            operands = [node.left, *node.comparators]
        elif isinstance(node, ast.MatchValue):  # case "deferred":
            operands = [node.value]
        for operand in operands:
            for c in _constants(operand):
                if isinstance(c, ast.Constant) and isinstance(c.value, str) and c.value in VALUES:
                    found.append((c.lineno, c.value))
    return found


def test_the_scan_knows_every_choice_and_form():
    assert {"deferred", "direct", "hdr", "raytraced", "weighted", "native", "solid", "clamp"} <= VALUES
    assert compared_names('if mode == "deferred":\n    pass\n') == [(1, "deferred")]
    assert compared_names('ok = fill in ("solid", "points")\n') == [(1, "solid"), (1, "points")]
    assert compared_names('match form:\n    case "hdr":\n        pass\n') == [(2, "hdr")]
    assert compared_names('name = "deferred"\nif name == "deferred_lighting":\n    pass\n') == []


def test_no_mode_string_is_compared_outside_the_config():
    files = {f.relative_to(PACKAGE).as_posix(): f for f in sorted(PACKAGE.rglob("*.py"))}
    skip = ("render/config/", "bench/", *(f"{name}/" for name in OUTSIDE))
    files = {name: f for name, f in files.items() if not name.startswith(skip)}
    for name, module in OUTSIDE.items():
        folder = Path(module.__file__).parent
        files |= {f"{name}/{f.relative_to(folder).as_posix()}": f for f in sorted(folder.rglob("*.py"))}
    assert len(files) > 100 and "render/frame/renderer.py" in files  # the package was found
    places = [f"{name}:{line}: {value!r}" for name, f in files.items() for line, value in compared_names(f.read_text())]
    assert places == [], "compare the config's enum members (render/config/choices.py) instead:\n" + "\n".join(places)
