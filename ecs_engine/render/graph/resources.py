"""What the frame graph's resources are: descriptions of transient images and buffers, the
images and buffers a pass records with, and the names of Vulkan values (the access table is
access.py; `flags()` turns its names into bits when barriers are recorded)."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Any

from ...errors import UsageError
from .access import Access, Load


def flags(vk: Any, prefix: str, names: tuple[str, ...] | frozenset[str]) -> int:
    """The bits of `names` ("COMPUTE_SHADER") under `prefix` ("VK_PIPELINE_STAGE_2_")."""
    bits = 0
    for name in names:
        value = getattr(vk, f"{prefix}{name}", None)
        bits |= value if value is not None else getattr(vk, f"{prefix}{name}_BIT")
    return bits


# per prefix, value -> name: looking a value up by scanning the binding's names took about 2 ms
_NAMES: dict[str, dict[int, str]] = {}


def _named(vk: Any, prefix: str, value: int, skip: tuple[str, ...], what: str) -> str:
    table = _NAMES.get(prefix)
    if table is None:
        table = {}
        for name in dir(vk):  # in sorted order: the first of several names of one value wins
            if name.startswith(prefix) and not name.endswith(skip) and not name.startswith(prefix + "FEATURE_"):
                number = getattr(vk, name)
                if isinstance(number, int):
                    table.setdefault(number, name.removeprefix(prefix))
        _NAMES[prefix] = table
    found = table.get(int(value))
    if found is None:
        raise UsageError(f"unknown {what} {value}")
    return found


def format_name(vk: Any, fmt: int | str) -> str:
    """A VkFormat's name without the prefix ("R16G16B16A16_SFLOAT") from its value or name."""
    if isinstance(fmt, str):
        return fmt.removeprefix("VK_FORMAT_")
    return _named(vk, "VK_FORMAT_", fmt, ("_KHR",), "VkFormat")


def layout_name(vk: Any, layout: int | str) -> str:
    """A VkImageLayout's name without the prefix from its value or name."""
    if isinstance(layout, str):
        return layout.removeprefix("VK_IMAGE_LAYOUT_")
    return _named(vk, "VK_IMAGE_LAYOUT_", layout, ("_KHR", "_NV"), "VkImageLayout")


def is_depth(fmt: str) -> bool:
    return fmt.startswith(("D16", "D24", "D32", "X8_D24"))


