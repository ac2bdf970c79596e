"""Models with their materials: OBJ + .mtl and glTF/GLB PBR materials become Materials with
textures; a missing or broken texture loads as the fallback with one warning naming it; the demo
shows a file's own textures."""

from __future__ import annotations

import json
import logging
import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

from ecs_engine.render.assets.materials import Materials
from ecs_engine.render.assets.mesh_loading import DEFAULT_MODEL, load_mesh
from ecs_engine.render.assets.model_loading import load_model
from ecs_engine.render.assets.mtl import read_mtl

QUAD_OBJ = """mtllib {mtl}
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 2 0 0
v 2 1 0
vt 0 0
vt 1 0
vt 1 1
vt 0 1
usemtl shiny
f 1/1 2/2 3/3 4/4
usemtl textured
f 2/1 5/2 6/3 3/4
"""

MTL = """# two materials
newmtl shiny
Kd 0.8 0.1 0.1
Ks 0.5 0.5 0.5
Ns 120
Ke 0.0 0.1 0.0
newmtl textured
Kd 1 1 1
map_Kd {diffuse}
map_Bump -bm 0.5 normal.png
"""


def png(path, colour, side=8):
    px = np.zeros((side, side, 4), np.uint8)
    px[...] = colour
    Image.fromarray(px).save(path)
    return px


def write_obj(tmp_path, diffuse="wood.png", mtl="m.mtl"):
    (tmp_path / "m.obj").write_text(QUAD_OBJ.format(mtl=mtl))
    (tmp_path / "m.mtl").write_text(MTL.format(diffuse=diffuse))
    return tmp_path / "m.obj"


def by_name(parts, registry):
    return {registry[p.material].name: (p, registry[p.material]) for p in parts}


def test_obj_materials_and_textures_from_the_mtl(tmp_path, caplog):
    wood = png(tmp_path / "wood.png", (200, 120, 40, 255))
    png(tmp_path / "normal.png", (128, 128, 255, 255))
    registry = Materials()
    with caplog.at_level(logging.WARNING, logger="ecs_engine"):
        parts = load_model(write_obj(tmp_path), registry)
    assert caplog.records == []
    assert len(parts) == 2 and sum(len(p.mesh.indices) for p in parts) == 12
    found = by_name(parts, registry)
    shiny = found["shiny"][1]
    assert shiny.model == "blinn_phong" and shiny.base_color == pytest.approx((0.8, 0.1, 0.1, 1.0))
    assert shiny.shininess == 120 and shiny.specular == pytest.approx(0.5) and shiny.emissive == (0.0, 0.1, 0.0)
    assert shiny.base_color_texture is None
    textured = found["textured"][1]
    assert (registry.textures[textured.base_color_texture].pixels == wood).all()
    assert registry.textures[textured.base_color_texture].color
    assert not registry.textures[textured.normal_texture].color and textured.normal_scale == 0.5
    assert found["textured"][0].mesh.uvs is not None


def test_a_missing_texture_loads_the_model_with_the_fallback_and_one_warning(tmp_path, caplog):
    png(tmp_path / "normal.png", (128, 128, 255, 255))
    registry = Materials()
    with caplog.at_level(logging.WARNING, logger="ecs_engine"):
        parts = load_model(write_obj(tmp_path, diffuse="gone.png"), registry)
    assert len(parts) == 2
    textured = by_name(parts, registry)["textured"][1]
    assert textured.base_color_texture == registry.textures.fallback
    lines = [r.getMessage() for r in caplog.records]
    assert len(lines) == 1 and "gone.png" in lines[0] and "fallback" in lines[0]


def test_a_missing_material_library_warns_and_leaves_parts_without_material(tmp_path, caplog):
    registry = Materials()
    with caplog.at_level(logging.WARNING, logger="ecs_engine"):
        parts = load_model(write_obj(tmp_path, mtl="nowhere.mtl"), registry)
    assert [p.material for p in parts] == [None] * len(parts)
    assert len(caplog.records) == 1 and "nowhere.mtl" in caplog.records[0].getMessage()


def test_mtl_options_and_odd_lines(tmp_path, caplog):
    (tmp_path / "x.mtl").write_text(
        "newmtl a\nKd 0.5\nd 0.25\nmap_Kd -o 1 1 1 -s 2 2 2 my texture.png\nNs not-a-number\nnewmtl b\nTr 0.1\n"
    )
    with caplog.at_level(logging.WARNING, logger="ecs_engine"):
        found = read_mtl(tmp_path / "x.mtl")
    assert found["a"].diffuse == (0.5, 0.5, 0.5) and found["a"].opacity == 0.25
    assert found["a"].maps["diffuse"].path == tmp_path / "my texture.png"
    assert found["b"].opacity == pytest.approx(0.9)
    assert len(caplog.records) == 1 and "line 5" in caplog.records[0].getMessage()


