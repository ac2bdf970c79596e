"""Loading triangle meshes from files (OBJ, glTF/GLB, PLY, STL, read by trimesh), with checks that
turn every bad file into one line: a `UsageError` naming the file and what is wrong."""

from __future__ import annotations

import importlib.resources
import io
import os
from pathlib import Path
from typing import Any, Final

import numpy as np

from ...errors import UsageError
from ...user_files import MODEL, UserFileError, read_user_file
from ...user_json import parse_json
from .mesh_data import MeshData
from .named_files import NamedFiles

__all__ = ["DEFAULT_MODEL", "SUPPORTED_FORMATS", "Part", "assemble", "load_mesh", "read_parts"]

#: File extension -> format name, in the order error messages list them.
SUPPORTED_FORMATS: Final[dict[str, str]] = {".obj": "OBJ", ".gltf": "glTF", ".glb": "GLB", ".ply": "PLY", ".stl": "STL"}

#: The model demos show when given none: a (2,3) torus knot, centred, largest extent 2.0. It lives in the
#: repo's demos/assets/, which installs as package data of `ecs_engine.demos`.
DEFAULT_MODEL: Final[Path] = Path(str(importlib.resources.files("ecs_engine.demos") / "assets" / "torus_knot.obj"))

# A triangle counts as degenerate when twice its area is below this fraction of the mesh's squared size:
# such triangles have no usable normal and nothing to draw.
_DEGENERATE_AREA: Final = 1e-12


def load_mesh(path: str | os.PathLike[str], *, max_triangles: int | None = None) -> MeshData:
    """Load a triangle mesh from OBJ, glTF/GLB, PLY or STL; scenes are flattened with their transforms.

    Polygons are triangulated, zero-area triangles dropped, files without normals get smooth ones;
    texture coordinates are kept (flipped to glTF's top-left origin) and tangents made from them.
    Any problem with the file (or more than `max_triangles` triangles) raises `UsageError` with one
    line naming the file, so the CLI can show it without a traceback."""
    file, parts, _ = read_parts(path, max_triangles)
    return assemble(file, parts, source={"file": str(file.resolve())})  # saved scenes name the file


def read_parts(
    path: str | os.PathLike[str], max_triangles: int | None = None
) -> tuple[Path, list[Part], list[object | None]]:
    """The file's geometry as parts (one per scene node), each with trimesh's material for it
    (None where it has none), checked as `load_mesh` says; `assemble` makes a MeshData of parts."""
    if max_triangles is not None and max_triangles < 1:
        raise ValueError(f"max_triangles must be at least 1, got {max_triangles}")
    file = Path(path)
    fmt = _check_path(file)
    try:
        data = read_user_file(file, MODEL)
    except UserFileError as exc:
        raise UsageError(str(exc)) from None
    except OSError as exc:
        raise UsageError(f"{file}: cannot read the file: {exc.strerror or exc}") from None
    if not data.strip():
        raise UsageError(f"{file}: the file is empty")
    _sniff(file, fmt, data)
    parts, materials, only_points_or_lines = _read_parts(file, fmt, data)
    faces_total = sum(len(f) for _, f, _, _ in parts)
    if faces_total == 0:
        if only_points_or_lines:
            raise UsageError(f"{file}: has no triangles (only points/lines)")
        raise UsageError(f"{file}: contains no triangles (an empty mesh, or not a valid {fmt} file)")
    if max_triangles is not None and faces_total > max_triangles:
        raise UsageError(f"{file}: has {faces_total} triangles, more than the limit of {max_triangles}")
    _check_values(file, parts)
    return file, parts, materials


def _check_path(file: Path) -> str:
    """Reject what cannot be a mesh file before reading it; return the format name."""
    if not file.exists():
        raise UsageError(f"{file}: no such file")
    fmt = SUPPORTED_FORMATS.get(file.suffix.lower())
    if fmt is None:
        what = f"format '{file.suffix}'" if file.suffix else "file type (no extension)"
        raise UsageError(f"{file}: unsupported mesh {what}; supported: {', '.join(SUPPORTED_FORMATS)}")
    return fmt


def _sniff(file: Path, fmt: str, data: bytes) -> None:
    """Cheap format checks that give a clear message where trimesh would crash, guess, or stay silent."""
    if fmt == "OBJ":
        if b"\0" in data:
            raise UsageError(f"{file}: is binary data, not a text OBJ file")
        _check_obj_faces(file, data.decode("utf-8", errors="replace"))
    elif fmt == "STL":
        # Binary STL: an 84-byte header whose triangle count matches the size; otherwise ASCII "solid ...".
        binary = len(data) >= 84 and len(data) == 84 + 50 * int.from_bytes(data[80:84], "little")
        if not binary and not data.lstrip()[:5].lower() == b"solid":
            raise UsageError(f"{file}: not a valid STL file (neither binary STL nor ASCII 'solid ...' text)")
    elif fmt == "glTF":
        try:
            parse_json(data)
        except ValueError as exc:
            raise UsageError(f"{file}: not a valid glTF file ({exc})") from None


