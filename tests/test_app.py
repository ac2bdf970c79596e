"""The public App (ecs_engine.App): built from plugins, startup systems before the first frame,
systems by stage with run conditions, one clear error for each kind of bad input, a run that
returns its RunResult and prints the demos' lines; headless with a screenshot, in a window under
Xvfb with the Window resource changing it, falling back to headless with a PNG without a display;
Esc and Ctrl-C; systems replaced by name while it runs; a pure simulation with no GPU at all."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from ecs_engine import App, DefaultPlugins, MinimalPlugins, Time, Window
from ecs_engine.app.plugins import PerfPlugin, RenderPlugin
from ecs_engine.components import Camera, DirectionalLight, Mesh, Transform, Velocity
from ecs_engine.maths.camera import look_rotation
from ecs_engine.render.assets.meshes import Meshes
from ecs_engine.render.assets.primitives import cube_mesh

BACKGROUND_TOLERANCE = 12


def cube_app(title: str = "Cube test", size: tuple[int, int] = (64, 48), plugins=DefaultPlugins) -> App:
    """An App that draws one cube, lit, in front of its camera (made by a startup system)."""
    app = App(title=title, size=size)
    app.add_plugins(plugins)

    def setup(world, dt):
        cube = world.resources[Meshes].add(cube_mesh())
        world.spawn(Transform(), Mesh(handle=cube, material=0))
        world.spawn(Transform(rotation=look_rotation((-0.3, -1.0, -0.5))), DirectionalLight(illuminance=2.0))
        world.spawn(Transform(position=(0.0, 1.2, 3.0), rotation=look_rotation((0.0, -1.2, -3.0))), Camera())

    app.add_startup_systems(setup)
    return app


def drawn(pixels: np.ndarray) -> float:
    """The share of pixels unlike the corner's (the background)."""
    rgb = pixels[..., :3].astype(np.int64)
    return float((np.abs(rgb - rgb[0, 0]).sum(axis=-1) > BACKGROUND_TOLERANCE).mean())


# ---------------------------------------------------------------------------------- bad input
@pytest.mark.parametrize(
    ("build", "message"),
    [
        (lambda app: app.add_systems("upate", lambda world, dt: None), "unknown stage 'upate'"),
        (lambda app: app.add_systems("update", 42), "not a system: 42"),
        (lambda app: app.add_systems("update", Transform), "not a system: the class Transform (pass an instance)"),
        (lambda app: app.add_systems("update"), "add_systems('update') was given no systems"),
        (lambda app: app.add_systems("update", print, run_if=True), "run_if must be a function of the world"),
        (lambda app: app.add_startup_systems("setup"), "not a system: 'setup'"),
        (lambda app: app.add_plugins(RenderPlugin), "plugin RenderPlugin is already added"),
        (lambda app: app.add_plugins(object()), "not a plugin"),
        (lambda app: app.add_plugins(int), "int is not a plugin"),
        (lambda app: app.insert_resource(Time), "insert_resource takes a value, such as Time()"),
        (lambda app: app.add_systems("update", print, print), "a system named 'print' is already in the App"),
        (lambda app: app.add_systems("update", print, print), "its own name (system(name='print_2')(print))"),
        (lambda app: app.replace_system("nothing", print), "no system named 'nothing'"),
        (lambda app: app.add_ui("hud"), "add_ui takes a function"),
        (lambda app: setattr(app, "size", (0, 10)), "a window size is (width, height)"),
    ],
)
def test_bad_input_is_one_clear_error(build, message):
    from ecs_engine.errors import UsageError

    app = App(title="Bad")
    app.add_plugins(DefaultPlugins)
    with pytest.raises((UsageError, ValueError)) as caught:
        build(app)
    assert message in str(caught.value) and "\n" not in str(caught.value)


def test_run_options_and_a_second_run_are_refused(capsys):
    app = App(title="Twice").add_plugins(MinimalPlugins)
    with pytest.raises(SystemExit) as exit_:
        app.run(frames=1, colour="red")
    assert exit_.value.code == 2
    assert capsys.readouterr().err.startswith("twice: error: App.run() has no option 'colour'; it takes ")
    app.run(frames=1)
    with pytest.raises(SystemExit) as exit_:
        app.run(frames=1)
    assert exit_.value.code == 2
    assert capsys.readouterr().err.strip() == (
        "twice: error: this App has run already: an App runs once (make another for another run)"
    )


def test_a_run_without_rendering_refuses_a_screenshot(capsys):
    with pytest.raises(SystemExit):
        App(title="Sim").add_plugins(MinimalPlugins).run(frames=2, screenshot="x.png")
    assert "sim draws nothing (no RenderPlugin), so there is no screenshot to write" in capsys.readouterr().err


