"""glTF 2.0 files as the engine's assets: the document and its accessors (document.py,
accessors.py), and scenes spawned as entities (scene.py)."""

from .document import GltfDocument, GltfError

__all__ = ["GltfDocument", "GltfError"]
