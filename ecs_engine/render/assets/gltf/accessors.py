"""glTF accessors decoded as the specification (3.6.2) says: component types, element types,
byte offsets and strides, matrix columns padded to 4 bytes, normalized integers mapped to
[0, 1] or [-1, 1], sparse substitutions over a buffer view or over zeros, and the bounds of
every byte checked against the view that holds it."""

from __future__ import annotations

from typing import Any

import numpy as np

# componentType -> little-endian dtype
COMPONENTS: dict[int, np.dtype] = {
    5120: np.dtype("<i1"),
    5121: np.dtype("<u1"),
    5122: np.dtype("<i2"),
    5123: np.dtype("<u2"),
    5125: np.dtype("<u4"),
    5126: np.dtype("<f4"),
}
# type -> the element's shape (matrices: rows, columns)
SHAPES: dict[str, tuple[int, ...]] = {
    "SCALAR": (),
    "VEC2": (2,),
    "VEC3": (3,),
    "VEC4": (4,),
    "MAT2": (2, 2),
    "MAT3": (3, 3),
    "MAT4": (4, 4),
}
SPARSE_INDICES = (5121, 5123, 5125)


def decode(document: Any, index: int) -> np.ndarray:
    """Accessor `index` of `document` (a GltfDocument: its JSON, views and errors) as an array
    (count, *shape): float32 for FLOAT and normalized integers, else the component's own
    integer type. Matrices come row-major (m[..., row, column]), as NumPy and the engine use them."""
    entry = document.json["accessors"][index]
    here = f"accessors[{index}]"
    component = entry.get("componentType")
    if component not in COMPONENTS:
        raise document.error(f"{here}.componentType", f"is {component!r}, not one of {sorted(COMPONENTS)}")
    kind = entry.get("type")
    if kind not in SHAPES:
        raise document.error(f"{here}.type", f"is {kind!r}, not one of {', '.join(SHAPES)}")
    dtype, shape = COMPONENTS[component], SHAPES[kind]
    count = document.number(entry, "count", here, minimum=1)
    normalized = entry.get("normalized", False)
    if normalized not in (True, False) or (normalized and component in (5125, 5126)):
        raise document.error(f"{here}.normalized", f"is {normalized!r} for componentType {component}")
    if "bufferView" in entry:
        values = _read(document, entry, here, dtype, shape, count)
    else:
        document.number(entry, "byteOffset", here, default=0)
        values = np.zeros((count, *shape), dtype)
    sparse = entry.get("sparse")
    if sparse is not None:
        values = _sparse(document, sparse, f"{here}.sparse", values, dtype, shape)
    if normalized:
        values = _normalized(values, dtype)
    if values.dtype.kind == "f" and not np.isfinite(values).all():
        row = int(np.flatnonzero(~np.isfinite(values.reshape(count, -1)).all(axis=1))[0])
        raise document.error(here, f"element {row} is not finite ({values[row].tolist()})")
    values.setflags(write=False)
    return values


def element_layout(dtype: np.dtype, shape: tuple[int, ...]) -> tuple[int, int, int]:
    """(bytes of one element as stored, columns, bytes of a column as stored): a matrix's
    columns start on 4-byte boundaries, so 1- and 2-byte MAT2 and MAT3 columns are padded."""
    if len(shape) == 2:
        rows, columns = shape
        column = rows * dtype.itemsize
        padded = column + (-column % 4)
        return padded * columns, columns, padded
    width = int(np.prod(shape)) if shape else 1
    return width * dtype.itemsize, 1, width * dtype.itemsize


