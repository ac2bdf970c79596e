"""Hot reload (`--watch`): a game's system edited while its App runs behaves the new way from the
next frames on, with the same entities; a broken edit keeps the old code running and says one
line naming the file and line; the reload is seen within a second of the write."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from ecs_engine.app.file_watch import FileWatch
from ecs_engine.app.game_module import find_game, make_app
from ecs_engine.app.hot_reload import HotReload
from ecs_engine.ecs.schema import object_component

GAME = """
import time
import numpy as np
from dataclasses import dataclass
from ecs_engine import Component, Field, MinimalPlugins


class Counter(Component):
    value = Field(np.int64, default=0)


@dataclass
class Tally:
    frames: int = 0


def setup(world, dt):
    world.spawn_batch(3, Counter())


def step(world, dt):
    for batch in world.query(Counter):
        batch[Counter].value += STEP
    world.resources[Tally].frames += 1
    time.sleep(SLEEP)


def build(app):
    app.add_plugins(MinimalPlugins)
    app.insert_resource(Tally())
    app.add_startup_systems(setup)
    app.add_systems("update", step)
    app.set_summary(lambda world: f"counters {world.query(Counter).column(Counter.value).tolist()}")
"""


def game_source(step: int = 1, sleep: float = 0.0, extra: str = "") -> str:
    return GAME.replace("STEP", str(step)).replace("SLEEP", str(sleep)) + extra


def write(path: Path, text: str) -> None:
    """Write `text` and move the mtime on: a write within the filesystem's mtime resolution
    must still be seen (the inode and size may be the same)."""
    before = path.stat().st_mtime_ns if path.exists() else 0
    path.write_text(text)
    os.utime(path, ns=(before + 1_000_000_000, before + 1_000_000_000))


@pytest.fixture
def game_file(tmp_path, request):
    name = f"hot_{request.node.name.replace('[', '_').replace(']', '').replace('-', '_')}"[:60]
    path = tmp_path / f"{name}.py"
    path.write_text(game_source())
    yield path
    sys.modules.pop(name, None)


def run_with_edits(game_file: Path, edits: dict[int, str], frames: int = 6, **reload_args):
    """Run the game `frames` frames; before frame k+1 (after k frames) write edits[k]. Returns the
    counters and entity ids after each frame, the HotReload and the lines it said."""
    game = find_game(str(game_file))
    app = make_app(game)
    seen: list[tuple[list[int], list[int]]] = []
    said: list[str] = []

    def record_and_edit(session, editor):
        from_world = session.world.query(game.module.Counter)
        seen.append((from_world.entities().tolist(), from_world.column(game.module.Counter.value).tolist()))
        if len(seen) in edits:
            write(game_file, edits[len(seen)])

    app.on_frame_end(record_and_edit)
    reload_args.setdefault("interval", 0.0)
    hot = HotReload(app, game.module, game_file.name, say=said.append, warn=said.append, **reload_args).install()
    app.run(frames=frames)
    return seen, hot, said


def test_an_edited_system_runs_the_new_way_on_the_same_entities(game_file):
    seen, hot, said = run_with_edits(game_file, {3: game_source(step=10)})
    ids = [entities for entities, _ in seen]
    assert all(e == ids[0] for e in ids) and len(ids[0]) == 3  # the same entities throughout
    assert [values[0] for _, values in seen] == [1, 2, 3, 13, 23]  # the last frame records nothing after it
    assert hot.reloads == 1 and hot.failures == 0
    assert said == [said[0]] and said[0].startswith(f"hot reload: {game_file.name}: 1 system replaced")


@pytest.mark.parametrize(
    "broken, where, what",
    [
        ("def step(world, dt)\n    pass\n", "syntax error: expected ':'", "syntax"),
        ("BOOM = 1 / 0\n", "importing it raised ZeroDivisionError: division by zero", "import"),
        ("def build(app):\n    raise RuntimeError('no build today')\n", "build(app) raised RuntimeError", "build"),
    ],
)
def test_a_broken_edit_keeps_the_old_code_and_says_one_line(game_file, broken, where, what):
    source = game_source(step=10, extra=broken)
    line = source.count("\n") - broken.count("\n") + 1 + (1 if what == "build" else 0)
    seen, hot, said = run_with_edits(game_file, {2: source}, frames=5)
    assert [values[0] for _, values in seen] == [1, 2, 3, 4]  # the old step ran on
    assert hot.reloads == 0 and hot.failures == 1
    assert len(said) == 1 and said[0].startswith(f"hot reload: {game_file.name}:{line}: {where}")
    assert said[0].endswith("; the old code keeps running")


def test_a_broken_edit_then_a_fixed_one_goes_in(game_file):
    seen, hot, _ = run_with_edits(game_file, {2: game_source(step=10, extra="x = (\n"), 3: game_source(step=100)})
    assert [values[0] for _, values in seen] == [1, 2, 3, 103, 203]
    assert (hot.failures, hot.reloads) == (1, 1)


def test_a_reloaded_system_that_raises_brings_back_the_code_before(game_file):
    raising = game_source(step=10).replace(
        "    for batch in world.query(Counter):\n        batch[Counter].value += 10",
        "    raise ZeroDivisionError('new code, bad code')",
    )
    assert "raise ZeroDivisionError" in raising
    line = raising.splitlines().index("    raise ZeroDivisionError('new code, bad code')") + 1
    seen, hot, said = run_with_edits(game_file, {2: raising}, frames=6)
    assert [values[0] for _, values in seen] == [1, 2, 2, 3, 4]  # the frame it raised in, then the old step
    assert (hot.reloads, hot.rolled_back) == (1, 1)
    assert said[1] == (
        f"hot reload: {game_file.name}:{line}: system step raised ZeroDivisionError: new code, bad code; "
        "back to the code before the reload"
    )
    assert hot.app.system("step").fn.__module__ == game_file.stem  # the old function, not a guard's


def test_a_component_keeps_its_class_unless_its_fields_change(game_file):
    same_fields = game_source(step=5).replace(
        "    value = Field(np.int64, default=0)\n",
        "    value = Field(np.int64, default=0)\n\n    def twice(self):\n        return 2\n",
    )
    seen, hot, _ = run_with_edits(game_file, {2: same_fields})
    assert [values[0] for _, values in seen] == [1, 2, 7, 12, 17]  # the new step finds the world's Counters
    assert not hasattr(hot.module.Counter, "twice")  # the world's class, kept

    game_file.write_text(game_source())
    more_fields = game_source(step=5).replace(
        "    value = Field(np.int64, default=0)\n",
        "    value = Field(np.int64, default=0)\n    extra = Field(np.float32)\n",
    )
    seen, hot, said = run_with_edits(game_file, {2: more_fields})
    assert [values[0] for _, values in seen] == [1, 2, 3, 4, 5]
    assert said == [
        f"hot reload: {game_file.name}: component Counter's fields changed (value: int64 -> value: int64, "
        "extra: float32): the world holds it as it was; restart to use the new fields; the old code keeps running"
    ]


def test_a_resource_class_is_kept_so_the_new_systems_find_the_resource(game_file):
    # without keeping Tally, the new step's world.resources[Tally] would be a KeyError
    seen, hot, _ = run_with_edits(game_file, {2: game_source(step=3)})
    assert [values[0] for _, values in seen] == [1, 2, 5, 8, 11]
    assert hot.app.world.resources[hot.module.Tally].frames == 6


def test_a_new_system_declaring_a_kept_class_reads_and_writes_the_worlds(game_file):
    # @system(writes=[Counter]) runs as the module runs, with the new Counter class: the world's
    # is the old one, which the new system must declare or its query is refused
    declared = game_source(step=10).replace("def step(", "@system(writes=[Counter, Tally])\ndef step(")
    declared = declared.replace("import Component,", "import Component, system,")
    seen, hot, _ = run_with_edits(game_file, {2: declared})
    assert [values[0] for _, values in seen] == [1, 2, 12, 22, 32]
    assert hot.app.system("step").writes == {hot.module.Counter, object_component(hot.module.Tally)}


def test_systems_added_and_removed_by_an_edit(game_file):
    added = game_source().replace(
        'app.add_systems("update", step)', 'app.add_systems("update", step)\n    app.add_systems("fixed", double)'
    ) + ("\n\ndef double(world, dt):\n    for batch in world.query(Counter):\n        batch[Counter].value *= 2\n\n")
    removed = game_source().replace('app.add_systems("update", step)', 'app.add_systems("update", other)') + (
        "\n\ndef other(world, dt):\n    for batch in world.query(Counter):\n        batch[Counter].value -= 1\n"
    )
    seen, hot, said = run_with_edits(game_file, {2: added, 4: removed}, frames=7)
    # the fixed stage runs once a frame here (the simulation's dt is the fixed step)
    assert [values[0] for _, values in seen] == [1, 2, 5, 11, 10, 9]
    assert "added double" in said[0]
    assert "added other" in said[1] and "removed step, double" in said[1]
    assert "step" not in hot.app.systems() and hot.app.systems()["other"] == "update"


def test_a_new_startup_system_does_not_run_and_is_named(game_file):
    edited = (
        game_source().replace("app.add_startup_systems(setup)", "app.add_startup_systems(setup, more)")
        + "\n\ndef more(world, dt):\n    world.spawn_batch(5, Counter())\n"
    )
    seen, _, said = run_with_edits(game_file, {2: edited})
    assert all(len(entities) == 3 for entities, _ in seen)
    assert "startup systems do not run again (more is new: restart to run it)" in said[0]


def test_the_reload_is_seen_within_a_second_of_the_write(game_file):
    """With the default poll interval (0.25 s) and frames of about 10 ms."""
    game_file.write_text(game_source(sleep=0.01))
    game = find_game(str(game_file))
    app = make_app(game)
    hot = HotReload(app, game.module, game_file.name, say=lambda line: None).install()
    written: list[float] = []
    first_new: list[float] = []

    def watch_counters(session, editor):
        if written and not first_new and hot.reloads:
            first_new.append(time.monotonic())

    app.on_frame_end(watch_counters)

    def edit_now():
        write(game_file, game_source(step=10, sleep=0.01))
        written.append(time.monotonic())

    edit = threading.Timer(0.3, edit_now)
    edit.start()
    app.run(frames=150)
    edit.join()
    assert first_new, "the edit was never reloaded"
    assert first_new[0] - written[0] < 1.0


def test_file_watch_sees_changes_and_not_a_missing_file(tmp_path):
    now = [0.0]
    files = FileWatch(interval=0.25, clock=lambda: now[0])
    a = tmp_path / "a.txt"
    a.write_text("1")
    files.watch([a])
    assert files.changed() == []
    write(a, "2")
    now[0] = 0.1
    assert files.changed() == []  # not yet: at most every 0.25 s
    now[0] = 0.3
    assert files.changed() == [a.resolve()]
    a.unlink()
    now[0] = 0.6
    assert files.changed() == []  # gone (mid-save): not a change
    write(a, "3")
    now[0] = 0.9
    assert files.changed() == [a.resolve()]


def play_watch(game_file: Path, *extra: str) -> subprocess.Popen:
    env = dict(os.environ)
    env.pop("DISPLAY", None)
    return subprocess.Popen(
        [sys.executable, "-m", "ecs_engine", "play", str(game_file), "--watch", "--headless", *extra],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )


def test_play_watch_from_the_command_line(game_file):
    """A broken edit is one line on stderr, no traceback; the fixed edit goes in; exit 0."""
    started = game_file.with_suffix(".started")
    tell = (  # the run has begun: its startup system says so
        f"\n\ndef setup(world, dt):\n    world.spawn_batch(3, Counter())\n"
        f"    __import__('pathlib').Path({str(started)!r}).touch()\n"
    )
    game_file.write_text(game_source(sleep=0.01, extra=tell))
    run = play_watch(game_file, "--frames", "400")

    def edit():
        deadline = time.monotonic() + 60
        while not started.exists() and time.monotonic() < deadline:
            time.sleep(0.05)
        write(game_file, game_source(step=10, sleep=0.01, extra="oops(\n"))
        time.sleep(0.6)
        write(game_file, game_source(step=1000, sleep=0.01))

    editor = threading.Thread(target=edit)
    editor.start()
    out, err = run.communicate(timeout=120)
    editor.join()
    assert run.returncode == 0, err
    errors = [line for line in err.splitlines() if line.strip()]
    assert len(errors) == 1 and f"{game_file}:" in errors[0] and "syntax error" in errors[0], err
    assert "Traceback" not in err
    assert f"hot reload: {game_file}: 1 system replaced" in out
    counters = np.array(eval(out.split("counters ")[1].splitlines()[0]))
    assert counters[0] > 1000 and (counters == counters[0]).all()


def test_watch_needs_a_game_in_the_editor():
    run = subprocess.run(
        [sys.executable, "-m", "ecs_engine", "editor", "cube", "--watch", "--headless"],
        capture_output=True,
        text=True,
    )
    assert run.returncode == 2
    assert run.stderr.strip() == (
        "ecs-engine: error: --watch reloads a game's code and assets: name a game first (editor game.py --watch)"
    )


ASSET_GAME = """
from ecs_engine import DefaultPlugins
from ecs_engine.components import Camera, Mesh, Transform
from ecs_engine.render.assets.materials import Material, materials
from ecs_engine.render.assets.meshes import Meshes


