"""Texture views (render/frame/texture_views.py) with the window's post effects: FXAA after the
tone map into the texture's target, as the window and split-screen views have it."""

from __future__ import annotations

import shutil

import numpy as np
import pytest
from gpu_context import headless_gpu
from host_reads import host_barrier

from ecs_engine import World
from ecs_engine.gpu.memory import HOST, Buffer

W, H = 80, 60


def texture_view_pixels(renderer, name: str = "monitor") -> np.ndarray:
    """The RGB bytes (height, width, 3) int64 of texture view `name`'s target as its last frame
    left them (TRANSFER_SRC: what the copy into the texture's layer read); the frame waited for."""
    device = renderer.device
    vk = device.vk
    target = renderer.views.targets[name]
    out = Buffer(device, target.width * target.height * 4, vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT, HOST)
    try:
        color = vk.VK_IMAGE_ASPECT_COLOR_BIT
        region = vk.VkBufferImageCopy(
            imageSubresource=vk.VkImageSubresourceLayers(aspectMask=color, mipLevel=0, baseArrayLayer=0, layerCount=1),
            imageOffset=vk.VkOffset3D(0, 0, 0),
            imageExtent=vk.VkExtent3D(target.width, target.height, 1),
        )

        def record(cb):
            src = vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL
            vk.vkCmdCopyImageToBuffer(cb, target.color.handle, src, out.handle, 1, [region])
            host_barrier(vk, cb)

        device.submit_once(record)
        return out.bytes().reshape(target.height, target.width, 4)[..., :3].astype(np.int64).copy()
    finally:
        out.destroy()


def monitor_frame(gpu, **settings) -> tuple[np.ndarray, str]:
    """The monitor demo's first frame: its texture view's picture and the views' graphs."""
    from ecs_engine.app.scenes import default_schedule
    from ecs_engine.demos import monitor
    from ecs_engine.render.frame.renderer import Renderer

    world = World()
    monitor.build(world, gpu.meshes.add)
    renderer = Renderer(gpu.device, gpu.target, gpu.meshes, **settings)
    try:
        default_schedule().run(world, 0.0)
        renderer.render(world, readback=True)
        return texture_view_pixels(renderer), renderer.views.describe()
    finally:
        renderer.destroy()


def _edges(img: np.ndarray) -> np.ndarray:
    """Pixels with a neighbour (4-connected) of another colour."""
    lum = img.sum(axis=-1)
    edge = np.zeros(lum.shape, bool)
    step = np.abs(np.diff(lum, axis=0)) > 30
    edge[:-1] |= step
    edge[1:] |= step
    step = np.abs(np.diff(lum, axis=1)) > 30
    edge[:, :-1] |= step
    edge[:, 1:] |= step
    return edge


def test_a_texture_view_gets_fxaa_when_the_config_asks_for_it() -> None:
    with headless_gpu(W, H) as gpu:
        plain, plain_graphs = monitor_frame(gpu, tone_map="aces")
        smooth, graphs = monitor_frame(gpu, tone_map="aces", post={"fxaa"})
    texture_graph = graphs.split("view 2 of 2")[0]
    assert "into texture 'monitor'" in texture_graph and "fxaa" in texture_graph
    assert "fxaa" not in plain_graphs
    assert plain.shape == (96, 128, 3)  # the screen's picture, at the RenderTexture's size
    changed = np.abs(smooth - plain).max(axis=-1) > 2
    assert changed.sum() >= 10  # the spinning cube's silhouette smoothed
    assert (changed & ~_edges(plain)).sum() <= changed.sum() // 10  # ... on its edges alone


