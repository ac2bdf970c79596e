"""What every scene-file codec of render assets shares (scene_assets.py: materials and
environment; scene_meshes.py: meshes): reading a typed value from a saved JSON document, and a
resource planned against the target world, committed only once every resource has planned."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ...ecs.scene_file import Remaps


def doc_value(value: Any, kind: type, what: str) -> Any:
    """`value` if it is a `kind` (a float may be written as an int; a bool is no number)."""
    kinds = (int, float) if kind is float else kind
    if not isinstance(value, kinds) or (isinstance(value, bool) and kind is not bool):
        raise ValueError(f"{what} must be a {kind.__name__}, got {str(value)[:80]}")
    return float(value) if isinstance(value, (int, float)) and kind is float else value


@dataclass
class Prepared:
    """A resource planned against the target world: lookup tables now, changes at commit."""

    tables: Remaps
    apply: Any  # (world) -> None

    def remaps(self) -> Remaps:
        return self.tables

    def commit(self, world: Any) -> None:
        self.apply(world)
