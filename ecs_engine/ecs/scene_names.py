"""How a scene file names component types and finds them again: a type's stable name (its
`scene_name`, else module and qualified name, `__main__` named for the module its script is when
imported) and every Component subclass imported, by that name. Apart from scene_file.py (the
format, saving and loading) because naming is its own question, which App asks too: a run is
named for its script's module (main_module_name)."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

from .scene_archive import check
from .schema import Component


def component_name(ct: type[Component]) -> str:
    """The name a scene file gives a component type (see the module docstring)."""
    own = ct.__dict__.get("scene_name")
    if isinstance(own, str):
        return own
    module = (main_module_name() or "__main__") if ct.__module__ == "__main__" else ct.__module__
    return f"{module}.{ct.__qualname__}"


def main_module_name() -> str | None:
    """What `__main__` is called in a scene file: the name it has when imported. A script run as
    `python catch.py` is `catch`, as `ecs-engine play catch.py` imports it, so what one saves the
    other loads; `python -m pkg.game` is `pkg.game`. None for no file (the REPL, `python -c`)."""
    main = sys.modules.get("__main__")
    spec = getattr(main, "__spec__", None)
    if spec is not None and spec.name and spec.name != "__main__":
        return str(spec.name).removesuffix(".__main__")
    file = getattr(main, "__file__", None)
    return Path(file).stem if file else None


def check_saveable(ct: type[Component], target: Path) -> None:
    """One line for a component type that no loader could find again by its name."""
    if ct.__module__ == "__main__" and "scene_name" not in ct.__dict__ and main_module_name() is None:
        why = "it is defined in __main__ with no file (typed in the REPL or python -c)"
        check(False, target, f"cannot save {ct.__qualname__}: {why}; define it in a module or give it a scene_name")


def known_components() -> dict[str, type[Component] | None]:
    """Every Component subclass imported, by component_name. Where two share a name (a game
    module imported again: a second run in one process, a reload) the one its module binds now
    is the one; None where that does not settle it."""
    found: dict[str, list[type[Component]]] = {}
    todo = list(Component.__subclasses__())
    while todo:
        ct = todo.pop()
        todo.extend(ct.__subclasses__())
        if not any(f.is_object for f in ct.__fields__.values()):
            same = found.setdefault(component_name(ct), [])
            if ct not in same:
                same.append(ct)
    return {name: same[0] if len(same) == 1 else _bound_now(same) for name, same in found.items()}


def _bound_now(classes: list[type[Component]]) -> type[Component] | None:
    """Of classes sharing a name, the one their module's attribute is now (None if no one)."""
    ct = classes[0]
    where: Any = sys.modules.get(ct.__module__)
    if ct.__module__ == "__main__" and main_module_name() is not None:
        where = sys.modules.get(str(main_module_name()), where)
    for part in ct.__qualname__.split("."):
        where = getattr(where, part, None)
    return where if any(where is c for c in classes) else None
