"""The one table that says what each kind of access means to Vulkan: pipeline stages, memory
accesses, the image layout and the usage bits it needs.

The table holds Vulkan names without their prefixes (stage "COMPUTE_SHADER", access
"SHADER_SAMPLED_READ", layout "GENERAL"), so a graph can be planned and its barrier plan checked
without a device; resources.flags() turns names into bits when barriers are recorded.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum


class Load(Enum):
    """What a write does with what the resource held: LOAD keeps it (the pass reads it: it
    depends on the pass that wrote it); CLEAR and DONT_CARE discard it (CLEAR fills attachments
    with the write's clear value; other writes clear themselves if they need to)."""

    LOAD = "load"
    CLEAR = "clear"
    DONT_CARE = "dont_care"


@dataclass(frozen=True)
class Usage:
    """One access kind: pipeline stages, memory accesses, the image layout (None: buffers only),
    whether it reads / writes, the image and buffer usage bits it needs, and whether it applies
    to images, buffers or both."""

    stages: tuple[str, ...]
    access: tuple[str, ...]
    layout: str | None
    reads: bool
    writes: bool
    image_usage: tuple[str, ...] = ()
    buffer_usage: tuple[str, ...] = ()
    buffers: bool = False  # for buffers although it needs no buffer usage bit (HOST_READ)


_FRAG_TESTS = ("EARLY_FRAGMENT_TESTS", "LATE_FRAGMENT_TESTS")
RAY_SHADERS = "RAY_TRACING_SHADER_BIT_KHR"
AS_BUILD_STAGE = "ACCELERATION_STRUCTURE_BUILD_BIT_KHR"
AS_READ_ACCESS = "ACCELERATION_STRUCTURE_READ_BIT_KHR"
#: names a device without ray tracing must not see in a barrier (its validation refuses the
#: stages and accesses of features it has not enabled): dropped when barriers are recorded there
RAY_TRACING_ONLY = frozenset({RAY_SHADERS, AS_BUILD_STAGE, AS_READ_ACCESS, "ACCELERATION_STRUCTURE_WRITE_BIT_KHR"})


class Access(Enum):
    COLOR_WRITE = Usage(
        ("COLOR_ATTACHMENT_OUTPUT",),
        ("COLOR_ATTACHMENT_WRITE",),
        "COLOR_ATTACHMENT_OPTIMAL",
        False,
        True,
        ("COLOR_ATTACHMENT",),
    )
    COLOR_READ_WRITE = Usage(
        ("COLOR_ATTACHMENT_OUTPUT",),
        ("COLOR_ATTACHMENT_READ", "COLOR_ATTACHMENT_WRITE"),
        "COLOR_ATTACHMENT_OPTIMAL",
        True,
        True,
        ("COLOR_ATTACHMENT",),
    )
    DEPTH_WRITE = Usage(
        _FRAG_TESTS,
        ("DEPTH_STENCIL_ATTACHMENT_READ", "DEPTH_STENCIL_ATTACHMENT_WRITE"),
        "DEPTH_STENCIL_ATTACHMENT_OPTIMAL",
        False,
        True,
        ("DEPTH_STENCIL_ATTACHMENT",),
    )
    DEPTH_READ = Usage(  # a depth attachment tested, not written (also sampled in this layout)
        _FRAG_TESTS,
        ("DEPTH_STENCIL_ATTACHMENT_READ",),
        "DEPTH_STENCIL_READ_ONLY_OPTIMAL",
        True,
        False,
        ("DEPTH_STENCIL_ATTACHMENT",),
    )
    RESOLVE_WRITE = Usage(  # MSAA resolves run in the colour output stage as attachment writes
        ("COLOR_ATTACHMENT_OUTPUT",),
        ("COLOR_ATTACHMENT_WRITE",),
        "COLOR_ATTACHMENT_OPTIMAL",
        False,
        True,
        ("COLOR_ATTACHMENT",),
    )
    FRAGMENT_SAMPLED = Usage(
        ("FRAGMENT_SHADER",), ("SHADER_SAMPLED_READ",), "SHADER_READ_ONLY_OPTIMAL", True, False, ("SAMPLED",)
    )
    COMPUTE_SAMPLED = Usage(
        ("COMPUTE_SHADER",), ("SHADER_SAMPLED_READ",), "SHADER_READ_ONLY_OPTIMAL", True, False, ("SAMPLED",)
    )
    COMPUTE_READ = Usage(
        ("COMPUTE_SHADER",), ("SHADER_STORAGE_READ",), "GENERAL", True, False, ("STORAGE",), ("STORAGE_BUFFER",)
    )
    COMPUTE_WRITE = Usage(
        ("COMPUTE_SHADER",), ("SHADER_STORAGE_WRITE",), "GENERAL", False, True, ("STORAGE",), ("STORAGE_BUFFER",)
    )
    COMPUTE_READ_WRITE = Usage(
        ("COMPUTE_SHADER",),
        ("SHADER_STORAGE_READ", "SHADER_STORAGE_WRITE"),
        "GENERAL",
        True,
        True,
        ("STORAGE",),
        ("STORAGE_BUFFER",),
    )
    TRANSFER_READ = Usage(
        ("TRANSFER",), ("TRANSFER_READ",), "TRANSFER_SRC_OPTIMAL", True, False, ("TRANSFER_SRC",), ("TRANSFER_SRC",)
    )
    TRANSFER_WRITE = Usage(
        ("TRANSFER",), ("TRANSFER_WRITE",), "TRANSFER_DST_OPTIMAL", False, True, ("TRANSFER_DST",), ("TRANSFER_DST",)
    )
    INDIRECT_READ = Usage(("DRAW_INDIRECT",), ("INDIRECT_COMMAND_READ",), None, True, False, (), ("INDIRECT_BUFFER",))
    VERTEX_READ = Usage(
        ("VERTEX_INPUT",),
        ("VERTEX_ATTRIBUTE_READ", "INDEX_READ"),
        None,
        True,
        False,
        (),
        ("VERTEX_BUFFER", "INDEX_BUFFER"),
    )
    UNIFORM_READ = Usage(
        ("VERTEX_SHADER", "FRAGMENT_SHADER", "COMPUTE_SHADER"),
        ("UNIFORM_READ",),
        None,
        True,
        False,
        (),
        ("UNIFORM_BUFFER",),
    )
    # a depth image sampled (shadow maps, the deferred lighting's and SSAO's depth) in the layout
    # the descriptors of those passes name
    DEPTH_SAMPLED = Usage(
        ("FRAGMENT_SHADER", "COMPUTE_SHADER", RAY_SHADERS),
        ("SHADER_SAMPLED_READ",),
        "DEPTH_STENCIL_READ_ONLY_OPTIMAL",
        True,
        False,
        ("SAMPLED",),
    )
    FRAGMENT_READ = Usage(  # storage buffer / image read in fragment shaders (clusters, lights)
        ("FRAGMENT_SHADER",), ("SHADER_STORAGE_READ",), "GENERAL", True, False, ("STORAGE",), ("STORAGE_BUFFER",)
    )
    VERTEX_STORAGE_READ = Usage(  # storage read in vertex shaders (ids written by culling)
        ("VERTEX_SHADER",), ("SHADER_STORAGE_READ",), "GENERAL", True, False, ("STORAGE",), ("STORAGE_BUFFER",)
    )
    RAY_SAMPLED = Usage((RAY_SHADERS,), ("SHADER_SAMPLED_READ",), "SHADER_READ_ONLY_OPTIMAL", True, False, ("SAMPLED",))
    RAY_READ = Usage(
        (RAY_SHADERS,), ("SHADER_STORAGE_READ",), "GENERAL", True, False, ("STORAGE",), ("STORAGE_BUFFER",)
    )
    RAY_WRITE = Usage(
        (RAY_SHADERS,), ("SHADER_STORAGE_WRITE",), "GENERAL", False, True, ("STORAGE",), ("STORAGE_BUFFER",)
    )
    # an acceleration structure's buffer built (or its scratch): a build reads and writes both
    AS_BUILD = Usage(
        (AS_BUILD_STAGE,),
        (AS_READ_ACCESS, "ACCELERATION_STRUCTURE_WRITE_BIT_KHR"),
        None,
        False,
        True,
        (),
        ("ACCELERATION_STRUCTURE_STORAGE_BIT_KHR",),
    )
    AS_READ = Usage(  # traced against (ray generation shaders; ray queries in fragment/compute)
        (RAY_SHADERS, "FRAGMENT_SHADER", "COMPUTE_SHADER"),
        (AS_READ_ACCESS,),
        None,
        True,
        False,
        (),
        ("ACCELERATION_STRUCTURE_STORAGE_BIT_KHR",),
    )
    # a readback buffer the host maps after the frame's fence: its copy's writes made visible to
    # the host (declared by a pass after the copy, which records nothing for it)
    HOST_READ = Usage(("HOST",), ("HOST_READ",), None, True, False, (), (), buffers=True)
    # handed to the presentation engine: nothing after it in the frame (the semaphore waits)
    PRESENT = Usage(("NONE",), ("NONE",), "PRESENT_SRC_KHR", True, False)

    @property
    def usage(self) -> Usage:
        return self.value

    @property
    def for_images(self) -> bool:
        return self.usage.layout is not None

    @property
    def for_buffers(self) -> bool:
        return bool(self.usage.buffer_usage) or self.usage.buffers
