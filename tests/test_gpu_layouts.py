"""One source for every CPU/GPU layout: the dtypes of render/layouts.py, the generated
shaders/layouts.glsl, and what glslc actually lays out in the compiled shaders must agree on
every field, offset and size."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from spirv_layout import struct_layouts

from ecs_engine.gpu.layout import Struct
from ecs_engine.render import layouts

SHADERS = Path(__file__).resolve().parent.parent / "shaders"
SOURCES = sorted(p for p in SHADERS.iterdir() if p.suffix in (".vert", ".frag", ".comp"))


def test_generated_header_is_current():
    assert (SHADERS / "layouts.glsl").read_text() == layouts.glsl(), (
        "shaders/layouts.glsl differs from ecs_engine/render/layouts.py: run `make shaders`"
    )


def test_std430_and_std140_rules():
    s = Struct("S", [("a", "float"), ("b", "vec3"), ("c", "float"), ("d", "vec2"), ("e", "float[3]")])
    assert [m.offset for m in s.members] == [0, 16, 28, 32, 40]  # vec3 aligns to 16, a float fits after it
    assert s.size == 64  # rounded up to the largest alignment (16)
    u = Struct("U", [("a", "float"), ("v", "vec4[2]")], std140=True)
    assert [m.offset for m in u.members] == [0, 16] and u.size == 48
    with pytest.raises(ValueError, match="stride"):
        Struct("F", [("a", "float[3]")], std140=True)  # std140 float arrays have a 16-byte stride
    with pytest.raises(ValueError, match="unsupported GLSL type"):
        Struct("X", [("a", "dvec4")])
    assert np.zeros(1, s.dtype)["e"].shape == (1, 3)


def compiled_layouts(tmp_path: Path, wanted: set[str]) -> dict[str, tuple[list[tuple[str, int]], set[int]]]:
    """Per struct name in `wanted`: its (member, offset) list, the same in every shader that
    uses it, and the strides of arrays of it."""
    found: dict[str, list[tuple[str, int]]] = {}
    strides: dict[str, set[int]] = {}
    for src in SOURCES:
        out = tmp_path / f"{src.name}.spv"
        subprocess.run(["glslc", "--target-env=vulkan1.2", str(src), "-o", str(out)], check=True)  # no -O: names kept
        for name, layout in struct_layouts(out).items():
            if name not in wanted:
                continue  # a block (Lights, Cull, ...): its one member is a shared struct
            fields = layout.fields()
            assert found.setdefault(name, fields) == fields, f"{name} is laid out differently in {src.name}"
            strides.setdefault(name, set()).update(layout.strides)
    return {name: (fields, strides[name]) for name, fields in found.items()}


@pytest.mark.skipif(shutil.which("glslc") is None, reason="glslc not installed")
def test_every_shared_struct_matches_what_the_shaders_compile_to(tmp_path):
    compiled = compiled_layouts(tmp_path, {s.name for s in layouts.STRUCTS})
    for struct in layouts.STRUCTS:
        assert struct.name in compiled, f"no shader uses {struct.name}: its layout is checked nowhere"
        fields, strides = compiled[struct.name]
        expected = [(name, struct.dtype.fields[name][1]) for name in struct.dtype.names]
        assert fields == expected, f"{struct.name}: shaders {fields}, dtype {expected}"
        assert strides <= {struct.size}, f"{struct.name}: arrays of it have stride {strides}, dtype {struct.size}"


@pytest.mark.skipif(shutil.which("glslc") is None, reason="glslc not installed")
def test_the_check_catches_a_shifted_field(tmp_path):
    src = tmp_path / "probe.comp"
    src.write_text(
        "#version 450\nstruct Instance { vec4 model[3]; uint extra; uvec4 misc; };\n"
        "layout(std430, binding = 0) buffer B { Instance rows[]; };\n"
        "layout(local_size_x = 1) in;\nvoid main() { rows[0].extra = 1u; }\n"
    )
    out = tmp_path / "probe.spv"
    subprocess.run(["glslc", "--target-env=vulkan1.2", str(src), "-o", str(out)], check=True)
    layout = struct_layouts(out)["Instance"]
    assert layout.fields() == [("model", 0), ("extra", 48), ("misc", 64)]
    assert layout.strides == {80}
    assert layout.fields() != [(n, layouts.INSTANCE.dtype.fields[n][1]) for n in layouts.INSTANCE.dtype.names]
