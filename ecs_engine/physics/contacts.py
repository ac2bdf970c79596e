"""The library's contact records turned into the ECS's events, in bulk: Contact for bodies that
touch, Trigger for bodies entering and leaving sensors (components/physics.py)."""

from __future__ import annotations

from typing import Any

import numpy as np

from .. import native
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


def _entity_kernel(known, owners, handle):  # pragma: no cover
    """The entity of a body handle (known: our handles, sorted; owners beside them), or -1."""
    lo, hi = 0, len(known)
    while lo < hi:
        mid = (lo + hi) // 2
        if known[mid] < handle:
            lo = mid + 1
        else:
            hi = mid
    return owners[lo] if lo < len(known) and known[lo] == handle else -1


_entity = native.inner(_entity_kernel)


def _sort_kernel(flags, body1, body2, known, owners, sensor, stays):  # pragma: no cover
    """The records in one pass: (rows, a, b, phase) of those between two bodies of ours that
    are not sensors (STAY rows only with `stays`), and (sensor, other, entered) of the bodies
    entering or leaving a sensor."""
    n = len(flags)
    rows, a, b, phase = np.empty(n, np.int64), np.empty(n, np.int64), np.empty(n, np.int64), np.empty(n, np.uint8)
    sensors, others, entered = np.empty(n, np.int64), np.empty(n, np.int64), np.empty(n, np.bool_)
    k = t = 0
    for i in range(n):
        f = flags[i]
        if f == 1 and not stays:  # (most of a resting pile's records)
            continue
        ea, eb = _entity(known, owners, body1[i]), _entity(known, owners, body2[i])
        if ea < 0 or eb < 0:  # (a body made on `native` directly has no entity)
            continue
        kind = BEGIN if f == 0 else (STAY if f == 1 else END)
        sa, sb = sensor[ea & INDEX_MASK], sensor[eb & INDEX_MASK]
        if not (sa or sb):
            rows[k], a[k], b[k], phase[k] = i, ea, eb, kind
            k += 1
        elif kind != STAY:
            sensors[t], others[t], entered[t] = (ea, eb, kind == BEGIN) if sa else (eb, ea, kind == BEGIN)
            t += 1
    return rows[:k], a[:k], b[:k], phase[:k], sensors[:t], others[:t], entered[:t]


_sort = native.njit(_sort_kernel)


def _sort_numpy(records: np.ndarray, physics: Any, stays: bool) -> tuple:
    """_sort_kernel's answer in NumPy (without numba)."""
    rows = np.arange(len(records)) if stays else np.flatnonzero(records["flags"] != 1)
    flags = records["flags"][rows]
    phase = np.asarray(_PHASES, np.uint8)[flags.clip(0, 2)]
    a, b = physics.bodies.entities_of(records["body1"][rows]), physics.bodies.entities_of(records["body2"][rows])
    ours = (a >= 0) & (b >= 0)
    rows, a, b, phase = rows[ours], a[ours], b[ours], phase[ours]
    sensor = physics.bodies.sensor
    a_sensor, b_sensor = sensor[a & INDEX_MASK], sensor[b & INDEX_MASK]
    touching = ~a_sensor & ~b_sensor
    crossing = ~touching & (phase != STAY)
    sensors = np.where(a_sensor, a, b)[crossing]
    others = np.where(a_sensor, b, a)[crossing]
    return rows[touching], a[touching], b[touching], phase[touching], sensors, others, phase[crossing] == BEGIN


def send_contacts(world: Any, physics: Any, raw: Any, touches: bool, stays: bool) -> None:
    """The library's contact records since the last step (`raw`) sent as Trigger events and,
    with `touches`, Contact events (STAY rows only with `stays`)."""
    records = np.frombuffer(raw, physics.contact_dtype)
    if not len(records):
        return
    if _sort is not None:
        known, owners = physics.bodies.by_handle
        sorted_ = _sort(
            records["flags"], records["body1"], records["body2"], known, owners, physics.bodies.sensor, stays
        )
    else:
        sorted_ = _sort_numpy(records, physics, stays)
    rows, a, b, phase, sensors, others, entered = sorted_
    if touches and len(rows):
        speed = records["speed"][rows].astype(np.float64)
        world.events(Contact).send(
            Contact(
                a=a,
                b=b,
                phase=phase,
                point=records["point"][rows].astype(np.float64),
                normal=records["normal"][rows].astype(np.float64),
                speed=speed,
                impulse=np.where(phase == BEGIN, impact(physics.bodies, a, b) * speed, 0.0),
            )
        )
    if len(sensors):
        world.events(Trigger).send(Trigger(sensor=sensors, other=others, entered=entered))