def setup(world, dt):
    looks = materials(world)
    glow = looks.textures.load(TEXTURE)
    look = looks.add(Material("glow", base_color=(0.0, 0.0, 0.0, 1.0), emissive=(1.0, 1.0, 1.0), emissive_texture=glow))
    world.spawn(Transform(), Mesh(handle=world.resources[Meshes].load(MODEL), material=look))
    world.spawn(Transform(position=(0.0, 0.0, 3.0)), Camera())


def build(app):
    app.add_plugins(PLUGINS)
    app.add_startup_systems(setup)
"""


SHADOW_CASTING = """

def lit(world, dt):  # a light casting shadows: the raytraced case traces the quad's structure
    from ecs_engine.components import DirectionalLight, Shadow

    world.spawn(Transform(), DirectionalLight(illuminance=1.0), Shadow())


_build = build


def build(app):
    _build(app)
    app.add_startup_systems(lit)
"""


def quad_obj(x0: float, x1: float) -> str:
    """A quad over x in [x0, x1], y in [-2, 2], facing the camera (+Z), with texture coordinates."""
    return (
        f"v {x0} -2 0\nv {x1} -2 0\nv {x1} 2 0\nv {x0} 2 0\n"
        "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\nf 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n"
    )


def write_png(path: Path, rgb: tuple[int, int, int]) -> None:
    from PIL import Image

    before = path.stat().st_mtime_ns if path.exists() else 0
    Image.new("RGB", (16, 16), rgb).save(path)
    os.utime(path, ns=(before + 1_000_000_000, before + 1_000_000_000))


def asset_game(tmp_path: Path, name: str, plugins: str = "DefaultPlugins") -> tuple[Path, Path, Path]:
    texture, model = tmp_path / "glow.png", tmp_path / "quad.obj"
    write_png(texture, (255, 0, 0))
    model.write_text(quad_obj(-3.0, 0.0))  # the left half of the view
    source = ASSET_GAME.replace("TEXTURE", repr(str(texture))).replace("MODEL", repr(str(model)))
    game_file = tmp_path / f"{name}.py"
    game_file.write_text(source.replace("PLUGINS", plugins).replace("import DefaultPlugins", f"import {plugins}"))
    return game_file, texture, model


@pytest.mark.parametrize(
    "mode, shadows", [("instanced", "maps"), ("indirect", "maps"), ("per_entity", "maps"), ("instanced", "raytraced")]
)
def test_textures_and_meshes_changed_on_disk_show_in_the_next_frames(tmp_path, mode, shadows):
    if shadows == "raytraced":  # the mesh's bottom-level structure is built again (the GPU host runs this)
        from gpu_context import shared_device

        if shared_device().ray_tracing is None:
            pytest.skip(f"{shared_device().info.name} has no ray-tracing pipelines")
    game_file, texture, model = asset_game(tmp_path, "hot_assets_gpu")
    game_file.write_text(game_file.read_text() + SHADOW_CASTING)
    try:
        game = find_game(str(game_file))
        app = make_app(game)
        app.size = (32, 32)

        frames = [0]

        def edit(session, editor):
            frames[0] += 1
            if frames[0] == 2:
                write_png(texture, (0, 0, 255))
                model.write_text(quad_obj(0.0, 3.0))  # now the right half

        said: list[str] = []
        app.on_frame_end(edit)
        HotReload(app, game.module, game_file.name, interval=0.0, say=said.append, warn=said.append).install()
        shot = tmp_path / "shot.png"
        app.run(frames=4, headless=True, screenshot=str(shot), mode=mode, shadow_method=shadows)
    finally:
        sys.modules.pop("hot_assets_gpu", None)
    from PIL import Image

    pixels = np.asarray(Image.open(shot).convert("RGB")).astype(int)
    left, right = pixels[8:24, 2:12], pixels[8:24, 20:30]
    assert sorted(said) == ["hot reload: glow.png: texture reloaded", "hot reload: quad.obj: mesh reloaded"]
    assert left.max() < 80  # the quad moved away: the background (about 40, 40, 48)
    assert (right[..., 2] > 150).all() and (right[..., 2] - right[..., 0] > 100).all()  # blue (and the light's sheen)


def test_a_broken_asset_file_keeps_the_old_one_and_says_one_line(tmp_path):
    from ecs_engine.render.assets.materials import materials
    from ecs_engine.render.assets.meshes import Meshes

    game_file, texture, model = asset_game(tmp_path, "hot_assets_cpu", plugins="MinimalPlugins")
    try:
        game = find_game(str(game_file))
        app = make_app(game)
        kept: list[tuple[object, object]] = []

        frames = [0]

        def edit(session, editor):
            frames[0] += 1
            if frames[0] == 2:
                write(texture, "not a PNG")
                write(model, "v 0 0 0\nf 1 2 3\n")  # a face naming vertices that are not there
            world = session.world
            kept.append((materials(world).textures[0].pixels, world.resources[Meshes][0]))

        said: list[str] = []
        app.on_frame_end(edit)
        HotReload(app, game.module, game_file.name, interval=0.0, say=said.append, warn=said.append).install()
        app.run(frames=5)
    finally:
        sys.modules.pop("hot_assets_cpu", None)
    assert all(k[0] is kept[0][0] and k[1] is kept[0][1] for k in kept)  # the old assets throughout
    assert len(said) == 2, said
    image, mesh = sorted(said, key=lambda line: "quad.obj" in line)
    assert image.startswith("hot reload: glow.png: ") and image.endswith("; the old texture stays")
    assert f"hot reload: {tmp_path / 'quad.obj'}: face 1 (line 2)" in mesh and mesh.endswith("; the old mesh stays")


def test_the_editor_shows_a_failed_reload(tmp_path):
    from ecs_engine.app.plugins import EditorPlugin

    game_file, _, _ = asset_game(tmp_path, "hot_assets_editor")
    try:
        game = find_game(str(game_file))
        app = make_app(game)
        app.add_plugins(EditorPlugin)
        app.size = (320, 240)
        statuses: list[str] = []

        frames = [0]

        def edit(session, editor):
            frames[0] += 1
            if frames[0] == 1:
                write(game_file, game_file.read_text() + "\ndef (\n")

        def look(session, editor):
            statuses.append(editor.editor.settings_status)

        app.on_frame_end(edit)
        HotReload(app, game.module, game_file.name, interval=0.0, warn=lambda line: None).install()
        app.on_frame_end(look)
        app.run(frames=2, headless=True)
    finally:
        sys.modules.pop("hot_assets_editor", None)
    line = game_file.read_text().count("\n")
    assert statuses == [
        f"hot reload: {game_file.name}:{line}: syntax error: invalid syntax; the old code keeps running"
    ]


SHADER_GAME = """
from ecs_engine import DefaultPlugins
from ecs_engine.components import Camera, Mesh, Transform
from ecs_engine.render.assets.materials import Material, materials
from ecs_engine.render.assets.meshes import Meshes
from ecs_engine.render.assets.primitives import cube_mesh


