"""Playing animation clips (ecs_engine/animation): an `AnimationPlayer` on a character's root
entity plays a clip of the world's AnimationClips resource; every entity it moves carries an
`AnimationTarget` naming that player and its own place in the character (the id of its path of
names from the root, animation/clip.py's target_id), so one clip plays on every character whose
entities have the same names, whatever their ids."""

from __future__ import annotations

import numpy as np

from ecs_engine.ecs.schema import Component, Field

EVENT_NAME_LENGTH = 32  # characters of an AnimationEvent's name


class AnimationPlayer(Component):
    """The clip (a handle in AnimationClips; -1: none) at `time` seconds, moving at `speed` while
    `playing`; at the clip's end it starts again when `looping`, else it stops there (`playing`
    turns False).

    A cross-fade (animation/player.py's `crossfade`) keeps the clip it left in `from_clip`, at
    `from_time`, still moving, and blends it into `clip` over `fade` seconds (`faded` of them
    gone); then `from_clip` is -1 again."""

    clip = Field(np.int32, default=-1, minimum=-1)
    time = Field(np.float64, default=0.0, finite=True)
    speed = Field(np.float64, default=1.0, finite=True, minimum=-1e3, maximum=1e3)
    playing = Field(np.bool_, default=True)
    looping = Field(np.bool_, default=True)
    from_clip = Field(np.int32, default=-1, minimum=-1)
    from_time = Field(np.float64, default=0.0, finite=True)
    fade = Field(np.float64, default=0.0, finite=True, minimum=0.0)
    faded = Field(np.float64, default=0.0, finite=True, minimum=0.0)


class AnimationTarget(Component):
    """What an AnimationPlayer moves: `player`, the entity with the player, and `id`, the hash
    of this entity's path of names below it (animation/clip.py's target_id)."""

    player = Field(np.int64, default=-1, entity=True)
    id = Field(np.uint64, default=0)


class Skinned(Component):
    """A mesh its skin's joints move (animation/skins.py): `skin`, a skin of the world's Skins
    resource, and `copy`, which copy of that skin's joints (a prefab spawned many times has
    one copy per spawn). Its vertices follow the joints' world matrices, not its own: its
    ModelMatrix, which SkinSystem writes, only places `centre` and `radius` (its mesh's bounding
    sphere in the bind pose) around the pose, for culling, shadows and picking."""

    skin = Field(np.int32, default=-1, minimum=-1)
    copy = Field(np.int32, default=0, minimum=0)
    centre = Field(np.float32, 3, default=(0.0, 0.0, 0.0), finite=True)
    radius = Field(np.float32, default=0.0, finite=True, minimum=0.0)


class MorphWeights(Component):
    """How much each of its mesh's morph targets (render/assets/morph_targets.py) is applied: up
    to eight weights, the first as many as the mesh has targets. A clip's "weights" channel
    animates them on the node's entity."""

    weights = Field(np.float32, 8, default=(0.0,) * 8, finite=True)


class AnimationEvent(Component):
    """An event (world.events(AnimationEvent)) AnimationSystem sends when a player's time passes
    a time its clip marks (AnimationClips.mark): the `player` entity, its `clip`, the mark's
    `name` and its `time` in the clip (footsteps, a sword's hit, a sound's cue)."""

    player = Field(np.int64, default=-1, entity=True)
    clip = Field(np.int32, default=-1)
    name = Field(f"U{EVENT_NAME_LENGTH}", default="")
    time = Field(np.float64, default=0.0)


LAYERS = 2  # clips an AnimationLayers adds over a player's own


class AnimationLayers(Component):
    """Clips played over the AnimationPlayer's on the same entity, each on its own clock (`time`,
    `speed`, `playing`, `looping` as the player's), blended over what is below it by `weight` (0
    to 1: rotations by slerp, positions and scales linearly), on the targets of its `mask` only (a
    handle in the world's AnimationMasks, -1: every target). Layer 0 is applied first. An upper
    body waving over a walk is a layer with the walk's player below and an upper-body mask."""

    clip = Field(np.int32, LAYERS, default=(-1,) * LAYERS, minimum=-1)
    time = Field(np.float64, LAYERS, default=(0.0,) * LAYERS, finite=True)
    speed = Field(np.float64, LAYERS, default=(1.0,) * LAYERS, finite=True, minimum=-1e3, maximum=1e3)
    playing = Field(np.bool_, LAYERS, default=(True,) * LAYERS)
    looping = Field(np.bool_, LAYERS, default=(True,) * LAYERS)
    weight = Field(np.float64, LAYERS, default=(1.0,) * LAYERS, finite=True, minimum=0.0, maximum=1.0)
    mask = Field(np.int32, LAYERS, default=(-1,) * LAYERS, minimum=-1)
