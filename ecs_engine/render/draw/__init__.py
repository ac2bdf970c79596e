"""The render paths that draw the mesh rows: the RenderPath interface (path.py), the CPU-recorded
paths (chunk_paths.py), the indirect path, the instance rows and their recording."""
