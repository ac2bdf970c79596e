"""SSAO (GTAO) as frame-graph passes (ecs_engine/render/post/ssao.py) against the NumPy reference
of the same algorithm (ssao_reference.py) on an analytic depth image: a floor meeting a wall at
a right angle, a box on the floor, sky above the wall. On the device with validation on.

The depth reaches the graph as a D32_SFLOAT transient filled by a copy from a host buffer (a
graph pass, so the graph's own barrier takes it to the sampled layout): the same format and
aspect as the renderer's depth attachment, which is what the passes will sample there."""

from __future__ import annotations

import math

import numpy as np
import pytest
import ssao_reference as ref
from gpu_context import shared_device
from host_reads import host_barrier

from ecs_engine.errors import UsageError
from ecs_engine.gpu.memory import HOST, Buffer
from ecs_engine.maths.camera import orthographic
from ecs_engine.render.graph import Access, FrameGraph, ImageDesc, Load, Pass
from ecs_engine.render.post.ssao import SsaoSettings, SsaoView, add_ssao

W, H = 48, 32
SKY_COLOUR = (2.0, 1.0, 0.5, 1.0)


def layers(vk, aspect):
    return vk.VkImageSubresourceLayers(aspectMask=aspect, mipLevel=0, baseArrayLayer=0, layerCount=1)


class Upload(Pass):
    """The host buffer "depth_upload" copied into the D32_SFLOAT transient "depth"."""

    name = "upload"

    def setup(self, b):
        b.create("depth", ImageDesc(format="VK_FORMAT_D32_SFLOAT"))
        b.read("depth_upload", Access.TRANSFER_READ)
        b.write("depth", Access.TRANSFER_WRITE)

    def record(self, cb, ctx):
        vk = ctx.vk
        region = vk.VkBufferImageCopy(
            imageSubresource=layers(vk, vk.VK_IMAGE_ASPECT_DEPTH_BIT), imageExtent=vk.VkExtent3D(W, H, 1)
        )
        dst = vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL
        vk.vkCmdCopyBufferToImage(cb, ctx.buffer("depth_upload").handle, ctx.image("depth").handle, dst, 1, [region])


class Fill(Pass):
    """Clears the HDR image "hdr" to SKY_COLOUR (what the composite then darkens)."""

    name = "fill"

    def setup(self, b):
        b.create("hdr", ImageDesc(format="VK_FORMAT_R16G16B16A16_SFLOAT"))
        b.write("hdr", Access.COLOR_WRITE, load=Load.CLEAR, clear=SKY_COLOUR)

    def record(self, cb, ctx):
        ctx.begin_rendering(colors=("hdr",))
        ctx.end_rendering()


class Readback(Pass):
    """Copies image `src` into the imported host buffer `dst`, made visible to the host."""

    def __init__(self, src, dst):
        self.name, self.src, self.dst = f"read_{src}", src, dst

    def setup(self, b):
        b.read(self.src, Access.TRANSFER_READ)
        b.write(self.dst, Access.TRANSFER_WRITE)
        b.side_effect()

    def record(self, cb, ctx):
        vk = ctx.vk
        region = vk.VkBufferImageCopy(
            imageSubresource=layers(vk, vk.VK_IMAGE_ASPECT_COLOR_BIT), imageExtent=vk.VkExtent3D(W, H, 1)
        )
        src = vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL
        vk.vkCmdCopyImageToBuffer(cb, ctx.image(self.src).handle, src, ctx.buffer(self.dst).handle, 1, [region])
        host_barrier(vk, cb)


def run_ssao(depth, projection, settings, composite=False, recompile=False):
    """The passes on the device: {"ao": (H, W), "ao_noisy": (H, W, 4), "hdr": (H, W, 4)} as
    float32, and the graph's describe(). `recompile`: a first frame, then a recompile (new
    transients, whose views may reuse the old handles) and a second frame, which is returned."""
    device = shared_device()
    usage = device.vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT
    shapes = {"ao": (H, W), "ao_noisy": (H, W, 4), **({"hdr": (H, W, 4)} if composite else {})}
    made = []
    try:
        upload = Buffer(device, W * H * 4, device.vk.VK_BUFFER_USAGE_TRANSFER_SRC_BIT, HOST)
        made.append(upload)
        upload.array(np.float32, (H, W))[:] = depth
        outs = {name: Buffer(device, int(np.prod(shape)) * 2, usage, HOST) for name, shape in shapes.items()}
        made.extend(outs.values())
        graph = FrameGraph(device)
        made.append(graph)
        graph.import_buffer("depth_upload", handle=upload.handle, size=upload.size)
        for name, buf in outs.items():
            graph.import_buffer(f"out_{name}", handle=buf.handle, size=buf.size)
        graph.add_pass(Upload())
        if composite:
            graph.add_pass(Fill())
        add_ssao(
            graph, settings, depth="depth", out="ao", composite="hdr" if composite else None, view=SsaoView(projection)
        )
        for name in shapes:
            graph.add_pass(Readback(name, f"out_{name}"))
        graph.compile((W, H))
        device.submit_once(graph.execute)
        if recompile:
            for buf in outs.values():
                buf.array(np.uint8)[:] = 0
            graph.import_buffer("unused", handle=upload.handle, size=upload.size)  # imports changed
            graph.compile((W, H))
            assert graph.compiles == 2
            device.submit_once(graph.execute)
        got = {name: outs[name].array(np.float16, shape).astype(np.float32) for name, shape in shapes.items()}
        return got, graph.describe()
    finally:
        for thing in reversed(made):
            thing.destroy()