# ------------------------------------------------------------------------------ simulation
def test_minimal_plugins_step_a_simulation_without_vulkan(tmp_path):
    """No window, no GPU: Vulkan and GLFW are never imported, and the steps are the fixed 1/60 s."""
    script = tmp_path / "sim.py"
    script.write_text(
        textwrap.dedent(
            """
            import sys
            from ecs_engine import App, MinimalPlugins, Time
            from ecs_engine.components import Transform, Velocity

            app = App(title="Sim")
            app.add_plugins(MinimalPlugins)
            app.add_startup_systems(lambda world, dt: world.spawn(Transform(), Velocity(linear=(1.0, 0.0, 0.0))))
            seen = []
            app.add_systems("update", lambda world, dt: seen.append(world.resources[Time].elapsed))
            result = app.run(frames=30)
            x = app.world.query(Transform).column(Transform.position)[0, 0]
            print("stepped", result.frames, len(seen), round(seen[-1], 6), round(float(x), 6))
            print("loaded", "vulkan" in sys.modules, "glfw" in sys.modules, "imgui_bundle" in sys.modules)
            """
        )
    )
    env = dict(os.environ, VK_ICD_FILENAMES="/nonexistent.json", VK_DRIVER_FILES="/nonexistent.json")
    run = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, env=env, timeout=120)
    assert run.returncode == 0, run.stderr
    assert "stepped 30 30 0.5 0.5" in run.stdout  # 30 steps of 1/60 s at 1 unit a second
    assert "loaded False False False" in run.stdout
    assert run.stdout.startswith("sim: simulation, no rendering, 30 frames")


def test_systems_run_by_stage_with_run_conditions_and_startup_first():
    app = App(title="Order").add_plugins(MinimalPlugins)
    calls: list[str] = []
    app.add_startup_systems(lambda world, dt: calls.append("startup"))

    def fixed(world, dt):
        calls.append("fixed")

    def update(world, dt):
        calls.append("update")

    def odd(world, dt):
        calls.append("odd")

    app.add_systems("update", update)
    app.add_systems("fixed", fixed)
    app.add_systems("update", odd, run_if=lambda world: world.resources[Time].steps % 2 == 1)
    app.run(frames=4)
    assert calls == [
        "startup",
        "fixed",
        "update",
        "odd",
        "fixed",
        "update",
        "fixed",
        "update",
        "odd",
        "fixed",
        "update",
    ]
    assert app.systems()["odd"] == "update" and app.systems()["<lambda>#1"] == "startup"


def test_a_system_is_replaced_by_name_while_the_game_runs():
    """The next frames run the new code, with the same entities (what hot reload does)."""
    app = App(title="Swap").add_plugins(MinimalPlugins)
    app.add_startup_systems(lambda world, dt: world.spawn_batch(3, Transform()))

    def push(world, dt):
        for batch in world.query(Transform):
            batch[Transform].position[:, 0] += 1.0

    def swap(world, dt):
        if world.resources[Time].steps == 5:

            def push(world, dt):  # the "edited" system: the same name, the other way
                for batch in world.query(Transform):
                    batch[Transform].position[:, 0] -= 10.0

            app.replace_system("push", push)

    app.add_systems("update", push, swap)
    ids_before = []
    app.add_startup_systems(lambda world, dt: ids_before.extend(world.entities().tolist()))
    app.run(frames=8)
    x = app.world.query(Transform).column(Transform.position)[:, 0]
    assert np.allclose(x, 5.0 - 30.0)  # 5 frames of +1, then 3 of -10
    assert sorted(app.world.entities().tolist()) == sorted(ids_before)
    assert app.systems()["push"] == "update" and app.systems()["<lambda>#2"] == "startup"


def test_ctrl_c_in_a_run_is_one_line_and_exit_130(capsys):
    app = App(title="Stopped").add_plugins(MinimalPlugins)

    def stop(world, dt):
        if world.resources[Time].steps == 3:
            raise KeyboardInterrupt

    app.add_systems("update", stop)
    with pytest.raises(SystemExit) as exit_:
        app.run(frames=10)
    assert exit_.value.code == 130
    assert capsys.readouterr().err.strip() == "stopped: interrupted"


# -------------------------------------------------------------------------------- rendered
def test_a_headless_run_draws_the_startup_world_and_prints_the_demo_lines(tmp_path, capsys):
    app = cube_app()
    seen = {}

    def look(world, dt):
        seen.update(meshes=len(world.resources[Meshes]), window=world.resources[Window].shown)

    app.add_systems("update", look)
    app.set_summary(lambda world: f"cube test: {len(world)} entities")
    shot = tmp_path / "cube.png"
    result = app.run(frames=3, headless=True, screenshot=str(shot), threads=2)
    out = capsys.readouterr().out.splitlines()
    assert result.frames == 3 and result.validation_messages == [] and shot.is_file()
    assert drawn(result.pixels) > 0.05
    assert seen == {"meshes": 1, "window": False}
    assert out[0].startswith("cube-test: headless 64x48, 3 frames, mode instanced")
    assert out[-3].startswith("frame 3:") and out[-2] == "cube test: 3 entities" and out[-1] == f"wrote {shot}"


