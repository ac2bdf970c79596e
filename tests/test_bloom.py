"""The bloom post effect (ecs_engine/render/post/): its passes run through the frame graph on
the device, with validation on, against the NumPy reference (bloom_reference.py) on a small HDR
image; its settings' checks; the energy-conserving composite's bound; what the passes declare."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from bloom_reference import LUMA
from bloom_reference import bloom as reference_bloom
from gpu_context import shared_device
from image_readback import record_copy_in, record_copy_out, transition

from ecs_engine.errors import UsageError
from ecs_engine.render.graph import Access, FrameGraph, Pass, PassBuilder
from ecs_engine.render.post.bloom import BloomPipelines, add_bloom, bloom_passes
from ecs_engine.render.post.bloom_settings import (
    BloomComposite,
    BloomSettings,
    blend_factor,
    blend_weights,
    chain_extents,
)

FORMAT = "VK_FORMAT_R16G16B16A16_SFLOAT"


def scene(width: int = 64, height: int = 48) -> np.ndarray:
    """A dim background with a few pixels at 50 (one coloured, one on the border)."""
    rng = np.random.default_rng(7)
    image = np.ones((height, width, 4), np.float32)
    image[..., :3] = 0.05 + 0.1 * rng.random((height, width, 3))
    image[20, 30, :3] = 50.0
    image[10, 10, :3] = (50.0, 20.0, 5.0)
    image[height - 1, width // 2, :3] = 50.0
    return image.astype(np.float16)


# ---------------------------------------------------------------------------------- settings


@pytest.mark.parametrize(
    "bad",
    [
        {"intensity": math.nan},
        {"intensity": -0.1},
        {"intensity": 1.5},  # energy-conserving: a probability
        {"intensity": math.inf, "composite": BloomComposite.ADDITIVE},
        {"intensity": True},
        {"low_frequency_boost": -1.0},
        {"low_frequency_boost_curvature": 1.0},
        {"high_pass_frequency": 0.0},
        {"threshold": -1.0},
        {"threshold_softness": 2.0},
        {"max_mips": 0},
        {"max_mips": 2.5},
        {"composite": "additive"},
    ],
    ids=lambda d: ",".join(f"{k}={v!r}" for k, v in d.items()),
)
def test_bad_settings_are_a_usage_error(bad):
    with pytest.raises(UsageError, match="bloom"):
        BloomSettings(**bad)


def test_defaults_are_bevys_natural_and_frozen():
    s = BloomSettings()
    assert (s.intensity, s.low_frequency_boost, s.low_frequency_boost_curvature, s.high_pass_frequency) == (
        0.15,
        0.7,
        0.95,
        1.0,
    )
    assert s.threshold == 0.0 and s.composite is BloomComposite.ENERGY_CONSERVING
    with pytest.raises(AttributeError):
        s.intensity = 0.5  # type: ignore[misc]
    assert BloomSettings(intensity=3.0, composite=BloomComposite.ADDITIVE).intensity == 3.0


def test_blend_factors_follow_bevys_curve():
    s = BloomSettings()
    # the finest level: the intensity alone; the coarsest: intensity + boost * (1 - intensity)
    assert blend_factor(s, 0, 7) == pytest.approx(0.15)
    assert blend_factor(s, 7, 7) == pytest.approx(0.15 + 0.7 * 0.85)
    # by hand: x = 3/7, boost = (1 - (4/7)^20) * 0.7 * 0.85
    assert blend_factor(s, 3, 7) == pytest.approx(0.15 + (1 - (4 / 7) ** 20) * 0.7 * 0.85)
    assert blend_factor(BloomSettings(high_pass_frequency=0.25), 7, 7) == 0.0  # cut past twice the frequency
    for c, d in blend_weights(s, 8):
        assert 0.0 <= c <= 1.0 and c + d == pytest.approx(1.0)  # convex: energy-conserving
    additive = BloomSettings(composite=BloomComposite.ADDITIVE)
    assert all(d == 1.0 for _, d in blend_weights(additive, 8))
    assert blend_weights(s, 1) == [(pytest.approx(0.15), pytest.approx(0.85))]  # one mip: no division by 0


def test_chain_follows_the_viewport():
    s = BloomSettings()
    assert chain_extents((64, 48), s) == [(32, 24), (16, 12), (8, 6)]
    assert chain_extents((1920, 1080), s)[-1] == (7, 4)  # the short side ends at about 4, as Bevy's
    assert len(chain_extents((3840, 2160), s)) == 9
    assert chain_extents((1, 1), s) == [(1, 1)]
    assert chain_extents((65, 47), s) == [(33, 24), (16, 12), (8, 6)]
    assert len(chain_extents((1920, 1080), BloomSettings(max_mips=3))) == 3


def test_reference_conserves_energy_within_the_composite_bound():
    """The composite keeps (1 - c0) of the light where it was and moves at most the rest: the
    sum after lies in [(1 - c0) * before, before] (the Karis weights only take light away)."""
    image = scene()
    for s in (BloomSettings(), BloomSettings(intensity=0.6, low_frequency_boost=1.0)):
        before = image[..., :3].astype(np.float64) @ LUMA
        after = reference_bloom(image, s)[..., :3].astype(np.float64) @ LUMA
        c0 = blend_weights(s, 3)[0][0]
        assert (1 - c0) * before.sum() <= after.sum() <= before.sum() * (1 + 1e-3)
        assert after.max() < before.max()  # the fireflies spread
    flat = np.full((48, 64, 4), 0.5, np.float16)
    assert np.abs(reference_bloom(flat, BloomSettings()).astype(np.float64) - 0.5).max() < 1e-3  # nothing to move


# --------------------------------------------------------------------------------- on the GPU


class HdrImage:
    """The scene's HDR colour as the renderer would import it: R16G16B16A16_SFLOAT, sampled and
    storage (bloom reads and writes it), copied to and from a buffer by the test."""

    def __init__(self, device: Any, width: int, height: int) -> None:
        from ecs_engine.gpu.memory import Image

        vk = device.vk
        self.device, self.extent = device, (width, height)
        usage = (
            vk.VK_IMAGE_USAGE_SAMPLED_BIT
            | vk.VK_IMAGE_USAGE_STORAGE_BIT
            | vk.VK_IMAGE_USAGE_TRANSFER_SRC_BIT
            | vk.VK_IMAGE_USAGE_TRANSFER_DST_BIT
        )
        self.format = vk.VK_FORMAT_R16G16B16A16_SFLOAT
        self.image = Image(device, width, height, self.format, usage, vk.VK_IMAGE_ASPECT_COLOR_BIT)
        self.handle, self.view = self.image.handle, self.image.view

    def barrier(self, cb: Any, old: int, new: int) -> None:
        """Everything before (compute, transfer) done and visible before everything after."""
        transition(self.device.vk, cb, self.handle, old, new)

    def copy(self, cb: Any, buffer: Any, to_image: bool) -> None:
        """To the image (in TRANSFER_DST) or from it (in TRANSFER_SRC)."""
        vk = self.device.vk
        if to_image:
            record_copy_in(vk, cb, buffer, self.handle, self.extent)
        else:
            record_copy_out(vk, cb, self.handle, buffer, self.extent, vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL)

    def destroy(self) -> None:
        self.image.destroy()


def gpu_bloom(
    hdr: np.ndarray, settings: BloomSettings, every_pass: bool = False, sizes: tuple[tuple[int, int], ...] = ()
) -> tuple[np.ndarray, int, int]:
    """`hdr` after the bloom passes run through the frame graph on the device, how many passes
    ran (those `add_bloom` adds, or with `every_pass` the whole chain even where add_bloom would
    add none) and how many descriptor sets the pipelines held at the end. `sizes`: first run
    the same graph over other sizes of the HDR image (each a compile with new transients), the
    last run is `hdr`'s."""
    from ecs_engine.gpu.memory import HOST, Buffer

    device = shared_device()
    vk = device.vk
    height, width = hdr.shape[:2]
    usage = vk.VK_BUFFER_USAGE_TRANSFER_SRC_BIT | vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT
    buffer = Buffer(device, hdr.nbytes * 2, usage, HOST)
    graph = FrameGraph(device)
    pipelines = BloomPipelines(device).acquire()  # held until the end: the passes release theirs
    images: list[HdrImage] = []
    try:
        if every_pass:
            passes = bloom_passes(pipelines, settings, (width, height))
            for p in passes:
                graph.add_pass(p)
        else:
            passes = add_bloom(graph, settings, (width, height), pipelines=pipelines)
        graph.output("hdr")
        for w, h in (*sizes, (width, height)):
            image = HdrImage(device, w, h)
            images.append(image)
            data = np.ascontiguousarray(np.resize(hdr, (h, w, 4)), np.float16)
            buffer.bytes()[: data.nbytes] = data.view(np.uint8).reshape(-1)
            graph.import_image(
                "hdr",
                handle=image.handle,
                view=image.view,
                format=image.format,
                extent=(w, h),
                layout_before=vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                layout_after=vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
            )
            if passes:
                graph.compile((w, h))

            def record(cb: Any, image: HdrImage = image) -> None:
                image.barrier(cb, vk.VK_IMAGE_LAYOUT_UNDEFINED, vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL)
                image.copy(cb, buffer, to_image=True)
                if passes:
                    graph.execute(cb)  # ends with the image in TRANSFER_SRC_OPTIMAL
                else:
                    dst, src = vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL
                    image.barrier(cb, dst, src)
                image.copy(cb, buffer, to_image=False)

            device.submit_once(record)
        out = buffer.bytes()[: hdr.nbytes].view(np.float16).reshape(height, width, 4).copy()
        sets = len(pipelines._sets)
    finally:
        graph.destroy()
        pipelines.release()
        for image in images:
            image.destroy()
        buffer.destroy()
    return out, len(passes), sets


