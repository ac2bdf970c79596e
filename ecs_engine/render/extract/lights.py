"""Extract: the frame's light rows (light_rows.py), per table of point, spot and directional
lights. Reads the light components and Transform only."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ...components import DirectionalLight, PointLight, SpotLight, Transform
from ...ecs.schedule import any_with
from ...ecs.world import World
from ..lighting.rows import DirectionalLights, PositionalLights, local_minus_z, spot_cones

READS = (PointLight, SpotLight, DirectionalLight, Transform)  # a system running extract_lights declares these
LightKinds = tuple[Callable[[World], bool], ...]
KeptPoints = dict[int, tuple[Any, int, int, PositionalLights]]


def light_kinds() -> LightKinds:
    """Whether a world has point, spot and directional lights (run conditions, kept while its
    structure stays): absent kinds cost no query."""
    return any_with(PointLight, Transform), any_with(SpotLight, Transform), any_with(DirectionalLight, Transform)


def extract_lights(
    world: World, kinds: LightKinds | None = None, kept: KeptPoints | None = None
) -> tuple[list[PositionalLights], list[DirectionalLights]]:
    """Per table: point lights (views of their columns), spot lights (with the direction each
    shines, from its rotation, and its cone) and directional lights (see light_rows.py).
    `kinds`: light_kinds(); `kept`: a table's point lights, kept while it keeps its layout and
    rows (views see new values)."""
    points, spots, suns = kinds or (lambda w: True,) * 3
    kept = {} if kept is None else kept
    positional = []
    for batch in world.query(PointLight, Transform, write=()) if points(world) else ():
        table = batch.table
        found = kept.get(table.id)
        if found is None or found[0] is not table or found[1] != table.version or found[2] != len(batch):
            light = batch[PointLight]
            made = PositionalLights(
                batch[Transform].position, light.radius, light.color, light.intensity, entity=batch.entities
            )
            found = kept[table.id] = (table, table.version, len(batch), made)
        positional.append(found[3])
    for batch in world.query(SpotLight, Transform, write=()) if spots(world) else ():
        spot, transform = batch[SpotLight], batch[Transform]
        positional.append(
            PositionalLights(
                transform.position,
                spot.radius,
                spot.color,
                spot.intensity,
                local_minus_z(transform.rotation),
                spot_cones(spot.inner_angle, spot.outer_angle),
                batch.entities,
            )
        )
    directional = []
    for batch in world.query(DirectionalLight, Transform, write=()) if suns(world) else ():
        sun = batch[DirectionalLight]
        directional.append(
            DirectionalLights(local_minus_z(batch[Transform].rotation), sun.color, sun.illuminance, batch.entities)
        )
    return positional, directional
