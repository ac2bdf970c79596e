"""Wavefront .mtl material libraries, read here rather than through trimesh, which drops a texture
it cannot find without saying which: we need the file name for the warning, and the options
(`-bm`) trimesh ignores.

What is read, per `newmtl`: Kd (base colour), d or Tr (opacity), Ks and Ns (Blinn-Phong specular
strength and exponent), Ke (emission), map_Kd (base colour texture), map_Bump / bump / norm (a
tangent-space normal map, `-bm` its scale; most exporters write normal maps there), map_Ke
(emission texture). Texture paths are relative to the .mtl file.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path

from ...user_files import MATERIAL_LIBRARY, UserFileError, read_user_file

log = logging.getLogger("ecs_engine")

# texture map options and how many values each takes (the file name is what follows them)
_MAP_OPTIONS = {
    "-bm": 1,
    "-boost": 1,
    "-mm": 2,
    "-o": 3,
    "-s": 3,
    "-t": 3,
    "-texres": 1,
    "-clamp": 1,
    "-blendu": 1,
    "-blendv": 1,
    "-imfchan": 1,
    "-type": 1,
    "-cc": 1,
}


@dataclass
class MtlTexture:
    path: Path
    scale: float = 1.0  # -bm
    library: Path | None = None  # the .mtl naming it (warnings say who named a bad file)


@dataclass
class MtlMaterial:
    name: str
    diffuse: tuple[float, float, float] = (0.8, 0.8, 0.8)
    opacity: float = 1.0
    specular: tuple[float, float, float] = (0.0, 0.0, 0.0)
    shininess: float = 1.0
    emissive: tuple[float, float, float] = (0.0, 0.0, 0.0)
    maps: dict[str, MtlTexture] = field(default_factory=dict)  # diffuse, normal, emissive


_MAP_KEYS = {"map_kd": "diffuse", "map_bump": "normal", "bump": "normal", "norm": "normal", "map_ke": "emissive"}


def mtl_libraries(obj_text: str, obj_file: Path) -> list[Path]:
    """The .mtl files an OBJ names (`mtllib`, paths relative to the OBJ; names may hold spaces)."""
    out = []
    for line in obj_text.splitlines():
        if line.startswith("mtllib"):
            name = line[len("mtllib") :].strip()
            if name:
                out.append(obj_file.parent / name)
    return out


def read_mtl(file: Path, named_by: str | None = None) -> dict[str, MtlMaterial]:
    """Materials by name; a missing or unreadable library (or a FIFO, a device, one over
    MATERIAL_LIBRARY's size) logs one warning and gives none."""
    try:
        text = read_user_file(file, MATERIAL_LIBRARY, named_by).decode("utf-8", errors="replace")
    except UserFileError as exc:
        log.warning("%s; its materials are drawn with defaults", exc)
        return {}
    except OSError as exc:
        by = f" (named by {named_by})" if named_by else ""
        log.warning(
            "%s%s: cannot read the material library (%s); its materials are drawn with defaults",
            file,
            by,
            exc.strerror or exc,
        )
        return {}
    materials: dict[str, MtlMaterial] = {}
    current: MtlMaterial | None = None
    for line_no, line in enumerate(text.splitlines(), 1):
        tokens = line.split("#", 1)[0].split()
        if not tokens:
            continue
        key, args = tokens[0].lower(), tokens[1:]
        if key == "newmtl":
            current = materials[" ".join(args)] = MtlMaterial(" ".join(args))
            continue
        if current is None:
            continue
        try:
            if key in ("kd", "ks", "ke") and args and args[0] != "spectral":
                values = [float(v) for v in args[:3]]
                rgb = (values * 3)[:3] if len(values) == 1 else values
                if len(rgb) != 3:
                    raise ValueError(key)
                setattr(current, {"kd": "diffuse", "ks": "specular", "ke": "emissive"}[key], tuple(rgb))
            elif key == "ns":
                current.shininess = float(args[0])
            elif key == "d":
                current.opacity = float(args[-1])  # `d -halo 0.5`: the value is last
            elif key == "tr":
                current.opacity = 1.0 - float(args[0])
            elif key in _MAP_KEYS:
                texture = _map(args, file)
                if texture is not None:
                    current.maps[_MAP_KEYS[key]] = texture
        except (ValueError, IndexError):
            log.warning("%s: line %d (%r) is not readable; ignored", file, line_no, line.strip())
    return materials


def _map(args: list[str], library: Path) -> MtlTexture | None:
    scale = 1.0
    i = 0
    while i < len(args) and args[i].lower() in _MAP_OPTIONS:
        option = args[i].lower()
        if option == "-bm":
            scale = float(args[i + 1])
        i += 1 + _MAP_OPTIONS[option]
    name = " ".join(args[i:]).replace("\\", "/")
    return MtlTexture(library.parent / name, scale, library) if name else None
