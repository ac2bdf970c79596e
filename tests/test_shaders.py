"""Committed SPIR-V must match its GLSL: the manifest records a hash of every source (with the
shared include) at the time it was compiled; `make shaders` rebuilds both."""

from __future__ import annotations

import hashlib
import importlib.util
import json
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
SHADERS = ROOT / "shaders"
spec = importlib.util.spec_from_file_location("compile_shaders", ROOT / "scripts" / "compile_shaders.py")
compile_shaders = importlib.util.module_from_spec(spec)
spec.loader.exec_module(compile_shaders)

MANIFEST = json.loads((SHADERS / "manifest.json").read_text())
SOURCES = sorted(p for p in SHADERS.iterdir() if p.suffix in compile_shaders.STAGES)


def test_every_source_has_an_entry():
    assert sorted(MANIFEST["shaders"]) == [p.name for p in SOURCES]


@pytest.mark.parametrize("src", SOURCES, ids=lambda p: p.name)
def test_spirv_is_not_stale(src):
    entry = MANIFEST["shaders"][src.name]
    assert compile_shaders.source_digest(src) == entry["source_sha256"], (
        f"{src.name} changed since its SPIR-V was built: run `make shaders`"
    )
    spv = src.with_name(src.name + ".spv").read_bytes()
    assert spv[:4] == b"\x03\x02\x23\x07"  # SPIR-V magic, little-endian
    assert hashlib.sha256(spv).hexdigest() == entry["spirv_sha256"], f"{src.name}.spv was edited by hand"


@pytest.mark.skipif(shutil.which("glslc") is None, reason="glslc not installed")
def test_sources_compile_and_match_when_glslc_is_the_recorded_one(tmp_path):
    version = subprocess.run(["glslc", "--version"], capture_output=True, text=True).stdout.splitlines()[0]
    for src in SOURCES:
        out = tmp_path / (src.name + ".spv")
        subprocess.run(["glslc", "--target-env=vulkan1.2", "-O", str(src), "-o", str(out)], check=True)
        if version == MANIFEST["glslc"]:
            assert out.read_bytes() == src.with_name(src.name + ".spv").read_bytes(), src.name


def test_shader_path_takes_an_engine_name_or_a_games_own_spirv(tmp_path):
    from ecs_engine.errors import UsageError
    from ecs_engine.gpu.pipeline import SHADER_DIR, shader_path

    assert shader_path("tonemap.vert") == SHADER_DIR / "tonemap.vert.spv"  # (the installed package's)
    own = tmp_path / "glow.frag.spv"
    own.write_bytes(b"\x03\x02\x23\x07")
    assert shader_path(own) == own and shader_path(str(own)) == own
    with pytest.raises(UsageError, match=r"glow2\.frag\.spv is missing: compile it with glslc$"):
        shader_path(tmp_path / "glow2.frag.spv")
    with pytest.raises(UsageError, match=r"nothing\.frag\.spv is missing: run `make shaders`$"):
        shader_path("nothing.frag")