def setup(world, dt):
    red = materials(world).add(Material("red", base_color=(0.0, 0.0, 0.0, 1.0), emissive=(1.0, 0.0, 0.0)))
    world.spawn(Transform(scale=(10.0, 10.0, 1.0)), Mesh(handle=world.resources[Meshes].add(cube_mesh()), material=red))
    world.spawn(Transform(position=(0.0, 0.0, 3.0)), Camera())


def build(app):
    app.add_plugins(DefaultPlugins)
    app.add_startup_systems(setup)
"""

GREEN_FRAG = """#version 450
layout(location = 0) in vec3 v_position;  // what mesh.vert writes, read (validation checks it)
layout(location = 1) in vec3 v_normal;
layout(location = 2) flat in uint v_material;
layout(location = 0) out vec4 out_color;
void main() {
    out_color = vec4(0.0, 1.0, 0.0, 1.0);
    if (v_material == 0xFFFFFFFFu && v_position.x + v_normal.x > 1e30) out_color = vec4(1.0);  // never
}
"""


def run_shader_edits(tmp_path, monkeypatch, name: str, edits: dict[int, tuple[str, str]], frames: int, **run_args):
    """SHADER_GAME run `frames` frames at 32x32 over a copy of the engine's shaders; after frame k
    (1-based) the shader file edits[k][0] is written with edits[k][1]. Returns the HotReload,
    the lines it said, the RunResult and the last frame's pixels."""
    from PIL import Image

    import ecs_engine.gpu.pipeline as pipeline

    shaders = tmp_path / "shaders"
    shutil.copytree(pipeline.SHADER_DIR, shaders, ignore=shutil.ignore_patterns("__pycache__"))
    monkeypatch.setattr(pipeline, "SHADER_DIR", shaders)
    game_file = tmp_path / f"{name}.py"
    game_file.write_text(SHADER_GAME)
    try:
        game = find_game(str(game_file))
        app = make_app(game)
        app.size = (32, 32)
        done = [0]

        def edit(session, editor):
            done[0] += 1
            if done[0] in edits:
                file, text = edits[done[0]]
                write(shaders / file, text)

        said: list[str] = []
        app.on_frame_end(edit)
        hot = HotReload(
            app, game.module, game_file.name, interval=0.0, shader_dir=shaders, say=said.append, warn=said.append
        ).install()
        shot = tmp_path / "shot.png"
        result = app.run(frames=frames, headless=True, screenshot=str(shot), **run_args)
    finally:
        sys.modules.pop(name, None)
    return hot, said, result, np.asarray(Image.open(shot).convert("RGB")).astype(int)