def texel_bytes(fmt: str) -> int:
    """Bytes per texel of an uncompressed format, from its name (planning without a device)."""
    packed = re.search(r"PACK(\d+)", fmt)
    if packed:
        return int(packed[1]) // 8
    if fmt.startswith("D32_SFLOAT_S8"):
        return 8
    bits = sum(int(b) for b in re.findall(r"[RGBADSX](\d+)", fmt.split("_")[0]))
    if fmt.startswith(("D16_UNORM_S8", "D24_UNORM_S8")):
        bits = 32
    return max(1, bits // 8)


@dataclass(frozen=True)
class ImageDesc:
    """A transient image: its format's name, its size relative to the graph's extent (or an
    absolute `size`), mip levels, MSAA samples and array layers."""

    format: str = "VK_FORMAT_R16G16B16A16_SFLOAT"
    scale: float = 1.0
    size: tuple[int, int] | None = None
    mips: int = 1
    samples: int = 1
    layers: int = 1

    def __post_init__(self) -> None:
        if not self.format.removeprefix("VK_FORMAT_") or not re.fullmatch(r"(VK_FORMAT_)?[A-Z0-9_]+", self.format):
            raise UsageError(f"image format {self.format!r} is not a VkFormat's name")
        if self.scale <= 0 or (self.size is not None and min(self.size) < 1):
            raise UsageError(f"image size must be positive (scale {self.scale}, size {self.size})")
        if self.mips < 1 or self.samples not in (1, 2, 4, 8, 16, 32, 64):
            raise UsageError(f"an image has mips >= 1 and 1, 2, 4 ... 64 samples, not {self.mips}, {self.samples}")
        if self.mips > 1 and self.samples > 1:
            raise UsageError("a multisampled image has one mip level")
        if self.layers < 1:
            raise UsageError(f"an image has at least one layer, not {self.layers}")

    @property
    def format_name(self) -> str:
        return self.format.removeprefix("VK_FORMAT_")

    def extent(self, graph_extent: tuple[int, int]) -> tuple[int, int]:
        if self.size is not None:
            return (int(self.size[0]), int(self.size[1]))
        w, h = graph_extent
        return (max(1, math.ceil(w * self.scale)), max(1, math.ceil(h * self.scale)))

    def estimated_bytes(self, graph_extent: tuple[int, int]) -> int:
        """Memory the image takes by its texel size (the device's own figure replaces it)."""
        w, h = self.extent(graph_extent)
        texels = sum(max(1, w >> m) * max(1, h >> m) for m in range(self.mips))
        return texels * texel_bytes(self.format_name) * self.samples * self.layers


@dataclass(frozen=True)
class BufferDesc:
    """A transient buffer of `size` bytes."""

    size: int

    def __post_init__(self) -> None:
        if self.size < 1:
            raise UsageError(f"a buffer has at least one byte, not {self.size}")


def mip_extent(extent: tuple[int, int], mip: int) -> tuple[int, int]:
    return (max(1, extent[0] >> mip), max(1, extent[1] >> mip))


@dataclass
class GraphImage:
    """An image as a pass records with it: the handle, a view of all mips (and layers), views of
    each mip, the VkFormat (its value), size, mips and samples; with layers, a view of each
    layer (its first mip)."""

    name: str
    handle: Any
    view: Any
    format: int
    extent: tuple[int, int]
    mips: int
    samples: int
    mip_views: tuple[Any, ...] = ()
    layers: int = 1
    layer_views: tuple[Any, ...] = ()

    def layer_view(self, layer: int) -> Any:
        if not 0 <= layer < self.layers:
            raise UsageError(f"image {self.name!r} has {self.layers} layer(s); no layer {layer}")
        if self.layers == 1:
            return self.mip_view(0)
        if not self.layer_views:
            raise UsageError(f"image {self.name!r} was imported without views of each layer (layer_views=)")
        return self.layer_views[layer]

    def attachment_view(self, mip: int, layer: int) -> Any:
        """The view that renders to (mip, layer): a mip's view, or a layer's (of mip 0)."""
        if self.layers == 1:
            return self.mip_view(mip)
        if mip != 0:
            raise UsageError(f"image {self.name!r} has views of each layer at mip 0 only, not mip {mip}")
        return self.layer_view(layer)

    def mip_view(self, mip: int) -> Any:
        if not 0 <= mip < self.mips:
            raise UsageError(f"image {self.name!r} has {self.mips} mip level(s); no mip {mip}")
        if self.view is None:
            raise UsageError(f"image {self.name!r} has no view: no pass samples, stores or attaches it")
        if self.mips == 1:
            return self.view
        if not self.mip_views:
            raise UsageError(f"image {self.name!r} was imported without views of each mip (mip_views=)")
        return self.mip_views[mip]

    def mip_extent(self, mip: int) -> tuple[int, int]:
        return mip_extent(self.extent, mip)


@dataclass
class GraphBuffer:
    name: str
    handle: Any
    size: int


@dataclass(frozen=True)
class Use:
    """One declared access of a pass: resource, access, mip and layer (None: all), for writes the
    load op and clear value, and whether the write covers a region only (the rest is kept)."""

    resource: str
    access: Access
    mip: int | None
    write: bool
    load: Load = Load.LOAD
    clear: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)
    layer: int | None = None
    region: bool = False

    @property
    def keeps_contents(self) -> bool:
        """The access sees or keeps what was there before (a read, a LOAD, a read-modify-write,
        a write of a region: no UNDEFINED transition; it runs after the last writer)."""
        return not self.write or self.load is Load.LOAD or self.access.usage.reads or self.region

    @property
    def needs_writer(self) -> bool:
        """The access reads what an earlier pass wrote (a region write may be the first)."""
        return self.keeps_contents and not (self.region and not self.access.usage.reads and self.load is not Load.LOAD)

    def describe(self) -> str:
        where = "" if self.mip is None else f"[mip {self.mip}]"
        where += ("" if self.layer is None else f"[layer {self.layer}]") + (" region" if self.region else "")
        load = f" {self.load.value}" if self.write and self.load is not Load.LOAD else ""
        return f"{self.resource}{where} {self.access.name}{load}"
