"""GPU data layouts written once: a `Struct` of GLSL-typed fields gives both the NumPy structured
dtype that the CPU writes through and the GLSL declaration the shaders include.

Offsets follow GLSL's std430 rules (storage buffers, push constants) or std140 (uniform
buffers): a vec3 aligns like a vec4, an array's stride is its element's alignment (std140:
rounded up to 16), a struct's size is rounded up to its largest alignment. The engine's own
structs are declared in render/layouts.py; scripts/compile_shaders.py writes them into
shaders/layouts.glsl, and tests compare that file and the compiled shaders' offsets against
the dtypes, so a layout cannot change on one side only.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np

# GLSL type: (NumPy scalar type, shape of one element, alignment, size), std430
_TYPES: dict[str, tuple[str, tuple[int, ...], int, int]] = {
    "float": ("f4", (), 4, 4),
    "int": ("i4", (), 4, 4),
    "uint": ("u4", (), 4, 4),
    "vec2": ("f4", (2,), 8, 8),
    "vec3": ("f4", (3,), 16, 12),
    "vec4": ("f4", (4,), 16, 16),
    "ivec4": ("i4", (4,), 16, 16),
    "uvec2": ("u4", (2,), 8, 8),
    "uvec4": ("u4", (4,), 16, 16),
    "mat4": ("f4", (4, 4), 16, 64),  # column-major in GLSL: write a NumPy [row, col] matrix as .T
}
_ARRAY = re.compile(r"^(\w+)\[(\d+)\]$")


@dataclass(frozen=True)
class Member:
    name: str
    glsl: str  # "vec4", "vec4[3]", ...
    offset: int
    comment: str = ""


@dataclass
class Struct:
    """fields: (name, GLSL type) or (name, GLSL type, comment), in order."""

    name: str
    fields: list[tuple[str, ...]]
    std140: bool = False
    doc: str = ""
    members: list[Member] = field(init=False)
    dtype: np.dtype = field(init=False)
    size: int = field(init=False)  # bytes a row (dtype.itemsize): read every frame, so a plain attribute

    def __post_init__(self) -> None:
        names, formats, offsets, members = [], [], [], []
        offset = 0
        biggest = 4
        for name, glsl, *comment in self.fields:
            base, shape, align, size = _describe(glsl, self.std140)
            offset = -(-offset // align) * align
            names.append(name)
            formats.append((base, shape) if shape else base)
            offsets.append(offset)
            members.append(Member(name, glsl, offset, comment[0] if comment else ""))
            offset += size
            biggest = max(biggest, align)
        if self.std140:
            biggest = max(biggest, 16)
        self.members = members
        self.dtype = np.dtype(
            {"names": names, "formats": formats, "offsets": offsets, "itemsize": -(-offset // biggest) * biggest}
        )
        self.size = self.dtype.itemsize

    def offset(self, name: str) -> int:
        return next(m.offset for m in self.members if m.name == name)

    def glsl(self) -> str:
        """The GLSL struct declaration, with each member's offset in a comment."""
        lines = [f"// {line}" for line in self.doc.splitlines()] if self.doc else []
        lines.append(f"struct {self.name} {{  // {self.size} bytes, {'std140' if self.std140 else 'std430'}")
        for m in self.members:
            array = _ARRAY.match(m.glsl)
            decl = f"    {array.group(1)} {m.name}[{array.group(2)}];" if array else f"    {m.glsl} {m.name};"
            note = f"offset {m.offset}" + (f": {m.comment}" if m.comment else "")
            lines.append(f"{decl:<32}// {note}")
        lines.append("};")
        return "\n".join(lines)


def _describe(glsl: str, std140: bool) -> tuple[str, tuple[int, ...], int, int]:
    """(NumPy base type, shape, alignment, size) of a member."""
    array = _ARRAY.match(glsl)
    if array is None:
        if glsl not in _TYPES:
            raise ValueError(f"unsupported GLSL type {glsl!r}; known: {', '.join(_TYPES)}")
        return _TYPES[glsl]
    element, count = array.group(1), int(array.group(2))
    base, shape, align, size = _describe(element, std140)
    if std140:
        align = max(align, 16)
    stride = -(-size // align) * align
    if stride != size:
        raise ValueError(f"{glsl}: elements of {size} bytes with a stride of {stride} have no plain NumPy shape")
    return base, (count, *shape), align, stride * count


def glsl_header(structs: list[Struct], defines: dict[str, int], source: str) -> str:
    """A GLSL include with #defines (binding numbers, group sizes) and the struct declarations."""
    out = [
        f"// Generated from {source} by scripts/compile_shaders.py: do not edit.",
        "#ifndef LAYOUTS_GLSL",
        "#define LAYOUTS_GLSL",
        "",
    ]
    # values past int's range are written unsigned (GLSL rejects them as int literals)
    out += [f"#define {name} {value}{'u' if value > 0x7FFFFFFF else ''}" for name, value in defines.items()]
    for struct in structs:
        out += ["", struct.glsl()]
    return "\n".join([*out, "", "#endif"]) + "\n"