SCENE = ref.scene(W, H)
SETTINGS = [SsaoSettings(), SsaoSettings(radius=1.0, intensity=1.0, slices=2, steps=5)]


@pytest.mark.parametrize("settings", SETTINGS, ids=["default", "wide"])
def test_passes_match_the_numpy_reference(settings):
    depth, projection, _ = SCENE
    got, described = run_ssao(depth, projection, settings)
    noisy = ref.gtao(depth, projection, settings)
    ao = ref.denoise(depth, projection, noisy)
    vis_error = np.abs(got["ao_noisy"][..., 0] - noisy[..., 0])
    normal_error = np.abs(got["ao_noisy"][..., 1:] - noisy[..., 1:]).max()
    ao_error = np.abs(got["ao"] - ao)
    print(f"{settings}: gtao max {vis_error.max():.5f} (mean {vis_error.mean():.6f}), normal max {normal_error:.5f}")
    print(f"  ao max {ao_error.max():.5f} (mean {ao_error.mean():.6f})")
    assert normal_error < 2e-3
    assert vis_error.max() < 0.01 and vis_error.mean() < 1e-3  # float16 storage: ~5e-4
    assert ao_error.max() < 0.005 and ao_error.mean() < 1e-3
    # the denoise alone, fed with the GPU's own noisy image: only its arithmetic differs
    assert np.abs(got["ao"] - ref.denoise(depth, projection, got["ao_noisy"])).max() < 2e-3
    assert "ssao_gtao" in described and "depth COMPUTE_SAMPLED" in described


