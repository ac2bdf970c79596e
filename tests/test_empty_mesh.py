"""An empty mesh (0 vertices, 0 indices) is legal end to end (issue 34 #5): MeshData allows it
(a procedural mesh can come out empty; the LOD builder expects it), a scene saves it by value, and
the renderer draws nothing for it, in every render mode and with shadow maps, with no validation
message. The upload of an empty mesh used to issue a zero-size vkCmdCopyBuffer
(VUID-VkBufferCopy-size-01988), twice: vertices and indices."""

from __future__ import annotations

import numpy as np
import pytest
from golden_images import image_difference

from ecs_engine import World
from ecs_engine.app.loop import run
from ecs_engine.app.settings import RunOptions
from ecs_engine.components import Mesh, Transform
from ecs_engine.demos.shadows import build
from ecs_engine.ecs.scene_file import save_world
from ecs_engine.render.assets.mesh_data import MeshData
from ecs_engine.render.assets.scene_assets import MeshReferences, scene_codecs


class Meshes(list):
    def add(self, mesh):
        self.append(mesh)
        return len(self) - 1


EMPTY = MeshData.from_arrays(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0, np.uint32), "empty")


def scene(tmp_path, with_empty: bool):
    world, meshes = World(), Meshes()
    build(world, meshes.add)
    if with_empty:  # in view, in front of the lit cube
        world.spawn(Transform(position=(0.0, 1.0, 2.0)), Mesh(handle=meshes.add(EMPTY)))
    path = tmp_path / f"{'empty' if with_empty else 'plain'}.scene"
    save_world(world, path, resources=[*scene_codecs()[:2], MeshReferences(meshes, by_value=True)])
    return str(path)


def render(path, mode, shadow_method="maps"):
    screenshot = path.replace(".scene", f"-{mode}-{shadow_method}.png")
    options = RunOptions(
        scene=path, width=64, height=48, frames=2, validate=True, quiet=True, mode=mode, screenshot=screenshot,
        shadow_method=shadow_method,
    )  # fmt: skip
    result = run(options)
    assert result.validation_messages == []
    return result


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    return render(scene(tmp_path_factory.mktemp("plain"), False), "instanced").pixels


@pytest.mark.parametrize("mode", ["instanced", "per_entity", "indirect"])
def test_an_empty_mesh_saved_by_value_loads_and_draws_nothing(tmp_path, reference, mode):
    result = render(scene(tmp_path, True), mode)
    mean, outliers = image_difference(result.pixels, reference)
    assert mean < 0.05 and outliers == 0  # the same picture as without it


def test_an_empty_mesh_is_left_out_of_the_ray_traced_shadows(tmp_path):
    """A bottom level of no triangles is not built: the traced shadows' picture is that of the
    scene without the empty mesh, traced the same way."""
    from gpu_context import shared_device

    if shared_device().ray_tracing is None:
        pytest.skip(f"{shared_device().info.name} has no ray-tracing pipelines")
    plain = render(scene(tmp_path, False), "instanced", "raytraced").pixels
    result = render(scene(tmp_path, True), "instanced", "raytraced")
    mean, outliers = image_difference(result.pixels, plain)
    assert mean < 0.05 and outliers == 0
