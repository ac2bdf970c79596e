"""Files a user names, and files those files name, are opened only when they are regular files of
bounded size (issue 34 #2): a FIFO (what /dev/stdin is under a pipe) or a device (/dev/zero,
/dev/stdin on a terminal) named anywhere gives one message naming it and who named it, and never
blocks or reads without end. Every loader is tried: models and what they name, textures,
environments, scene files and what they name, input scripts, bindings files.

A FIFO with no writer blocks `open()` forever; `deadline` turns that into a failure (the code
before user_files.py hung in each of these)."""

from __future__ import annotations

import json
import logging
import os
import signal
import zipfile

import numpy as np
import pytest

from ecs_engine import World
from ecs_engine.errors import UsageError
from ecs_engine.user_files import FileKind, UserFileError, check_user_file, read_user_file

TRIANGLE = "v 0 0 0\nv 1 0 0\nv 0 1 0\n"


@pytest.fixture(autouse=True)
def deadline():
    """Fail (instead of hanging) when something blocks on a FIFO for 5 s; again each second
    after, as a library may catch the first (trimesh does)."""

    def late(signum, frame):
        raise TimeoutError("blocked on a FIFO or a device for 5 s")

    previous = signal.signal(signal.SIGALRM, late)
    signal.setitimer(signal.ITIMER_REAL, 5.0, 1.0)
    yield
    signal.setitimer(signal.ITIMER_REAL, 0)
    signal.signal(signal.SIGALRM, previous)


def fifo(path):
    os.mkfifo(path)
    return path


def device(path):
    """A link to a character device that is safe to read (/dev/zero would be read without end)."""
    os.symlink("/dev/null", path)
    return path


# ------------------------------------------------------------------------------ the module
def test_only_regular_files_of_bounded_size_are_opened(tmp_path):
    small = FileKind("test file", 10)
    (tmp_path / "ok.txt").write_bytes(b"0123456789")
    assert read_user_file(tmp_path / "ok.txt", small) == b"0123456789"
    os.symlink(tmp_path / "ok.txt", tmp_path / "link.txt")  # links are followed to a regular file
    assert read_user_file(tmp_path / "link.txt", small) == b"0123456789"

    (tmp_path / "big.txt").write_bytes(b"01234567890")
    with pytest.raises(UserFileError, match=r"big\.txt: is 11 bytes, more than the 10 bytes a test file may have$"):
        read_user_file(tmp_path / "big.txt", small)
    with pytest.raises(UserFileError, match=r"pipe: is a FIFO \(named pipe\), not a regular file; a test file must"):
        read_user_file(fifo(tmp_path / "pipe"), small)
    with pytest.raises(UserFileError, match=r"null \(named by me\.obj\): is a character device \(a link to /dev/null"):
        read_user_file(device(tmp_path / "null"), small, named_by="me.obj")
    with pytest.raises(UserFileError, match=r"is a directory"):
        check_user_file(tmp_path, small)
    with pytest.raises(FileNotFoundError):
        read_user_file(tmp_path / "none", small)
    assert isinstance(UserFileError("x", "why"), OSError)  # loaders handle it as any unreadable file


def test_a_file_that_says_it_is_empty_is_read_with_the_bound(tmp_path):
    # /proc files report size 0 and hold more: the bound holds while reading, not only from stat
    status = read_user_file("/proc/self/status", FileKind("proc file", 1 << 20))
    assert b"Name:" in status
    with pytest.raises(UserFileError, match=r"more than the 16 bytes"):
        read_user_file("/proc/self/status", FileKind("proc file", 16))


# ------------------------------------------------------------------------------------ models
def test_a_model_that_is_a_fifo_or_a_device_is_refused(tmp_path):
    from ecs_engine.render.assets.mesh_loading import load_mesh

    with pytest.raises(UsageError, match=r"pipe\.obj: is a FIFO"):
        load_mesh(fifo(tmp_path / "pipe.obj"))
    with pytest.raises(UsageError, match=r"null\.stl: is a character device"):
        load_mesh(device(tmp_path / "null.stl"))


