"""Every package folder is installed: pyproject lists its packages by hand (components/, systems/
and demos/ install under ecs_engine through package-dir), so a new sub-package left out of the
list works in an editable checkout and is missing from a wheel or a normal install."""

from __future__ import annotations

import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_every_package_folder_is_listed() -> None:
    setup = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    listed = set(setup["packages"])
    folders = {name: ROOT / path for name, path in setup.get("package-dir", {}).items() if name}
    folders.setdefault("ecs_engine", ROOT / "ecs_engine")
    found = set()
    for name, folder in folders.items():
        for init in folder.rglob("__init__.py"):
            rel = init.parent.relative_to(folder).parts
            found.add(".".join((name, *rel)))
    assert found - listed == set(), "add these to [tool.setuptools] packages in pyproject.toml"
