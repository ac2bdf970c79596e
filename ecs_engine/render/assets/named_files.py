"""The files a model file names (a glTF's buffers and images, an OBJ's material library and its
textures), handed to trimesh through user_files: trimesh's own resolver opens whatever a name
leads to, so a FIFO next to the model would block the load and a device would be read whole.

Names are relative to the model's folder (an absolute name stays absolute), as mtl.py reads
them; a name not found there is tried as its last part in that folder, as trimesh does (files
written on another machine often carry that machine's folders).
"""

from __future__ import annotations

import os
from pathlib import Path

import trimesh

from ...user_files import IMAGE, MATERIAL_LIBRARY, MODEL, FileKind, read_user_file

__all__ = ["NamedFiles", "kind_of"]

_IMAGE_SUFFIXES = frozenset((".png", ".jpg", ".jpeg", ".bmp", ".tga", ".tif", ".tiff", ".gif", ".webp", ".hdr"))


def kind_of(name: str) -> FileKind:
    suffix = Path(name).suffix.lower()
    if suffix == ".mtl":
        return MATERIAL_LIBRARY
    return IMAGE if suffix in _IMAGE_SUFFIXES else MODEL


class NamedFiles(trimesh.resolvers.Resolver):
    """A trimesh resolver reading only regular files of bounded size (user_files)."""

    def __init__(self, model: Path, folder: Path | None = None) -> None:  # no super(): it refuses to run
        self.model = model
        self.folder = model.parent if folder is None else folder
        self.file_name = model.name  # trimesh names OBJ materials after it

    def get(self, name: str) -> bytes:
        name = name.strip()
        candidates = [self.folder / name, self.folder / os.path.basename(name.replace("\\", "/"))]
        path = next((p for p in candidates if os.path.lexists(p)), None)
        if path is None:
            shown = name if len(name) <= 120 else name[:100] + "..."  # a broken data: URI can be megabytes
            raise FileNotFoundError(2, "no such file", shown)  # as the model names it
        return read_user_file(path, kind_of(name), named_by=str(self.model))

    def __getitem__(self, name: str) -> bytes:
        return self.get(name)

    def namespaced(self, namespace: str) -> NamedFiles:
        return NamedFiles(self.model, self.folder / namespace)

    def keys(self) -> list[str]:
        return []

    def write(self, name: str, data: str | bytes) -> None:
        raise OSError(f"{self.model}: loading a model writes no files ({name})")
