"""A render chunk's rows as top-level acceleration-structure instances (gpu/acceleration.py
AS_INSTANCE, VkAccelerationStructureInstanceKHR), written by the chunk jobs beside their
instance rows: a numba nogil kernel, and the NumPy reference it is tested against.

Every row of a chunk is an instance, culled or not (a shadow can fall from outside the view):
its camera-relative model rows 0-2 as the 3x4 transform, its row index as the custom index,
the mask 0xFF (0 for a table tagged NotShadowCaster: no ray with a non-zero mask sees it),
both faces hit (shadow rays must see the back of a one-sided mesh as well), and its mesh's
bottom level; a mesh without one (address 0) makes the instance inactive. A row whose material is
alpha-masked (`cutout`, per material; None where no material is) is forced non-opaque, so the
any-hit shader (shaders/shadow_rays.rahit) sees its hits; `rows` then gets each instance's mesh
handle and material, which that shader reads.
"""

from __future__ import annotations

import numpy as np

from ... import native

CASTER_MASK = 0xFF
FACING_CULL_DISABLE = 0x1  # VK_GEOMETRY_INSTANCE_TRIANGLE_FACING_CULL_DISABLE_BIT_KHR
FORCE_NO_OPAQUE = 0x8  # VK_GEOMETRY_INSTANCE_FORCE_NO_OPAQUE_BIT_KHR: the any-hit shader runs
INDEX_LIMIT = 1 << 24  # the custom index has 24 bits


def write_instances_numpy(
    model: np.ndarray,
    handle: np.ndarray,
    blas: np.ndarray,
    first: int,
    caster: bool,
    out: np.ndarray,
    material: np.ndarray | None = None,
    cutout: np.ndarray | None = None,
    rows: np.ndarray | None = None,
) -> None:
    """Reference version of `write_instances`."""
    n = len(handle)
    index = (np.arange(first, first + n, dtype=np.uint64) % INDEX_LIMIT).astype(np.uint32)
    out["transform"] = model[:, :3, :]
    out["index_mask"] = index | np.uint32((CASTER_MASK if caster else 0) << 24)
    out["sbt_flags"] = np.uint32(FACING_CULL_DISABLE << 24)
    out["blas"] = blas[handle]
    if cutout is not None:
        assert material is not None and rows is not None
        out["sbt_flags"] |= np.where(cutout[material], np.uint32(FORCE_NO_OPAQUE << 24), np.uint32(0))
        rows[:, 0] = handle
        rows[:, 1] = material


def _write_instances_kernel(
    model: np.ndarray,
    handle: np.ndarray,
    blas: np.ndarray,
    first: int,
    mask_word: int,
    floats: np.ndarray,
    words: np.ndarray,
    longs: np.ndarray,
    material: np.ndarray,
    cutout: np.ndarray,
    rows: np.ndarray,
) -> None:
    flags = np.uint32(FACING_CULL_DISABLE << 24)
    opaque_off = np.uint32(FORCE_NO_OPAQUE << 24)
    mask = np.uint32(mask_word)
    cutouts = len(cutout) > 0
    for i in range(len(handle)):
        o = 16 * i
        for r in range(3):
            for c in range(4):
                floats[o + 4 * r + c] = model[i, r, c]
        words[o + 12] = np.uint32((first + i) % INDEX_LIMIT) | mask
        words[o + 13] = flags
        longs[8 * i + 7] = blas[handle[i]]
        if cutouts:
            if cutout[material[i]]:
                words[o + 13] = flags | opaque_off
            rows[i, 0] = handle[i]
            rows[i, 1] = material[i]


_write_instances_native = native.njit(_write_instances_kernel)


_NO_CUTOUTS = np.zeros(0, dtype=bool)
_NO_ROWS = np.zeros((0, 2), dtype=np.uint32)


def write_instances(
    model: np.ndarray,
    handle: np.ndarray,
    blas: np.ndarray,
    first: int,
    caster: bool,
    out: np.ndarray,
    material: np.ndarray | None = None,
    cutout: np.ndarray | None = None,
    rows: np.ndarray | None = None,
) -> None:
    """Write AS_INSTANCE rows `out` (len(handle) of them) for a chunk's rows: `model` (n, 4, 4)
    float32, `handle` the mesh per row, `blas` the bottom-level address per mesh, `first` the
    chunk's first row (the custom index of its first instance). With `cutout` (per material,
    alpha-masked), `material` is the material per row and `rows` (n, 2) uint32 gets (mesh,
    material) per instance."""
    if len(handle) == 0:
        return
    if cutout is not None and (material is None or rows is None):
        raise ValueError("write_instances: cutout needs the rows' materials and the rows to write")
    if _write_instances_native is None:
        write_instances_numpy(model, handle, blas, first, caster, out, material, cutout, rows)
        return
    raw = out.view(np.uint8).reshape(-1)
    mask_word = (CASTER_MASK if caster else 0) << 24
    _write_instances_native(
        model,
        handle,
        blas,
        first,
        mask_word,
        raw.view(np.float32),
        raw.view(np.uint32),
        raw.view(np.uint64),
        handle if material is None else material,
        _NO_CUTOUTS if cutout is None else cutout,
        _NO_ROWS if rows is None else rows,
    )
