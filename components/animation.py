"""Playing animation clips (ecs_engine/animation): an `AnimationPlayer` on a character's root
entity plays a clip of the world's AnimationClips resource; every entity it moves carries an
`AnimationTarget` naming that player and its own place in the character (the id of its path of
names from the root, animation/clip.py's target_id), so one clip plays on every character whose
entities have the same names, whatever their ids."""

from __future__ import annotations

import numpy as np

from ecs_engine.ecs.schema import Component, Field


class AnimationPlayer(Component):
    """The clip (a handle in AnimationClips; -1: none) at `time` seconds, moving at `speed` while
    `playing`; at the clip's end it starts again when `looping`, else it stops there (`playing`
    turns False)."""

    clip = Field(np.int32, default=-1, minimum=-1)
    time = Field(np.float64, default=0.0, finite=True)
    speed = Field(np.float64, default=1.0, finite=True, minimum=-1e3, maximum=1e3)
    playing = Field(np.bool_, default=True)
    looping = Field(np.bool_, default=True)


class AnimationTarget(Component):
    """What an AnimationPlayer moves: `player`, the entity with the player, and `id`, the hash
    of this entity's path of names below it (animation/clip.py's target_id)."""

    player = Field(np.int64, default=-1, entity=True)
    id = Field(np.uint64, default=0)
