"""The skins' part of a frame: every skin copy's joint matrices (animation/skins.py's
SkinSystem computed them) as the rows the vertex shader reads, relative to the render origin,
and per skinned mesh row where its joints start (its Instance.misc.w).

The joint rows are the skins' copies one after the other (skin 0's copies, then skin 1's...),
each copy's J matrices in joint order, 3 rows of 4 floats each (the matrix's last row is 0 0 0 1).
A skinned row's misc.w is (first joint + 1) << 1: 0 for a row no skin moves, bit 0 being the
indirect mode's ROW_NOT_CASTER."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ...animation.skins import Skins
from ...components.animation import Skinned

READS = (Skins, Skinned)
_SKIN, _COPY = (Skinned, "skin"), (Skinned, "copy")


@dataclass
class SkinFrame:
    joints: np.ndarray  # (N, 3, 4) float32: every copy's joint matrices, relative to the render origin
    first: np.ndarray  # per skin: its first copy's first joint row
    counts: np.ndarray  # per skin: its joints
    copies: np.ndarray  # per skin: its copies computed this frame
    key: tuple[int, ...]  # equal keys, equal rows' misc.w (the skins' sizes)

    def row_skins(self, table: Any, rows: int) -> np.ndarray | None:
        """Per row of `table` (its first `rows`), its misc.w; None for a table without Skinned. A row
        naming a skin or copy the frame lacks is drawn as it is, unskinned (0)."""
        if not table.has(Skinned):
            return None
        skin = table.columns[_SKIN][:rows].astype(np.int64)
        copy = table.columns[_COPY][:rows].astype(np.int64)
        known = (skin >= 0) & (skin < len(self.first))
        s = np.where(known, skin, 0)
        known &= copy < self.copies[s]
        start = self.first[s] + copy * self.counts[s]
        return np.where(known, (start + 1) << 1, 0).astype(np.uint32)


def extract_skins(world: Any, origin: np.ndarray) -> SkinFrame | None:
    """The world's skins as a SkinFrame, or None when no skin has copies posed. The joints' rows
    are the skins' own (one skin: no copy) when they were posed at this origin."""
    skins = world.resources.get(Skins)
    if skins is None or not any(s.matrices is not None for s in skins.skins):
        return None
    parts, first, counts, copies, at = [], [], [], [], 0
    for s in skins.skins:
        posed = s.matrices if s.matrices is not None else np.empty((0, s.joint_count, 3, 4), np.float32)
        first.append(at)
        counts.append(s.joint_count)
        copies.append(len(posed))
        at += posed.shape[0] * posed.shape[1]
        rows = posed.reshape(-1, 3, 4)
        if len(rows) and not np.array_equal(s.origin, origin):  # posed before the origin moved
            rows = rows.copy()
            rows[:, :, 3] += (s.origin - origin).astype(np.float32)
        parts.append(rows)
    joints = parts[0] if len(parts) == 1 else np.concatenate(parts)
    key = tuple(counts) + tuple(copies)
    return SkinFrame(joints, np.array(first), np.array(counts), np.array(copies), key)