@pytest.mark.skipif(shutil.which("glslc") is None, reason="no glslc")
def test_an_edited_shader_is_compiled_and_drawn_with_and_a_broken_one_kept(tmp_path, monkeypatch):
    broken = ("mesh.frag", "#version 450\nvoid main() { nope }\n")
    hot, said, _, pixels = run_shader_edits(
        tmp_path, monkeypatch, "hot_shader_game", {1: broken, 2: ("mesh.frag", GREEN_FRAG)}, 4
    )
    assert said[0].startswith("hot reload: mesh.frag:2: error: ") and said[0].endswith("; the old shaders stay")
    assert said[1:] == ["hot reload: mesh.frag: compiled, the pipelines made again"]
    assert hot.shaders is not None and hot.shaders.reloaded == 1
    pixels = pixels[8:24, 8:24]
    assert (pixels[..., 1] > 150).all() and (pixels[..., 0] < 60).all()  # green, drawn by the new shader


STATE_GAME = """
from enum import Enum
import numpy as np
from ecs_engine import Component, Field, MinimalPlugins, in_state, request_state, system, NextState


class Mode(Enum):
    MENU = 1
    PLAYING = 2


class Counter(Component):
    value = Field(np.int64, default=0)


def setup(world, dt):
    world.spawn_batch(3, Counter())


@system(writes=[NextState[Mode]])
def start(world, dt):
    request_state(world, Mode.PLAYING)


def step(world, dt):
    for batch in world.query(Counter):
        batch[Counter].value += STEP


def build(app):
    app.add_plugins(MinimalPlugins)
    app.init_state(Mode.MENU)
    app.add_startup_systems(setup)
    app.add_systems("update", start, run_if=in_state(Mode.MENU))
    app.add_systems("update", step, run_if=in_state(Mode.PLAYING))
"""