def test_translucent_materials_import_as_blended(tmp_path):
    (tmp_path / "m.obj").write_text(QUAD_OBJ.format(mtl="m.mtl"))
    (tmp_path / "m.mtl").write_text("newmtl shiny\nKd 1 0 0\nd 0.4\nnewmtl textured\nKd 0 1 0\n")
    registry = Materials()
    found = by_name(load_model(tmp_path / "m.obj", registry), registry)
    glass = found["shiny"][1]
    assert glass.alpha_mode == "blend" and glass.base_color[3] == pytest.approx(0.4)
    assert found["textured"][1].alpha_mode == "opaque"
    path = gltf_quad(tmp_path, baseColorFactor=[1.0, 1.0, 1.0, 0.5], alphaMode="BLEND")
    (part,) = load_model(path, registry)
    assert registry[part.material].alpha_mode == "blend"


def test_the_torus_knot_keeps_one_part_without_a_material():
    parts = load_model(DEFAULT_MODEL, Materials())
    assert len(parts) == 1 and parts[0].material is None
    whole = load_mesh(DEFAULT_MODEL)
    assert np.array_equal(parts[0].mesh.positions, whole.positions)
    assert np.array_equal(parts[0].mesh.indices, whole.indices)


def gltf_quad(tmp_path, name="q.glb", **material):
    import trimesh

    mat = trimesh.visual.material.PBRMaterial(name="pbr", **material)
    mesh = trimesh.Trimesh(
        vertices=[[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]],
        faces=[[0, 1, 2], [0, 2, 3]],
        visual=trimesh.visual.TextureVisuals(uv=[[0, 0], [1, 0], [1, 1], [0, 1]], material=mat),
        process=False,
    )
    path = tmp_path / name
    mesh.export(path)
    return path


def test_gltf_pbr_material_and_textures(tmp_path, caplog):
    colour = np.zeros((8, 8, 4), np.uint8)
    colour[...] = (10, 200, 30, 255)
    mr = np.zeros((8, 8, 4), np.uint8)
    mr[...] = (0, 128, 255, 255)
    path = gltf_quad(
        tmp_path,
        baseColorFactor=[1.0, 0.5, 0.25, 1.0],
        baseColorTexture=Image.fromarray(colour),
        metallicFactor=0.3,
        roughnessFactor=0.7,
        metallicRoughnessTexture=Image.fromarray(mr),
        emissiveFactor=[0.1, 0.2, 0.3],
        alphaMode="MASK",
        alphaCutoff=0.4,
        doubleSided=True,
    )
    registry = Materials()
    with caplog.at_level(logging.WARNING, logger="ecs_engine"):
        parts = load_model(path, registry)
    assert caplog.records == []
    (part,) = parts
    m = registry[part.material]
    assert m.model == "cook_torrance" and m.alpha_mode == "mask" and m.alpha_cutoff == pytest.approx(0.4)
    assert m.base_color == pytest.approx((1.0, 0.5, 0.25, 1.0), abs=1 / 255)
    assert (m.metallic, m.roughness) == pytest.approx((0.3, 0.7))
    assert m.emissive == pytest.approx((0.1, 0.2, 0.3))
    assert (registry.textures[m.base_color_texture].pixels == colour).all()
    assert registry.textures[m.base_color_texture].color
    assert not registry.textures[m.metallic_roughness_texture].color
    assert m.normal_texture is None and m.double_sided


def test_gltf_with_a_missing_image_file(tmp_path, caplog):
    source = gltf_quad(tmp_path, name="q.gltf", baseColorTexture=Image.fromarray(np.full((4, 4, 4), 255, np.uint8)))
    header = json.loads(source.read_text())
    header["images"] = [{"uri": "lost.png"}]
    for texture in header["textures"]:
        texture["source"] = 0
    source.write_text(json.dumps(header))
    registry = Materials()
    with caplog.at_level(logging.WARNING, logger="ecs_engine"):
        (part,) = load_model(source, registry)
    assert registry[part.material].base_color_texture == registry.textures.fallback
    lines = [r.getMessage() for r in caplog.records]
    assert len(lines) == 1 and "lost.png" in lines[0] and "fallback" in lines[0]


def test_demo_model_shows_the_files_texture(tmp_path):
    """End to end: a GLB whose only colour is its base colour texture (unlit would hide lighting;
    cook_torrance under the demo's lights still shows the hue) comes out of the demo in that hue."""
    texture = np.zeros((16, 16, 4), np.uint8)
    texture[...] = (20, 40, 230, 255)  # blue
    path = gltf_quad(tmp_path, baseColorTexture=Image.fromarray(texture), metallicFactor=0.0, roughnessFactor=0.9)
    shot = tmp_path / "model.png"
    proc = subprocess.run(
        [sys.executable, "-m", "ecs_engine", "demo", "model", str(path), "--headless", "--frames", "2"]
        + ["--width", "96", "--height", "64", "--screenshot", str(shot), "--validate"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    assert "validation" not in proc.stderr.lower()
    img = np.asarray(Image.open(shot)).astype(int)
    lit = img[np.abs(img - img[0, 0]).sum(-1) > 30]  # not the background
    assert len(lit) > 200
    assert (lit[:, 2] > lit[:, 0] + 20).mean() > 0.9  # the quad is blue, not the default gold