def test_without_the_perf_plugin_a_run_prints_no_perf_lines(capsys):
    app = cube_app(plugins=DefaultPlugins.without(PerfPlugin))
    app.run(frames=2, headless=True, threads=1)
    out = capsys.readouterr().out.splitlines()
    assert len(out) == 1 and out[0].startswith("cube-test: headless")


def test_no_display_falls_back_to_headless_with_a_png(tmp_path, monkeypatch, capsys):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.chdir(tmp_path)
    app = cube_app(title="Fallback", size=(48, 32))
    result = app.run(frames=4, threads=1)
    out = capsys.readouterr().out
    assert "no display found: running fallback headless for 4 frames instead (last frame: fallback.png)" in out
    assert result.frames == 4 and (tmp_path / "fallback.png").is_file()


@pytest.mark.skipif(not os.environ.get("DISPLAY"), reason="needs a display (make test runs under Xvfb)")
def test_a_windowed_run_and_the_window_resource(tmp_path):
    """In a window under Xvfb: the title is the App's, a game's changes to the Window resource
    reach GLFW at once, and Esc (from an input script) ends the run early."""
    app = cube_app(title="Windowed", size=(160, 120))
    held = {}
    app.on_open(lambda world, session: held.update(source=session.source))
    seen = []

    def change(world, dt):
        window, source = world.resources[Window], held["source"]
        glfw, handle = source.glfw, source.window
        if world.resources[Time].steps > 0 and not seen:
            window.title = "Windowed: score 3"
            window.cursor_captured = True
            window.size = (200, 150)
            glfw.poll_events()
            seen.append(
                (
                    glfw.get_window_title(handle),
                    glfw.get_input_mode(handle, glfw.CURSOR) == glfw.CURSOR_DISABLED,
                    window.shown,
                )
            )

    app.add_systems("update", change)
    script = tmp_path / "esc.txt"
    script.write_text("6 down escape\n")
    result = app.run(frames=200, input_script=str(script), validate=True, threads=1)
    assert seen == [("Windowed: score 3", True, True)]
    assert result.frames == 7 and result.validation_messages == []  # Esc at frame 6 ends the run
    assert not app.window.shown and app.window.title == "Windowed: score 3"


def test_the_world_outlives_the_run_and_saves(tmp_path):
    """After the run the meshes are still there for World.save (by reference: the cube's recipe)."""
    from ecs_engine.ecs.scene_file import SceneFileError

    app = cube_app()
    app.run(frames=1, headless=True, threads=1)
    app.world.save(tmp_path / "after.scene")
    from ecs_engine import World

    with pytest.raises(SceneFileError, match="has no Meshes resource"):
        World.load(tmp_path / "after.scene")
    again = World()
    again.resources[Meshes] = Meshes()
    World.load(tmp_path / "after.scene", into=again)
    assert len(again.resources[Meshes]) == 1 and again.resources[Meshes][0].source == {"primitive": "cube", "args": {}}


def test_velocity_moves_entities_in_a_rendered_app_too():
    app = cube_app()
    app.add_startup_systems(lambda world, dt: world.spawn(Transform(), Velocity(linear=(0.0, 6.0, 0.0))))
    app.run(frames=10, headless=True, threads=1)
    ys = app.world.query(Transform, with_=[Velocity]).column(Transform.position)[:, 1]
    assert np.allclose(ys, 1.0)  # 10 steps of 1/60 s at 6 units a second


@pytest.mark.parametrize("plugins", ["minimal", "default"])
def test_the_action_map_of_add_actions_reads_the_run_s_input(tmp_path, plugins, config_home):
    """`world.resources[ActionMap]` as add_actions made it hears the keys of the run (a script's
    here, a window's in a game), not a still input of its own."""
    from ecs_engine.systems import ActionMap

    app = cube_app() if plugins == "default" else App(title="Keys").add_plugins(MinimalPlugins)
    app.add_actions({"steer": ["a/d"], "jump": ["space"]})
    seen = []
    app.add_systems(
        "update",
        lambda world, dt: seen.append(
            (world.resources[ActionMap].axis("steer"), world.resources[ActionMap].action_down("jump"))
        ),
    )
    script = tmp_path / "keys.txt"
    script.write_text("1 down d\n2 down space\n3 up d\n")
    app.run(frames=5, headless=True, input_script=str(script))
    assert seen == [(0.0, False), (1.0, False), (1.0, True), (0.0, True), (0.0, True)]


def test_a_game_s_hud_is_drawn_in_the_editor_too(capsys):
    """`add_ui` windows float over the editor as over the game: the HUD's draw runs each UI build."""
    from ecs_engine.app.plugins import EditorPlugin

    app = cube_app(size=(480, 320))
    app.add_plugins(EditorPlugin)
    seen = []

    def hud(imgui, world):
        imgui.begin("HUD")
        imgui.text(f"{len(world)} entities")
        imgui.end()
        seen.append(len(world))

    app.add_ui(hud)
    app.run(frames=3, headless=True)
    assert seen and seen[-1] == 3  # the cube, the light, the camera