def test_an_objs_material_library_and_textures_that_are_devices_only_warn(tmp_path, caplog):
    from ecs_engine.render.assets.materials import Materials
    from ecs_engine.render.assets.model_loading import load_model

    fifo(tmp_path / "pipe.mtl")
    (tmp_path / "a.obj").write_text("mtllib pipe.mtl\n" + TRIANGLE + "usemtl red\nf 1 2 3\n")
    with caplog.at_level(logging.WARNING, "ecs_engine"):
        parts = load_model(tmp_path / "a.obj", Materials())
    assert len(parts) == 1 and parts[0].mesh.triangle_count == 1
    said = [r.getMessage() for r in caplog.records]
    assert len(said) == 1 and "pipe.mtl (named by" in said[0] and "a.obj): is a FIFO" in said[0]

    caplog.clear()
    device(tmp_path / "zero.mtl")  # mtllib /dev/zero read 4.9 GB, then MemoryError
    (tmp_path / "b.obj").write_text(f"mtllib {tmp_path / 'zero.mtl'}\n" + TRIANGLE + "f 1 2 3\n")
    with caplog.at_level(logging.WARNING, "ecs_engine"):
        load_model(tmp_path / "b.obj", Materials())
    assert any("zero.mtl (named by" in r.getMessage() and "character device" in r.getMessage() for r in caplog.records)

    caplog.clear()
    fifo(tmp_path / "pipe.png")
    (tmp_path / "c.mtl").write_text("newmtl red\nKd 1 0 0\nmap_Kd pipe.png\n")
    (tmp_path / "c.obj").write_text("mtllib c.mtl\n" + TRIANGLE + "vt 0 0\nusemtl red\nf 1/1 2/1 3/1\n")
    registry = Materials()
    with caplog.at_level(logging.WARNING, "ecs_engine"):
        (part,) = load_model(tmp_path / "c.obj", registry)
    texture = registry[part.material].base_color_texture
    assert texture == registry.textures.fallback
    said = [r.getMessage() for r in caplog.records]
    assert any("pipe.png (named by" in m and "c.mtl): is a FIFO" in m and "fallback" in m for m in said), said


def test_a_gltf_buffer_that_is_a_fifo_is_refused(tmp_path):
    import trimesh

    from ecs_engine.render.assets.mesh_loading import load_mesh

    files = trimesh.exchange.gltf.export_gltf(trimesh.Scene(trimesh.creation.box()))
    for name, data in files.items():
        (tmp_path / name).write_bytes(data)
    buffer = next(n for n in files if n.endswith(".bin"))
    (tmp_path / buffer).unlink()
    fifo(tmp_path / buffer)
    with pytest.raises(UsageError, match=rf"{buffer} \(named by .*model\.gltf\): is a FIFO"):
        load_mesh(tmp_path / "model.gltf")


# ------------------------------------------------------------------ textures and environments
def test_textures_and_environment_maps_that_are_devices(tmp_path, caplog):
    from ecs_engine.render.assets.textures import Textures
    from ecs_engine.render.lighting.environment_maps import load_cube

    textures = Textures()
    with caplog.at_level(logging.WARNING, "ecs_engine"):
        assert textures.load(fifo(tmp_path / "pipe.png"), named_by="m.mtl") == textures.fallback
    assert "pipe.png (named by m.mtl): is a FIFO" in caplog.records[0].getMessage()
    with pytest.raises(UsageError, match=r"environment map .*pipe\.hdr: is a FIFO"):
        load_cube(fifo(tmp_path / "pipe.hdr"))
    with pytest.raises(UsageError, match=r"environment map .*pipe\.png: is a FIFO"):
        load_cube(tmp_path / "pipe.png")
    with pytest.raises(UsageError, match=r"environment map .*null\.jpg: is a character device"):
        load_cube(device(tmp_path / "null.jpg"))