# OBJ lines of numbers: how many each may have (a vertex may carry a colour after x y z)
_OBJ_NUMBERS: Final = {"v": (3, 4, 6, 7), "vn": (3,), "vt": (1, 2, 3)}
_OBJ_WHAT: Final = {
    "v": "a vertex needs 3 numbers (x y z; 4 with w, 6 or 7 with a colour)",
    "vn": "a normal needs 3 numbers",
    "vt": "a texture coordinate needs 1 to 3 numbers",
}


def _check_obj_numbers(file: Path, line_no: int, tokens: list[str]) -> None:
    """A `v`, `vn` or `vt` line with too few or too many numbers, or a word that is no number:
    trimesh reads the numbers of all such lines as one array, so one short line shifts every
    vertex after it (an error far from the cause, or a wrong mesh)."""
    key, numbers = tokens[0], tokens[1:]
    allowed = _OBJ_NUMBERS[key]
    if len(numbers) not in allowed:
        raise UsageError(f"{file}: line {line_no}: {_OBJ_WHAT[key]}, got {len(numbers)}")
    for word in numbers:
        try:
            float(word)
        except ValueError:
            raise UsageError(f"{file}: line {line_no}: {word[:40]!r} is not a number") from None


def _check_obj_faces(file: Path, text: str) -> None:
    """Check every OBJ face index: trimesh crashes on indices past the end and silently wraps 0 and
    too-negative ones to other vertices, so the user would get a traceback or a wrong mesh."""
    vertices = 0
    faces: list[tuple[int, int, int, list[str]]] = []  # (face number, line number, vertices so far, tokens)
    other = 0  # points and lines
    for line_no, line in enumerate(text.splitlines(), 1):
        tokens = line.split()
        if not tokens:
            continue
        if tokens[0] in _OBJ_NUMBERS:
            _check_obj_numbers(file, line_no, line.split("#", 1)[0].split())
        if tokens[0] == "v":
            vertices += 1
        elif tokens[0] == "f":
            faces.append((len(faces) + 1, line_no, vertices, tokens[1:]))
        elif tokens[0] in ("l", "p"):
            other += 1
    if not faces:
        if vertices or other:
            raise UsageError(f"{file}: has no triangles (only points/lines)")
        raise UsageError(f"{file}: contains no vertices or faces (an empty mesh, or not an OBJ file)")
    for face_no, line_no, before, tokens in faces:
        where = f"face {face_no} (line {line_no})"
        if len(tokens) < 3:
            raise UsageError(f"{file}: {where} has {len(tokens)} vertices; a face needs at least 3")
        for token in tokens:
            try:
                k = int(token.split("/")[0])
            except ValueError:
                raise UsageError(f"{file}: {where} has an unreadable vertex reference {token!r}") from None
            if k == 0:
                raise UsageError(f"{file}: {where} refers to vertex 0, but OBJ vertex numbers start at 1")
            if k > vertices:
                raise UsageError(f"{file}: {where} refers to vertex {k} but the file has only {vertices} vertices")
            if k < 0 and before + k < 0:
                raise UsageError(
                    f"{file}: {where} refers to vertex {k} (counted back), but only {before} vertices come before it"
                )


# positions (V,3) f8, faces (F,3) i8, normals (V,3) or None, texture coordinates (V,2) or None
Part = tuple[np.ndarray, np.ndarray, "np.ndarray | None", "np.ndarray | None"]


