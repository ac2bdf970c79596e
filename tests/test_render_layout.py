"""The layout of ecs_engine/render/ (issue 36): modules live in sub-packages by concern
(scripts/render_layout.py says which goes where, scripts/move_render.py moves them and rewrites
every reference), so the top level keeps only a few modules, and no file of the repository names
a module by its old path.

The two checks of the tree are skipped until the move is applied (render/frame/ exists): the move
is a script the lead runs on main once the branches that edit render/ in parallel are merged, and
until then the old paths are the real ones. Once applied they run for good, with no marker to
remove. The script's rewriting is checked here either way, on small sources."""

from __future__ import annotations

import importlib
import importlib.util
import sys
from pathlib import Path
from types import ModuleType

import pytest

import ecs_engine.render

ROOT = Path(__file__).resolve().parent.parent
RENDER = Path(ecs_engine.render.__file__).resolve().parent  # installed: the GPU host runs tests from a copy


def _script(name: str) -> ModuleType:
    """A module of scripts/ (not a package), loaded once; move_render imports render_layout."""
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(name, ROOT / "scripts" / f"{name}.py")
        assert spec is not None and spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
    return sys.modules[name]


layout = _script("render_layout")
mover = _script("move_render")
applied = pytest.mark.skipif(
    not (RENDER / "frame").is_dir(), reason="the sub-package move (scripts/move_render.py) is not applied yet"
)


@applied
def test_render_keeps_only_a_few_top_level_modules() -> None:
    top = sorted(p.stem for p in RENDER.glob("*.py"))
    assert set(top) <= set(layout.STAY), "put these in a sub-package (scripts/render_layout.py MOVES)"


@applied
def test_no_file_names_a_module_by_its_old_path() -> None:
    """A file the script would still rewrite names an old path (an import, a dotted name in a
    string, a path in prose): run `python scripts/move_render.py` (a branch merged after the move)."""
    if not (ROOT / ".git").exists():
        pytest.skip("reads the checkout's files (git ls-files): run from the repository")
    stale = [
        f.relative_to(ROOT).as_posix()
        for f in mover.scanned_files()
        if f.relative_to(ROOT).as_posix() not in layout.KEEP_OLD_PATHS
        if mover.rewrite_file(f, layout.MOVES) != f.read_text()
    ]
    assert stale == []


def test_the_table_moves_each_module_once_and_keeps_names_apart() -> None:
    news = list(layout.MOVES.values())
    assert len(news) == len(set(news))
    packages = {n.split(".")[0] for n in news if "." in n}
    existing = {p.parent.name for p in RENDER.glob("*/__init__.py")}
    assert packages <= set(layout.PACKAGES) | existing | set(layout.MOVES), packages
    for old, new in layout.MOVES.items():
        # a new name that starts with an old one would be rewritten again by a second run
        assert new == old or not any(new == o or new.startswith(o + ".") for o in layout.MOVES if layout.MOVES[o] != o)
        assert old not in layout.STAY


def test_every_public_name_is_where_the_table_says() -> None:
    moved = {new: old for old, new in layout.MOVES.items()}
    for name, module in layout.PUBLIC.items():
        here = module if (RENDER / f"{module.replace('.', '/')}.py").exists() else moved[module]
        assert hasattr(importlib.import_module(f"ecs_engine.render.{here}"), name), (name, here)


RENDERER = ("ecs_engine.render.renderer", False)


@pytest.mark.parametrize(
    ("source", "where", "expected"),
    [
        # a moved file's relative imports, from its new place (renderer.py -> frame/renderer.py)
        ("from .camera import X\n", RENDERER, "from .camera import X\n"),
        ("from .. import native\n", RENDERER, "from ... import native\n"),
        ("from .graph import Pass\n", RENDERER, "from ..graph import Pass\n"),
        ("from .config import Mode\n", RENDERER, "from ..config import Mode\n"),
        (
            "from .shadow_pass import (\n    A,  # why\n)\n",
            RENDERER,
            "from ..shadows.maps_pass import (\n    A,  # why\n)\n",
        ),
        # a module imported from its package: split by where each goes, the bound name kept
        (
            "from . import layouts, shadow_pass\n",
            RENDERER,
            "from .. import layouts\nfrom ..shadows import maps_pass as shadow_pass\n",
        ),
        (
            "    from . import temporal_kernels as k\n",
            ("ecs_engine.render.temporal_culling", False),
            "    from . import temporal_kernels as k\n",
        ),
        # a file that stays, importing a moved one
        (
            "from ..temporal_culling import T\n",
            ("ecs_engine.render.culling.temporal", False),
            "from .temporal_culling import T\n",
        ),
        (
            "from ..render.meshes import M\n",
            ("ecs_engine.app.session", False),
            "from ..render.assets.meshes import M\n",
        ),
        # config.py becomes config/__init__.py: its own relative imports start one level deeper
        (
            "from .config_support import C\nfrom .post import registry\n",
            ("ecs_engine.render.config", False),
            "from .choices import C\nfrom ..post import registry\n",
        ),
        # outside the package: absolute imports, strings, a public name left as it is
        (
            "from ecs_engine.render import graph, renderer as r\n",
            None,
            "from ecs_engine.render import graph\nfrom ecs_engine.render.frame import renderer as r\n",
        ),
        (
            'patch("ecs_engine.render.mesh_loading.read_user_file")\n',
            None,
            'patch("ecs_engine.render.assets.mesh_loading.read_user_file")\n',
        ),
        ("import ecs_engine.render.chunk_paths as c\n", None, "import ecs_engine.render.draw.chunk_paths as c\n"),
        ("from ecs_engine.render import materials\n", None, "from ecs_engine.render import materials\n"),
        (
            'ALLOWED = {"frame_data.py": 1}  # render/shadow_pass.py\n',
            None,
            'ALLOWED = {"extract/frame_data.py": 1}  # render/shadows/maps_pass.py\n',
        ),
    ],
)
def test_the_script_rewrites_each_form_once(source: str, where: tuple[str, bool] | None, expected: str) -> None:
    def rewrite(text: str) -> str:
        return mover.rewrite_text(mover.rewrite_imports(text, where, layout.MOVES), "tests/x.py", layout.MOVES)

    assert rewrite(source) == expected
    if where is None:
        assert rewrite(expected) == expected  # a second run changes nothing


def test_games_import_the_public_names_from_ecs_engine_render() -> None:
    """In docs (and demos, the README, the new-game template) a run of imports of public names
    becomes one import from ecs_engine.render; other names get their new module."""
    doc = [
        "```python",
        "from ecs_engine.render.materials import Material, materials",
        "from ecs_engine.render.meshes import Meshes",
        "from ecs_engine.render.mesh_lod import build_lods",
        "```",
    ]
    assert mover.rewrite_text("\n".join(doc), "docs/x.md", layout.MOVES).split("\n") == [
        "```python",
        "from ecs_engine.render import Material, Meshes, materials",
        "from ecs_engine.render.assets.mesh_lod import build_lods",
        "```",
    ]
    # the same lines in a test keep their modules
    assert "render.assets.materials import" in mover.rewrite_text("\n".join(doc), "tests/x.py", layout.MOVES)
