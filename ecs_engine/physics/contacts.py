"""The library's contact records turned into the ECS's events, in bulk: Contact for bodies that
touch, Trigger for bodies entering and leaving sensors (components/physics.py)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..components.physics import BEGIN, DYNAMIC, END, STAY, Contact, Trigger
from ..ecs.entities import INDEX_MASK

# culverin's record of a contact (128 bytes; its positions are float64 in its double-precision
# builds, float32 and padded otherwise). Its documentation calls the float after the normal the
# impact's "impulse"; measured, it is the speed the bodies met at along the normal (a ball
# dropped from h: sqrt(2 g h), whatever its mass)
_SLIM = [("body1", np.uint64), ("body2", np.uint64)]
_AFTER = [("normal", np.float32, 3), ("speed", np.float32), ("sliding", np.float32), ("flags", np.uint32)]
_FAT = [
    ("udata1", np.uint64),
    ("udata2", np.uint64),
    ("relative_velocity", np.float32, 3),
    ("toi", np.float32),
    ("penetration", np.float32),
    ("materials", np.uint32, 2),
    ("sub_shapes", np.uint32, 2),
    ("pad_fat", np.uint32, 3),
]


def record_dtype(double: bool) -> np.dtype:
    position = [("point", np.float64 if double else np.float32, 3)]
    pad = [] if double else [("pad_slim", np.uint32, 3)]
    dtype = np.dtype(_SLIM + position + _AFTER + pad + _FAT)
    assert dtype.itemsize == 128, dtype.itemsize
    return dtype


# the library's phases (EVENT_ADDED, EVENT_PERSISTED, EVENT_REMOVED) in Contact.phase's order
_PHASES = (BEGIN, STAY, END)


def impact(bodies: Any, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Per pair of bodies (entities a and b), the impulse a unit speed of impact gives each:
    (1 + e) times their reduced mass, e the larger restitution (the library's combination), a
    body that is not dynamic counting as infinitely heavy."""
    sa, sb = a & INDEX_MASK, b & INDEX_MASK
    spec, dynamic = bodies.spec, bodies.kind == DYNAMIC
    inverse = np.where(dynamic[sa], 1.0 / spec["mass"][sa], 0.0) + np.where(dynamic[sb], 1.0 / spec["mass"][sb], 0.0)
    restitution = np.maximum(spec["restitution"][sa], spec["restitution"][sb])
    with np.errstate(divide="ignore"):
        return np.where(inverse > 0.0, (1.0 + restitution) / inverse, 0.0)


def send_contacts(world: Any, physics: Any, raw: Any, touches: bool, stays: bool) -> None:
    """The library's contact records since the last step (`raw`) sent as Trigger events and,
    with `touches`, Contact events (STAY rows only with `stays`)."""
    records = np.frombuffer(raw, physics.contact_dtype)
    if not len(records):
        return
    if not stays:  # most records of a resting pile are STAY: leave them before anything else
        records = records[records["flags"] != 1]
        if not len(records):
            return
    phase = np.asarray(_PHASES, np.uint8)[records["flags"].clip(0, 2)]
    a, b = physics.bodies.entities_of(records["body1"]), physics.bodies.entities_of(records["body2"])
    ours = (a >= 0) & (b >= 0)  # (a body made on `native` directly has no entity)
    sensor = physics.bodies.sensor
    a_sensor = np.zeros(len(a), bool)
    b_sensor = np.zeros(len(b), bool)
    a_sensor[ours] = sensor[a[ours] & INDEX_MASK]
    b_sensor[ours] = sensor[b[ours] & INDEX_MASK]
    touching = ours & ~a_sensor & ~b_sensor
    if touches and touching.any():
        a, b, phase = a[touching], b[touching], phase[touching]
        speed = records["speed"][touching].astype(np.float64)
        world.events(Contact).send(
            Contact(
                a=a,
                b=b,
                phase=phase,
                point=records["point"][touching].astype(np.float64),
                normal=records["normal"][touching].astype(np.float64),
                speed=speed,
                impulse=np.where(phase == BEGIN, impact(physics.bodies, a, b) * speed, 0.0),
            )
        )
    crossing = ours & (a_sensor | b_sensor) & (phase != STAY)
    if crossing.any():
        sensors = np.where(a_sensor, a, b)[crossing]
        others = np.where(a_sensor, b, a)[crossing]
        world.events(Trigger).send(Trigger(sensor=sensors, other=others, entered=phase[crossing] == BEGIN))