def _read_parts(file: Path, fmt: str, data: bytes) -> tuple[list[Part], list[object | None], bool]:
    """Parse with trimesh (unprocessed, so NaNs and bad indices stay visible to our checks) and bake each
    scene node's transform into its geometry; each part's trimesh material beside it. Also says
    whether the file held only points/lines."""
    try:
        import trimesh

        with np.errstate(all="ignore"):  # NaNs in the file warn inside trimesh; _check_values names them
            scene = trimesh.load_scene(
                io.BytesIO(data),
                file_type=fmt.lower(),
                process=False,
                resolver=NamedFiles(file),
            )
        parts: list[Part] = []
        materials: list[object | None] = []
        non_mesh = 0
        for node in scene.graph.nodes_geometry:
            transform, geometry_name = scene.graph[node]
            geometry = scene.geometry[geometry_name]
            if not isinstance(geometry, trimesh.Trimesh):
                non_mesh += 1
                continue
            # trimesh keeps normals read from the file in its cache; asking `vertex_normals` would compute them.
            normals = geometry._cache["vertex_normals"] if "vertex_normals" in geometry._cache else None
            _check_shapes(file, fmt, geometry.vertices, geometry.faces, normals)
            positions, faces, normals = _transformed(
                np.array(geometry.vertices, np.float64),
                np.array(geometry.faces, np.int64).reshape(-1, 3),
                None if normals is None else np.array(normals, np.float64),
                np.asarray(transform, np.float64),
            )
            parts.append((positions, faces, normals, _uvs(geometry, len(positions))))
            materials.append(getattr(getattr(geometry, "visual", None), "material", None))
    except UsageError:
        raise
    except UserFileError as exc:  # a glTF's buffer that is a device, a FIFO, or too large
        raise UsageError(str(exc)) from None
    except FileNotFoundError as exc:  # a glTF's buffer or image file is not next to it
        raise UsageError(f"{file}: refers to a file that is missing: {exc.filename or exc}") from None
    except Exception as exc:
        reason = (str(exc).strip().splitlines() or [""])[0] or type(exc).__name__
        raise UsageError(f"{file}: not a valid {fmt} file ({reason})") from None
    return parts, materials, non_mesh > 0 and not any(len(f) for _, f, _, _ in parts)


def _check_shapes(file: Path, fmt: str, vertices: Any, faces: Any, normals: Any) -> None:
    """What trimesh read from a broken file can have any shape: refuse it before NumPy's own
    errors (an AxisError that names no file) or a wrong mesh."""
    v, f = np.shape(vertices), np.shape(faces)
    if len(v) != 2 or v[1] != 3:
        raise UsageError(f"{file}: not a valid {fmt} file (its vertices read as an array of shape {v}, not N x 3)")
    if len(f) != 2 or f[1] != 3 or not np.issubdtype(np.asarray(faces).dtype, np.integer):
        raise UsageError(f"{file}: not a valid {fmt} file (its faces read as an array of shape {f}, not N x 3)")
    if normals is not None and np.shape(normals) != v:
        raise UsageError(f"{file}: not a valid {fmt} file ({np.shape(normals)[0]} normals for {v[0]} vertices)")


def _uvs(geometry: object, count: int) -> np.ndarray | None:
    """The texture coordinates trimesh read (its origin is bottom-left, as OBJ's), with v flipped to
    glTF's top-left origin; None when the geometry has none, or not one per vertex."""
    uv = getattr(getattr(geometry, "visual", None), "uv", None)
    if uv is None:
        return None
    uv = np.array(uv, np.float64)
    if uv.shape != (count, 2):
        return None
    uv[:, 1] = 1.0 - uv[:, 1]
    return uv


