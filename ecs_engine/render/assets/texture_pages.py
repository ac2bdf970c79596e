"""The GPU copy of a `Textures` registry: one array image per size class (textures.py), bound
together as set 0's `texture_pages` (two views per class: sRGB, then UNORM), and `refs`, the value
a material row carries for each texture handle: page << 16 | layer.

Why pages and not one descriptor per texture: indexing a descriptor array with an index that
varies within a draw (instanced draws mix materials) needs descriptor indexing's non-uniform
indexing, which lavapipe, the CI's driver, lacks (Mesa 22: shaderSampledImageArrayNonUniformIndexing
0 and 32 samplers per stage). A page is picked by a switch with constant indices and sampled with
explicit gradients, legal everywhere; the layer is a coordinate. The price: each texture is resized
to its class's square power of two.

Textures get added, and replaced only by hot reload: an addition uploads the classes that grew,
a replacement all of them (after the GPU is idle: this happens when models load or a file is
edited, not per frame).

A render target (textures.py: `Textures.render_target`) is uploaded as opaque black, like any
texture, and is a colour texture; `place(handle)` says where it lives (the page's image, its
layer) for the pass that draws into it each frame (render/passes/render_texture.py). An upload
that remakes its page fills it black again: the next frame draws it again, and the new image
changes the pass's key, so frame replay records that frame anew.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ...errors import UsageError
from ...gpu.array_image import ArrayImage, sampler_anisotropy, texture_sampler
from ...gpu.device import Device
from ...gpu.owned import Owned
from ..layouts import NO_TEXTURE, TEXTURE_PAGES
from .textures import CLASS_SIZES, Textures, mip_chain, resized, size_class

assert TEXTURE_PAGES == 2 * len(CLASS_SIZES)


@dataclass(frozen=True)
class TexturePlace:
    """Where a texture lives after `sync`: `image`'s layer `layer`, `side` x `side` texels and
    `mips` levels; `page` is its index into the descriptor's texture_pages (2 * class for
    sRGB colour, + 1 for linear data); `generation`, the upload that made `image`."""

    image: ArrayImage
    layer: int
    side: int
    mips: int
    page: int
    generation: int


class TexturePages:
    def __init__(self, device: Device, anisotropy: int | None = None) -> None:
        """`anisotropy`: the sampler's maximum (1: off; None: the device's, up to 16; checked by
        gpu/array_image.sampler_anisotropy). Lavapipe's anisotropic filter, unlike its trilinear
        one, strays from bilinear filtering where a texture is magnified (tests/test_textures.py):
        tests that compare with a bilinear reference turn it off."""
        self.device = device
        self.anisotropy = sampler_anisotropy(device, anisotropy)
        # the sampler and the fallback live as long as this; the pages, made again as textures
        # arrive, in a scope of their own
        self.owned = Owned(device)
        self._pages = Owned(device)
        try:
            sampler = self.sampler = texture_sampler(device, self.anisotropy)
            self.owned.add(sampler, lambda: device.vk.vkDestroySampler(device.handle, sampler, None))
            self.fallback = self.owned.add(ArrayImage(device, 1, 1))  # bound where a class has no textures yet
            self.fallback.upload([[np.full((1, 1, 4), 255, np.uint8)]])
        except BaseException:
            self.owned.destroy()
            raise
        self.pages: dict[int, ArrayImage] = {}
        self._chains: dict[int, list[np.ndarray]] = {}  # handle -> its mip chain (kept for re-uploads)
        self._black: dict[int, list[np.ndarray]] = {}  # side -> the opaque black chain render targets share
        self.render_targets: set[int] = set()  # handles of render targets (a camera draws their layer)
        self._layers: dict[int, list[int]] = {}  # class -> handles, by layer
        self._source: tuple[Textures, int, int] | None = None  # (the registry, how many uploaded, its edits)
        self.refs = np.zeros(0, np.uint32)
        self.generation = 0  # counts uploads: descriptor sets and material rows written before are stale
        self.max_layers = int(device.limits.maxImageArrayLayers)

    def sync(self, textures: Textures) -> bool:
        """Upload what `textures` added since the last call (all of it for another registry);
        True when anything changed (the caller rewrites descriptors and material rows)."""
        same = self._source is not None and self._source[0] is textures and self._source[2] == textures.edits
        if same and self._source is not None and self._source[1] == len(textures):
            return False
        if not same and not len(textures) and not self.pages:
            self._source = (textures, 0, textures.edits)  # nothing to upload, nothing bound to replace
            return False
        self.device.wait_idle()  # frames in flight may sample the pages replaced below
        start = self._source[1] if same and self._source is not None else 0
        if not same:
            self._clear()
        grown: set[int] = set()
        refs = np.full(len(textures), NO_TEXTURE, np.uint32)
        refs[: len(self.refs)] = self.refs[: min(len(self.refs), len(textures))]
        for handle in range(start, len(textures)):
            texture = textures[handle]
            target = textures.render_target_of(handle)
            cls = size_class(*(texture.size if target is None else (target.width, target.height)))
            layers = self._layers.setdefault(cls, [])
            if len(layers) >= min(self.max_layers, 1 << 16):
                raise UsageError(
                    f"more than {len(layers)} textures of about {CLASS_SIZES[cls]} pixels: the device's limit"
                )
            page = 2 * cls + (0 if texture.color else 1)
            refs[handle] = (page << 16) | len(layers)
            layers.append(handle)
            if target is not None:
                self._chains[handle] = self._black_chain(CLASS_SIZES[cls])
                self.render_targets.add(handle)
            else:
                self._chains[handle] = mip_chain(resized(texture.pixels, CLASS_SIZES[cls]), texture.color)
            grown.add(cls)
        for cls in sorted(grown):
            old = self.pages.pop(cls, None)
            if old is not None:
                self._pages.release(old)
            handles = self._layers[cls]
            image = self.pages[cls] = self._pages.add(ArrayImage(self.device, CLASS_SIZES[cls], len(handles)))
            image.upload([self._chains[h] for h in handles])
        self.refs = refs
        self._source = (textures, len(textures), textures.edits)
        self.generation += 1
        return True

    def place(self, handle: int) -> TexturePlace:
        """Where texture `handle` lives on the GPU since the last `sync` (its image is made again
        by a later sync that adds to its class: ask again after each)."""
        handle = int(handle)
        ref = int(self.refs[handle]) if 0 <= handle < len(self.refs) else NO_TEXTURE
        if ref == NO_TEXTURE:
            raise UsageError(f"texture {handle} is not on the GPU yet: TexturePages.sync uploads it")
        page, layer = ref >> 16, ref & 0xFFFF
        image = self.pages[page // 2]
        return TexturePlace(image, layer, image.side, image.levels, page, self.generation)

    def _black_chain(self, side: int) -> list[np.ndarray]:
        """Opaque black from side x side down to 1 x 1, one read-only chain per side."""
        chain = self._black.get(side)
        if chain is None:
            chain = []
            level_side = side
            while level_side:
                level = np.zeros((level_side, level_side, 4), np.uint8)
                level[..., 3] = 255
                level.flags.writeable = False
                chain.append(level)
                level_side //= 2
            self._black[side] = chain
        return chain

    def image_infos(self) -> list[Any]:
        """TEXTURE_PAGES VkDescriptorImageInfo: per class its sRGB then its UNORM view."""
        vk = self.device.vk
        infos = []
        for cls in range(len(CLASS_SIZES)):
            image = self.pages.get(cls, self.fallback)
            for view in (image.srgb_view, image.unorm_view):
                infos.append(
                    vk.VkDescriptorImageInfo(
                        sampler=self.sampler, imageView=view, imageLayout=vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL
                    )
                )
        return infos

    def map_rows(self, rows: np.ndarray) -> None:
        """Material rows' texture handles -> refs, in place (NO_TEXTURE stays)."""
        for name in ("textures", "textures2"):
            handles = rows[name]
            present = handles != NO_TEXTURE
            if present.any():
                handles[present] = self.refs[handles[present]]

    def _clear(self) -> None:
        self._pages.destroy()
        self.pages.clear()
        self._chains.clear()
        self._layers.clear()
        self.render_targets.clear()
        self.refs = np.zeros(0, np.uint32)

    def destroy(self) -> None:
        self._clear()
        self.owned.destroy()  # the fallback, then the sampler