def test_open_floor_is_unoccluded_and_the_crease_is_not():
    depth, projection, label = SCENE
    got, _ = run_ssao(depth, projection, SsaoSettings())
    ao = got["ao"]
    floor = label == ref.FLOOR
    # floor rows with only floor within the radius: the near, lower part of the image, left of the box
    open_floor = floor.copy()
    open_floor[: H - 6] = False
    open_floor[:, W // 2 :] = False
    assert open_floor.sum() > 50
    # the crease: floor pixels right below the wall
    crease = floor & np.roll(label == ref.WALL, 1, axis=0)
    crease[:, W // 2 :] = False  # left of the box: the wall's corner with the floor only
    assert crease.sum() > 10
    print(
        f"open floor: min {ao[open_floor].min():.3f}; crease: mean {ao[crease].mean():.3f} max {ao[crease].max():.3f}"
    )
    assert ao[open_floor].min() > 0.97
    assert ao[crease].max() < 0.9 and ao[crease].mean() < 0.85
    assert (ao[label == ref.SKY] == 1.0).all()


def test_the_composite_multiplies_the_hdr_image_by_ao():
    depth, projection, _ = SCENE
    got, described = run_ssao(depth, projection, SsaoSettings(), composite=True)
    expected = np.array(SKY_COLOUR, np.float32) * np.concatenate(
        [np.repeat(got["ao"][..., None], 3, -1), np.ones((H, W, 1))], -1
    )
    np.testing.assert_allclose(got["hdr"], expected, rtol=2e-3, atol=1e-3)
    assert "hdr COMPUTE_READ_WRITE" in described


def test_a_recompiled_graph_rewrites_the_passes_descriptor_sets(monkeypatch):
    """Every view's handle read as 0: as a driver reusing a destroyed view's handle value for
    the new transient's would look (the validation layer's handles are never reused); a set
    kept across the recompile would name destroyed views, which validation reports."""
    import ecs_engine.render.post.ssao_passes as passes

    monkeypatch.setattr(passes, "handle_int", lambda vk, handle: 0)
    depth, projection, _ = SCENE
    first, _ = run_ssao(depth, projection, SsaoSettings())
    second, _ = run_ssao(depth, projection, SsaoSettings(), recompile=True)
    np.testing.assert_array_equal(second["ao"], first["ao"])


def test_intensity_0_turns_it_off():
    depth, projection, _ = SCENE
    got, _ = run_ssao(depth, projection, SsaoSettings(intensity=0.0))
    # visibility**0 is 1; the denoise's normalised weighted mean of ones may round a float32 step
    # below 1, and the H200 stores that in the R16F image as the half below 1 (1 - 2**-11)
    np.testing.assert_allclose(got["ao"], 1.0, rtol=0, atol=2.0**-11)


def test_an_orthographic_camera_matches_the_reference():
    """The passes take any projection through its inverse: an orthographic view of the scene's
    depth (linear in reverse-Z) agrees too."""
    depth, _, _ = SCENE
    projection = orthographic(6.0, W / H, 0.1, 10.0)
    d = np.where(depth > 0, np.clip(depth * 3.0, 0.05, 0.95), 0.0).astype(np.float32)  # some relief
    settings = SsaoSettings(radius=0.8)
    got, _ = run_ssao(d, projection, settings)
    expected = ref.ssao(d, projection, settings)
    error = np.abs(got["ao"] - expected)
    print(f"orthographic: ao max {error.max():.5f}")
    assert error.max() < 0.005 and expected.min() < 0.9  # occlusion there to match


def test_the_passes_plan_reads_and_writes_and_cull_without_a_reader():
    graph = FrameGraph(None)
    graph.import_image(
        "depth",
        handle=1,
        view=2,
        format="VK_FORMAT_D32_SFLOAT",
        extent=(W, H),
        layout_before="DEPTH_STENCIL_ATTACHMENT_OPTIMAL",
        layout_after="DEPTH_STENCIL_ATTACHMENT_OPTIMAL",
    )
    view = add_ssao(graph, SsaoSettings(), view=SsaoView(SCENE[1]))
    graph.output("ao")
    graph.compile((W, H))
    assert graph.order == ["ssao_gtao", "ssao_denoise"]
    uses = {(u.resource, u.access) for u in graph.compiled.structure.uses["ssao_denoise"]}
    assert uses == {
        ("depth", Access.COMPUTE_SAMPLED),
        ("ao_noisy", Access.COMPUTE_SAMPLED),
        ("ao", Access.COMPUTE_WRITE),
    }
    assert graph.compiled.structure.resources["ao"].format == "R16_SFLOAT"
    key = graph.key()
    view.projection = SCENE[1] * np.float32(2.0)
    assert graph.key() != key  # a new projection: a new recording
    unread = FrameGraph(None)
    unread.import_image(
        "depth",
        handle=1,
        view=2,
        format="VK_FORMAT_D32_SFLOAT",
        extent=(W, H),
        layout_before="UNDEFINED",
        layout_after="UNDEFINED",
    )
    add_ssao(unread, SsaoSettings())
    unread.compile((W, H))
    assert unread.order == [] and unread.culled == ["ssao_gtao", "ssao_denoise"]


@pytest.mark.parametrize(
    "kwargs",
    [
        {"radius": math.nan},
        {"radius": -0.5},
        {"radius": 0.0},
        {"radius": math.inf},
        {"intensity": -1.0},
        {"intensity": math.nan},
        {"slices": 0},
        {"slices": 2.5},
        {"slices": True},
        {"steps": -1},
        {"steps": 100},
        {"falloff": 0.0},
        {"radius": "1"},
    ],
)
def test_bad_settings_are_usage_errors(kwargs):
    with pytest.raises(UsageError, match="SSAO"):
        SsaoSettings(**kwargs)


def test_bad_projections_and_arguments_are_usage_errors():
    with pytest.raises(UsageError, match="4 x 4"):
        SsaoView(np.eye(3))
    with pytest.raises(UsageError, match="finite"):
        SsaoView(np.full((4, 4), np.nan))
    with pytest.raises(UsageError, match="inverted"):
        SsaoView(np.zeros((4, 4)))
    with pytest.raises(UsageError, match="no projection"):
        SsaoView().push_constants(SsaoSettings(), (W, H))
    with pytest.raises(UsageError, match="SsaoSettings"):
        add_ssao(FrameGraph(None), {"radius": 1.0})


def test_the_reference_sees_the_crease_and_not_the_open_floor():
    """The reference alone (no device): the same property the GPU test checks, so a reference
    that lost its occlusion would fail here too."""
    depth, projection, label = SCENE
    ao = ref.ssao(depth, projection, SsaoSettings())
    crease = (label == ref.FLOOR) & np.roll(label == ref.WALL, 1, axis=0)
    assert ao[crease].mean() < 0.85 and ao[H - 3 :, : W // 2].min() > 0.97
