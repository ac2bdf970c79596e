"""Extract: the shadow-casting lights (those with a `Shadow`, components/shadow.py), as copies of
the columns the shadow maps' views (shadow_views.py) and the traced lights (ray_shadows.py) are
made from. Reads the light components, Transform and Shadow only.

The snapshot is one object kept while nothing it copies can have changed (`views_stamp`), so a
pass may keep what it made from it while it gets the same object; a world without a Shadow costs
one run condition and gives None.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...components import DirectionalLight, PointLight, Shadow, SpotLight, Transform
from ...ecs.schedule import any_with
from ...ecs.schema import schema_of
from ...ecs.world import World

READS = (DirectionalLight, SpotLight, PointLight, Transform, Shadow)  # a system extracting casters declares these


@dataclass(frozen=True)
class ShadowRows:
    """The Shadow columns of a table's casting lights (components/shadow.py says what each means)."""

    resolution: np.ndarray
    cascades: np.ndarray
    distance: np.ndarray
    bias: np.ndarray
    normal_offset: np.ndarray
    filter: np.ndarray
    softness: np.ndarray


@dataclass(frozen=True)
class CasterRows:
    """One table's lights of one kind with a Shadow."""

    entities: np.ndarray
    position: np.ndarray  # (n, 3) float64, in the world
    rotation: np.ndarray  # (n, 4) float64 quaternions: a light shines along its local -Z
    radius: np.ndarray  # (n,) a spot or point light's range (0: unbounded); zeros for directional lights
    outer_angle: np.ndarray  # (n,) a spot light's outer cone angle; zeros for the other kinds
    shadow: ShadowRows


@dataclass(frozen=True)
class ShadowCasters:
    """Per kind, per table (in world order): the casting lights. Views are made in this order
    (directional, spot, point), the shadow map layers numbered so."""

    directional: tuple[CasterRows, ...]
    spot: tuple[CasterRows, ...]
    point: tuple[CasterRows, ...]
    stamp: tuple[Any, ...]  # views_stamp when it was extracted


# what is read of the lights: these components of the tables holding each kind
_READS = ((DirectionalLight, Transform, Shadow), (SpotLight, Transform, Shadow), (PointLight, Transform, Shadow))
_READ_COLUMNS: list[list[tuple[Any, str]]] = []  # per kind, its columns' keys (found on first use)
_SHADOW_FIELDS = tuple(f for f in ShadowRows.__dataclass_fields__)


def views_stamp(world: World) -> tuple[Any, ...]:
    """A value that stays equal while nothing `extract_shadow_casters` reads of the lights can
    have changed: per table holding a kind of casting light, its id, layout, rows and the change
    ticks of the light's, Transform's and Shadow's columns (World.change_stamp's rule: a write
    to any row of a table counts)."""
    if not _READ_COLUMNS:
        _READ_COLUMNS.extend([(ct, name) for ct in map(schema_of, kind) for name in ct.__fields__] for kind in _READS)
    out: list[Any] = []
    for kind, keys in zip(_READS, _READ_COLUMNS, strict=True):
        for table in world.query(*kind, write=()).tables:
            ticks = table.column_ticks
            out.append((table.id, table.version, table.count, *[ticks.get(k) for k in keys]))
    return tuple(out)


def _rows(batch: Any, light: Any) -> CasterRows:
    n = len(batch)
    shadow, transform, own = batch[Shadow], batch[Transform], batch[light]
    zeros = np.zeros(n)
    return CasterRows(
        np.array(batch.entities, np.int64),
        np.array(transform.position, np.float64),
        np.array(transform.rotation, np.float64),
        np.array(own.radius, np.float64) if light is not DirectionalLight else zeros,
        np.array(own.outer_angle, np.float64) if light is SpotLight else zeros,
        ShadowRows(*[np.array(getattr(shadow, name)) for name in _SHADOW_FIELDS]),
    )


def extract_shadow_casters(world: World, stamp: tuple[Any, ...] | None = None) -> ShadowCasters:
    """The casting lights of `world` (copies: the snapshot stays as it was when the world changes)."""
    directional, spot, point = (
        tuple(_rows(batch, kind[0]) for batch in world.query(*kind, write=()) if len(batch)) for kind in _READS
    )
    return ShadowCasters(directional, spot, point, views_stamp(world) if stamp is None else stamp)


class ShadowExtract:
    """extract_shadow_casters, the same object kept while the world and its views_stamp stay;
    None for a world without a Shadow (one run condition)."""

    def __init__(self) -> None:
        self._has = any_with(Shadow)  # kept while the world's structure stays
        self._kept: tuple[Any, tuple[Any, ...], ShadowCasters] | None = None  # (world, stamp, casters)

    def __call__(self, world: World) -> ShadowCasters | None:
        if not self._has(world):
            return None
        stamp = views_stamp(world)
        kept = self._kept
        if kept is not None and kept[0]() is world and kept[1] == stamp:
            return kept[2]
        casters = extract_shadow_casters(world, stamp)
        self._kept = (weakref.ref(world), stamp, casters)
        return casters