def error(got: np.ndarray, want: np.ndarray) -> float:
    """The largest difference, relative above 1 and absolute below."""
    want = want.astype(np.float32)
    return float((np.abs(got.astype(np.float32) - want) / np.maximum(np.abs(want), 1.0)).max())


SETTINGS = [
    BloomSettings(),
    BloomSettings(intensity=0.5, low_frequency_boost=1.0, high_pass_frequency=0.5),
    BloomSettings(intensity=0.3, threshold=1.0, threshold_softness=0.5, composite=BloomComposite.ADDITIVE),
]


@pytest.mark.parametrize("size", [(64, 48), (65, 37)], ids=lambda s: f"{s[0]}x{s[1]}")
@pytest.mark.parametrize("settings", SETTINGS, ids=["natural", "boosted", "thresholded-additive"])
def test_bloom_on_the_gpu_matches_the_reference(size, settings):
    """Odd sizes too: there a level is not exactly half the one above, and the taps fall
    between texels at fractions other than a half."""
    image = scene(*size)
    got, count, _ = gpu_bloom(image, settings)
    assert count == 2 * len(chain_extents(size, settings))  # N down, N - 1 up, the composite
    found = error(got, reference_bloom(image, settings))
    print(f"max error vs the reference: {found:.2e}")
    assert found < 2e-3  # a float16 step is 1e-3 relative: at most a rounding or two apart
    assert np.abs(got.astype(np.float32) - image.astype(np.float32)).max() > 0.05  # it did bloom


