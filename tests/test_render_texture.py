"""Render to texture, the texture side: `Textures.render_target` (one name, one handle, one
size), where its layer lives (`TexturePages.place`), and `RenderTexturePass` copying a graph
image into that layer and blitting its mips (in linear light: the page is stored as sRGB),
checked on lavapipe (validation on) against NumPy; a re-sync that remakes the page; and a
material that samples the layer, drawn by the Renderer."""

from __future__ import annotations

import math
from contextlib import contextmanager

import numpy as np
import pytest
from gpu_context import headless_gpu, shared_device
from host_reads import host_barrier

from ecs_engine import World
from ecs_engine.app.scenes import default_schedule
from ecs_engine.components import Camera, Mesh, Transform
from ecs_engine.errors import UsageError
from ecs_engine.gpu.memory import HOST, Buffer
from ecs_engine.render.assets.materials import Material, materials
from ecs_engine.render.assets.primitives import plane_mesh
from ecs_engine.render.assets.texture_pages import TexturePages
from ecs_engine.render.assets.textures import CLASS_SIZES, Texture, Textures, linear_to_srgb, size_class
from ecs_engine.render.graph import Access, FrameGraph, Load, Pass
from ecs_engine.render.passes.render_texture import RenderTargetImage, RenderTexturePass, blit_filter

A = (0.2, 0.6, 1.0, 1.0)  # linear: the clear values of an sRGB attachment
B = (1.0, 0.1, 0.0, 1.0)


def srgb8(c) -> np.ndarray:
    rgb = np.round(linear_to_srgb(np.asarray(c[:3], np.float64)) * 255.0)
    return np.concatenate([rgb, [round(c[3] * 255.0)]]).astype(np.int64)


# ---------------------------------------------------------------------------------------- CPU
def test_one_name_is_one_handle_and_one_size():
    t = Textures()
    t.add(Texture("other", np.zeros((4, 4, 4), np.uint8)))
    tv = t.render_target("tv", 320, 240)
    assert t.render_target("tv", 320, 240) == tv and len(t) == 2
    assert t.render_target_handle("tv") == tv and t.render_target_handle("map") is None
    target = t.render_target_of(tv)
    assert target is not None and (target.name, target.width, target.height) == ("tv", 320, 240)
    assert target.side == CLASS_SIZES[size_class(320, 240)] == 256
    assert t.render_target_of(0) is None
    minimap = t.render_target("map", 64, 64)
    assert minimap != tv and [r.name for r in t.render_targets] == ["tv", "map"]
    assert t[tv].color and t[tv].pixels.tolist() == [[[0, 0, 0, 255]]]  # one black texel on the CPU
    with pytest.raises(UsageError, match=r"'tv' is 320 x 240 pixels and was asked for again at 64 x 64"):
        t.render_target("tv", 64, 64)


@pytest.mark.parametrize(
    "args, match",
    [
        (("", 16, 16), "needs a name"),
        (("x", 0, 16), "'x': its width must be a whole number of pixels from 1 to 8192, not 0$"),
        (("x", 16, 2.5), "its height must be a whole number of pixels from 1 to 8192, not 2.5$"),
        (("x", 16, True), "its height must be"),
        (("x", 8193, 16), "its width must be a whole number of pixels from 1 to 8192, not 8193$"),
    ],
)
def test_bad_render_targets_are_refused_with_one_message(args, match):
    with pytest.raises(UsageError, match=match):
        Textures().render_target(*args)


@pytest.mark.parametrize("size", [(8193, 16), (16, 16384), (0, 16)])
def test_the_component_and_the_texture_share_one_limit_and_message(size):
    """RenderTexture (a ValueError, as every component check) and Textures.render_target (a
    UsageError) refuse the same sizes with the same words; the largest side is taken by both."""
    from ecs_engine.components import RenderTexture
    from ecs_engine.components.camera import MAX_RENDER_TEXTURE_SIDE

    with pytest.raises(UsageError) as by_texture:
        Textures().render_target("tv", *size)
    with pytest.raises(ValueError) as by_component:
        World().spawn(RenderTexture(name="tv", width=size[0], height=size[1]))
    assert str(by_component.value) == f"new entity: {by_texture.value}"
    side = MAX_RENDER_TEXTURE_SIDE
    World().spawn(RenderTexture(name="tv", width=side, height=side))
    assert Textures().render_target("tv", side, side) == 0


