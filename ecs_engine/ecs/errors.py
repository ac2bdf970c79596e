"""Exceptions a user of the world can cause. Each message names the entity and the field."""

from __future__ import annotations


class EcsError(Exception):
    """Base class for errors raised by the ECS API."""


class DeadEntityError(EcsError, LookupError):
    """An entity id that was destroyed (or never existed) was used."""


class MissingComponentError(EcsError, LookupError):
    """The entity exists but does not have the requested component."""


class AccessError(EcsError, PermissionError):
    """A system asked for access it did not declare."""


def describe_entity(eid: int) -> str:
    """Human form of a 64-bit id: the raw value plus its index and generation."""
    eid = int(eid)
    return f"entity {eid} (index {eid & 0xFFFFFFFF}, generation {eid >> 32})"