def _transformed(
    positions: np.ndarray, faces: np.ndarray, normals: np.ndarray | None, transform: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Apply a 4x4 node transform; normals use the inverse transpose, mirroring flips the winding."""
    if np.array_equal(transform, np.eye(4)):
        return positions, faces, normals
    linear = transform[:3, :3]
    positions = positions @ linear.T + transform[:3, 3]
    det = float(np.linalg.det(linear)) if np.isfinite(linear).all() else 0.0
    if det < 0:
        faces = faces[:, ::-1]
    if normals is not None:
        normals = normals @ np.linalg.inv(linear) if abs(det) > 1e-300 else None
    return positions, faces, normals


def assemble(file: Path, parts: list[Part], name: str | None = None, source: dict[str, Any] | None = None) -> MeshData:
    """Drop zero-area triangles and unused vertices, fill in normals, build one MeshData of `parts`
    (checked by read_parts); `source`: its MeshData.source."""
    everything = np.concatenate([p for p, _, _, _ in parts])
    size = float((everything.max(0) - everything.min(0)).max())
    has_uvs = any(uv is not None for _, _, _, uv in parts)
    out_p, out_n, out_uv, out_i, offset, total = [], [], [], [], 0, 0
    for positions, faces, normals, uvs in parts:
        total += len(faces)
        if has_uvs and uvs is None:
            uvs = np.zeros((len(positions), 2))
        if normals is None:  # no normals in the file: weld equal vertices so the computed ones are smooth
            welded = positions if uvs is None else np.concatenate([positions, uvs], axis=1)
            welded, inverse = np.unique(welded, axis=0, return_inverse=True)
            faces = inverse.reshape(-1)[faces]
            positions, uvs = welded[:, :3], (None if uvs is None else welded[:, 3:])
        cross = _face_cross(positions, faces)
        keep = np.linalg.norm(cross, axis=1) > _DEGENERATE_AREA * size * size
        faces, cross = faces[keep], cross[keep]
        used, faces = np.unique(faces, return_inverse=True)
        faces = faces.reshape(-1, 3)
        positions = positions[used]
        # vertices split only by their texture coordinates (a UV seam) share one smooth normal
        _, groups = np.unique(positions, axis=0, return_inverse=True)
        normals = _vertex_normals(groups.reshape(-1), faces, cross, None if normals is None else normals[used])
        out_p.append(positions)
        out_n.append(normals)
        if uvs is not None:
            out_uv.append(uvs[used])
        out_i.append(faces + offset)
        offset += len(positions)
    if offset == 0:
        raise UsageError(f"{file}: all {total} triangles are degenerate (zero area)")
    return MeshData.from_arrays(
        np.concatenate(out_p),
        np.concatenate(out_n),
        np.concatenate(out_i),
        name or file.stem,
        uvs=np.concatenate(out_uv) if has_uvs else None,
        source=source,
    )


def _check_values(file: Path, parts: list[Part]) -> None:
    """Non-finite, float32-overflowing and out-of-range values: one line naming the first."""
    bad = sum(int((~np.isfinite(p)).any(axis=1).sum()) for p, _, _, _ in parts)
    if bad:
        what = "vertex has" if bad == 1 else "vertices have"
        raise UsageError(f"{file}: {bad} {what} NaN or infinite coordinates")
    bad = sum(int((~np.isfinite(uv)).any(axis=1).sum()) for _, _, _, uv in parts if uv is not None)
    if bad:
        what = "vertex has" if bad == 1 else "vertices have"
        raise UsageError(f"{file}: {bad} {what} NaN or infinite texture coordinates")
    limit = float(np.finfo(np.float32).max)  # vertices are uploaded as float32
    first = 0  # vertex numbers count across the file's parts, from 1 as in OBJ
    for positions, _, _, _ in parts:
        huge = (np.abs(positions) > limit).any(axis=1)
        if huge.any():
            i = int(np.argmax(huge))
            value = float(positions[i][np.abs(positions[i]) > limit][0])
            more = f" ({int(huge.sum())} vertices)" if huge.sum() > 1 else ""
            raise UsageError(
                f"{file}: vertex {first + i + 1} has the coordinate {value:g}, outside float32's range "
                f"(-{limit:.3g} to {limit:.3g}){more}"
            )
        first += len(positions)
    for positions, faces, _, _ in parts:
        if faces.size and (faces.min() < 0 or faces.max() >= len(positions)):
            i = int(np.argmax(((faces < 0) | (faces >= len(positions))).any(axis=1)))
            k = int(faces[i][(faces[i] < 0) | (faces[i] >= len(positions))][0])
            raise UsageError(
                f"{file}: face {i + 1} refers to vertex {k} but the file has only {len(positions)} vertices"
            )


def _face_cross(positions: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(v1 - v0) x (v2 - v0) per face: along the outward normal for counter-clockwise faces, length 2x area."""
    v0, v1, v2 = (positions[faces[:, k]] for k in range(3))
    return np.cross(v1 - v0, v2 - v0)


def _vertex_normals(groups: np.ndarray, faces: np.ndarray, cross: np.ndarray, given: np.ndarray | None) -> np.ndarray:
    """Unit normals per vertex: the file's where usable, else area-weighted face normals summed over
    the vertex's group (the vertices at one position); where those cancel (a two-sided sheet) fall back
    to one adjacent face's normal. Every vertex here has a non-degenerate face."""
    count = len(groups)
    flat = groups[faces.reshape(-1)]
    summed = np.stack([np.bincount(flat, weights=np.repeat(cross[:, k], 3), minlength=count) for k in range(3)], 1)
    smooth = summed[groups]
    unit_faces = cross / np.linalg.norm(cross, axis=1, keepdims=True)
    fallback = np.zeros((count, 3))
    fallback[faces.reshape(-1)] = np.repeat(unit_faces, 3, axis=0)
    result = fallback
    for candidate in (smooth, given):
        if candidate is None:
            continue
        with np.errstate(invalid="ignore", over="ignore"):
            length = np.linalg.norm(candidate, axis=1, keepdims=True)
            ok = (np.isfinite(length) & (length > 1e-12)).reshape(-1)
            result = np.where(ok[:, None], candidate / np.where(ok[:, None], length, 1.0), result)
    return result
