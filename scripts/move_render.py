"""Split ecs_engine/render/ into sub-packages by concern (issue 36's layout): `git mv` each module
of MOVES that is still a top-level module of render/, then rewrite every reference to its old
name in the checkout, so the move is one re-runnable step instead of a commit of moved files.

    python scripts/move_render.py --dry-run    # the plan: moves, skipped entries, unmapped modules
    python scripts/move_render.py              # apply it (a second run changes nothing)
    python scripts/move_render.py --rewrite-only PATH...   # old imports in a game's own files

What is rewritten, in the package, components/, systems/, tests/, bench/ (not bench/results/, the
record of past runs), demos/, scripts/, docs/, *.md and pyproject.toml:
- imports, absolute and relative (`from .x import`, `from ..x import`, `from . import x`, which
  stays relative, recomputed from the importing file's new place when that file moves too);
- dotted names anywhere (`"ecs_engine.render.mesh_loading.read_user_file"` in monkeypatch,
  `importlib.import_module` strings, prose);
- paths in prose (`render/shadow_pass.py`), but not in render/layouts.py, whose comments are
  written into shaders/layouts.glsl (tests/test_gpu_layouts.py compares them), nor in shaders/,
  whose sources are hashed (tests/test_shaders.py);
- a string that is a moved module's path relative to render/ (`"frame_data.py"`, the keys of
  tests/test_extract_stage.py's lists);
- in the files games copy (docs, README, demos, the `ecs-engine new` template), a one-line import
  of the public names (PUBLIC) becomes `from ecs_engine.render import ...`;
- pyproject.toml's packages list (tests/test_packages_listed.py).
Each new package gets an `__init__.py` that is a docstring only: code imports the module that
defines a name (rewritten so), never a package's re-export, so importing one module of a package
runs no other (lod_worker.py's child process, numba's kernels) and no package init can form an
import circle at run time. render/__init__.py gets the public names, loaded on first use.
"""

from __future__ import annotations

import argparse
import ast
import re
import subprocess
import sys
import textwrap
from pathlib import Path

from render_layout import FIXUPS, KEEP_OLD_PATHS, MOVES, PACKAGES, PUBLIC, STAY

ROOT = Path(__file__).resolve().parent.parent
RENDER = ROOT / "ecs_engine" / "render"
PKG = "ecs_engine.render"

SCANNED = ("ecs_engine", "components", "systems", "tests", "bench", "demos", "scripts", "docs")
# the tables name the old modules on purpose
SKIPPED = (
    "bench/results/",
    "shaders/",
    "scripts/move_render.py",
    "scripts/render_layout.py",
    "tests/test_render_layout.py",
)
GAME_FACING = ("docs/", "README.md", "demos/", "ecs_engine/app/new_game.py")
NO_PATH_PROSE = ("ecs_engine/render/layouts.py",)


def new_file(old: str) -> Path:
    new = MOVES[old].split(".")
    return RENDER.joinpath(*new[:-1], f"{new[-1]}.py") if new != [old] else RENDER / old / "__init__.py"


def remap(module: str, moves: dict[str, str]) -> str:
    """The module's name after the moves (a name under a moved module too)."""
    parts = module.split(".")
    if module.startswith(PKG + ".") and parts[2] in moves:
        return ".".join([PKG, moves[parts[2]], *parts[3:]])
    return module


def module_of(path: Path, moves: dict[str, str]) -> tuple[str, bool] | None:
    """(dotted name, is a package) of a file of ecs_engine/, as it is before the moves."""
    rel = path.relative_to(ROOT).with_suffix("")
    if rel.parts[0] != "ecs_engine":
        return None
    init = rel.name == "__init__"
    return ".".join(rel.parts[:-1] if init else rel.parts), init


def relative(target: str, package: str) -> str:
    """`target` as a relative import's module text from inside `package`."""
    t, p = target.split("."), package.split(".")
    common = 0
    while common < min(len(t), len(p)) and t[common] == p[common]:
        common += 1
    return "." * (len(p) - common + 1) + ".".join(t[common:])


def packages_of(where: tuple[str, bool], moves: dict[str, str]) -> tuple[str, str]:
    """The package a file's relative imports start from, before and after the moves."""
    name, init = where
    old_pkg = name if init else name.rpartition(".")[0]
    parts = name.split(".")
    if init or old_pkg != PKG or parts[-1] not in moves:
        return old_pkg, old_pkg
    new = f"{PKG}.{moves[parts[-1]]}"
    return old_pkg, new if moves[parts[-1]] == parts[-1] else new.rpartition(".")[0]


