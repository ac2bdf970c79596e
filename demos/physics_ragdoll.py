"""A ragdoll for the physics playground (demos/physics_playground.py): a body of eleven parts,
boxes for the pelvis and chest, a ball for the head and capsules for the limbs, joined as a
body is (balls at the shoulders and hips, hinges within a person's limits at the spine, neck,
elbows and knees). Its parts pass through one another (category RAGDOLL, left out of their
masks) but touch everything else."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ecs_engine import World
from ecs_engine.components import Mesh, Transform
from ecs_engine.components.physics import BALL, BOX, CAPSULE, HINGE, SPHERE, Collider, Joint, RigidBody

RAGDOLL = 16  # the parts' collision category
TOUCHES = 0xFFFF & ~RAGDOLL  # their mask: everything but one another


@dataclass(frozen=True)
class Part:
    """A part standing upright with its feet at y = 0: its shape and Collider size, its centre,
    its mass (kg), and the joint to the part it hangs from (`parent`, an index into PARTS; -1:
    none) at `pivot`, a hinge about x within `limits` or a ball."""

    name: str
    shape: int
    size: tuple[float, float, float]
    centre: tuple[float, float, float]
    mass: float
    parent: int = -1
    pivot: tuple[float, float, float] = (0.0, 0.0, 0.0)
    joint: int = BALL
    limits: tuple[float, float] = (-np.inf, np.inf)


def _limb(name: str, x: float, top: float, length: float, radius: float, mass: float, parent: int, joint: int,
          limits: tuple[float, float] = (-np.inf, np.inf)) -> Part:  # fmt: skip
    """A capsule hanging from (x, top) down `length` (its ends included), joined there."""
    half = (length - 2 * radius) / 2
    return Part(
        name, CAPSULE, (radius, half, radius), (x, top - length / 2, 0.0), mass, parent, (x, top, 0.0), joint, limits
    )


BEND = (-2.3, 0.0)  # an elbow's or a knee's hinge about x: one way only, as a person's
PARTS = (
    Part("pelvis", BOX, (0.16, 0.1, 0.1), (0.0, 1.0, 0.0), 12.0),
    Part("chest", BOX, (0.18, 0.2, 0.11), (0.0, 1.31, 0.0), 18.0, 0, (0.0, 1.1, 0.0), HINGE, (-0.4, 0.7)),
    Part("head", SPHERE, (0.12, 0.12, 0.12), (0.0, 1.65, 0.0), 5.0, 1, (0.0, 1.52, 0.0), HINGE, (-0.6, 0.6)),
    _limb("left upper arm", -0.25, 1.48, 0.32, 0.05, 2.0, 1, BALL),
    _limb("left forearm", -0.25, 1.16, 0.3, 0.045, 1.5, 3, HINGE, BEND),
    _limb("right upper arm", 0.25, 1.48, 0.32, 0.05, 2.0, 1, BALL),
    _limb("right forearm", 0.25, 1.16, 0.3, 0.045, 1.5, 5, HINGE, BEND),
    _limb("left thigh", -0.09, 0.9, 0.46, 0.07, 7.0, 0, BALL),
    _limb("left shin", -0.09, 0.44, 0.44, 0.06, 4.0, 7, HINGE, (0.0, 2.3)),
    _limb("right thigh", 0.09, 0.9, 0.46, 0.07, 7.0, 0, BALL),
    _limb("right shin", 0.09, 0.44, 0.44, 0.06, 4.0, 9, HINGE, (0.0, 2.3)),
)


def spawn_ragdoll(world: World, at: tuple[float, float, float], box: int, ball: int, limb: int, look: int) -> list[int]:
    """A ragdoll standing with its feet at `at`, drawn with the meshes `box` (a unit cube),
    `ball` (a sphere of radius 0.5) and `limb` (a cylinder of radius 0.5 and height 1): its
    parts' entities, in PARTS' order."""
    made: list[int] = []
    offset = np.asarray(at, np.float64)
    for part in PARTS:
        centre = tuple((np.asarray(part.centre) + offset).tolist())
        if part.shape == BOX:
            drawn, scale = box, tuple(2 * s for s in part.size)
        elif part.shape == SPHERE:
            drawn, scale = ball, (2 * part.size[0],) * 3
        else:  # a capsule drawn as a cylinder as long as it, ends included
            drawn, scale = limb, (2 * part.size[0], 2 * (part.size[1] + part.size[0]), 2 * part.size[0])
        joint = []
        if part.parent >= 0:
            pivot = tuple((np.asarray(part.pivot) + offset).tolist())
            joint = [
                Joint(kind=part.joint, other=made[part.parent], pivot=pivot, axis=(1.0, 0.0, 0.0), limits=part.limits)
            ]
        made.append(
            world.spawn(
                Transform(position=centre, scale=scale),
                Mesh(handle=drawn, material=look),
                RigidBody(mass=part.mass),
                Collider(shape=part.shape, size=part.size, friction=0.8, category=RAGDOLL, mask=TOUCHES),
                *joint,
            )
        )
    return made
