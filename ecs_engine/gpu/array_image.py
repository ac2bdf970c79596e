"""A sampled 2D array image with a full mip chain and two views of the same texels: sRGB (the
sampler decodes to linear before filtering) and UNORM (data read as stored); or, with `cube`, six
half-float RGBA layers seen as one cube map (render/lighting/environment.py). Layers are uploaded from
NumPy mip chains through a bounded staging buffer.

The 2D array is stored as sRGB (its UNORM view reads the same bytes as they are): uploads copy
bytes unchanged, and blits into and within it (a render target's image copied in and its mips made,
render/passes/render_texture.py) decode and filter in linear light, as the CPU's mip_chain does.
Hence TRANSFER_SRC too: a blit reads the level above."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from .allocator import DEVICE
from .device import Device
from .image_barrier import image_barrier, record_image_barriers
from .memory import HOST, Buffer
from .owned import Owned

_STAGING_BYTES = 64 * 2**20  # one submit copies at most this much (a 4096^2 layer's chain is 85 MiB: alone)


class ArrayImage:
    """side x side texels, `levels` mips, `layers` layers; `srgb_view` and `unorm_view` (with
    `cube`: 6 RGBA16F layers and `cube_view`)."""

    def __init__(self, device: Device, side: int, layers: int, cube: bool = False) -> None:
        vk = device.vk
        self.device = device
        self.side, self.layers = side, 6 if cube else layers
        self.levels = side.bit_length()  # side is a power of two: log2(side) + 1
        if cube:
            flags, storage = vk.VK_IMAGE_CREATE_CUBE_COMPATIBLE_BIT, vk.VK_FORMAT_R16G16B16A16_SFLOAT
            views = [(vk.VK_FORMAT_R16G16B16A16_SFLOAT, vk.VK_IMAGE_VIEW_TYPE_CUBE)]
        else:
            flags, storage = vk.VK_IMAGE_CREATE_MUTABLE_FORMAT_BIT, vk.VK_FORMAT_R8G8B8A8_SRGB
            kind = vk.VK_IMAGE_VIEW_TYPE_2D_ARRAY
            views = [(vk.VK_FORMAT_R8G8B8A8_SRGB, kind), (vk.VK_FORMAT_R8G8B8A8_UNORM, kind)]
        self.format = storage  # what blits into it convert to
        self.owned = Owned(device)  # the image, its memory, its views: destroyed views first
        self.views: list[Any] = []
        try:
            self.handle = self.owned.create(
                "Image",
                vk.VkImageCreateInfo(
                    flags=flags,
                    imageType=vk.VK_IMAGE_TYPE_2D,
                    format=storage,
                    extent=vk.VkExtent3D(side, side, 1),
                    mipLevels=self.levels,
                    arrayLayers=self.layers,
                    samples=vk.VK_SAMPLE_COUNT_1_BIT,
                    tiling=vk.VK_IMAGE_TILING_OPTIMAL,
                    usage=vk.VK_IMAGE_USAGE_SAMPLED_BIT
                    | vk.VK_IMAGE_USAGE_TRANSFER_DST_BIT
                    | vk.VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                    sharingMode=vk.VK_SHARING_MODE_EXCLUSIVE,
                    initialLayout=vk.VK_IMAGE_LAYOUT_UNDEFINED,
                ),
            )
            req = vk.vkGetImageMemoryRequirements(device.handle, self.handle)
            self.allocation = self.owned.allocation(device.allocator.allocate(req, DEVICE, "image"))
            vk.vkBindImageMemory(device.handle, self.handle, self.allocation.memory, self.allocation.offset)
            for fmt, view_type in views:
                info = vk.VkImageViewCreateInfo(
                    image=self.handle, viewType=view_type, format=fmt, subresourceRange=self._range()
                )
                self.views.append(self.owned.create("ImageView", info))
        except BaseException:
            self.destroy()
            raise

    @property
    def srgb_view(self) -> Any:
        return self.views[0]

    @property
    def unorm_view(self) -> Any:
        return self.views[1]

    @property
    def cube_view(self) -> Any:
        return self.views[0]

    def _range(self) -> Any:
        vk = self.device.vk
        return vk.VkImageSubresourceRange(
            aspectMask=vk.VK_IMAGE_ASPECT_COLOR_BIT,
            baseMipLevel=0,
            levelCount=self.levels,
            baseArrayLayer=0,
            layerCount=self.layers,
        )

    def upload(self, chains: Sequence[Sequence[np.ndarray]]) -> None:
        """Fill layers 0.. with `chains` (per layer: its levels, RGBA8, or RGBA16F for a cube,
        largest first); the rest of the layers stay undefined. Ends with every layer ready for
        sampling."""
        vk = self.device.vk
        if len(chains) > self.layers:
            raise ValueError(f"{len(chains)} layers for an image of {self.layers}")
        self._barrier(vk.VK_IMAGE_LAYOUT_UNDEFINED, vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL)
        batch: list[tuple[int, int, np.ndarray]] = []
        size = 0
        for layer, chain in enumerate(chains):
            if len(chain) != self.levels or chain[0].shape != (self.side, self.side, 4):
                raise ValueError(f"layer {layer}: needs {self.levels} levels from {self.side} x {self.side} RGBA")
            nbytes = sum(level.nbytes for level in chain)
            if batch and size + nbytes > _STAGING_BYTES:
                self._copy(batch, size)
                batch, size = [], 0
            batch.extend((layer, level, pixels) for level, pixels in enumerate(chain))
            size += nbytes
        if batch:
            self._copy(batch, size)
        self._barrier(vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL)

    def _copy(self, batch: list[tuple[int, int, np.ndarray]], size: int) -> None:
        vk = self.device.vk
        staging = Buffer(self.device, size, vk.VK_BUFFER_USAGE_TRANSFER_SRC_BIT, HOST)
        try:
            raw = staging.bytes()
            regions = []
            offset = 0
            for layer, level, pixels in batch:
                raw[offset : offset + pixels.nbytes] = np.ascontiguousarray(pixels).view(np.uint8).reshape(-1)
                side = pixels.shape[0]
                regions.append(
                    vk.VkBufferImageCopy(
                        bufferOffset=offset,
                        bufferRowLength=0,
                        bufferImageHeight=0,
                        imageSubresource=vk.VkImageSubresourceLayers(
                            aspectMask=vk.VK_IMAGE_ASPECT_COLOR_BIT, mipLevel=level, baseArrayLayer=layer, layerCount=1
                        ),
                        imageOffset=vk.VkOffset3D(0, 0, 0),
                        imageExtent=vk.VkExtent3D(side, side, 1),
                    )
                )
                offset += pixels.nbytes
            self.device.submit_once(
                lambda cb: vk.vkCmdCopyBufferToImage(
                    cb, staging.handle, self.handle, vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, len(regions), regions
                )
            )
        finally:
            staging.destroy()

    def _barrier(self, old: int, new: int) -> None:
        vk = self.device.vk
        to_read = new == vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL
        barrier = image_barrier(
            vk,
            self.handle,
            aspect=vk.VK_IMAGE_ASPECT_COLOR_BIT,
            mips=self.levels,
            layers=self.layers,
            old=old,
            new=new,
            src_stage=vk.VK_PIPELINE_STAGE_2_TRANSFER_BIT if to_read else vk.VK_PIPELINE_STAGE_2_TOP_OF_PIPE_BIT,
            src_access=vk.VK_ACCESS_2_TRANSFER_WRITE_BIT if to_read else 0,
            dst_stage=vk.VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT if to_read else vk.VK_PIPELINE_STAGE_2_TRANSFER_BIT,
            dst_access=vk.VK_ACCESS_2_SHADER_READ_BIT if to_read else vk.VK_ACCESS_2_TRANSFER_WRITE_BIT,
        )
        self.device.submit_once(lambda cb: record_image_barriers(vk, cb, [barrier]))

    def destroy(self) -> None:
        self.owned.destroy()
        self.handle = None


ANISOTROPY_CHOICES = (1, 2, 4, 8, 16)  # --anisotropy: 1 is off; 16, the most GPUs offer, the default's cap


def sampler_anisotropy(device: Device, anisotropy: int | None = None) -> float:
    """The material textures' maximum anisotropy: `anisotropy` (1: off, plain trilinear), or
    None for the device's best up to 16 (1 without the samplerAnisotropy feature). A number the
    device cannot filter with is a UsageError naming the flag and what the device offers."""
    from ..errors import UsageError

    offered = min(16.0, float(device.limits.maxSamplerAnisotropy)) if device.features.get("samplerAnisotropy") else 1.0
    if anisotropy is None:
        return offered
    if anisotropy not in ANISOTROPY_CHOICES:
        raise UsageError(f"--anisotropy {anisotropy!r}: one of {', '.join(map(str, ANISOTROPY_CHOICES))} (1: off)")
    if anisotropy > offered:
        what = f"at most {offered:g}" if offered > 1 else "no anisotropic filtering (use 1)"
        raise UsageError(f"--anisotropy {anisotropy}: {device.info.name} offers {what}")
    return float(anisotropy)


def texture_sampler(device: Device, anisotropy: float = 1.0) -> Any:
    """Trilinear, repeating, with `anisotropy` (sampler_anisotropy: above 1, anisotropic)."""
    return _trilinear(device, device.vk.VK_SAMPLER_ADDRESS_MODE_REPEAT, anisotropy, None)


def clamped_sampler(device: Device, max_lod: float | None = None) -> Any:
    """Trilinear, clamped to the edges (ImGui's textures: max_lod 1; a cube map: every mip)."""
    return _trilinear(device, device.vk.VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE, 0.0, max_lod)


def nearest_sampler(device: Device) -> Any:
    """Nearest, clamped to the edges: for images read texel by texel (depth, the G-buffer)."""
    vk = device.vk
    clamp = vk.VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE
    return vk.vkCreateSampler(
        device.handle,
        vk.VkSamplerCreateInfo(
            magFilter=vk.VK_FILTER_NEAREST,
            minFilter=vk.VK_FILTER_NEAREST,
            addressModeU=clamp,
            addressModeV=clamp,
            addressModeW=clamp,
        ),
        None,
    )


def _trilinear(device: Device, address_uv: int, anisotropy: float, max_lod: float | None) -> Any:
    vk = device.vk
    return vk.vkCreateSampler(
        device.handle,
        vk.VkSamplerCreateInfo(
            magFilter=vk.VK_FILTER_LINEAR,
            minFilter=vk.VK_FILTER_LINEAR,
            mipmapMode=vk.VK_SAMPLER_MIPMAP_MODE_LINEAR,
            addressModeU=address_uv,
            addressModeV=address_uv,
            addressModeW=vk.VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE,
            anisotropyEnable=vk.VK_TRUE if anisotropy > 1 else vk.VK_FALSE,
            maxAnisotropy=max(anisotropy, 1.0),
            minLod=0.0,
            maxLod=vk.VK_LOD_CLAMP_NONE if max_lod is None else max_lod,
        ),
        None,
    )
