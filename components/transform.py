"""Where an entity is: position (float64, world units), rotation, scale; and its derived matrices."""

from __future__ import annotations

import numpy as np

from ecs_engine.ecs.schema import Component, Field

# The largest length a stock component holds (positions, scales, distances, radii): the float32
# matrices and rows made from them stay finite (float32 ends at 3.4e38) with room to spare.
LIMIT = 1e30
# The smallest positive length where one must be positive (a near plane, a view's height): it
# stays a normal float32 (those end at 1.2e-38), not 0.
SMALLEST = 1e-30


class Transform(Component):
    """Position stays float64 so a world 10,000 km across keeps millimetre precision; the
    renderer subtracts the camera position before casting to float32. The rotation is a unit
    quaternion (x, y, z, w), normalised on write; a zero-length one is rejected. Position and
    scale components stay within +-1e30 (LIMIT), so the float32 matrices made from them stay
    finite (float32 ends at 3.4e38) and no infinity or NaN reaches the GPU."""

    position = Field(np.float64, (3,), default=(0.0, 0.0, 0.0), finite=True, minimum=-LIMIT, maximum=LIMIT)
    rotation = Field(np.float64, (4,), default=(0.0, 0.0, 0.0, 1.0), finite=True, unit=True)
    scale = Field(np.float64, (3,), default=(1.0, 1.0, 1.0), finite=True, minimum=-LIMIT, maximum=LIMIT)


class ModelMatrix(Component):
    """Written by the transform system: the camera-relative model matrix, float32, indexed
    [row, column] (see ecs_engine.maths.transform). The renderer reads only this: its vertex
    shader derives the normal matrix."""

    model = Field(np.float32, (4, 4), default=np.eye(4))


class NormalMatrix(Component):
    """Opt-in: the transform system also writes the 3x3 normal matrix (the model's cofactor,
    scaled so its largest column is 1) for entities that have this, for CPU-side use. The
    renderer does not need it; leaving it out of a million entities saves the transform system
    36 bytes a row (2.9 -> 1.7 ms at 1M entities and 16 threads on the GPU host)."""

    normal = Field(np.float32, (3, 3), default=np.eye(3))


class PreviousTransform(Component):
    """Position and rotation at the start of the last fixed step; an entity with it is drawn
    interpolated between the two (systems.SnapshotSystem writes it, systems.TransformSystem
    reads it)."""

    position = Field(np.float64, (3,), default=(0.0, 0.0, 0.0), finite=True)
    rotation = Field(np.float64, (4,), default=(0.0, 0.0, 0.0, 1.0), finite=True)