def spelt(target: str, level: int, package: str) -> str:
    """The module text of an import of `target`: relative from `package` if it was relative."""
    return relative(target, package) if level else target


def rewrite_imports(source: str, where: tuple[str, bool] | None, moves: dict[str, str]) -> str:
    """Imports naming a moved module (or any relative import of a moved file) rewritten; `where` is
    the file's (module, is a package) before the moves, None outside the package."""
    try:
        tree = ast.parse(source)
    except SyntaxError:
        return source
    old_pkg, new_pkg = packages_of(where, moves) if where else ("", "")
    lines = source.splitlines(keepends=True)
    edits: list[tuple[int, int, int, int, str]] = []
    head = re.compile(r"from\s+[.\w]+\s+import")
    for node in ast.walk(tree):
        if not isinstance(node, ast.ImportFrom) or (node.level and not where):
            continue
        assert node.end_lineno is not None and node.end_col_offset is not None
        if node.level:
            up = old_pkg.split(".")[: len(old_pkg.split(".")) - node.level + 1]
            base = ".".join(up + ([node.module] if node.module else []))
        else:
            base = node.module or ""
        new_base = remap(base, moves)
        stay: list[ast.alias] = []
        split: dict[str, list[str]] = {}
        for alias in node.names:
            module = f"{base}.{alias.name}"
            # a public name (PUBLIC) imported from ecs_engine.render is render/__init__.py's own
            public = base == PKG and alias.name in PUBLIC
            if new_base == base and remap(module, moves) != module and not public:
                parent, _, last = remap(module, moves).rpartition(".")
                bound = alias.asname or alias.name
                split.setdefault(parent, []).append(last if last == bound else f"{last} as {bound}")
            else:
                stay.append(alias)
        if not split and new_base == base and (not node.level or new_pkg == old_pkg):
            continue
        first = lines[node.lineno - 1]
        if not split:  # only the module's text changes: names, brackets and comments are kept
            found = head.search(first, node.col_offset)
            assert found, first
            text = first[: found.start()] + f"from {spelt(new_base, node.level, new_pkg)} import" + first[found.end() :]
            edits.append((node.lineno, 0, node.lineno, len(first.encode()), text))
            continue
        stmts = []
        if stay:
            names = ", ".join(a.name + (f" as {a.asname}" if a.asname else "") for a in stay)
            stmts.append(f"from {spelt(new_base, node.level, new_pkg)} import {names}")
        stmts += [f"from {spelt(p, node.level, new_pkg)} import {', '.join(n)}" for p, n in split.items()]
        text = ("\n" + " " * node.col_offset).join(stmts)
        edits.append((node.lineno, node.col_offset, node.end_lineno, node.end_col_offset, text))
    for l0, c0, l1, c1, text in sorted(edits, reverse=True):
        # ast's columns count UTF-8 bytes
        start, end = lines[l0 - 1].encode()[:c0].decode(), lines[l1 - 1].encode()[c1:].decode()
        lines[l0 - 1 : l1] = [start + text + end]
    return "".join(lines)


def rewrite_text(text: str, rel: str, moves: dict[str, str]) -> str:
    """Dotted names, prose paths, render-relative path strings and (game-facing files) the public
    names' imports."""
    if not moves:
        return text
    olds = "|".join(sorted((re.escape(o) for o in moves if moves[o] != o), key=len, reverse=True))
    if rel.startswith(GAME_FACING):
        text = _public_imports(text, moves)
    if olds:
        dotted = re.compile(rf"(?<![\w.])ecs_engine\.render\.({olds})(?!\w)")
        text = dotted.sub(lambda m: f"{PKG}.{moves[m.group(1)]}", text)
    every = "|".join(sorted((re.escape(o) for o in moves), key=len, reverse=True))
    if rel not in NO_PATH_PROSE:
        prose = re.compile(rf"(?<![\w/.])((?:ecs_engine/)?render/)({every})\.py\b")
        text = prose.sub(lambda m: m.group(1) + new_file(m.group(2)).relative_to(RENDER).as_posix(), text)
    if rel.endswith(".py"):
        literal = re.compile(rf"([\"'])({every})\.py\1")
        text = literal.sub(
            lambda m: m.group(1) + new_file(m.group(2)).relative_to(RENDER).as_posix() + m.group(1), text
        )
    return text


