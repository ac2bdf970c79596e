"""Layers of clips over a player's (components/animation.py's AnimationLayers): each frame,
after AnimationSystem wrote the players' clips, AnimationLayerSystem moves every layer's clock
on and blends its clip over the Transforms and morph weights below, by its weight, on the
targets its mask names (the world's AnimationMasks). Masks are sets of target ids: `targets_below` gives a scene's
subtree's (an upper body: everything under the chest)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ecs_engine.components import Parent, Transform
from ecs_engine.components.animation import LAYERS, AnimationLayers, AnimationTarget, MorphWeights
from ecs_engine.ecs.schedule import System, any_with

from ..errors import UsageError
from .clip import AnimationClips, ClipChannel, target_id
from .player import _COLUMNS, _group, _moved, weights_to_parts
from .sampling import slerp


class AnimationMasks:
    """World resource: sets of target ids (AnimationLayers.mask names them by handle)."""

    def __init__(self) -> None:
        self.masks: list[np.ndarray] = []

    def add(self, ids: Any) -> int:
        """A mask of the target ids `ids` (AnimationTarget.id values, `target_id(path)`); its handle."""
        mask = np.unique(np.asarray(list(ids), np.uint64))
        if not len(mask):
            raise UsageError("an animation mask needs at least one target")
        self.masks.append(mask)
        return len(self.masks) - 1

    def __getitem__(self, handle: int) -> np.ndarray:
        if not 0 <= handle < len(self.masks):
            raise UsageError(f"no animation mask {handle}: the world has {len(self.masks)}")
        return self.masks[handle]


def targets_below(paths: Any, *roots: str) -> list[int]:
    """The target ids of the node `paths` (a scene's: "hips/spine/chest", ...) at or under any of
    `roots`: a mask's ids for `AnimationMasks.add`."""
    found = [p for p in paths if any(p == r or p.startswith(r + "/") for r in roots)]
    if not found:
        raise UsageError(f"no node at or under {', '.join(roots)}")
    return [target_id(p) for p in found]


class AnimationLayerSystem(System):
    def __init__(self) -> None:
        super().__init__(
            reads=[AnimationClips, AnimationMasks, AnimationTarget, Parent],
            writes=[AnimationLayers, Transform, MorphWeights],
            name="animation_layers",
            run_if=any_with(AnimationLayers),
        )

    def run(self, world: Any, dt: float) -> None:
        clips = world.resources.get(AnimationClips)
        if clips is None or not len(clips):
            return
        layers = _advance(world, clips, dt)
        if layers is None:
            return
        masks = world.resources.get(AnimationMasks)
        for batch in world.query(AnimationTarget, Transform):
            transform = batch[Transform]
            columns = {prop: getattr(transform, name) for prop, name in _COLUMNS.items()}
            _blend_layers(batch[AnimationTarget], columns, layers, clips, masks)
        if any(c.property == "weights" for clip in clips.clips for c in clip.channels):
            for batch in world.query(AnimationTarget, MorphWeights):  # the morph targets' weights
                _blend_layers(batch[AnimationTarget], {"weights": batch[MorphWeights].weights}, layers, clips, masks)
            weights_to_parts(world)


def _blend_layers(
    target: Any, columns: dict[str, np.ndarray], layers: tuple[np.ndarray, ...], clips: AnimationClips, masks: Any
) -> None:
    """Every layer's clip blended over `columns` (by property) of the rows `target` (their
    AnimationTarget) names, where a layer's player and mask take them."""
    entity, clip, time, weight, mask = layers
    at = np.minimum(np.searchsorted(entity, target.player), len(entity) - 1)
    found = entity[at] == target.player
    for k in range(LAYERS):
        playing = np.where(found, clip[at, k], -1)
        for c in np.unique(playing[playing >= 0]).tolist():
            rows = np.flatnonzero(playing == c)
            rows = rows[_in_mask(masks, mask[at[rows], k], target.id[rows])]
            if not len(rows):
                continue
            rows, spans = _group(rows, target.id, clips[c])
            _blend(columns, rows, spans, time[at[rows], k], weight[at[rows], k])


def _advance(world: Any, clips: AnimationClips, dt: float) -> tuple[np.ndarray, ...] | None:
    """Every layer's clock moved on (looping or held at its end, as a player's); then, sorted by
    entity: (entities, clip (n, L), time, weight, mask)."""
    durations = clips.durations()
    parts = []
    for batch in world.query(AnimationLayers):
        layer = batch[AnimationLayers]
        clip = layer.clip.astype(np.int64)
        if clip.max(initial=-1) >= len(clips):
            row = int(np.argwhere(clip >= len(clips))[0, 0])
            raise UsageError(
                f"entity {int(batch.entities[row])}: AnimationLayers.clip names clip {int(clip.max())}, "
                f"but the world's AnimationClips holds {len(clips)} clips"
            )
        layer.time, ended = _moved(layer.time, clip, layer, durations, dt)  # as a player's clock
        if ended.any():
            layer.playing = layer.playing & ~ended
        parts.append((batch.entities, clip, layer.time.copy(), layer.weight.copy(), layer.mask.astype(np.int64)))
    if not parts:
        return None
    columns = [np.concatenate(c) for c in zip(*parts)]
    order = np.argsort(columns[0])
    return tuple(c[order] for c in columns)


def _in_mask(masks: AnimationMasks | None, handles: np.ndarray, ids: np.ndarray) -> np.ndarray:
    """Per row, whether its target is in its layer's mask (-1: every target)."""
    keep = handles < 0
    for h in np.unique(handles[handles >= 0]).tolist():
        if masks is None:
            raise UsageError(f"AnimationLayers.mask names mask {h}, but the world has no AnimationMasks")
        mine = handles == h
        keep[mine] = np.isin(ids[mine], masks[h])
    return keep


def _blend(
    columns: dict[str, np.ndarray], rows: np.ndarray, spans: list[tuple[ClipChannel, int, int]],
    times: np.ndarray, weight: np.ndarray,
) -> None:  # fmt: skip
    """A layer's channels at `times` blended over the columns' rows by `weight` (per row)."""
    for channel, lo, hi in spans:
        column = columns.get(channel.property)
        if column is None:
            continue
        if channel.property == "weights":  # as many of the eight as the mesh has targets
            column = column[:, : channel.curve.values.shape[1]]
        here, w = rows[lo:hi], weight[lo:hi]
        value, now = channel.curve.sample(times[lo:hi]), column[here]
        column[here] = slerp(now, value, w) if channel.property == "rotation" else now + (value - now) * w[:, None]
