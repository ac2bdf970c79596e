"""The skins' and morph targets' part of a frame: what the vertex shaders deform vertices by
(shaders/deform.glsl), as one array of vec4 rows (`rows`), and per mesh row the bits of
its Instance misc.z and misc.w that point into it (`row_extra`).

- Joint matrices: every skin copy's (animation/skins.py's SkinSystem posed them), the skins one
  after the other, each copy's J matrices in joint order, 3 rows each (the last row is 0 0 0 1),
  relative to the render origin. A skinned row's misc.w is (its first joint's row / 3 + 1) << 1
  (0: not skinned; bit 0 is the indirect mode's ROW_NOT_CASTER).
- Morph weights: after the joints, 2 rows (8 weights) for each row of every table with a mesh
  and MorphWeights. A morphed row's misc.z is (its first weights row + 1) << 1 (bit 0 is
  NotShadowReceiver's)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...animation.skins import Skins
from ...components import Mesh
from ...components.animation import MorphWeights, Skinned

READS = (Skins, Skinned, MorphWeights, Mesh)
_SKIN, _COPY, _WEIGHTS = (Skinned, "skin"), (Skinned, "copy"), (MorphWeights, "weights")


@dataclass
class DeformFrame:
    rows: np.ndarray  # (K, 4) float32: the joints' rows, then the morph weights' rows
    first: np.ndarray  # per skin: its first copy's first joint
    counts: np.ndarray  # per skin: its joints
    copies: np.ndarray  # per skin: its copies posed this frame
    morphs: dict[int, int] = field(default_factory=dict)  # table id -> its first weights row in `rows`
    key: tuple[Any, ...] = ()  # equal keys, equal rows' misc bits (the skins' and morph tables' sizes)

    def row_extra(self, table: Any, rows: int) -> np.ndarray | None:
        """Per row of `table` (its first `rows`), the bits it adds to its Instance's misc.z and
        misc.w (z | w << 32); None for a table neither skinned nor morphed. A row naming a skin
        or copy the frame lacks is drawn unskinned."""
        skinned, morphed = table.has(Skinned), table.id in self.morphs
        if not skinned and not morphed:
            return None
        extra = np.zeros(rows, np.uint64)
        if skinned:
            skin = table.columns[_SKIN][:rows].astype(np.int64)
            copy = table.columns[_COPY][:rows].astype(np.int64)
            known = (skin >= 0) & (skin < len(self.first))
            s = np.where(known, skin, 0)
            known &= copy < self.copies[s]
            start = self.first[s] + copy * self.counts[s]
            extra |= np.where(known, (start + 1) << 1, 0).astype(np.uint64) << np.uint64(32)
        if morphed:
            first = self.morphs[table.id] + 2 * np.arange(rows)
            extra |= ((first + 1) << 1).astype(np.uint64)
        return extra


def deformed(world: Any) -> bool:
    """Whether some entity is skinned or has morph weights (a structural answer: the usual world
    has neither, and its frame then skips extract_deform)."""
    return bool(world.query(Skinned, write=()).count() or world.query(MorphWeights, write=()).count())


def extract_deform(world: Any, origin: np.ndarray) -> DeformFrame | None:
    """The world's posed skins and morph weights as a DeformFrame, or None when it has neither.
    One skin and no morph targets: its own rows, not a copy (when posed at this origin)."""
    skins = world.resources.get(Skins)
    posed = skins is not None and any(s.matrices is not None for s in skins.skins)
    tables = [(b.table.id, b[MorphWeights].weights) for b in world.query(Mesh, MorphWeights, write=()) if len(b)]
    if not posed and not tables:
        return None
    parts, first, counts, copies, at = [], [], [], [], 0
    for s in skins.skins if skins is not None else []:
        matrices = s.matrices if s.matrices is not None else np.empty((0, s.joint_count, 3, 4), np.float32)
        first.append(at)
        counts.append(s.joint_count)
        copies.append(len(matrices))
        at += matrices.shape[0] * matrices.shape[1]
        rows = matrices.reshape(-1, 3, 4)
        if len(rows) and not np.array_equal(s.origin, origin):  # posed before the origin moved
            rows = rows.copy()
            rows[:, :, 3] += (s.origin - origin).astype(np.float32)
        parts.append(rows.reshape(-1, 4))
    morphs, row = {}, 3 * at
    for tid, weights in tables:
        morphs[tid] = row
        parts.append(np.asarray(weights, np.float32).reshape(-1, 4))
        row += 2 * len(weights)
    rows = parts[0] if len(parts) == 1 else np.concatenate(parts) if parts else np.zeros((0, 4), np.float32)
    key = (tuple(counts), tuple(copies), tuple((tid, len(w)) for tid, w in tables))
    first_, counts_, copies_ = (np.array(v, np.int64) for v in (first, counts, copies))
    return DeformFrame(rows, first_, counts_, copies_, morphs, key)