def test_a_game_with_states_reloads_and_its_run_conditions_still_see_the_state(game_file):
    """The state's Enum class keeps its old class as components do: the new systems' run
    conditions ask about the state the world holds, not a new Enum of the same name."""
    game_file.write_text(STATE_GAME.replace("STEP", "1"))
    seen, hot, said = run_with_edits(game_file, {3: STATE_GAME.replace("STEP", "10")})
    assert hot.failures == 0, said
    assert [values[0] for _, values in seen] == [0, 1, 2, 12, 22]  # frame 1 starts, frame 2 on: steps


def test_a_state_whose_values_changed_is_refused_and_the_old_code_runs(game_file):
    game_file.write_text(STATE_GAME.replace("STEP", "1"))
    edit = STATE_GAME.replace("STEP", "10").replace("    PLAYING = 2\n", "    PLAYING = 2\n    PAUSED = 3\n")
    seen, hot, said = run_with_edits(game_file, {3: edit})
    assert hot.failures == 1 and [values[0] for _, values in seen] == [0, 1, 2, 3, 4]
    assert "state Mode's fields changed (MENU=1, PLAYING=2 -> MENU=1, PLAYING=2, PAUSED=3)" in said[0]


GREEN_TONE_MAP = """#version 450
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_samplerless_texture_functions : require
#include "layouts.glsl"
layout(set = 0, binding = 0) uniform texture2D hdr;
layout(push_constant) uniform Push { ToneMapPush push; };
layout(location = 0) out vec4 out_color;
void main() {
    out_color = vec4(0.0, 1.0, 0.0, 1.0);
    if (push.exposure < -1e30 && texelFetch(hdr, ivec2(0), 0).r > 1e30) out_color = vec4(1.0);  // never
}
"""


@pytest.mark.skipif(shutil.which("glslc") is None, reason="no glslc")
def test_an_edited_output_pass_shader_is_drawn_with_too(tmp_path, monkeypatch):
    """The tone map (a pass made once, against the render pass) takes the edited shader too."""
    _, said, result, pixels = run_shader_edits(
        tmp_path,
        monkeypatch,
        "hot_tone_map_game",
        {1: ("tonemap.frag", GREEN_TONE_MAP)},
        3,
        tone_map="aces",
        validate=True,
    )
    assert said == ["hot reload: tonemap.frag: compiled, the pipelines made again"]
    assert result.validation_messages == []
    assert (pixels[..., 1] > 200).all() and (pixels[..., 0] < 30).all()  # every pixel: the new tone map's
