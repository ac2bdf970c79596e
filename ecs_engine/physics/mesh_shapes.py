"""Bodies shaped by the entity's own data: its Mesh's convex hull (any motion) or triangles
(static only), the mesh's vertices scaled by the entity's Transform.scale as it is drawn; or its
HeightField (static only)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..components import Mesh
from ..components.physics import HEIGHT_FIELD, MESH, SHAPE_NAMES, STATIC, HeightField
from ..errors import UsageError


def make_from_mesh(
    world: Any, lib: Any, native: Any, motions: dict, e: int, shape: int, body: Any, col: Any, t: Any, r: int
) -> int:
    """The body of row `r` (entity `e`) of a table whose Collider.shape is CONVEX_HULL or MESH
    (`motions`: RigidBody.kind -> the library's motion's name)."""
    from ..render.assets.meshes import Meshes  # (numpy only: no GPU)

    name = SHAPE_NAMES[shape]
    if shape == HEIGHT_FIELD:
        return _height_field(world, native, e, body, col, t, r)
    meshes = world.resources.get(Meshes)
    if meshes is None or not world.has(e, Mesh):
        raise UsageError(f"entity {e}: a {name} Collider takes its shape from the entity's Mesh, and it has none")
    handle = int(world.get(e, Mesh).handle)
    if not 0 <= handle < len(meshes):
        raise UsageError(f"entity {e}: its Mesh.handle {handle} names no mesh (there are {len(meshes)})")
    data = meshes[handle]
    points = np.ascontiguousarray((data.positions.astype(np.float64) * t.scale[r]).astype(np.float32))
    kind = int(body.kind[r])
    place = {"pos": tuple(t.position[r].tolist()), "rot": tuple(t.rotation[r].tolist())}
    filters = {"user_data": e, "category": int(col.category[r]), "mask": int(col.mask[r])}
    if shape == MESH:
        if kind != STATIC:
            raise UsageError(
                f"entity {e}: a mesh Collider is for static bodies (RigidBody.kind STATIC); "
                "a moving one takes CONVEX_HULL"
            )
        if len(data.indices) < 3:
            raise UsageError(f"entity {e}: its mesh has no triangles to collide with")
        indices = np.ascontiguousarray(data.indices, np.uint32)
        return int(native.create_mesh_body(vertices=points.ravel(), indices=indices, **place, **filters))
    if len(points) < 4:
        raise UsageError(f"entity {e}: a convex hull needs 4 points or more, its mesh has {len(points)}")
    return int(
        native.create_convex_hull(
            points=points.ravel(),
            motion=getattr(lib, motions[kind]),
            mass=float(body.mass[r]),
            is_sensor=bool(col.sensor[r]),
            friction=float(col.friction[r]),
            restitution=float(col.restitution[r]),
            ccd=bool(body.ccd[r]),
            **place,
            **filters,
        )
    )


def _height_field(world: Any, native: Any, e: int, body: Any, col: Any, t: Any, r: int) -> int:
    if int(body.kind[r]) != STATIC:
        raise UsageError(f"entity {e}: a height field Collider is for static bodies (RigidBody.kind STATIC)")
    if not world.has(e, HeightField):
        raise UsageError(
            f"entity {e}: a height field Collider takes its heights from the entity's HeightField, and it has none"
        )
    field = world.get(e, HeightField)
    heights = np.asarray(field.heights, np.float64) if field.heights is not None else np.zeros((0, 0))
    if heights.ndim != 2 or heights.shape[0] != heights.shape[1] or heights.shape[0] < 2:
        raise UsageError(f"entity {e}: HeightField.heights must be a square grid of 2 x 2 or more, got {heights.shape}")
    if not np.isfinite(heights).all():
        raise UsageError(f"entity {e}: HeightField.heights must be finite")
    spacing = float(field.spacing)
    return int(
        native.create_heightfield(
            pos=tuple(t.position[r].tolist()),
            rot=tuple(t.rotation[r].tolist()),
            scale=(spacing, 1.0, spacing),
            heights=np.ascontiguousarray(heights, np.float32).ravel(),
            grid_size=len(heights),
            user_data=e,
            category=int(col.category[r]),
            mask=int(col.mask[r]),
            friction=float(col.friction[r]),
            restitution=float(col.restitution[r]),
        )
    )