@pytest.mark.parametrize("settings", [{"light_culling": "deferred"}, {"msaa": 4}, {"post": {"fxaa", "bloom", "ssao"}}])
def test_a_texture_view_with_fxaa_in_every_form(settings: dict) -> None:
    """The deferred form, MSAA (FXAA after the resolve and tone map) and the hdr-stage effects
    before it: the texture view's picture is drawn (its magenta cube) through FXAA."""
    from ecs_engine.gpu.offscreen import OffscreenTarget

    samples = settings.pop("msaa", 1)
    settings.setdefault("post", {"fxaa"})
    with headless_gpu(W, H) as gpu:
        if samples > 1:
            gpu.target.destroy()
            gpu.target = OffscreenTarget(gpu.device, W, H, samples=samples)
        picture, graphs = monitor_frame(gpu, **settings)
    assert "fxaa" in graphs.split("view 2 of 2")[0]
    r, g, b = picture[..., 0], picture[..., 1], picture[..., 2]
    assert ((r > 90) & (b > 80) & (g < 0.5 * np.minimum(r, b))).sum() >= 100


# ------------------------------------------------------------------------------ hot reload
GREEN_FXAA = """#version 450
layout(set = 0, binding = 0) uniform sampler2D source;
layout(location = 0) out vec4 out_color;
void main() {
    out_color = vec4(0.0, 1.0, 0.0, 1.0);
    if (textureLod(source, vec2(0.5), 0.0).r > 1e30) out_color = vec4(1.0);  // never: the set is used
}
"""

GREEN_BLOOM = """#version 460
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform sampler2D source;
layout(set = 0, binding = 1, rgba16f) uniform image2D target;
layout(push_constant) uniform Push { float src; float dst; } push;
void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(target);
    if (p.x >= size.x || p.y >= size.y) return;
    vec4 green = vec4(0.0, 4.0, 0.0, 1.0);
    if (push.src > 1e30 && textureLod(source, vec2(0.5), 0.0).r > 1e30) green = vec4(1.0);  // never
    imageStore(target, p, green);
}
"""


def _green(img: np.ndarray) -> np.ndarray:
    return (img[..., 1] > 200) & (img[..., 0] < 30) & (img[..., 2] < 30)


@pytest.mark.skipif(shutil.which("glslc") is None, reason="no glslc")
@pytest.mark.parametrize(
    "post, file, text", [("fxaa", "fxaa.frag", GREEN_FXAA), ("bloom", "bloom_upsample.comp", GREEN_BLOOM)]
)
def test_a_reloaded_post_effect_shader_draws_in_every_view(tmp_path, monkeypatch, post, file, text) -> None:
    """Hot reload (app/shader_reload.py, Renderer.rebuild_pipelines) remakes the post effects,
    and each camera view's copies and graphs follow: the window's view (the left half) and
    the texture view draw with the new shader (green everywhere), not the old."""
    import ecs_engine.gpu.pipeline as pipeline
    from ecs_engine.app.file_watch import FileWatch
    from ecs_engine.app.scenes import default_schedule
    from ecs_engine.app.shader_reload import ShaderReload
    from ecs_engine.components import Camera, FlyCamera, Viewport
    from ecs_engine.demos import monitor
    from ecs_engine.render.frame.renderer import Renderer

    shaders = tmp_path / "shaders"
    shutil.copytree(pipeline.SHADER_DIR, shaders, ignore=shutil.ignore_patterns("__pycache__"))
    monkeypatch.setattr(pipeline, "SHADER_DIR", shaders)
    with headless_gpu(W, H) as gpu:
        world = World()
        monitor.build(world, gpu.meshes.add)
        (room,) = world.query(Camera, FlyCamera, write=()).entities()
        world.add(int(room), Viewport(width=0.5))
        default_schedule().run(world, 0.0)
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes, post={post})
        try:
            renderer.render(world, readback=True)
            before = gpu.target.pixels()[..., :3].astype(np.int64), texture_view_pixels(renderer)
            (shaders / file).write_text(text)
            said = ShaderReload(FileWatch(), shaders).reload([shaders / file], renderer)
            assert said == [(True, f"hot reload: {file}: compiled, the pipelines made again")]
            renderer.render(world, readback=True)
            after = gpu.target.pixels()[..., :3].astype(np.int64), texture_view_pixels(renderer)
        finally:
            renderer.destroy()
    assert not _green(before[0]).any() and not _green(before[1]).any()
    assert _green(after[0][:, : W // 2]).all()  # the window's view
    assert not _green(after[0][:, W // 2 :]).any()  # outside it: the background
    assert _green(after[1]).all()  # the texture view
