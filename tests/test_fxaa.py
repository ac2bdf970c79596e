"""FXAA (render/post/fxaa.py) through a frame graph on the device with validation on: a small
display-referred image with a diagonal edge, a vertical edge and flat regions is uploaded into an
imported image, anti-aliased into a transient and read back, and compared with the NumPy
reference (tests/fxaa_reference.py); the settings' checks; the pass's declarations."""

from __future__ import annotations

import math
import re
import shutil
import subprocess
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest
from fxaa_reference import STEPS, fxaa_outcomes, linear_to_srgb, outcome_errors, srgb_to_linear
from gpu_context import shared_device
from host_reads import host_barrier
from spirv_layout import struct_layouts

from ecs_engine.errors import UsageError
from ecs_engine.gpu.memory import HOST, Buffer, Image
from ecs_engine.render.graph import Access, FrameGraph, ImageDesc, Pass
from ecs_engine.render.post.fxaa import PRESET, QUALITY_STEPS, FxaaPass, FxaaSettings, add_fxaa

W, H = 48, 32
UNORM = "VK_FORMAT_R8G8B8A8_UNORM"
SRGB = "VK_FORMAT_R8G8B8A8_SRGB"
FLAT = (slice(0, 8), slice(24, 34))  # rows, columns far (> 1 texel) from every edge
ON_DIAGONAL = (14, 10)  # (y, x): a pixel of the diagonal's staircase


def scene() -> np.ndarray:
    """Bytes (H, W, 4): a light background; below a shallow diagonal (slope 0.55) on the left a
    dark blue field; a bright rectangle on the right (vertical edges at x = 38 and beyond the
    image, horizontal at y = 6 and 22). Every byte is a multiple of 4, so that the bilinear
    averages the search reads (of 2 or 4 texels, at half-texel positions) are exact in 8 bits."""
    img = np.empty((H, W, 4), np.uint8)
    img[:] = (200, 180, 120, 255)
    ys, xs = np.mgrid[0:H, 0:W]
    img[(ys > 0.55 * xs + 8) & (xs < 30)] = (40, 60, 100, 255)
    img[6:22, 38:] = (248, 244, 236, 255)
    return img


class Upload(Pass):
    """Copies the imported host buffer "pixels" into the imported image "ldr"."""

    name = "upload"

    def setup(self, b):
        b.read("pixels", Access.TRANSFER_READ)
        b.write("ldr", Access.TRANSFER_WRITE)

    def record(self, cb, ctx):
        vk = ctx.vk
        region = vk.VkBufferImageCopy(imageSubresource=_layers(vk), imageExtent=vk.VkExtent3D(W, H, 1))
        dst = ctx.image("ldr").handle
        vk.vkCmdCopyBufferToImage(
            cb, ctx.buffer("pixels").handle, dst, vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, [region]
        )


class Readback(Pass):
    """Copies `src` into the imported host buffer "out", made visible to the host."""

    name = "readback"

    def __init__(self, src):
        self.src = src

    def setup(self, b):
        b.read(self.src, Access.TRANSFER_READ)
        b.write("out", Access.TRANSFER_WRITE)
        b.side_effect()

    def record(self, cb, ctx):
        vk = ctx.vk
        region = vk.VkBufferImageCopy(imageSubresource=_layers(vk), imageExtent=vk.VkExtent3D(W, H, 1))
        src = ctx.image(self.src).handle
        vk.vkCmdCopyImageToBuffer(
            cb, src, vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, ctx.buffer("out").handle, 1, [region]
        )
        host_barrier(vk, cb)


def _layers(vk):
    return vk.VkImageSubresourceLayers(
        aspectMask=vk.VK_IMAGE_ASPECT_COLOR_BIT, mipLevel=0, baseArrayLayer=0, layerCount=1
    )


@contextmanager
def fxaa_graph(pixels: np.ndarray, fmt: str = UNORM, settings: FxaaSettings | None = None, target_size=None):
    """A graph that uploads `pixels` (bytes of format `fmt`) into the imported image "ldr",
    runs FXAA into a transient "aa" of `fmt` and copies that into the host buffer "out":
    (graph, the FXAA pass, a function that runs a frame and returns the bytes read back)."""
    device = shared_device()
    vk = device.vk
    made: list = []
    try:
        usage = vk.VK_IMAGE_USAGE_SAMPLED_BIT | vk.VK_IMAGE_USAGE_TRANSFER_DST_BIT
        source = Image(device, W, H, getattr(vk, fmt), usage, vk.VK_IMAGE_ASPECT_COLOR_BIT)
        made.append(source)
        staging = Buffer(device, pixels.nbytes, vk.VK_BUFFER_USAGE_TRANSFER_SRC_BIT, HOST)
        made.append(staging)
        staging.bytes()[:] = pixels.reshape(-1)
        out = Buffer(device, pixels.nbytes, vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT, HOST)
        made.append(out)
        graph = FrameGraph(device)
        made.append(graph)
        graph.import_buffer("pixels", handle=staging.handle, size=staging.size)
        graph.import_buffer("out", handle=out.handle, size=out.size)

        def frame():
            graph.import_image(  # again each frame, as a renderer imports its images
                "ldr",
                handle=source.handle,
                view=source.view,
                format=getattr(vk, fmt),
                extent=(W, H),
                layout_before=vk.VK_IMAGE_LAYOUT_UNDEFINED,
                layout_after=vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
            )
            graph.compile((W, H))
            device.submit_once(graph.execute)
            return out.array(np.uint8, (H, W, 4)).copy()

        graph.add_pass(Upload())
        p = add_fxaa(graph, settings, source="ldr", target="aa", create=ImageDesc(format=fmt, size=target_size))
        graph.add_pass(Readback("aa"))
        yield graph, p, frame
    finally:
        for thing in reversed(made):
            thing.destroy()


