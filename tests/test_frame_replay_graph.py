"""Frame replay keyed by the frame graph (render/frame/replay.py `frame_key`): the key is the
output graph's passes' keys (graph.key()) beside a prelude of the work still recorded by hand, so
a pass whose key changes makes the frame record, and one whose key is UNREPLAYABLE makes every
frame record; a hand-kept list of fields would replay both stale."""

from __future__ import annotations

from collections.abc import Hashable, Iterator
from contextlib import contextmanager
from typing import Any

from gpu_context import headless_gpu

from ecs_engine import World
from ecs_engine.app.scenes import default_schedule
from ecs_engine.components import Mesh, PointLight, Transform
from ecs_engine.demos.scene_kit import add_camera
from ecs_engine.render.assets.primitives import cube_mesh
from ecs_engine.render.graph import UNREPLAYABLE, Pass


class Probe(Pass):
    """A pass of the output graph that records nothing but counts its recordings; its key is
    whatever the test sets."""

    name = "probe"

    def __init__(self) -> None:
        self.value: Hashable = 0
        self.recorded = 0

    def setup(self, builder: Any) -> None:
        builder.side_effect()  # never culled

    def record(self, cb: Any, ctx: Any) -> None:
        self.recorded += 1

    def key(self) -> Hashable:
        return self.value


@contextmanager
def probed_renderer(**settings: Any) -> Iterator[tuple[Any, World, Probe]]:
    """A renderer of a one-cube world whose output graph (made by its first frame) has a Probe."""
    from ecs_engine.render.frame.renderer import Renderer

    with headless_gpu(32, 24) as gpu:
        world = World()
        world.spawn(Transform(), Mesh(handle=gpu.meshes.add(cube_mesh())))
        world.spawn(Transform(position=(2.0, 3.0, 3.0)), PointLight(intensity=8.0))
        add_camera(world, eye=(0.0, 1.0, 4.0), target=(0.0, 0.0, 0.0))
        renderer = Renderer(gpu.device, gpu.target, gpu.meshes, **settings)
        gpu.owned.append(renderer)
        default_schedule().run(world, 0.0)
        renderer.render(world)
        graph = renderer.output.graph.graph  # the form's graph, kept for the renderer's life
        probe = Probe()
        graph.add_pass(probe)
        yield renderer, world, probe


def replays_within(renderer: Any, world: World, frames: int = 6) -> bool:
    return any(renderer.render(world).replayed for _ in range(frames))


def test_a_pass_whose_key_changes_makes_the_frame_record():
    for settings in ({}, {"tone_map": "aces"}):  # the direct form's graph and the hdr form's
        with probed_renderer(**settings) as (renderer, world, probe):
            assert replays_within(renderer, world)  # the probe's key stays: frames replay
            slots = len(renderer.frames.frames)
            recorded = probe.recorded
            probe.value = 1  # nothing else changes: only the probe's key says the frame differs
            for _ in range(slots):  # each slot's last recording had the old key
                assert not renderer.render(world).replayed
            assert probe.recorded == recorded + slots
            assert replays_within(renderer, world)  # and then the new key replays
            assert probe.recorded == recorded + slots


def test_a_pass_returning_unreplayable_makes_every_frame_record():
    with probed_renderer() as (renderer, world, probe):
        assert replays_within(renderer, world)
        probe.value = UNREPLAYABLE
        replayed, recorded = renderer.replay.replayed, probe.recorded
        for _ in range(5):
            assert not renderer.render(world).replayed
        assert renderer.replay.replayed == replayed and probe.recorded == recorded + 5
        probe.value = 2
        assert replays_within(renderer, world)


def test_the_tone_map_pass_keys_the_exposure():
    """The exposure is no field of the prelude any more: the tone map pass's key holds it."""
    from ecs_engine.render.frame.replay import frame_key

    with probed_renderer(tone_map="aces") as (renderer, world, _):
        assert replays_within(renderer, world)
        state = renderer.output._last[1]  # the target state the frames drew with
        slot = renderer.frames.index
        stops = ([], [], False)

        def key() -> Any:
            return frame_key(renderer, state, slot, (0, None, 0, False), stops)

        before = key()
        assert before is not None and before == key()
        renderer.exposure = 1.0
        assert key() != before
        renderer.exposure = 0.0
        assert key() == before
        renderer.overlay = object()  # the UI pass draws anew each frame
        assert key() is None
        renderer.overlay = None


def test_a_frame_recorded_without_a_key_leaves_no_stale_target_in_the_next_key():
    """A frame that records without a key (replay off here) imports its own output image into
    the graph; the next key (OutputGraph.prepare) imports again and names the image it draws into."""
    from ecs_engine.gpu.functions import handle_int
    from ecs_engine.gpu.memory import Image
    from ecs_engine.render.frame.renderer import Renderer
    from ecs_engine.render.frame.replay import frame_key

    with headless_gpu(32, 24) as gpu:
        device, vk = gpu.device, gpu.device.vk
        world = World()
        world.spawn(Transform(), Mesh(handle=gpu.meshes.add(cube_mesh())))
        add_camera(world, eye=(0.0, 1.0, 4.0), target=(0.0, 0.0, 0.0))
        renderer = Renderer(device, gpu.target, gpu.meshes)
        gpu.owned.append(renderer)
        usage = vk.VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | vk.VK_IMAGE_USAGE_TRANSFER_SRC_BIT
        images = [Image(device, 32, 24, gpu.target.color_format, usage, vk.VK_IMAGE_ASPECT_COLOR_BIT) for _ in range(2)]
        try:
            default_schedule().run(world, 0.0)
            for _ in range(3):
                renderer.render(world, framebuffer=images[0], extent=(32, 24))
            renderer.replay.enabled = False  # recorded without a key, into the other image
            renderer.render(world, framebuffer=images[1], extent=(32, 24))
            renderer.replay.enabled = True
            state = renderer.target_state(images[0], 32, 24)
            key = frame_key(renderer, state, renderer.frames.index, (0, None, 0, False), ([], [], False))
            assert key is not None
            kept = key[-1][0]  # the output graph's kept entry for the slot: (inputs, shape, graph, imports)
            handles = {name: handle for name, handle, _ in kept[3][1][4]}
            assert handles["target"] == handle_int(vk, images[0].handle) != handle_int(vk, images[1].handle)
        finally:
            device.wait_idle()
            for image in images:
                image.destroy()
