"""Physics as components (the bodies are stepped by ecs_engine.physics, an optional extra).

A `RigidBody` with a `Collider` and a `Transform` is a body of the physics world: dynamic ones
are moved by it (their Transform written each fixed step, their Velocity and AngularVelocity
when they have them), kinematic ones follow their Transform and push dynamic ones, static ones
stay where they were made. The collider's size is in world units (the Transform's scale does
not scale it)."""

from __future__ import annotations

import numpy as np

from ecs_engine.ecs.schema import Component, Field

from .transform import LIMIT

# RigidBody.kind
DYNAMIC, KINEMATIC, STATIC = 0, 1, 2
# Collider.shape: what its `size` holds
BOX, SPHERE, CAPSULE, CYLINDER = 0, 1, 2, 3  # half extents (x, y, z); (radius,); (radius, half height)
# the entity's Mesh (its vertices scaled by the Transform's scale) wrapped in its convex hull, or
# its triangles as they are (static bodies only); `size` is not used
CONVEX_HULL, MESH = 4, 5
HEIGHT_FIELD = 6  # the entity's HeightField (static bodies only); `size` is not used
SHAPE_NAMES = {BOX: "box", SPHERE: "sphere", CAPSULE: "capsule", CYLINDER: "cylinder", CONVEX_HULL: "convex hull"}
SHAPE_NAMES.update({MESH: "mesh", HEIGHT_FIELD: "height field"})
PRIMITIVES = (BOX, SPHERE, CAPSULE, CYLINDER)  # the shapes `size` describes
# RigidBody.locked: the axes a body may not move or turn along (world axes; a mask of these)
LOCK_X, LOCK_Y, LOCK_Z, LOCK_ROTATE_X, LOCK_ROTATE_Y, LOCK_ROTATE_Z = 1, 2, 4, 8, 16, 32
LOCK_ROTATION = LOCK_ROTATE_X | LOCK_ROTATE_Y | LOCK_ROTATE_Z


class RigidBody(Component):
    """`kind`: DYNAMIC, KINEMATIC or STATIC; `mass` in kg (its inertia follows from the collider);
    `ccd`: continuous collision detection (small fast bodies that would pass through walls);
    `locked`: a mask of LOCK_* axes it may not move or turn along (a character upright:
    LOCK_ROTATION); `gravity_scale` (0: it floats); `linear_damping` and `angular_damping` (per
    second: each step takes that share of the velocity away, on top of the library's 0.05)."""

    kind = Field(np.uint8, default=DYNAMIC, maximum=STATIC)
    mass = Field(np.float64, default=1.0, finite=True, minimum=0.0, min_exclusive=True, maximum=LIMIT)
    ccd = Field(np.bool_, default=False)
    locked = Field(np.uint8, default=0, maximum=63)
    gravity_scale = Field(np.float64, default=1.0, finite=True, minimum=-LIMIT, maximum=LIMIT)
    linear_damping = Field(np.float64, default=0.0, finite=True, minimum=0.0, maximum=LIMIT)
    angular_damping = Field(np.float64, default=0.0, finite=True, minimum=0.0, maximum=LIMIT)


class Collider(Component):
    """The body's shape: `shape` (BOX, SPHERE, CAPSULE, CYLINDER) with its `size` (see the
    constants; the unused entries are ignored), CONVEX_HULL or MESH of the entity's Mesh, or
    HEIGHT_FIELD of its HeightField;
    `friction` and `restitution` (0: no bounce, 1: elastic); collision filtering by `category`
    and `mask` bits (two bodies touch when each one's category is in the other's mask);
    `sensor`: it reports what enters it and pushes nothing."""

    shape = Field(np.uint8, default=BOX, maximum=HEIGHT_FIELD)
    size = Field(np.float64, (3,), default=(0.5, 0.5, 0.5), finite=True, minimum=0.0, min_exclusive=True, maximum=LIMIT)
    friction = Field(np.float64, default=0.5, finite=True, minimum=0.0, maximum=LIMIT)
    restitution = Field(np.float64, default=0.0, finite=True, minimum=0.0, maximum=1.0)
    category = Field(np.uint16, default=0xFFFF)
    mask = Field(np.uint16, default=0xFFFF)
    sensor = Field(np.bool_, default=False)


class HeightField(Component):
    """Terrain for a static body whose Collider.shape is HEIGHT_FIELD: `heights` (m), a square
    grid of n x n samples (n of 2 or more), row by row along +z, each row along +x, `spacing`
    (m) apart; the entity's Transform.position is the grid's first corner."""

    heights = Field(object)
    spacing = Field(np.float64, default=1.0, finite=True, minimum=0.0, min_exclusive=True, maximum=LIMIT)


# Contact.phase
BEGIN, STAY, END = 0, 1, 2


