"""Read struct layouts out of SPIR-V: per named struct, its members' names and byte offsets, and
the array stride where the struct is the element of an array. Enough of the format for that
(opcodes from the SPIR-V specification, section 3); compile without -O to keep the names."""

from __future__ import annotations

import struct
from dataclasses import dataclass, field
from pathlib import Path

OP_NAME, OP_MEMBER_NAME, OP_TYPE_ARRAY, OP_TYPE_RUNTIME_ARRAY, OP_TYPE_STRUCT = 5, 6, 28, 29, 30
OP_DECORATE, OP_MEMBER_DECORATE = 71, 72
DECORATION_ARRAY_STRIDE, DECORATION_OFFSET = 6, 35


@dataclass
class StructLayout:
    name: str
    members: dict[int, str] = field(default_factory=dict)  # index -> name
    offsets: dict[int, int] = field(default_factory=dict)  # index -> byte offset
    strides: set[int] = field(default_factory=set)  # of arrays whose element is this struct

    def fields(self) -> list[tuple[str, int]]:
        return [(self.members[i], self.offsets[i]) for i in sorted(self.offsets)]


def _string(words: list[int]) -> str:
    raw = struct.pack(f"<{len(words)}I", *words)
    return raw.split(b"\0", 1)[0].decode()


def struct_layouts(spirv: bytes | Path) -> dict[str, StructLayout]:
    data = spirv.read_bytes() if isinstance(spirv, Path) else spirv
    words = list(struct.unpack(f"<{len(data) // 4}I", data))
    if words[0] != 0x07230203:
        raise ValueError("not SPIR-V (bad magic number)")
    names: dict[int, str] = {}
    members: dict[int, dict[int, str]] = {}
    offsets: dict[int, dict[int, int]] = {}
    strides: dict[int, int] = {}
    structs: set[int] = set()
    arrays: dict[int, int] = {}  # array type id -> element type id
    i = 5
    while i < len(words):
        count, op = words[i] >> 16, words[i] & 0xFFFF
        args = words[i + 1 : i + count]
        if op == OP_NAME:
            names[args[0]] = _string(args[1:])
        elif op == OP_MEMBER_NAME:
            members.setdefault(args[0], {})[args[1]] = _string(args[2:])
        elif op == OP_MEMBER_DECORATE and args[2] == DECORATION_OFFSET:
            offsets.setdefault(args[0], {})[args[1]] = args[3]
        elif op == OP_DECORATE and args[1] == DECORATION_ARRAY_STRIDE:
            strides[args[0]] = args[2]
        elif op == OP_TYPE_STRUCT:
            structs.add(args[0])
        elif op in (OP_TYPE_ARRAY, OP_TYPE_RUNTIME_ARRAY):
            arrays[args[0]] = args[1]
        i += count
    out: dict[str, StructLayout] = {}
    for sid in structs:
        if sid not in names or sid not in offsets:
            continue  # unnamed, or not laid out in memory (a plain local struct)
        layout = out.setdefault(names[sid], StructLayout(names[sid]))
        layout.members.update(members.get(sid, {}))
        layout.offsets.update(offsets[sid])
        layout.strides.update(strides[a] for a, element in arrays.items() if element == sid and a in strides)
    return out
