"""Shadow maps: one 32-bit depth image with a layer per shadow view (a cascade, a spot light's
map; render/shadows/views.py), square, a view per layer that dynamic rendering draws into
(render/shadows/maps_pass.py), and the view and samplers the lighting reads them through.

Depth is reverse-Z, cleared to 0 (far); the comparison samplers compare with GREATER_OR_EQUAL,
so a receiver whose depth is at least the nearest caster's is lit. The filtering one is linear
(each tap a bilinear 2 x 2 comparison: percentage-closer filtering in hardware), the hard one
nearest; a third reads the depths themselves (PCSS looks for its blockers with it).
Frames in flight share the image: the shadow pass's barriers (render/shadows/maps_pass.py) order this
frame's writes after the previous frame's reads and before this frame's lighting.

The editor shows each layer (preview_view: the depth in R, G and B, read through the plain
sampler) in the overlay, drawn after the lighting, where every layer is in READ_LAYOUT.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from .image_barrier import dependency, image_barrier
from .image_clear import clear_once
from .memory import Image
from .owned import Owned
from .pipeline import AttachmentFormats

if TYPE_CHECKING:
    from .device import Device

SHADOW_FORMAT_NAME = "VK_FORMAT_D32_SFLOAT"
READ_LAYOUT_NAME = "VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL"  # after the shadow pass: sampled
WRITE_LAYOUT_NAME = "VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL"  # while a layer is drawn


def shadow_formats(vk: Any, samples: int = 1) -> AttachmentFormats:
    """What the depth-only pipelines and secondaries are made for: 32-bit depth, no colour."""
    return AttachmentFormats(colors=(), depth=getattr(vk, SHADOW_FORMAT_NAME), samples=samples)


def depth_barriers(vk: Any, image: Any, layers: tuple[int, ...], discard: bool) -> tuple[Any, Any]:
    """What a depth-only render pass's layouts and subpass dependencies did, as two
    VkDependencyInfo for vkCmdPipelineBarrier2 (each (pointer, struct): keep the struct): before
    drawing, `layers` of `image` from READ_LAYOUT (from UNDEFINED with `discard`: contents
    dropped) to WRITE_LAYOUT once the previous frame's readers are done (frames in flight share
    the image; a read before a write needs no memory dependency); after, the depth written to
    READ_LAYOUT for the fragment and compute shaders that sample it."""
    tests = vk.VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | vk.VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT
    readers = vk.VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT | vk.VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT
    write = vk.VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT
    read, written = getattr(vk, READ_LAYOUT_NAME), getattr(vk, WRITE_LAYOUT_NAME)

    def batch(src: int, src_access: int, dst: int, dst_access: int, old: int, new: int) -> tuple[Any, Any]:
        barriers = [
            image_barrier(
                vk,
                image,
                aspect=vk.VK_IMAGE_ASPECT_DEPTH_BIT,
                base_layer=layer,
                old=old,
                new=new,
                src_stage=src,
                src_access=src_access,
                dst_stage=dst,
                dst_access=dst_access,
            )
            for layer in layers
        ]
        info = dependency(vk, barriers)
        return vk.ffi.addressof(info), info

    depth_rw = vk.VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT | write
    before = batch(readers | tests, 0, tests, depth_rw, vk.VK_IMAGE_LAYOUT_UNDEFINED if discard else read, written)
    return before, batch(tests, write, readers, vk.VK_ACCESS_2_SHADER_READ_BIT, written, read)


class ShadowMaps:
    """`layers` square depth maps of `resolution` texels, each drawn through its layer view with
    dynamic rendering (pipelines and secondaries made for shadow_formats())."""

    def __init__(self, device: Device, resolution: int, layers: int) -> None:
        vk = self.vk = device.vk
        self.device = device
        self.resolution, self.layers = int(resolution), int(layers)
        self.image: Image | None = None
        self.layer_views: list[Any] = []
        self.samplers: list[Any] = []
        self._previews: dict[int, Any] = {}  # layer -> its grey view (preview_view)
        # built once (each cffi struct costs microseconds a frame), kept while the maps live:
        self.read_layout = getattr(vk, READ_LAYOUT_NAME)
        # the image, then its layer views and samplers (and preview views, made later): destroyed
        # last made first, so every view goes before its image
        self.owned = Owned(device)
        try:
            self.image = self.owned.add(
                Image(
                    device,
                    self.resolution,
                    self.resolution,
                    getattr(vk, SHADOW_FORMAT_NAME),
                    vk.VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT
                    | vk.VK_IMAGE_USAGE_SAMPLED_BIT
                    | vk.VK_IMAGE_USAGE_TRANSFER_DST_BIT,
                    vk.VK_IMAGE_ASPECT_DEPTH_BIT,
                    layers=self.layers,
                )
            )
            for layer in range(self.layers):
                self.layer_views.append(self._own_view(self.image.layer_view(layer)))
            kinds = ((vk.VK_FILTER_LINEAR, True), (vk.VK_FILTER_NEAREST, True), (vk.VK_FILTER_NEAREST, False))
            for filtering, compare in kinds:
                self.samplers.append(
                    self.owned.create(
                        "Sampler",
                        vk.VkSamplerCreateInfo(
                            magFilter=filtering,
                            minFilter=filtering,
                            addressModeU=vk.VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE,
                            addressModeV=vk.VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE,
                            addressModeW=vk.VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE,
                            compareEnable=vk.VK_TRUE if compare else vk.VK_FALSE,
                            compareOp=vk.VK_COMPARE_OP_GREATER_OR_EQUAL,
                        ),
                    )
                )
            self._clear()
        except BaseException:
            self.destroy()
            raise

    def _clear(self) -> None:
        """Every layer cleared to the far plane (reverse-Z: 0) and left in READ_LAYOUT, once, when
        the maps are made: a frame then draws only its views' corners, and a layer no view drew
        is read as lit (so the frame graph's shadow pass declares the same accesses every frame)."""
        vk = self.vk
        assert self.image is not None
        readers = vk.VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT | vk.VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT
        access = vk.VK_ACCESS_SHADER_READ_BIT
        layout = self.read_layout
        clear_once(
            self.device,
            self.image.handle,
            depth=True,
            layers=self.layers,
            value=0.0,
            layout=layout,
            readers=readers,
            read_access=access,
        )

    def _own_view(self, view: Any) -> Any:
        handle, vk = self.device.handle, self.vk
        return self.owned.add(view, lambda: vk.vkDestroyImageView(handle, view, None))

    def image_infos(self) -> list[Any]:
        """VkDescriptorImageInfo of the array with the filtering comparison sampler, the hard
        (nearest) one, and the plain nearest one that reads depths."""
        vk = self.vk
        layout = self.read_layout
        assert self.image is not None
        view = self.image.view  # the 2D array of every layer
        return [vk.VkDescriptorImageInfo(sampler=s, imageView=view, imageLayout=layout) for s in self.samplers]

    @property
    def plain_sampler(self) -> Any:
        """The nearest sampler that reads depths (no comparison)."""
        return self.samplers[2]

    @property
    def destroyed(self) -> bool:
        return self.image is None

    def preview_view(self, layer: int) -> Any:
        """A 2D view of `layer` whose R, G and B are its depth (A one): a grey image, near
        (reverse-Z: 1) white, far black; read it with plain_sampler in read_layout. Made on first
        use, destroyed with the maps."""
        assert self.image is not None
        if not 0 <= layer < self.layers:
            raise IndexError(f"layer {layer} of {self.layers}")
        view = self._previews.get(layer)
        if view is None:
            vk = self.vk
            r, one = vk.VK_COMPONENT_SWIZZLE_R, vk.VK_COMPONENT_SWIZZLE_ONE
            view = vk.vkCreateImageView(
                self.device.handle,
                vk.VkImageViewCreateInfo(
                    image=self.image.handle,
                    viewType=vk.VK_IMAGE_VIEW_TYPE_2D,
                    format=self.image.format,
                    components=vk.VkComponentMapping(r=r, g=r, b=r, a=one),
                    subresourceRange=vk.VkImageSubresourceRange(
                        aspectMask=vk.VK_IMAGE_ASPECT_DEPTH_BIT,
                        baseMipLevel=0,
                        levelCount=1,
                        baseArrayLayer=layer,
                        layerCount=1,
                    ),
                ),
                None,
            )
            self._previews[layer] = self._own_view(view)
        return view

    def destroy(self) -> None:
        self.owned.destroy()
        self._previews = {}
        self.samplers, self.layer_views = [], []
        self.image = None