def test_a_render_target_is_not_replaced_by_pixels():
    t = Textures()
    tv = t.render_target("tv", 16, 16)
    with pytest.raises(UsageError, match="drawn by its camera"):
        t.replace(tv, Texture("x", np.zeros((16, 16, 4), np.uint8)))


# ---------------------------------------------------------------------------------------- GPU
class Halves(Pass):
    """Clears "target" to A, then its right (or bottom) half to B."""

    name = "halves"

    def __init__(self, split: str = "x") -> None:
        self.split = split

    def setup(self, b):
        b.write("target", Access.COLOR_WRITE, load=Load.CLEAR, clear=A)

    def record(self, cb, ctx):
        vk = ctx.vk
        w, h = ctx.image("target").extent
        x, y = (w // 2, 0) if self.split == "x" else (0, h // 2)
        ctx.begin_rendering(colors=("target",))
        value = vk.VkClearValue(color=vk.VkClearColorValue(float32=list(B)))
        attachment = vk.VkClearAttachment(aspectMask=vk.VK_IMAGE_ASPECT_COLOR_BIT, colorAttachment=0, clearValue=value)
        rect = vk.VkRect2D(vk.VkOffset2D(x, y), vk.VkExtent2D(w - x, h - y))
        vk.vkCmdClearAttachments(cb, 1, [attachment], 1, [vk.VkClearRect(rect=rect, baseArrayLayer=0, layerCount=1)])
        ctx.end_rendering()


@contextmanager
def render_view(pages, handle, width, height, split="x"):
    """A graph drawing halves into a RenderTargetImage, then the pass copying it into the layer;
    yields a function that records and submits one frame of it and returns the graph's key."""
    device = pages.device
    image = RenderTargetImage(device, width, height)
    graph = FrameGraph(device)
    try:
        image.import_into(graph)
        graph.add_pass(Halves(split))
        graph.add_pass(RenderTexturePass(pages, handle))
        graph.compile((width, height))
        assert graph.order == ["halves", "render_texture"]

        def frame():
            device.submit_once(graph.execute)
            return graph.key()

        yield frame
    finally:
        graph.destroy()
        image.destroy()


def draw_into(pages, handle, width, height, split="x"):
    with render_view(pages, handle, width, height, split) as frame:
        return frame()


def read_layer(pages, handle, mips):
    """The texture's layer at each of `mips`: (side, side, 4) int64 arrays."""
    device, vk = pages.device, pages.device.vk
    place = pages.place(handle)
    sides = [max(place.side >> m, 1) for m in mips]
    offsets = np.cumsum([0] + [s * s * 4 for s in sides])
    out = Buffer(device, int(offsets[-1]), vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT, HOST)
    whole = vk.VkImageSubresourceRange(
        aspectMask=vk.VK_IMAGE_ASPECT_COLOR_BIT,
        baseMipLevel=0,
        levelCount=place.mips,
        baseArrayLayer=place.layer,
        layerCount=1,
    )

    def barrier(cb, old, new, src, dst):
        b = vk.VkImageMemoryBarrier2(
            srcStageMask=src[0],
            srcAccessMask=src[1],
            dstStageMask=dst[0],
            dstAccessMask=dst[1],
            oldLayout=old,
            newLayout=new,
            srcQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED,
            dstQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED,
            image=place.image.handle,
            subresourceRange=whole,
        )
        vk.vkCmdPipelineBarrier2(cb, vk.VkDependencyInfo(pImageMemoryBarriers=[b]))

    def record(cb):
        shaders = (vk.VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, vk.VK_ACCESS_2_NONE)
        transfer = (vk.VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, vk.VK_ACCESS_2_TRANSFER_READ_BIT)
        read_only, src = vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL
        barrier(cb, read_only, src, shaders, transfer)
        regions = [
            vk.VkBufferImageCopy(
                bufferOffset=int(offset),
                imageSubresource=vk.VkImageSubresourceLayers(
                    aspectMask=vk.VK_IMAGE_ASPECT_COLOR_BIT, mipLevel=m, baseArrayLayer=place.layer, layerCount=1
                ),
                imageOffset=vk.VkOffset3D(0, 0, 0),
                imageExtent=vk.VkExtent3D(s, s, 1),
            )
            for m, s, offset in zip(mips, sides, offsets, strict=False)
        ]
        vk.vkCmdCopyImageToBuffer(cb, place.image.handle, src, out.handle, len(regions), regions)
        sampled = (shaders[0], vk.VK_ACCESS_2_SHADER_SAMPLED_READ_BIT)
        barrier(cb, src, read_only, (transfer[0], vk.VK_ACCESS_2_NONE), sampled)
        host_barrier(vk, cb)

    try:
        device.submit_once(record)
        raw = out.bytes()
        return [raw[offsets[i] : offsets[i + 1]].reshape(s, s, 4).astype(np.int64) for i, s in enumerate(sides)]
    finally:
        out.destroy()


def halves(side, split="x"):
    img = np.empty((side, side, 4), np.int64)
    img[:] = srgb8(A)
    if split == "x":
        img[:, side // 2 :] = srgb8(B)
    else:
        img[side // 2 :] = srgb8(B)
    return img


@pytest.fixture
def pages():
    made = TexturePages(shared_device(), anisotropy=1)
    yield made
    made.destroy()


def test_the_pass_copies_the_image_into_its_layer_and_makes_the_mips_in_linear_light(pages):
    device = pages.device
    vk = device.vk
    assert blit_filter(device, vk.VK_FORMAT_R8G8B8A8_SRGB) == vk.VK_FILTER_LINEAR  # lavapipe blits sRGB linearly
    textures = Textures()
    green = textures.add(Texture("green", np.tile(np.array([0, 255, 0, 255], np.uint8), (32, 32, 1))))
    tv = textures.render_target("tv", 32, 32)
    assert pages.sync(textures) and pages.render_targets == {tv}
    place = pages.place(tv)
    assert (place.layer, place.side, place.mips, place.page) == (1, 32, 6, 2 * size_class(32, 32))
    assert place.image is pages.place(green).image and pages.place(green).layer == 0
    (before,) = read_layer(pages, tv, [0])
    assert (before == [0, 0, 0, 255]).all()  # opaque black until drawn

    draw_into(pages, tv, 32, 32)
    mip0, mip1, last = read_layer(pages, tv, [0, 1, 5])
    assert np.abs(mip0 - halves(32)).max() <= 1
    assert np.abs(mip1 - halves(16)).max() <= 1
    # 1 x 1: the mean of the halves in linear light (the encoded bytes' mean would be 189.5 red)
    mean = (np.asarray(A) + np.asarray(B)) / 2
    assert np.abs(last[0, 0] - srgb8(mean)).max() <= 2, (last[0, 0], srgb8(mean))
    (other,) = read_layer(pages, green, [0])
    assert (other == [0, 255, 0, 255]).all()  # the page's other layer is untouched


def test_a_view_of_another_size_is_scaled_into_the_square_layer(pages):
    textures = Textures()
    wide = textures.render_target("wide", 24, 12)
    pages.sync(textures)
    assert pages.place(wide).side == 32
    draw_into(pages, wide, 24, 12)
    (mip0,) = read_layer(pages, wide, [0])
    assert np.abs(mip0[:, :14] - srgb8(A)).max() <= 1  # away from the blended middle columns
    assert np.abs(mip0[:, 18:] - srgb8(B)).max() <= 1


def test_a_sync_that_remakes_the_page_keeps_the_render_target_and_changes_the_key(pages):
    textures = Textures()
    tv = textures.render_target("tv", 16, 16)
    pages.sync(textures)
    first = pages.place(tv)
    with render_view(pages, tv, 16, 16, split="y") as frame:
        key = frame()
        textures.add(Texture("late", np.full((16, 16, 4), 255, np.uint8)))  # the same class: its page is remade
        assert pages.sync(textures)
        again = pages.place(tv)
        assert (again.layer, again.side, again.page) == (first.layer, first.side, first.page)
        assert again.generation > first.generation and again.image is not first.image
        assert pages.render_targets == {tv}
        (black,) = read_layer(pages, tv, [0])
        assert (black == [0, 0, 0, 255]).all()  # filled black again: the next frame draws it
        assert frame() != key  # the same graph and pass record the new page (frame replay records anew)
    mip0, mip1 = read_layer(pages, tv, [0, 1])
    assert np.abs(mip0 - halves(16, "y")).max() <= 1 and np.abs(mip1 - halves(8, "y")).max() <= 1
    with pytest.raises(UsageError, match="not on the GPU yet"):
        pages.place(len(textures))
    with pytest.raises(UsageError, match="texture 1 is not a render target"):
        RenderTexturePass(pages, 1).key()  # "late", a texture with pixels of its own


def test_a_material_samples_the_render_target_as_any_texture():
    from ecs_engine.render.frame.renderer import Renderer

    size = 32
    with headless_gpu(size, size) as gpu:
        world = World()
        registry = materials(world)
        monitor = registry.textures.render_target("monitor", 16, 16)
        screen = registry.add(Material("screen", "unlit", base_color_texture=monitor))
        facing = (math.sin(math.pi / 4), 0.0, 0.0, math.cos(math.pi / 4))  # the plane's +Y normal -> +Z
        world.spawn(Transform(rotation=facing), Mesh(handle=gpu.meshes.add(plane_mesh(2.0)), material=screen))
        world.spawn(Transform(position=(0.0, 0.0, 1.0)), Camera(fov_y=math.radians(90.0), near=0.05))
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes, anisotropy=1)
        try:
            default_schedule().run(world, 0.0)
            renderer.render(world, readback=True)
            assert (gpu.target.pixels()[..., :3] == 0).all()  # black: no camera drew it yet
            draw_into(renderer.texture_pages, monitor, 16, 16, split="y")
            renderer.render(world, readback=True)
            img = gpu.target.pixels().astype(np.int64)
        finally:
            renderer.destroy()
    q = size // 4
    assert np.abs(img[q, q, :3] - srgb8(A)[:3]).max() <= 2, img[q, q]  # the view's top is the texture's top
    assert np.abs(img[3 * q, 3 * q, :3] - srgb8(B)[:3]).max() <= 2, img[3 * q, 3 * q]


def test_without_linear_blits_it_blits_nearest_and_without_blits_it_copies_mip_0(pages, monkeypatch):
    """The fallbacks for a device whose format features lack linear filtering or blits (none
    known: Vulkan requires both for R8G8B8A8_SRGB), forced here."""
    import ecs_engine.render.passes.render_texture as module

    vk = pages.device.vk
    textures = Textures()
    tv = textures.render_target("tv", 16, 16)
    pages.sync(textures)
    monkeypatch.setattr(module, "blit_filter", lambda device, *formats: vk.VK_FILTER_NEAREST)
    draw_into(pages, tv, 16, 16)
    mip0, mip1, last = read_layer(pages, tv, [0, 1, 4])
    assert np.abs(mip0 - halves(16)).max() <= 1 and np.abs(mip1 - halves(8)).max() <= 1
    assert any(np.abs(last[0, 0] - srgb8(c)).max() <= 1 for c in (A, B))  # one texel picked, not a mean
    monkeypatch.setattr(module, "blit_filter", lambda device, *formats: None)
    draw_into(pages, tv, 16, 16, split="y")
    mip0, mip1 = read_layer(pages, tv, [0, 1])
    assert np.abs(mip0 - halves(16, "y")).max() <= 1  # copied as it is
    assert np.abs(mip1 - halves(8)).max() <= 1  # the lower mips keep what they held
    with pytest.raises(UsageError, match="cannot blit 8 x 8 pixels into its 16 x 16 layer"):
        draw_into(pages, tv, 8, 8)