# ------------------------------------------------------------------------------ scene files
def scene_naming(tmp_path, texture_file=None, environment=None):
    """A scene file whose texture (by reference) or environment names the given path."""
    import ecs_engine.render.assets.scene_assets  # noqa: F401 - registers the materials and environment codecs
    from ecs_engine.components.environment import Environment
    from ecs_engine.render.assets.materials import Material, materials
    from ecs_engine.render.assets.textures import Texture

    world = World()
    if texture_file is not None:
        registry = materials(world)
        pixels = np.zeros((4, 4, 4), np.uint8)
        registry.add(Material("m", base_color_texture=registry.textures.add(Texture("t", pixels, source="x.png"))))
    if environment is not None:
        world.resources[Environment] = Environment(environment)
    path = tmp_path / "s.scene"
    world.save(path)
    if texture_file is not None:  # point the saved texture at the file
        with zipfile.ZipFile(path) as archive:
            members = {n: archive.read(n) for n in archive.namelist()}
        header = json.loads(members["header.json"])
        resource = next(r for r in header["resources"] if r["name"] == "materials")
        resource["doc"]["textures"][0]["file"] = str(texture_file)
        members["header.json"] = json.dumps(header).encode()
        with zipfile.ZipFile(path, "w") as archive:
            for name, data in members.items():
                archive.writestr(name, data)
    return path


def test_a_scene_naming_a_device_is_refused_at_load(tmp_path):
    from ecs_engine.ecs.scene_file import SceneFileError

    with pytest.raises(SceneFileError, match=r"s\.scene: resource 'materials': texture 0 \(.*pipe\.png\): is a FIFO"):
        World.load(scene_naming(tmp_path, texture_file=fifo(tmp_path / "pipe.png")))
    # the environment is read at the first frame: a FIFO hung the editor there; refused at load now
    with pytest.raises(SceneFileError, match=r"s\.scene: resource 'environment': .*sky\.hdr: is a FIFO"):
        World.load(scene_naming(tmp_path, environment=str(fifo(tmp_path / "sky.hdr"))))
    with pytest.raises(SceneFileError, match=r"s\.scene: resource 'environment': .*null\.hdr: is a character dev"):
        World.load(scene_naming(tmp_path, environment=str(device(tmp_path / "null.hdr"))))


def test_a_scene_file_that_is_a_fifo_or_a_directory_is_refused(tmp_path):
    from ecs_engine.ecs.scene_file import SceneFileError

    with pytest.raises(SceneFileError, match=r"scene file .*pipe\.scene: is a FIFO"):
        World.load(fifo(tmp_path / "pipe.scene"))
    (tmp_path / "dir.scene").mkdir()
    with pytest.raises(SceneFileError, match=r"scene file .*dir\.scene: is a directory"):
        World.load(tmp_path / "dir.scene")


# ------------------------------------------------------------------ input scripts and bindings
def test_an_input_script_or_bindings_file_that_is_a_fifo(tmp_path, monkeypatch):
    from ecs_engine.app.bindings import bindings_file, load_bindings
    from ecs_engine.app.input_script import read_script

    with pytest.raises(UsageError, match=r"input script .*pipe\.txt: is a FIFO"):
        read_script(fifo(tmp_path / "pipe.txt"))
    with open(tmp_path / "long.txt", "wb") as sparse:  # 17 MiB that take no disk: refused from its size
        sparse.truncate(17 << 20)
    with pytest.raises(UsageError, match=r"long\.txt: is 17\.0 MiB, more than the 16\.0 MiB an input script may"):
        read_script(tmp_path / "long.txt")
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path))
    path = bindings_file("game")
    path.parent.mkdir(parents=True)
    fifo(path)
    said: list[str] = []
    actions = load_bindings({"fire": ["space"]}, "game", warn=said.append)
    assert actions.bound("fire") == ["space"]  # the defaults, and one warning
    assert len(said) == 1 and f"input bindings {path}: is a FIFO" in said[0]
