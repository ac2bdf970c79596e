"""Transient images and buffers: where in memory each one lives, and making them.

Images whose lifetimes (first..last pass position) do not overlap share memory: images of one
memory-type mask are packed into one "heap" (one suballocation of the device's block allocator)
by a greedy interval packing, largest first, each at the lowest offset (a multiple of its
alignment) that no image alive at the same time occupies. Several VkImages are then bound to the
same VkDeviceMemory at those offsets. An image placed over an earlier one starts from UNDEFINED
after a barrier on that earlier image's last accesses (barriers.py).

Buffers are not aliased: they are few and small next to the images.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ...gpu.allocator import DEVICE
from ...gpu.memory import Buffer
from ...gpu.owned import Owned
from .compile import Structure
from .resources import BufferDesc, GraphBuffer, GraphImage, ImageDesc, flags, is_depth

VIEWED = {"SAMPLED", "STORAGE", "COLOR_ATTACHMENT", "DEPTH_STENCIL_ATTACHMENT"}  # usages an image view needs
ESTIMATED_ALIGNMENT = 4096  # planning without a device: a typical optimal-tiling alignment


@dataclass(frozen=True)
class Requirement:
    name: str
    size: int
    alignment: int
    type_bits: int
    first: int
    last: int


@dataclass(frozen=True)
class Placement:
    name: str
    heap: int
    offset: int
    size: int


@dataclass
class Packing:
    placements: dict[str, Placement]
    heap_sizes: list[int]
    heap_alignments: list[int]
    heap_type_bits: list[int]
    unaliased_bytes: int = 0  # what the images would take each in its own memory

    @property
    def transient_bytes(self) -> int:
        return sum(self.heap_sizes)

    def overlapping(self, a: str, b: str) -> bool:
        """Whether two placed images share bytes of one heap."""
        pa, pb = self.placements[a], self.placements[b]
        return pa.heap == pb.heap and pa.offset < pb.offset + pb.size and pb.offset < pa.offset + pa.size


def _align(x: int, a: int) -> int:
    return (x + a - 1) // a * a


def pack(requirements: list[Requirement]) -> Packing:
    """Place each image in a heap of its memory-type mask so that no two alive at once overlap."""
    groups: dict[int, list[Requirement]] = {}
    for r in requirements:
        groups.setdefault(r.type_bits, []).append(r)
    packing = Packing({}, [], [], [], sum(_align(r.size, r.alignment) for r in requirements))
    for heap, (type_bits, group) in enumerate(sorted(groups.items())):
        placed: list[tuple[Requirement, int]] = []
        for r in sorted(group, key=lambda r: (-r.size, r.first, r.name)):
            busy = sorted(
                (offset, offset + other.size)
                for other, offset in placed
                if other.first <= r.last and r.first <= other.last
            )
            offset = 0
            for start, end in busy:  # the lowest gap that fits, walking the busy ranges in order
                if _align(offset, r.alignment) + r.size <= start:
                    break
                offset = max(offset, end)
            offset = _align(offset, r.alignment)
            placed.append((r, offset))
            packing.placements[r.name] = Placement(r.name, heap, offset, r.size)
        packing.heap_sizes.append(max((o + r.size for r, o in placed), default=0))
        packing.heap_alignments.append(max(r.alignment for r in group))
        packing.heap_type_bits.append(type_bits)
    return packing


def estimated_requirements(s: Structure) -> list[Requirement]:
    """Sizes from the formats (planning without a device)."""
    found = []
    for name, (first, last) in s.lifetimes.items():
        desc = s.resources[name].desc
        if isinstance(desc, ImageDesc):
            size = _align(desc.estimated_bytes(s.extent), ESTIMATED_ALIGNMENT)
            found.append(Requirement(name, size, ESTIMATED_ALIGNMENT, 1, first, last))
    return found


class _Needs:
    """A VkMemoryRequirements for the block allocator (size, alignment, memoryTypeBits)."""

    def __init__(self, size: int, alignment: int, type_bits: int) -> None:
        self.size, self.alignment, self.memoryTypeBits = size, alignment, type_bits


def aspect_of(vk: Any, fmt: str) -> int:
    if not is_depth(fmt):
        return int(vk.VK_IMAGE_ASPECT_COLOR_BIT)
    stencil = vk.VK_IMAGE_ASPECT_STENCIL_BIT if "_S8" in fmt else 0
    return int(vk.VK_IMAGE_ASPECT_DEPTH_BIT | stencil)


class Transients:
    """The transient images and buffers of one compile, all owned by `owned` (recompiling
    destroys them and makes new ones)."""

    def __init__(self, device: Any, s: Structure, owned: Owned) -> None:
        vk = device.vk
        self.images: dict[str, GraphImage] = {}
        self.buffers: dict[str, GraphBuffer] = {}
        self.memory: dict[str, Any] = {}  # image name -> its heap's VkDeviceMemory
        self.absolute_offset: dict[str, int] = {}  # image name -> its offset in that memory
        made: dict[str, tuple[Any, int, ImageDesc]] = {}
        requirements = []
        for name, (first, last) in s.lifetimes.items():
            desc = s.resources[name].desc
            usage_names = s.usage.get(name, set())
            if isinstance(desc, BufferDesc):
                usage = flags(vk, "VK_BUFFER_USAGE_", tuple(sorted(usage_names))) or vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT
                buf = owned.add(Buffer(device, desc.size, usage, DEVICE))
                self.buffers[name] = GraphBuffer(name, buf.handle, desc.size)
                continue
            assert isinstance(desc, ImageDesc)
            fmt = getattr(vk, desc.format if desc.format.startswith("VK_") else f"VK_FORMAT_{desc.format}")
            w, h = desc.extent(s.extent)
            image = owned.create(
                "Image",
                vk.VkImageCreateInfo(
                    imageType=vk.VK_IMAGE_TYPE_2D,
                    format=fmt,
                    extent=vk.VkExtent3D(w, h, 1),
                    mipLevels=desc.mips,
                    arrayLayers=desc.layers,
                    samples=desc.samples,
                    tiling=vk.VK_IMAGE_TILING_OPTIMAL,
                    usage=flags(vk, "VK_IMAGE_USAGE_", tuple(sorted(usage_names))),
                    sharingMode=vk.VK_SHARING_MODE_EXCLUSIVE,
                    initialLayout=vk.VK_IMAGE_LAYOUT_UNDEFINED,
                ),
            )
            req = vk.vkGetImageMemoryRequirements(device.handle, image)
            made[name] = (image, fmt, desc)
            requirements.append(
                Requirement(name, int(req.size), int(req.alignment), int(req.memoryTypeBits), first, last)
            )
        self.packing = pack(requirements)
        heaps = []
        for size, alignment, type_bits in zip(
            self.packing.heap_sizes, self.packing.heap_alignments, self.packing.heap_type_bits, strict=True
        ):
            heaps.append(
                owned.allocation(device.allocator.allocate(_Needs(size, alignment, type_bits), DEVICE, "image"))
            )
        for name, (image, fmt, desc) in made.items():
            place = self.packing.placements[name]
            heap = heaps[place.heap]
            self.memory[name] = heap.memory
            self.absolute_offset[name] = heap.offset + place.offset
            vk.vkBindImageMemory(device.handle, image, heap.memory, heap.offset + place.offset)
            # views sample or attach the depth; an image only copied has none (a view needs a usage that views)
            aspect = int(vk.VK_IMAGE_ASPECT_DEPTH_BIT) if is_depth(desc.format_name) else aspect_of(vk, "")
            views: list[Any] = [None]
            layer_views: list[Any] = []
            n = desc.layers
            if s.usage.get(name, set()) & VIEWED:
                views = [_view(vk, owned, image, fmt, aspect, (0, desc.mips), (0, n))]
                if desc.mips > 1:
                    views += [_view(vk, owned, image, fmt, aspect, (m, 1), (0, n)) for m in range(desc.mips)]
                if n > 1:  # what a pass renders to one layer with
                    layer_views = [_view(vk, owned, image, fmt, aspect, (0, 1), (k, 1)) for k in range(n)]
            self.images[name] = GraphImage(
                name,
                image,
                views[0],
                fmt,
                desc.extent(s.extent),
                desc.mips,
                desc.samples,
                tuple(views[1:]),
                n,
                tuple(layer_views),
            )


def _view(
    vk: Any, owned: Owned, image: Any, fmt: int, aspect: int, mips: tuple[int, int], layers: tuple[int, int]
) -> Any:
    """A view of mips (first, count) and layers (first, count); an array view over several layers."""
    return owned.create(
        "ImageView",
        vk.VkImageViewCreateInfo(
            image=image,
            viewType=vk.VK_IMAGE_VIEW_TYPE_2D_ARRAY if layers[1] > 1 else vk.VK_IMAGE_VIEW_TYPE_2D,
            format=fmt,
            subresourceRange=vk.VkImageSubresourceRange(
                aspectMask=aspect,
                baseMipLevel=mips[0],
                levelCount=mips[1],
                baseArrayLayer=layers[0],
                layerCount=layers[1],
            ),
        ),
    )