def test_zero_intensity_leaves_the_image_as_it_was():
    image = scene()
    settings = BloomSettings(intensity=0.0, low_frequency_boost=1.0)
    got, count, _ = gpu_bloom(image, settings)
    assert count == 0  # add_bloom adds nothing: c_0 = 0 whatever the boost
    assert np.array_equal(got, image)
    got, count, _ = gpu_bloom(image, settings, every_pass=True)  # and the chain itself, run anyway
    assert count == 6 and np.array_equal(got.view(np.uint16), image.view(np.uint16))


@pytest.mark.parametrize("settings", SETTINGS[:2], ids=["natural", "boosted"])
def test_gpu_bloom_conserves_energy_within_the_composite_bound(settings):
    """Energy-conserving: the frame's light after lies in [(1 - c0) * before, before]."""
    image = scene()
    got, _, _ = gpu_bloom(image, settings)
    before = (image[..., :3].astype(np.float64) @ LUMA).sum()
    after = (got[..., :3].astype(np.float64) @ LUMA).sum()
    c0 = blend_weights(settings, len(chain_extents((64, 48), settings)))[0][0]
    assert (1 - c0) * before <= after <= before * (1 + 1e-3)
    assert after < before * (1 - 1e-3)  # the Karis weights took some of the fireflies' light


def test_a_recompiled_graph_names_its_new_views():
    """The same passes over a new HDR image of another size (the same chain depth): the graph
    compiles again with a new chain, whose views may take the old ones' handle values, so the
    descriptor sets made for the old views go (a stale one would name a destroyed view)."""
    image, settings = scene(), BloomSettings()
    got, count, sets = gpu_bloom(image, settings, sizes=((66, 50),))
    assert error(got, reference_bloom(image, settings)) < 2e-3
    assert sets == count  # one per pass, made for the last compile's views


class ToneMap(Pass):
    name = "tonemap"

    def setup(self, builder: PassBuilder) -> None:
        builder.read("hdr", Access.FRAGMENT_SAMPLED)
        builder.side_effect()

    def record(self, cb: Any, ctx: Any) -> None:
        pass


