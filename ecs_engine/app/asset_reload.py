"""Textures and meshes reloaded from their files when they change on disk (`--watch`).

The files watched are those the game loaded: each texture read from an image file
(`Texture.source`, in the world's Materials) and each mesh from a model file (`Meshes.files`),
picked up as the game loads them. A changed file is read again and goes in under the same handle,
so materials and `Mesh` components keep naming it; the GPU copy is made again between frames after
the frames in flight are done (Textures.replace -> TexturePages.sync, Meshes.replace ->
MeshRegistry.replace). A file that cannot be read any more (half written, broken) keeps the old
asset and is one line naming it.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ..ecs.world import World
from ..errors import UsageError
from .file_watch import FileWatch


class AssetReload:
    """The texture and mesh files of `world`, watched through `files` (the hot reload's watch)."""

    def __init__(self, world: World, files: FileWatch) -> None:
        self.world = world
        self.files = files
        self._seen = (-1, -1)  # (textures, meshes) when the watched list was last brought up to date
        self.reloaded = 0

    def follow(self) -> None:
        """Watch the files of textures and meshes loaded since the last call (a few len() calls
        when there are none)."""
        textures, meshes = self._textures(), self._meshes()
        now = (len(textures) if textures is not None else 0, len(meshes.files) if meshes is not None else 0)
        if now == self._seen:
            return
        self._seen = now
        paths = [] if meshes is None else list(meshes.files.values())
        if textures is not None:
            paths += [textures[h].source for h in range(len(textures)) if textures[h].source is not None]
        self.files.watch(paths)

    def reload(self, changed: list[Path]) -> list[tuple[bool, str]]:
        """Reload the textures and meshes read from `changed`: (went in, the line to say) each."""
        said = []
        for path in changed:
            for reload in (self._reload_textures, self._reload_meshes):
                outcome = reload(path)
                if outcome is not None:
                    said.append(outcome)
        return said

    def _reload_textures(self, path: Path) -> tuple[bool, str] | None:
        from ..render.assets.textures import ImageError, Texture, read_image

        textures = self._textures()
        handles = [] if textures is None else [h for h in range(len(textures)) if textures[h].source == str(path)]
        if textures is None or not handles:
            return None
        try:
            pixels = read_image(path)
        except ImageError as exc:
            return False, f"hot reload: {path.name}: {exc}; the old texture stays"
        for handle in handles:
            old = textures[handle]
            textures.replace(handle, Texture(old.name, pixels, old.color, old.source))
        self.reloaded += 1
        return True, f"hot reload: {path.name}: texture reloaded"

    def _reload_meshes(self, path: Path) -> tuple[bool, str] | None:
        from ..render.assets.mesh_loading import load_mesh

        meshes = self._meshes()
        handles = [] if meshes is None else [h for h, file in meshes.files.items() if file == path]
        if meshes is None or not handles:
            return None
        try:
            mesh = load_mesh(path)
        except (UsageError, ValueError, OSError) as exc:
            return False, f"hot reload: {' '.join(str(exc).split())}; the old mesh stays"
        for handle in handles:
            meshes.replace(handle, mesh)
        self.reloaded += 1
        return True, f"hot reload: {path.name}: mesh reloaded"

    def _textures(self) -> Any:
        from ..render.assets.materials import Materials

        found = self.world.resources.get(Materials)
        return None if found is None else found.textures

    def _meshes(self) -> Any:
        from ..render.assets.meshes import Meshes

        return self.world.resources.get(Meshes)