def _isort_key(name: str) -> tuple[int, str]:
    return (0 if name.isupper() else 1 if name[:1].isupper() else 2, name)


def _public_imports(text: str, moves: dict[str, str]) -> str:
    """One-line imports of public names only, from their old modules: from ecs_engine.render, the
    lines of a run merged into one."""
    line = re.compile(r"^([ \t]*)from ecs_engine\.render\.(\w+) import ([\w, ]+)$")
    out: list[str] = []
    run: tuple[str, list[str]] | None = None
    for raw in text.split("\n"):
        m = line.match(raw)
        names = [n.strip() for n in m.group(3).split(",")] if m else []
        public = bool(m) and m.group(2) in moves and all(PUBLIC.get(n) == moves[m.group(2)] for n in names)
        if public and run and run[0] == m.group(1):
            run[1].extend(names)
            continue
        if run:
            out.append(f"{run[0]}from {PKG} import {', '.join(sorted(set(run[1]), key=_isort_key))}")
            run = None
        if public:
            run = (m.group(1), names)
        else:
            out.append(raw)
    if run:
        out.append(f"{run[0]}from {PKG} import {', '.join(sorted(set(run[1]), key=_isort_key))}")
    return "\n".join(out)


def rewrite_file(path: Path, moves: dict[str, str], text: str | None = None) -> str:
    text = path.read_text() if text is None else text
    rel = path.relative_to(ROOT).as_posix() if path.is_relative_to(ROOT) else path.as_posix()
    if path.suffix == ".py":
        if rel.startswith(GAME_FACING):  # before the imports' renames, which would hide the old modules
            text = _public_imports(text, moves)
        where = module_of(path, moves) if path.is_relative_to(ROOT) else None
        text = rewrite_imports(text, where, moves)
    return rewrite_text(text, rel, moves)


