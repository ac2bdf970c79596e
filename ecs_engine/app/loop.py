"""The one run loop, for every frame source: headless (offscreen image, fixed dt) and windowed
(swapchain, wall-clock dt) differ only in the source's open, begin, end and close. A run driven
by an input script steps as the script says, whatever the source (app/input_script.py).

One turn: the source gives a frame target (or None: minimised, nothing to draw), the schedule
runs (fixed steps, then the per-frame stages), the editor builds its UI, the renderer records
and submits, the source presents, and the editor's requests are applied between frames. A scene
the editor opened that fails in its first frames is rolled back (Session.roll_back), not fatal.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from ..ecs.errors import EcsError
from ..errors import UsageError
from ..jobs import default_threads
from ..systems import ActionMap, InputState
from .editor_session import EditorSession
from .imgui_session import ImGuiSession
from .input_script import InputRecorder, read_script
from .offscreen import OffscreenSource
from .output_files import check_run_files
from .perf import PerfMonitor
from .profiling import Profiler
from .report import RunResult, describe_device, save_png, summary_line
from .session import FrameSource, Session, one_line
from .settings import RunOptions
from .trace import TraceRecorder


def run(
    options: RunOptions,
    source: FrameSource | None = None,
    log: Callable[[str], None] | None = None,
    max_ui_hz: float | None = 120.0,
    make_session: Callable[[RunOptions, FrameSource], Session] = Session,
    ui: Callable[[Session, Any], ImGuiSession] | None = None,
    summary: Callable[[Session], str] | None = None,
    between: Callable[[Session, ImGuiSession | None], None] | None = None,
) -> RunResult:
    """Open the source, run `options.frames` frames (a window: until it closes), close it.
    Headless by default; pass a window.WindowSource to draw in a window. `make_session` makes
    the session (a game's, play.py); `ui(session, window)` its ImGui (the editor's by default
    when options.editor is set); `summary(session)` the line said when the frames are done (a
    game's score), before the files are written, so a failed write or Ctrl-C does not lose it.
    `between(session, editor)` runs between two frames (an App's on_frame_end: hot reload).

    Stopped from outside (Ctrl-C, stdout's reader gone), the run writes the perf log and the
    input recording of the frames it ran (no screenshot: the last frame was not read back),
    then the KeyboardInterrupt or BrokenPipeError goes on to the caller."""
    say = log or (lambda text: None if options.quiet else print(text))
    source = source or OffscreenSource()
    check_run_files(options)  # now, not after the whole run
    script = read_script(options.input_script) if options.input_script else None  # before a window opens
    if script is not None:
        source.clock = script.clock()  # a script steps the same in a window and headless (input_script.py)
    recorder = InputRecorder(options.record_input) if options.record_input else None
    result = RunResult()
    result.perf = PerfMonitor(log=options.perf_json or False)  # checks its path too
    if options.trace or options.perf_json or options.editor or ui is not None:  # else nothing shows timings
        result.profiler = Profiler(TraceRecorder(options.trace) if options.trace else None, bool(options.perf_json))
    session: Session | None = None
    editor: ImGuiSession | None = None
    try:
        session = make_session(options, source)
        check_sound_capture(options, session)
        result.device = describe_device(session.device)
        if ui is not None:  # after the source's key callbacks: ImGui's GLFW backend chains to them
            editor = result.editor = ui(session, source.window)
        elif options.editor:
            if script is not None and source.window is None:
                max_ui_hz = None  # a UI built every frame: a script's frames are the UI's, whatever the speed
            editor = result.editor = EditorSession(session, options.scenes, default_threads(), source.window, max_ui_hz)
        say(f"{source.describe(session)} on {result.device}")
        start = time.perf_counter()
        frames = 0
        stopped: BaseException | None = None
        try:
            frames = run_frames(options, source, session, editor, script, recorder, result, say, between)
        except (KeyboardInterrupt, BrokenPipeError) as exc:
            stopped, frames = exc, len(result.cpu_ms)
        session.device.wait_idle()
        result.frames = frames
        result.wall_s = time.perf_counter() - start
        result.settings = session.settings
        result.recreations = source.recreations
        result.minimised_waits = source.minimised_waits
        if stopped is not None:
            keep_what_ran(options, result, recorder, summary, session, say)
            raise stopped
        if options.screenshot is not None:
            result.pixels = source.pixels()
        if frames and options.perf_lines:
            say(summary_line(result, frames, result.wall_s, final=True))
        if summary is not None:
            say(summary(session))
        write_outputs(options, result, say)
        if recorder is not None:
            recorder.write()
    finally:
        if editor is not None:
            editor.destroy()
        if session is not None:
            session.close()  # a Session that failed half-built has closed its source already
        result.validation_messages = source.validation_messages()
    return result


def check_sound_capture(options: RunOptions, session: Session) -> None:
    """`--audio-out` for a run that makes no sound (no AudioPlugin: a demo scene, a game without
    it) would write nothing: one line, before the first frame."""
    from ..audio import Audio

    if options.audio_out is not None and Audio not in session.world.resources:
        raise UsageError(
            f"--audio-out {options.audio_out}: {options.scene} makes no sound (no AudioPlugin), so there is nothing "
            "to capture"
        )


def run_frames(
    options: RunOptions,
    source: FrameSource,
    session: Session,
    editor: ImGuiSession | None,
    script: Any,
    recorder: InputRecorder | None,
    result: RunResult,
    say: Callable[[str], None],
    between: Callable[[Session, ImGuiSession | None], None] | None = None,
) -> int:
    """The frames, until the source stops; how many ran."""
    perf, profiler = result.perf, result.profiler
    perf.gauges = lambda: session.world.resources  # the world of the moment (the editor may switch it)
    frames = 0
    while source.running(frames):
        session.renderer.ensure_output()  # HDR colour or not, as settings and materials need
        target = source.begin(session, frames)  # events, resize, acquire: not the frame's CPU work
        if target is None:
            continue
        t0 = time.perf_counter()
        if profiler is not None:  # timed while the Perf window is drawn (or always: a trace, a perf log)
            profiler.begin_frame(session, getattr(getattr(editor, "overlay", None), "visible", False))
        dt, max_dt = target.dt, source.max_frame_dt
        if script is not None:  # a script's frames step as it says (input_script.py), in a window too
            dt, max_dt = script.step(frames)
        if script is not None or recorder is not None or source.input is not None:
            keys = held_keys(session)  # a window's own InputState, or the script's headless
            if editor is not None:
                keys.keyboard_captured_by_ui = editor.wants_keyboard  # keys typed into the UI
                # over a UI window, or dragging one; the Scene window's image is the game's view
                scene = getattr(editor, "scene", None)
                keys.mouse_captured_by_ui = editor.wants_mouse and not (scene is not None and scene.hovered)
                keys.view = scene.view() if scene is not None else None
            if source.window is None:  # headless: a script's mouse is in the offscreen image's pixels
                keys.viewport = (float(options.width), float(options.height))
            if script is not None:
                script.apply(frames, keys)
                if editor is not None:  # the UI gets the script's clicks, keys and text too
                    editor.feed(script.events.get(frames, ()))
            if recorder is not None:
                recorder.frame(frames, keys, dt)
        try:
            session.schedule.run_frame(session.world, dt, source.clock, max_frame_dt=max_dt)
            held = session.world.resources.get(InputState)
            if held is not None:
                if "escape" in held.just_pressed and not held.keyboard_captured_by_ui:
                    source.request_close()  # Esc quits (unless a text field or dialog has the keys)
                held.end_frame()  # the systems saw this frame's presses and releases
            if editor is not None:
                width, height = target.extent or (options.width, options.height)
                editor.build(session.world, result.last_stats, perf, dt, width, height)
            stats = session.renderer.render(
                session.world,
                readback=target.readback,
                framebuffer=target.framebuffer,
                extent=target.extent,
                wait=target.wait,
                signal=target.signal,
                dt=dt,
            )
        except Exception as exc:  # a scene opened moments ago may fail in any way: not the run's end
            failed = session.roll_back()  # the scene before it, if there is one to go back to
            if failed is None:
                raise
            source.abandon(session, target)
            if editor is not None:
                editor.in_force(session.settings)
                editor.scene_failed(failed, f"{failed} cannot run: {one_line(exc)}")
            continue
        session.frame_done()
        end = time.perf_counter()
        timings = None
        if profiler is not None:
            timings = profiler.end_frame(frames, int(t0 * 1e9), int(end * 1e9), session.renderer.frames.last_gpu)
        # CPU work: not the waits for the GPU (renderer); the wait for an image came before t0
        result.add_frame(
            stats,
            (end - t0) * 1e3 - stats.wait_ms,
            end,
            target.waited_ms,
            ui_ms=editor.cost_ms if editor is not None else None,
            timings=timings,
        )
        source.end(session, target)
        frames += 1
        if options.perf_lines and perf.summary_due():
            say(perf.summary_line())
        if editor is not None and source.running(frames):
            apply_requests(session, editor)
        if between is not None and source.running(frames):
            between(session, editor)
    return frames


def keep_what_ran(
    options: RunOptions,
    result: RunResult,
    recorder: InputRecorder | None,
    summary: Callable[[Session], str] | None,
    session: Session,
    say: Callable[[str], None],
) -> None:
    """A run stopped early: its summary, perf log and input recording as far as it got."""
    try:
        if result.frames and options.perf_lines:
            say(summary_line(result, result.frames, result.wall_s, final=True))
        if summary is not None:
            say(summary(session))
    except BrokenPipeError:  # nobody reads stdout any more: the files still matter
        say = lambda text: None
    result.write_perf_json(options, say)
    result.write_trace(options, say)
    if recorder is not None:
        recorder.write()


def held_keys(session: Session) -> Any:
    """The world's InputState resource (a headless run gets one on first use)."""
    state = session.world.resources.get(InputState)
    if state is None:
        state = session.world.resources[InputState] = InputState()
    actions = session.world.resources.get(ActionMap)
    if actions is not None:
        actions.input = state  # the game's actions hear the script's keys
    return state


def apply_requests(session: Session, editor: ImGuiSession) -> None:
    """The editor's requests, between frames. One the session refuses (a mode this device lacks,
    a scene that fails to load) changes nothing and is shown in the editor, not raised."""
    wanted = editor.take_requests()
    if wanted is None:
        return
    try:
        session.apply(wanted)
    except (UsageError, EcsError, ValueError) as exc:
        editor.refused(str(exc))
    editor.in_force(session.settings)


def write_outputs(options: RunOptions, result: RunResult, say: Callable[[str], None]) -> None:
    """The perf log, the trace, then the screenshot: each is written even when another fails,
    and the failures are reported together after all."""
    failed = []
    writes = (
        lambda: result.write_perf_json(options, say),
        lambda: result.write_trace(options, say),
        lambda: _screenshot(options, result, say),
    )
    for write in writes:
        try:
            write()
        except UsageError as exc:
            failed.append(str(exc))
    if failed:
        raise UsageError("; ".join(failed))


def _screenshot(options: RunOptions, result: RunResult, say: Callable[[str], None]) -> None:
    if options.screenshot is not None and result.pixels is not None:
        save_png(result.pixels, options.screenshot)
        say(f"wrote {options.screenshot}")
