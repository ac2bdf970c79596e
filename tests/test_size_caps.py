"""What a small file may ask for is capped (issue 34 #6): deflate lets a 1 MB scene hold a 1 GiB
texture or environment, and a 60-byte image header can claim 15000 x 15000 pixels. Each is
refused from its header, before anything of that size is read or decoded, with one message
naming the array or file and the cap (docs/scene-format.md, "Size caps"); and what the engine
saves by value, it loads."""

from __future__ import annotations

import json
import re
import struct
import tracemalloc
import zipfile
import zlib

import numpy as np
import pytest

from ecs_engine import World
from ecs_engine.components import Mesh, Transform
from ecs_engine.components.environment import Environment
from ecs_engine.ecs.scene_file import SceneFileError, load_world, save_world
from ecs_engine.errors import UsageError
from ecs_engine.render.assets.materials import Material, materials
from ecs_engine.render.assets.mesh_data import MeshData
from ecs_engine.render.assets.scene_assets import MeshReferences
from ecs_engine.render.assets.textures import Texture


class Registry(list):
    def add(self, mesh):
        self.append(mesh)
        return len(self) - 1


def swap_array(path, out, key, dtype, shape):
    """`path` saved again as `out` with resource array `key` replaced by zeros of `dtype` and
    `shape`, deflated and written in chunks (a few MB of file for hundreds of MB of array)."""
    with zipfile.ZipFile(path) as archive:
        members = {n: archive.read(n) for n in archive.namelist()}
    header = json.loads(members["header.json"])
    said = next(r["arrays"][key] for r in header["resources"] if key in r["arrays"])
    said.update(dtype=np.dtype(dtype).str, shape=list(shape))
    members["header.json"] = json.dumps(header).encode()
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as archive:
        for name, data in members.items():
            if name != said["member"]:
                archive.writestr(name, data)
        with archive.open(said["member"], "w", force_zip64=True) as member:
            npy = {"descr": np.dtype(dtype).str, "fortran_order": False, "shape": tuple(shape)}
            np.lib.format.write_array_header_1_0(member, npy)
            left, chunk = int(np.prod(shape)) * np.dtype(dtype).itemsize, bytes(16 << 20)
            while left:
                member.write(chunk[: min(left, len(chunk))])
                left -= min(left, len(chunk))
    return out


def load_peak(path, codecs) -> tuple[str, int]:
    """The error loading `path` gives and the most memory Python allocated meanwhile."""
    tracemalloc.start()
    try:
        with pytest.raises(SceneFileError) as caught:
            load_world(path, World(), resources=codecs)
        return str(caught.value), tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def textured_scene(tmp_path):
    world = World()
    registry = materials(world)
    texture = registry.textures.add(Texture("pixels", np.zeros((16, 16, 4), np.uint8)))
    registry.add(Material("m", base_color_texture=texture))
    save_world(world, tmp_path / "t.scene")
    return tmp_path / "t.scene"


@pytest.mark.parametrize(
    ("shape", "message"),
    [((8200, 8200, 4), r"8200 x 8200 pixels is larger than"), ((16, 16385, 4), r"16385 x 16 pixels is larger")],
)
def test_a_texture_by_value_over_the_cap_is_refused_before_it_is_read(tmp_path, shape, message):
    bad = swap_array(textured_scene(tmp_path), tmp_path / "big.scene", "texture0", np.uint8, shape)
    assert bad.stat().st_size < 2 << 20  # 269 MB of pixels in under 2 MB
    said, peak = load_peak(bad, None)
    assert "resources/materials/texture0.npy" in said and "16384 a side and 67,108,864 pixels" in said
    assert re.search(message, said)
    assert peak < 32 << 20  # nothing the size of the array was allocated


def test_an_environment_by_value_over_the_cap_is_refused_before_it_is_read(tmp_path):
    world = World()
    world.resources[Environment] = Environment(np.zeros((16, 32, 3), np.float32))
    save_world(world, tmp_path / "e.scene")
    bad = swap_array(tmp_path / "e.scene", tmp_path / "big.scene", "pixels", np.float16, (6, 2400, 2400, 3))
    said, peak = load_peak(bad, None)
    assert "resources/environment/pixels.npy" in said and "more than the 33,554,432 texels" in said
    assert peak < 32 << 20
    # the largest allowed loads; one over the cap in code is not saved (it could not be loaded)
    world.resources[Environment] = Environment(np.zeros((4096, 8192, 3), np.float16))
    save_world(world, tmp_path / "ok.scene")
    loaded = World.load(tmp_path / "ok.scene")
    assert loaded.resources[Environment].source.shape == (4096, 8192, 3)
    world.resources[Environment] = Environment(np.zeros((4097, 8194, 3), np.float16))
    with pytest.raises(SceneFileError, match=r"cannot save resource 'environment': .*more than the 33,554,432"):
        save_world(world, tmp_path / "no.scene")


def test_a_mesh_by_value_over_the_cap_is_refused_before_it_is_read(tmp_path):
    world, registry = World(), Registry()
    registry.add(MeshData.from_arrays(np.eye(3), np.eye(3), [0, 1, 2], "triangle"))
    world.spawn(Transform(), Mesh(handle=0))
    save_world(world, tmp_path / "m.scene", resources=[MeshReferences(registry)])
    bad = swap_array(tmp_path / "m.scene", tmp_path / "big.scene", "mesh0_positions", np.int8, ((1 << 24) + 1, 3))
    said, peak = load_peak(bad, [MeshReferences(Registry())])
    assert "mesh0_positions has 16,777,217 vertices; a mesh saved by value has at most 16,777,216" in said
    assert peak < 32 << 20


def png_header(width: int, height: int) -> bytes:
    """A PNG whose header claims width x height (its one IDAT holds a single row)."""

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    ihdr = struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(bytes(1 + 4 * width)))


@pytest.mark.parametrize("side", [9000, 15000])
def test_image_files_are_checked_from_their_header(tmp_path, caplog, side):
    from ecs_engine.render.assets.textures import Textures
    from ecs_engine.render.lighting.environment_maps import load_cube

    path = tmp_path / "huge.png"
    path.write_bytes(png_header(side, side))  # 15000: Pillow's own bomb error escaped as an internal error
    textures = Textures()
    assert textures.load(path) == textures.fallback
    claimed = f"({side} x {side}|{side * side:,}) pixels is larger than an image may be"  # Pillow's check, or ours
    assert re.search(rf"huge\.png: {claimed}", caplog.records[-1].getMessage())
    with pytest.raises(UsageError, match=rf"environment map .*huge\.png: {claimed}"):
        load_cube(path)


def test_an_hdr_file_is_checked_from_its_header(tmp_path):
    from ecs_engine.render.lighting.environment_maps import load_cube

    path = tmp_path / "huge.hdr"
    path.write_bytes(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 8192 +X 16384\n" + bytes(64))
    with pytest.raises(UsageError, match=r"huge\.hdr: 16384 x 8192 is more than the 33,554,432 texels"):
        load_cube(path)