def scanned_files() -> list[Path]:
    listed = subprocess.run(
        ["git", "ls-files", "--cached", "--others", "--exclude-standard"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
    ).stdout.split()
    keep = []
    for rel in sorted(set(listed)):
        top = rel.split("/")[0]
        ok_place = top in SCANNED or ("/" not in rel and rel.endswith((".md", ".toml")))
        if (
            ok_place
            and rel.endswith((".py", ".md", ".toml"))
            and not rel.startswith(SKIPPED)
            and (ROOT / rel).is_file()
        ):
            keep.append(ROOT / rel)
    return keep


def public_init() -> str:
    by_module: dict[str, list[str]] = {}
    for name, module in PUBLIC.items():
        by_module.setdefault(module, []).append(name)
    checks = "\n".join(
        f"    from .{m} import {', '.join(sorted(n, key=_isort_key))}" for m, n in sorted(by_module.items())
    )
    table = "\n".join(f'    "{n}": "{m}",' for n, m in PUBLIC.items())
    listed = "\n".join(f'    "{n}",' for n in sorted(PUBLIC, key=_isort_key))
    packages = "\n".join(textwrap.fill(f"- {p}/: {d}", 96, subsequent_indent="  ") for p, d in PACKAGES.items())
    return f'''"""From the world to the GPU, by concern: graph/ (the frame graph), config/ (one render
configuration and its rules), extract/ (the World turned into the frame's snapshot), culling/,
post/ (post effects as plugins), and
{packages}
layouts.py holds the layouts the CPU and the shaders share; picking.py the entity under a pixel.

Games import what scenes are made of from here (`from ecs_engine.render import Material, Meshes,
cube_mesh`): each name is loaded on first use, so importing one module of a sub-package loads no
other (numba's kernels, trimesh). Code of the engine imports the module that defines a name.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
{checks}

_PUBLIC = {{
{table}
}}


def __getattr__(name: str) -> Any:
    if name in _PUBLIC:
        return getattr(importlib.import_module(f".{{_PUBLIC[name]}}", __name__), name)
    raise AttributeError(f"module {{__name__!r}} has no attribute {{name!r}}")


__all__ = [
{listed}
]
'''


def list_packages(text: str) -> str:
    m = re.search(r"^packages = \[(.*)\]$", text, re.M)
    if not m:
        print("pyproject.toml: no one-line packages list found; add the render packages by hand")
        return text
    listed = re.findall(r'"([^"]+)"', m.group(1))
    found = sorted(
        f"{PKG}.{p.parent.relative_to(RENDER).as_posix().replace('/', '.')}" for p in RENDER.glob("*/__init__.py")
    )
    missing = [p for p in found if p not in listed]
    if not missing:
        return text
    return text[: m.start(1)] + ", ".join(f'"{p}"' for p in listed + missing) + text[m.end(1) :]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--dry-run", action="store_true", help="print the plan, change nothing")
    ap.add_argument("--rewrite-only", nargs="+", metavar="PATH", help="rewrite old imports in these files or folders")
    args = ap.parse_args()
    if args.rewrite_only:
        files = [f for p in map(Path, args.rewrite_only) for f in (sorted(p.rglob("*.py")) if p.is_dir() else [p])]
        for f in files:
            new = rewrite_file(f.resolve(), MOVES)
            if new != f.read_text():
                print(f"rewritten: {f}")
                if not args.dry_run:
                    f.write_text(new)
        return 0
    top = sorted(p.stem for p in RENDER.glob("*.py"))
    moves = {old: new for old, new in MOVES.items() if old in top}
    done = [old for old in MOVES if old not in top and new_file(old).exists()]
    if done:
        print(f"table: {len(done)} modules already moved")
    for old in sorted(set(MOVES) - set(moves) - set(done)):
        print(f"table: render/{old}.py -> {new_file(old).relative_to(RENDER)} (no such file, skipped)")
    unmapped = [m for m in top if m not in MOVES and m not in STAY]
    for m in unmapped:
        print(f"NOT IN THE TABLE, left in place: render/{m}.py")
    for old in sorted(moves):
        print(f"move: render/{old}.py -> render/{new_file(old).relative_to(RENDER)}")
    # references are rewritten even when nothing moves now: a branch merged after the move
    # brings old imports of modules that moved before
    every = {old: MOVES[old] for old in [*done, *moves]}
    changed = {}
    for f in scanned_files():
        text = original = f.read_text()
        for module, name, old_text, new_text, why in FIXUPS:
            if module in every and f == ROOT / name and old_text in text and not (new_text and new_text in text):
                text = text.replace(old_text, new_text)
                print(f"fix-up: {name}: {why}")
        if f.relative_to(ROOT).as_posix() not in KEEP_OLD_PATHS:
            text = rewrite_file(f, every, text)
        if text != original:
            changed[f] = text
            print(f"rewrite: {f.relative_to(ROOT)}")
    if args.dry_run:
        return 0
    for old in sorted(moves):
        target = new_file(old)
        target.parent.mkdir(parents=True, exist_ok=True)
        subprocess.run(["git", "mv", str(RENDER / f"{old}.py"), str(target)], cwd=ROOT, check=True)
        if RENDER / f"{old}.py" in changed:
            changed[target] = changed.pop(RENDER / f"{old}.py")
    for package, doc in PACKAGES.items():
        init = RENDER / package / "__init__.py"
        if (RENDER / package).is_dir() and not init.exists():
            init.write_text(f'"""{textwrap.fill(doc, 96)}"""\n')
            subprocess.run(["git", "add", str(init)], cwd=ROOT, check=True)
            print(f"created: {init.relative_to(ROOT)}")
    init = RENDER / "__init__.py"
    if moves and "_PUBLIC" not in init.read_text():
        changed[init] = public_init()
    pyproject = ROOT / "pyproject.toml"
    changed[pyproject] = list_packages(changed.get(pyproject, pyproject.read_text()))
    for f, text in changed.items():
        if text != f.read_text():
            f.write_text(text)
    py = [str(f) for f in changed if f.suffix == ".py"] + [str(p) for p in RENDER.glob("*/__init__.py")]
    if py:
        ruff = [sys.executable, "-m", "ruff"]
        # renamed imports may sort elsewhere and run longer than a line
        sort = subprocess.run([*ruff, "check", "--fix", "--select", "I,RUF022", "--quiet", *py], cwd=ROOT, check=False)
        form = subprocess.run([*ruff, "format", "--quiet", *py], cwd=ROOT, check=False)
        if sort.returncode or form.returncode:
            print("ruff failed (run this with the project's .venv/bin/python): sort the imports and format by hand")
    return 0


if __name__ == "__main__":
    sys.exit(main())
