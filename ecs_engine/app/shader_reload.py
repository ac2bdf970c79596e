"""The engine's shaders recompiled and the mesh pipelines made again when a GLSL source changes
(`--watch`, for engine developers editing shaders/).

A changed stage source (`*.vert`, `*.frag`, `*.comp`) is compiled with glslc to its `.spv`, as
scripts/compile_shaders.py does; a changed include (`*.glsl`) recompiles every stage source. Then
the renderer's path is made again (Renderer.rebuild_pipelines: the frames in flight are waited
for), which remakes the mesh, shadow and set-aside pipelines, the output passes' (lighting, sky,
tone map), the post effects' (bloom, SSAO, FXAA; the camera views' copies of them follow) and the
UI's from the new SPIR-V. The compute passes made once (light clusters,
occlusion culling, the deferred lighting's compute path) and the ray tracing shaders take a new
shader at the next start.
A compile error keeps the old `.spv` and is one line naming the file and line. The manifest is
not touched: run scripts/compile_shaders.py before committing shaders.
"""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path
from typing import Any

from .file_watch import FileWatch

STAGES = (".vert", ".frag", ".comp")  # what the raster and compute passes use; ray tracing ones are left alone
TARGET_ENV = "--target-env=vulkan1.2"  # as scripts/compile_shaders.py


class ShaderReload:
    def __init__(self, files: FileWatch, shader_dir: Path | None = None) -> None:
        if shader_dir is None:
            from ..gpu.pipeline import SHADER_DIR

            shader_dir = SHADER_DIR
        self.dir = shader_dir.resolve()
        self.files = files
        self.sources = sorted(p for p in self.dir.iterdir() if p.suffix in (*STAGES, ".glsl"))
        files.watch(self.sources)
        self.reloaded = 0

    def owns(self, path: Path) -> bool:
        return path.parent == self.dir and path.suffix in (*STAGES, ".glsl")

    def reload(self, changed: list[Path], renderer: Any) -> list[tuple[bool, str]]:
        """Compile what `changed` touches, then remake the renderer's pipelines: (went in, line) each."""
        mine = [p for p in changed if self.owns(p)]
        if not mine:
            return []
        if any(p.suffix == ".glsl" for p in mine):
            stages = [p for p in self.sources if p.suffix in STAGES]
        else:
            stages = mine
        glslc = shutil.which("glslc")
        if glslc is None:
            return [(False, "hot reload: glslc not found (apt-get install glslc): shaders are not recompiled")]
        for source in stages:
            failed = _compile(glslc, source)
            if failed is not None:
                return [(False, f"hot reload: {failed}; the old shaders stay")]
        rebuild = getattr(renderer, "rebuild_pipelines", None)
        if rebuild is None:  # a run that draws nothing
            return [(True, f"hot reload: {_names(mine)}: compiled")]
        try:
            rebuild()
        except Exception as exc:
            text = " ".join(str(exc).split())
            return [(False, f"hot reload: {_names(mine)}: the pipelines cannot be made: {text}; the old ones stay")]
        self.reloaded += 1
        return [(True, f"hot reload: {_names(mine)}: compiled, the pipelines made again")]


def _compile(glslc: str, source: Path) -> str | None:
    """Compile `source` to its .spv (replaced only when it compiles); the first error, or None."""
    out = source.with_name(source.name + ".spv")
    temporary = out.with_name(out.name + ".new")
    run = subprocess.run(
        [glslc, TARGET_ENV, "-O", str(source), "-o", str(temporary)], capture_output=True, text=True, check=False
    )
    if run.returncode != 0:
        temporary.unlink(missing_ok=True)
        lines = [line for line in run.stderr.splitlines() if ": error:" in line] or run.stderr.splitlines() or ["?"]
        first = lines[0]
        return first.replace(str(source.parent) + os.sep, "", 1)
    os.replace(temporary, out)
    return None


def _names(paths: list[Path]) -> str:
    return ", ".join(p.name for p in paths)