class Contact(Component):
    """An event (world.events(Contact)), a row per touching pair and step, sent by PhysicsSystem:
    bodies `a` and `b` began touching (`phase` BEGIN), still touch (STAY: only when the
    PhysicsWorld reports them, `contacts="all"`) or parted (END: point, normal, speed and
    impulse zero); the contact `point`, the `normal` (pointing from a to b), the `speed` they
    met at along the normal (m/s) and, for BEGIN, the impact's `impulse` (N s): the momentum
    the collision gives each body along the normal, (1 + e) m v with e the pair's restitution
    (the larger one's, as the library combines them), m the pair's reduced mass (a static or
    kinematic body's counts as infinite) and v the speed; their turning is not counted. STAY
    rows carry no impulse (a resting body's support is not an impact)."""

    a = Field(np.int64, default=-1, entity=True)
    b = Field(np.int64, default=-1, entity=True)
    phase = Field(np.uint8, default=BEGIN, maximum=END)
    point = Field(np.float64, (3,), default=(0.0, 0.0, 0.0))
    normal = Field(np.float64, (3,), default=(0.0, 0.0, 0.0))
    speed = Field(np.float64, default=0.0)
    impulse = Field(np.float64, default=0.0)


class Trigger(Component):
    """An event (world.events(Trigger)) sent by PhysicsSystem: body `other` `entered` (or, False,
    left) the `sensor` (an entity whose Collider.sensor is set)."""

    sensor = Field(np.int64, default=-1, entity=True)
    other = Field(np.int64, default=-1, entity=True)
    entered = Field(np.bool_, default=True)


# Joint.kind
FIXED, HINGE, BALL, SLIDER, DISTANCE = 0, 1, 2, 3, 4
JOINT_NAMES = {FIXED: "fixed", HINGE: "hinge", BALL: "ball", SLIDER: "slider", DISTANCE: "distance"}


class Joint(Component):
    """Joins this entity's body to `other`'s (an entity with a body too), made with the bodies:
    FIXED (welded as they stand), BALL (turning freely about `pivot`), HINGE (turning about
    `axis` through `pivot`, within `limits` in radians), SLIDER (moving along `axis` through
    `pivot`, within `limits` in metres from where it started) or DISTANCE (their centres kept
    within `limits` metres apart; infinite limits: at the distance they start at). `pivot` and
    `axis` are in world space at the moment the joint is made; the bodies joined do not collide
    with each other only if their colliders' category and mask say so. A hinge or slider with a
    finite `target` has a motor driving it there (radians from where it was made, or metres
    along the axis), with at most `strength` (N m or N); a system may move the target."""

    kind = Field(np.uint8, default=HINGE, maximum=DISTANCE)
    other = Field(np.int64, default=-1, entity=True)
    pivot = Field(np.float64, (3,), default=(0.0, 0.0, 0.0), finite=True, minimum=-LIMIT, maximum=LIMIT)
    axis = Field(np.float64, (3,), default=(0.0, 1.0, 0.0), finite=True, unit=True)
    limits = Field(np.float64, (2,), default=(-np.inf, np.inf))
    target = Field(np.float64, default=np.nan)
    strength = Field(np.float64, default=1000.0, finite=True, minimum=0.0, min_exclusive=True, maximum=LIMIT)


class CharacterController(Component):
    """A walking capsule moved by the physics' character controller (with Transform; its
    position is the capsule's centre): `height` and `radius` (m), the highest `step_height` it
    walks up, the steepest `max_slope` it walks up (radians), the `strength` (N) it pushes
    dynamic bodies with. The game sets `walk` (m/s; its vertical part is ignored) and `jump` (the
    upward speed of a jump, taken at the next step on the ground, then set back to 0); the
    physics writes `grounded` and `vertical` (the speed along the world's up now, m/s)."""

    height = Field(np.float64, default=1.8, finite=True, minimum=0.0, min_exclusive=True, maximum=LIMIT)
    radius = Field(np.float64, default=0.4, finite=True, minimum=0.0, min_exclusive=True, maximum=LIMIT)
    step_height = Field(np.float64, default=0.4, finite=True, minimum=0.0, maximum=LIMIT)
    max_slope = Field(np.float64, default=np.pi / 4, finite=True, minimum=0.0, maximum=np.pi / 2)
    strength = Field(np.float64, default=100.0, finite=True, minimum=0.0, maximum=LIMIT)
    walk = Field(np.float64, (3,), default=(0.0, 0.0, 0.0), finite=True, minimum=-LIMIT, maximum=LIMIT)
    jump = Field(np.float64, default=0.0, finite=True, minimum=0.0, maximum=LIMIT)
    grounded = Field(np.bool_, default=False)
    vertical = Field(np.float64, default=0.0, finite=True)
