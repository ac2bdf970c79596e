"""Errors a user of the engine can cause outside the ECS API (the ECS's own are in ecs.errors)."""

from __future__ import annotations


class UsageError(Exception):
    """A problem with what the user asked for (bad file, bad value, no GPU): the CLI prints the
    message as one line and exits 2."""