def run_fxaa(pixels: np.ndarray, fmt: str = UNORM, settings: FxaaSettings | None = None) -> tuple[np.ndarray, str]:
    """The bytes FXAA writes for `pixels` and the graph's description."""
    with fxaa_graph(pixels, fmt, settings) as (graph, _, frame):
        return frame(), graph.describe()


def unorm_bytes(colour):
    return np.asarray(colour) * 255.0


def srgb_bytes(colour):
    """Linear colour as an _SRGB attachment stores it (alpha stays linear)."""
    colour = np.asarray(colour, np.float64)
    return np.concatenate([linear_to_srgb(colour[..., :3]), colour[..., 3:]], axis=-1) * 255.0


def ambiguous(reference, to_bytes):
    """How many pixels' ties allow outcomes more than 1.5/255 apart."""
    return sum(np.ptp(to_bytes(np.array(outcomes)), axis=0).max() > 1.5 for outcomes in reference[1].values())


SETTINGS = [FxaaSettings(), FxaaSettings(subpix=0.0, edge_threshold=0.125, edge_threshold_min=0.0312)]


@pytest.mark.parametrize("settings", SETTINGS, ids=["defaults", "no_subpix_high_quality"])
def test_unorm_image_matches_the_reference(settings):
    image = scene()
    gpu, described = run_fxaa(image, UNORM, settings)
    reference = fxaa_outcomes(
        image / 255.0,
        subpix=settings.subpix,
        edge_threshold=settings.edge_threshold,
        edge_threshold_min=settings.edge_threshold_min,
    )
    error = outcome_errors(gpu, reference, unorm_bytes)
    changed = np.any(np.abs(unorm_bytes(reference[0]) - image) > 2.0, axis=-1)
    open_ = ambiguous(reference, unorm_bytes)
    print(f"max error {error.max():.3f}/255; {changed.sum()} pixels changed, {open_} of them left open by ties")
    assert error.max() <= 1.5, np.argwhere(error > 1.5)[:10]
    assert "fxaa" in described and "reads  ldr FRAGMENT_SAMPLED" in described
    # the test could fail: FXAA changed many pixels, most of them to one colour the reference allows
    assert changed.sum() > 40 and open_ < changed.sum() // 3


def test_flat_regions_pass_unchanged_exactly_and_edges_are_smoothed():
    image = scene()
    gpu, _ = run_fxaa(image)
    np.testing.assert_array_equal(gpu[FLAT], image[FLAT])
    # far from every edge, everywhere: what has no neighbour of another colour is untouched
    same = np.ones((H, W), bool)
    padded = np.pad(image, ((1, 1), (1, 1), (0, 0)), mode="edge")
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            same &= np.all(padded[1 + dy : 1 + dy + H, 1 + dx : 1 + dx + W] == image, axis=-1)
    np.testing.assert_array_equal(gpu[same], image[same])
    # a pixel of the staircase moves towards the mean of the two colours by a clear amount
    y, x = ON_DIAGONAL
    light, dark = image[0, 0, :3].astype(float), image[H - 1, 0, :3].astype(float)
    mean = (light + dark) / 2
    before = np.abs(image[y, x, :3] - mean).sum()
    after = np.abs(gpu[y, x, :3].astype(float) - mean).sum()
    assert after < before - 30, (image[y, x], gpu[y, x])
    assert np.any(gpu[:, 37:39] != image[:, 37:39])  # the vertical edge's pixels are touched too


def test_srgb_source_is_filtered_linear_and_matches_the_reference():
    image = scene()
    gpu, _ = run_fxaa(image, SRGB)
    reference = fxaa_outcomes(
        np.concatenate([srgb_to_linear(image[..., :3] / 255.0), image[..., 3:] / 255.0], -1), linear=True
    )
    error = outcome_errors(gpu, reference, srgb_bytes)
    print(f"max error {error.max():.3f}/255, {len(reference[1])} pixels with ties")
    assert error.max() <= 2.0, np.argwhere(error > 2.0)[:10]
    np.testing.assert_array_equal(gpu[FLAT], image[FLAT])
    assert np.count_nonzero(np.any(gpu != image, axis=-1)) > 40