def test_passes_declare_their_mips_and_go_before_the_tone_map():
    device = shared_device()
    graph = FrameGraph(device)
    try:
        graph.import_image(
            "hdr", handle=None, view=None, format=FORMAT, extent=(64, 48),
            layout_before="SHADER_READ_ONLY_OPTIMAL", layout_after="SHADER_READ_ONLY_OPTIMAL",
        )  # fmt: skip
        graph.add_pass(ToneMap())
        passes = add_bloom(graph, BloomSettings(), (64, 48), before="tonemap")
        graph.compile((64, 48))
        down = [f"bloom_downsample_{k}" for k in range(3)]
        assert graph.order == [*down, "bloom_upsample_2", "bloom_upsample_1", "bloom_composite", "tonemap"]
        declared = {}
        for p in passes:
            builder = PassBuilder(p.name)
            p.setup(builder)
            declared[p.name] = {(u.resource, u.access.name, u.mip) for u in builder.declared().uses}
        assert declared["bloom_downsample_0"] == {("hdr", "COMPUTE_SAMPLED", None), ("bloom", "COMPUTE_WRITE", 0)}
        assert declared["bloom_downsample_2"] == {("bloom", "COMPUTE_SAMPLED", 1), ("bloom", "COMPUTE_WRITE", 2)}
        assert declared["bloom_upsample_2"] == {("bloom", "COMPUTE_SAMPLED", 2), ("bloom", "COMPUTE_READ_WRITE", 1)}
        assert declared["bloom_composite"] == {("bloom", "COMPUTE_SAMPLED", 0), ("hdr", "COMPUTE_READ_WRITE", None)}
        assert graph.transient_bytes >= 8 * (32 * 24 + 16 * 12 + 8 * 6)  # the chain: half size, 3 mips
    finally:
        graph.destroy()


def test_the_effect_added_to_a_graph_matches_the_reference():
    """BloomEffect's passes as the output graph adds them (`add_hdr`) over an imported "hdr": right
    on a first image, on a second of the same size (a remade target) and after a resize."""
    from ecs_engine.gpu.memory import Buffer
    from ecs_engine.render.graph import FrameGraph
    from ecs_engine.render.post.bloom_effect import BloomEffect

    device = shared_device()
    vk = device.vk
    read, dst, src = (
        getattr(vk, f"VK_IMAGE_LAYOUT_{n}_OPTIMAL") for n in ("SHADER_READ_ONLY", "TRANSFER_DST", "TRANSFER_SRC")
    )
    effect = BloomEffect(device, BloomSettings())
    buffer = Buffer(device, 66 * 50 * 8, vk.VK_BUFFER_USAGE_TRANSFER_SRC_BIT | vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT)
    graph = None
    try:
        for width, height in ((64, 48), (64, 48), (66, 50)):
            hdr = scene(width, height)
            image = HdrImage(device, width, height)
            buffer.bytes()[: hdr.nbytes] = hdr.view(np.uint8).reshape(-1)
            if graph is None or graph.compiled.structure.extent != (width, height):
                if graph is not None:
                    graph.destroy()
                graph = FrameGraph(device)  # a new size: a new graph (the chain's depth follows it)
                effect.add_hdr(graph, (width, height))
                graph.output("hdr")
            read_only = {"layout_before": "SHADER_READ_ONLY_OPTIMAL", "layout_after": "SHADER_READ_ONLY_OPTIMAL"}
            view, fmt = image.image.view, "VK_FORMAT_R16G16B16A16_SFLOAT"
            graph.import_image(
                "hdr", handle=image.image.handle, view=view, format=fmt, extent=(width, height), **read_only
            )
            graph.compile((width, height))

            def record(cb: Any, image: HdrImage = image, graph: FrameGraph = graph) -> None:
                image.barrier(cb, vk.VK_IMAGE_LAYOUT_UNDEFINED, dst)
                image.copy(cb, buffer, to_image=True)
                image.barrier(cb, dst, read)
                graph.execute(cb)
                image.barrier(cb, read, src)
                image.copy(cb, buffer, to_image=False)

            try:
                device.submit_once(record)
            finally:
                got = buffer.bytes()[: hdr.nbytes].view(np.float16).reshape(height, width, 4).copy()
                device.wait_idle()
                image.destroy()
            assert error(got, reference_bloom(hdr, effect.settings)) < 2e-3
    finally:
        if graph is not None:
            graph.destroy()
        effect.destroy()
        buffer.destroy()
