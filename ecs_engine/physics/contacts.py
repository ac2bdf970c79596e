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


def _sort_kernel(flags, body1, body2, point, normal, speed, known, owners, bodies, stays):  # pragma: no cover
    """The records in one pass: the Contact columns (a, b, phase, point, normal, speed,
    impulse) of those between two bodies of ours that are not sensors (STAY rows only with
    `stays`), and the Trigger columns (sensor, other, entered) of the bodies entering or
    leaving a sensor. `bodies`: (sensor, kind, mass, restitution) by entity index."""
    sensor, kind, mass, restitution = bodies
    n = len(flags)
    a, b, phase = np.empty(n, np.int64), np.empty(n, np.int64), np.empty(n, np.uint8)
    at, toward, met, impulse = np.empty((n, 3)), np.empty((n, 3)), np.empty(n), np.empty(n)
    sensors, others, entered = np.empty(n, np.int64), np.empty(n, np.int64), np.empty(n, np.bool_)
    k = t = 0
    for i in range(n):
        f = flags[i]
        if f == 1 and not stays:  # (most of a resting pile's records)
            continue
        ea, eb = _entity(known, owners, body1[i]), _entity(known, owners, body2[i])
        if ea < 0 or eb < 0:  # (a body made on `native` directly has no entity)
            continue
        p = BEGIN if f == 0 else (STAY if f == 1 else END)
        ia, ib = ea & INDEX_MASK, eb & INDEX_MASK
        if not (sensor[ia] or sensor[ib]):
            a[k], b[k], phase[k] = ea, eb, p
            for c in range(3):
                at[k, c], toward[k, c] = point[i, c], normal[i, c]
            met[k], impulse[k] = speed[i], 0.0
            if p == BEGIN:  # (STAY and END rows carry no impulse)
                inverse = 1.0 / mass[ia] if kind[ia] == DYNAMIC else 0.0
                inverse += 1.0 / mass[ib] if kind[ib] == DYNAMIC else 0.0
                if inverse > 0.0:
                    impulse[k] = (1.0 + max(restitution[ia], restitution[ib])) / inverse * met[k]
            k += 1
        elif p != STAY:
            sensors[t], others[t], entered[t] = (ea, eb, p == BEGIN) if sensor[ia] else (eb, ea, p == BEGIN)
            t += 1
    contacts = (a[:k], b[:k], phase[:k], at[:k], toward[:k], met[:k], impulse[:k])
    return contacts, (sensors[:t], others[:t], entered[:t])


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
    triggers = (np.where(a_sensor, a, b)[crossing], np.where(a_sensor, b, a)[crossing], phase[crossing] == BEGIN)
    rows, a, b, phase = rows[touching], a[touching], b[touching], phase[touching]
    speed = records["speed"][rows].astype(np.float64)
    impulse = np.where(phase == BEGIN, impact(physics.bodies, a, b) * speed, 0.0)
    point, normal = records["point"][rows].astype(np.float64), records["normal"][rows].astype(np.float64)
    return (a, b, phase, point, normal, speed, impulse), triggers


def sorted_records(records: np.ndarray, physics: Any, stays: bool) -> tuple:
    """The Contact columns and the Trigger columns of the library's records (_sort_kernel),
    compiled where numba is, else in NumPy."""
    if _sort is None:
        return _sort_numpy(records, physics, stays)
    bodies = physics.bodies
    spec = bodies.spec
    known, owners = bodies.by_handle
    by_entity = (bodies.sensor, bodies.kind, spec["mass"], spec["restitution"])
    fields = (records["flags"], records["body1"], records["body2"], records["point"], records["normal"])
    return _sort(*fields, records["speed"], known, owners, by_entity, stays)


def send_contacts(world: Any, physics: Any, raw: Any, touches: bool, stays: bool) -> None:
    """The library's contact records since the last step (`raw`) sent as Trigger events and,
    with `touches`, Contact events (STAY rows only with `stays`)."""
    records = np.frombuffer(raw, physics.contact_dtype)
    if not len(records):
        return
    contacts, triggers = sorted_records(records, physics, stays)
    if touches and len(contacts[0]):
        world.events(Contact).send_rows(dict(zip(Contact.__fields__, contacts)), len(contacts[0]))
    if len(triggers[0]):
        world.events(Trigger).send_rows(dict(zip(Trigger.__fields__, triggers)), len(triggers[0]))