def test_frames_reuse_the_descriptor_set_until_the_graph_compiles_again():
    image = scene()
    with fxaa_graph(image) as (graph, p, frame):
        first = frame()
        (kept,) = p._sets.values()
        np.testing.assert_array_equal(frame(), first)  # the import is a new GraphImage: same set
        assert list(p._sets.values()) == [kept] and graph.compiles == 1
        graph.output("aa")  # a change of outputs compiles again: new transients
        np.testing.assert_array_equal(frame(), first)
        assert graph.compiles == 2 and len(p._sets) == 1 and next(iter(p._sets.values())) is not kept
        graph.destroy()
        p.destroy()  # again: nothing left to destroy
        assert p._owned is None and not p._sets


def test_a_target_of_another_size_is_refused_when_recorded():
    with fxaa_graph(scene(), target_size=(W // 2, H // 2)) as (_, _, frame):
        with pytest.raises(UsageError, match="same size"):
            frame()


def test_the_quality_table_is_the_same_in_shader_module_and_reference():
    source = (Path(__file__).resolve().parent.parent / "shaders" / "fxaa.frag").read_text()
    table = re.search(r"STEP\[STEPS\] = float\[\]\(([^)]*)\)", source)
    assert table is not None
    assert tuple(float(v) for v in table[1].split(",")) == QUALITY_STEPS == STEPS
    assert PRESET == 39 and len(STEPS) == 12


@pytest.mark.skipif(shutil.which("glslc") is None, reason="glslc not installed")
def test_the_push_constants_are_laid_out_as_the_module_packs_them(tmp_path):
    out = tmp_path / "fxaa.frag.spv"
    src = Path(__file__).resolve().parent.parent / "shaders" / "fxaa.frag"
    subprocess.run(["glslc", "--target-env=vulkan1.2", str(src), "-o", str(out)], check=True)  # no -O: names kept
    fields = struct_layouts(out)["Push"].fields()
    # the offset: where a camera view's rectangle starts in the target (render/frame/view_graph.py)
    assert fields == [("subpix", 0), ("edge_threshold", 4), ("edge_threshold_min", 8), ("offset", 16)]
    assert FxaaSettings(0.5, 0.25, 0.125).push().tolist() == [0.5, 0.25, 0.125, 0.0]
    push = FxaaPass(FxaaSettings(0.5, 0.25, 0.125))._push
    assert push.dtype.fields["offset"][1] == 16 and push.itemsize == 24


def test_settings_defaults_and_bad_values():
    s = FxaaSettings()
    assert (s.subpix, s.edge_threshold, s.edge_threshold_min) == (0.75, 0.166, 0.0833)
    assert s.push().tolist()[:3] == pytest.approx([0.75, 0.166, 0.0833])
    with pytest.raises(AttributeError):
        s.subpix = 1.0  # frozen
    for bad in (math.nan, math.inf, -0.01, 1.01, True, "0.5", None):
        for name in ("subpix", "edge_threshold", "edge_threshold_min"):
            with pytest.raises(UsageError, match=name):
                FxaaSettings(**{name: bad})
    assert FxaaSettings(subpix=0, edge_threshold=1).subpix == 0
    with pytest.raises(UsageError):
        FxaaPass("fast")
    with pytest.raises(UsageError):
        FxaaPass(source="ldr", target="ldr")
    assert FxaaPass(FxaaSettings(subpix=0.5)).key() != FxaaPass().key()


def test_the_pass_declares_a_sampled_read_and_a_discarding_colour_write():
    """Planned without a device: FXAA runs between the tone map and the UI, which loads it."""

    class ToneMap(Pass):
        name = "tonemap"

        def setup(self, b):
            b.create("ldr", ImageDesc(format=SRGB))
            b.write("ldr", Access.COLOR_WRITE)

    class Ui(Pass):
        name = "ui"

        def setup(self, b):
            from ecs_engine.render.graph import Load

            b.write("target", Access.COLOR_WRITE, load=Load.LOAD)

    graph = FrameGraph(None)
    graph.import_image(
        "target",
        handle=1,
        view=2,
        format="VK_FORMAT_B8G8R8A8_SRGB",
        extent=(64, 32),
        layout_before="UNDEFINED",
        layout_after="PRESENT_SRC_KHR",
    )
    graph.add_pass(ToneMap())
    graph.add_pass(Ui())
    p = add_fxaa(graph, before="ui")
    graph.output("target")
    graph.compile((64, 32))
    assert graph.order == ["tonemap", "fxaa", "ui"] and p.name == "fxaa"
    rows = {r.resource: r for r in graph.compiled.barriers.before["fxaa"]}
    assert (rows["ldr"].old_layout, rows["ldr"].new_layout) == ("COLOR_ATTACHMENT_OPTIMAL", "SHADER_READ_ONLY_OPTIMAL")
    assert rows["target"].new_layout == "COLOR_ATTACHMENT_OPTIMAL"
    graph.destroy()