def _read(
    document: Any, entry: dict[str, Any], here: str, dtype: np.dtype, shape: tuple[int, ...], count: int
) -> np.ndarray:
    data, view_offset, view_length, stride = document.view(
        document.number(entry, "bufferView", here), f"{here}.bufferView"
    )
    offset = document.number(entry, "byteOffset", here, default=0)
    size, columns, column = element_layout(dtype, shape)
    step = size if stride is None else stride
    if step < size:
        raise document.error(here, f"its view's byteStride {step} is shorter than one {size}-byte element")
    if offset % dtype.itemsize or (view_offset + offset) % dtype.itemsize:
        raise document.error(f"{here}.byteOffset", f"is {offset}, not aligned to its {dtype.itemsize}-byte components")
    end = offset + step * (count - 1) + size
    if end > view_length:
        raise document.error(here, f"{count} elements end at byte {end} of a {view_length}-byte buffer view")
    raw = np.frombuffer(data, np.uint8, count=end - offset, offset=view_offset + offset)
    rows = np.lib.stride_tricks.as_strided(raw, shape=(count, size), strides=(step, 1))
    if columns > 1:  # keep each column's bytes, not its padding; columns were stored one after another
        rows_per_column = shape[0] * dtype.itemsize
        rows = rows.reshape(count, columns, column)[:, :, :rows_per_column]
    flat = np.ascontiguousarray(rows).view(dtype)
    if len(shape) == 2:  # stored column-major: element [column][row]
        return np.ascontiguousarray(flat.reshape(count, shape[1], shape[0]).transpose(0, 2, 1))
    return flat.reshape(count, *shape)


def _sparse(
    document: Any, sparse: Any, here: str, values: np.ndarray, dtype: np.dtype, shape: tuple[int, ...]
) -> np.ndarray:
    if not isinstance(sparse, dict):
        raise document.error(here, "is not an object")
    count = document.number(sparse, "count", here, minimum=1)
    if count > len(values):
        raise document.error(f"{here}.count", f"is {count}, more than the accessor's {len(values)} elements")
    indices, where = sparse.get("indices"), f"{here}.indices"
    if not isinstance(indices, dict):
        raise document.error(where, "is not an object")
    component = indices.get("componentType")
    if component not in SPARSE_INDICES:
        raise document.error(f"{where}.componentType", f"is {component!r}, not one of {list(SPARSE_INDICES)}")
    at = _tight(document, indices, where, COMPONENTS[component], (), count).astype(np.int64)
    if (np.diff(at) <= 0).any() or at[-1] >= len(values):
        raise document.error(where, f"are not strictly increasing indices below {len(values)} ({at[:8].tolist()}...)")
    replaced = _tight(document, sparse.get("values"), f"{here}.values", dtype, shape, count)
    out = values.copy()
    out[at] = replaced
    return out


def _tight(document: Any, part: Any, where: str, dtype: np.dtype, shape: tuple[int, ...], count: int) -> np.ndarray:
    """A sparse section's indices or values: `count` tightly packed elements in a buffer view."""
    if not isinstance(part, dict):
        raise document.error(where, "is not an object")
    data, view_offset, view_length, _ = document.view(document.number(part, "bufferView", where), f"{where}.bufferView")
    offset = document.number(part, "byteOffset", where, default=0)
    size, columns, column = element_layout(dtype, shape)
    if offset + size * count > view_length:
        raise document.error(where, f"{count} elements end past its {view_length}-byte buffer view")
    raw = np.frombuffer(data, np.uint8, count=size * count, offset=view_offset + offset).reshape(count, size)
    if columns > 1:
        raw = raw.reshape(count, columns, column)[:, :, : shape[0] * dtype.itemsize]
    flat = np.ascontiguousarray(raw).view(dtype)
    if len(shape) == 2:
        return flat.reshape(count, shape[1], shape[0]).transpose(0, 2, 1)
    return flat.reshape(count, *shape)


def _normalized(values: np.ndarray, dtype: np.dtype) -> np.ndarray:
    """Integers to floats as the specification maps them (3.11, "normalized")."""
    bits = dtype.itemsize * 8
    if dtype.kind == "u":
        return (values.astype(np.float64) / (2**bits - 1)).astype(np.float32)
    return np.maximum(values.astype(np.float64) / (2 ** (bits - 1) - 1), -1.0).astype(np.float32)
