"""`ecs-engine` / `python -m ecs_engine`: run demos. Errors a user can cause print one line and
exit 2; other failures exit 1; `--debug` shows the traceback as well (the exit status stays).
Ctrl-C is one line and exit 130; a closed stdout (`| head`) ends it quietly (entry_point.py).

The render configuration's flags (render/config/flags.py: modes, culling...) and the present
modes are imported when the parser is built, inside main's guard: they bring numba, seconds of
start-up a Ctrl-C may land in."""

from __future__ import annotations

import argparse
import sys
import traceback
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, NoReturn

from ..ecs.errors import EcsError
from ..errors import UsageError
from .cli_graph import PRINT_GRAPH_HELP, print_graph
from .cli_types import dimension, non_negative_int, positive_int  # noqa: F401 (games import them from here)
from .entry_point import run_command
from .scenes import SCENE_FILE_SUFFIX, SEED_SCENES, is_scene_file
from .scenes import SCENES as RENDERED_SCENES

if TYPE_CHECKING:
    from .game_module import Game


# the lists come from their owners: the scenes module, the render configuration's enums, the
# swapchain's present modes
SCENES = (*RENDERED_SCENES, "motion")  # motion: the text-mode ECS scene, no rendering
EDITOR_SCENES = RENDERED_SCENES
DEFAULT_SCENE = "grid100"


def editor_scene(text: str) -> str:
    """A demo scene's name, a saved scene file's path (ending in .scene), or a game (the first)."""
    from .game_module import is_game_spec

    # a type, not choices=: argparse checks an empty nargs="*" list against choices and fails
    if is_game_spec(text):
        return text
    if is_scene_file(text):
        if not Path(text).is_file():
            raise argparse.ArgumentTypeError(f"no scene file {text!r}")
        return text
    if text not in EDITOR_SCENES:
        choices = f"{', '.join(EDITOR_SCENES)}, a {SCENE_FILE_SUFFIX} file, or a game first (game.py)"
        raise argparse.ArgumentTypeError(f"invalid choice: {text!r} (choose from {choices})")
    return text


HELP = ("-h", "--help")


class OneLineParser(argparse.ArgumentParser):
    """argparse's errors as one line with a pointer to --help (not seven lines of usage)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def render_flags(headless_frames: int = 1) -> OneLineParser:
    """The flags `demo`, `editor` and `play` share (`headless_frames`: the command's --headless
    run without --frames, for the help)."""
    from ..gpu.swapchain import PRESENT_MODES
    from ..render.config.flags import add_config_flags
    from .settings import HEADLESS_FALLBACK_FRAMES

    common = OneLineParser(add_help=False)
    common.add_argument("--headless", action="store_true", help="render offscreen, no window (no display needed)")
    common.add_argument(
        "--frames",
        type=positive_int,
        help=f"frames to run (default: until the window closes; headless: {headless_frames}, "
        f"or {HEADLESS_FALLBACK_FRAMES} when falling back from a window)",
    )
    common.add_argument("--screenshot", metavar="PNG", help="write the last frame to this PNG file")
    common.add_argument("--width", type=dimension, default=1280)
    common.add_argument("--height", type=dimension, default=720)
    common.add_argument(
        "--present", choices=tuple(PRESENT_MODES), default="fifo", help="swapchain present mode (windowed)"
    )
    common.add_argument("--validate", action="store_true", help="enable the Vulkan validation layers")
    common.add_argument(
        "--threads", type=positive_int, help="worker threads, counting the main one (default: all cores)"
    )
    add_config_flags(common)  # --mode, --culling, --tone-map...: the render configuration's (render/config/__init__.py)
    common.add_argument(
        "--no-frame-reuse",
        dest="frame_reuse",
        action="store_false",
        help="record every frame, even one that would record what its frame slot recorded last time "
        "(by default that recording is submitted again: render/frame/replay.py)",
    )
    common.add_argument("--lights", type=int, help="lights scene: how many point and spot lights (default 1,024)")
    common.add_argument(
        "--no-shadows", action="store_true", help="shadows scene: no light casts a shadow (for comparison)"
    )
    common.add_argument(
        "--entities", type=positive_int, help="scaling and motion scenes: entity count (default 10,000 and 100,000)"
    )
    common.add_argument(
        "--perf-json",
        metavar="PATH",
        help="write every frame's perf samples (CPU, GPU, record ms, psutil) to this JSON file at the end",
    )
    common.add_argument(
        "--trace",
        metavar="PATH",
        help="write a Chrome/Perfetto trace (JSON) of the frames, systems, jobs and GPU passes to this file at the "
        "end (the last 3,000 frames)",
    )
    common.add_argument(
        "--input-script",
        metavar="PATH",
        help="replay input by frame (keys, buttons, pad axes, mouse, scroll) from this file (app/input_script.py)",
    )
    common.add_argument("--record-input", metavar="PATH", help="write the run's input by frame to this file")
    common.add_argument(
        "--audio-out",
        metavar="WAV",
        help="a game with sound (AudioPlugin): write what it would play to this WAV file, frame by frame, "
        "instead of the sound device",
    )
    common.add_argument(
        "--force",
        action="store_true",
        help="let --screenshot, --perf-json, --trace and --record-input replace a file of another kind (a PNG, a "
        "perf log, a trace and an input script are replaced without it)",
    )
    common.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help="show tracebacks")
    return common


def build_parser(
    game: Game | None = None, parser_class: type[OneLineParser] = OneLineParser
) -> argparse.ArgumentParser:
    """The command line; `game`: the game named on it, whose own options (add_arguments) join
    `play` and `editor`."""
    from .play import WATCH_HELP, add_game_arguments
    from .play import add_parser as add_play_parser
    from .settings import HEADLESS_FRAMES

    parser = parser_class(prog="ecs-engine", description=__doc__)
    parser.add_argument("--debug", action="store_true", help="show tracebacks")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=parser_class)
    demo = sub.add_parser("demo", help="run a demo scene", parents=[render_flags(HEADLESS_FRAMES["demo"])])
    demo.add_argument(
        "scene",
        nargs="?",
        default=DEFAULT_SCENE,
        choices=SCENES,
        help="cube, grid100, model: the seed's scenes; scaling: --entities moving entities; "
        "materials: the shading models side by side; lights: --lights small lights (default 1,024); "
        "shadows: a cube, a pillar and boxes under casting lights (--no-shadows: none cast); "
        "environment: spheres mirroring, refracting and lit by a sky (PATH: an equirectangular .hdr or image); "
        "split_screen: grid100 seen by two cameras, half the window each, and a picture-in-picture; "
        "monitor: a room with a screen showing a second camera's picture (render to texture); "
        "animation: a crowd of skinned characters strolling, idle, walk and run cross-faded by speed "
        "(--entities characters, default 200); "
        "motion: text-mode ECS scene (no rendering)",
    )
    demo.add_argument(
        "path",
        nargs="?",
        help="model file for the model scene (OBJ, glTF/GLB, PLY, STL); sky image for the environment scene",
    )
    demo.add_argument("--print-graph", action="store_true", help=PRINT_GRAPH_HELP)
    editor = sub.add_parser(
        "editor",
        help="the ImGui editor and Perf window on demo scenes",
        parents=[render_flags(HEADLESS_FRAMES["editor"])],
    )
    editor.add_argument(
        "scenes",
        nargs="*",
        type=editor_scene,
        metavar="SCENE",
        help=f"scenes to switch between, the first one opened (default {DEFAULT_SCENE}; "
        f"choices: {', '.join(EDITOR_SCENES)}, or a saved {SCENE_FILE_SUFFIX} file); or a game first "
        "(as `play` takes one: game.py, a folder, asteroids), its scenes after it",
    )
    editor.add_argument("--watch", action="store_true", help=WATCH_HELP)
    if game is not None:
        add_game_arguments(editor, game)
    add_play_parser(sub, render_flags(HEADLESS_FRAMES["play"]), game)
    new = sub.add_parser("new", help="write a starter game folder NAME/game.py (ecs-engine play NAME runs it)")
    new.add_argument("name", metavar="NAME", help="the folder to make (it must not exist)")
    new.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help="show tracebacks")
    # Every argument goes to the benchmark runner, --help first included: REMAINDER skips a leading
    # option, so this parser has a prefix no argument can start with ("\0") and sees none.
    bench = sub.add_parser(
        "bench",
        help="run a benchmark: ecs, seed-tables, scaling, numerics (ecs-engine bench --help for more)",
        add_help=False,
        prefix_chars="\0",
    )
    bench.add_argument("bench_args", nargs=argparse.REMAINDER)
    return parser


def run(args: argparse.Namespace) -> int:
    from .settings import check_entities, check_threads

    if args.command == "demo":
        if args.scene == "motion":
            from ..demos import motion

            refuse_unused(args, MOTION_FLAGS, "motion is a text-mode ECS scene (no rendering)", ("print_graph",))
            check_entities(args.entities or 100_000)
            check_threads(args.threads)
            return motion.main(args.entities or 100_000, args.frames or 300, args.threads)
        return run_scene(args)
    if args.command == "new":
        from .new_game import write_game

        return write_game(args.name)
    if args.command == "bench":
        from ..bench.__main__ import main as bench_main

        return bench_main(list(args.bench_args), prog="ecs-engine bench")
    if args.command == "editor":
        if args.watch:
            raise UsageError("--watch reloads a game's code and assets: name a game first (editor game.py --watch)")
        scenes = tuple(dict.fromkeys(args.scenes or [DEFAULT_SCENE]))
        args.scene, args.path = scenes[0], None
        switcher = tuple(dict.fromkeys(scenes + SEED_SCENES))
        return run_scene(args, editor_scenes=switcher)
    raise UsageError(f"unknown command {args.command!r}")


# the flags the text-mode motion demo uses; any other given is refused, not ignored
MOTION_FLAGS = ("entities", "frames", "threads", "debug")


def refuse_unused(args: argparse.Namespace, used: tuple[str, ...], why: str, more: tuple[str, ...] = ()) -> None:
    """UsageError naming every render flag (and switch in `more`) given that `used` does not include."""
    defaults = vars(render_flags().parse_args([])) | dict.fromkeys(more, False)
    given = [
        f"--{name.replace('_', '-')}"
        for name, default in defaults.items()
        if name not in used and getattr(args, name, default) != default
    ]
    if given:
        raise UsageError(f"{why}: {', '.join(given)} do{'es' if len(given) == 1 else ''} not apply")


def check_flags_apply(args: argparse.Namespace, scenes: tuple[str, ...], editor: bool) -> None:
    """Refuse a flag that would change nothing in this run, instead of ignoring it (the editor
    may switch to what makes --recorder and --no-shadow-denoise count later)."""
    from ..render.config import RenderConfig, inert_refusal

    if args.entities is not None and "scaling" not in scenes:
        raise UsageError(f"--entities sizes the scaling and motion scenes; {', '.join(scenes)} has fixed content")
    if args.lights is not None and "lights" not in scenes:
        raise UsageError(f"--lights sizes the lights scene; {', '.join(scenes)} has fixed content")
    if args.no_shadows and "shadows" not in scenes:
        raise UsageError(f"--no-shadows applies to the shadows scene, not {', '.join(scenes)}")
    if args.headless and args.present != "fifo":
        raise UsageError("--present chooses a window's present mode; a --headless run has no window")
    config = RenderConfig.from_strings(mode=args.mode, shadows=args.shadow_method)
    given = {"recorder": args.recorder is not None, "shadow_denoise": not args.shadow_denoise}
    for field in (f for f, on in given.items() if on and not editor):
        refusal = inert_refusal(field, config)  # config.INERT: what a flag changes nothing in
        if refusal is not None:
            raise UsageError(refusal)


def run_scene(args: argparse.Namespace, editor_scenes: tuple[str, ...] | None = None) -> int:
    from .loop import run
    from .output_files import check_run_files
    from .report import report_validation
    from .settings import HEADLESS_FALLBACK_FRAMES, RunOptions

    if args.path is not None and args.scene not in ("model", "environment"):
        raise UsageError(f"a path goes with the model scene (a model) or environment (a sky), not {args.scene!r}")
    editor = editor_scenes is not None
    check_flags_apply(args, editor_scenes or (args.scene,), editor)
    options = RunOptions.from_flags(
        args,
        scene=args.scene,
        path=args.path,
        lights=args.lights,
        shadows=not args.no_shadows,
        entities=args.entities or 10_000,
        editor=editor,
        scenes=editor_scenes or (),
    )
    if getattr(args, "print_graph", False):  # demo --print-graph: the graph of one frame, no window
        return print_graph(options)
    if not args.headless:
        from .window import WindowSource, open_glfw

        check_run_files(options)  # before a window opens
        glfw = open_glfw()
        if glfw is not None:
            return report_validation(run(options, WindowSource(glfw)))
        options = replace(
            options,
            headless=True,
            frames=args.frames or HEADLESS_FALLBACK_FRAMES,
            screenshot=options.screenshot or f"{args.scene}.png",
        )
        check_run_files(options)  # the screenshot's default too, before the message says where it goes
        shot = Path(options.screenshot or "").resolve()
        saved = f"last frame saved to {shot}" + (" (replacing the file there)" if shot.exists() else "")
        what = "the editor and its scene" if editor else "the scene"
        print(f"no display found: drawing {what} headless for {options.frames} frames instead ({saved})")
    return report_validation(run(options))


def main(argv: Sequence[str] | None = None) -> int:
    return run_command("ecs-engine", lambda: parse_and_run(argv))


def run_game(args: argparse.Namespace, game: Game) -> int:
    """`play GAME` or `editor GAME [SCENE...]`."""
    from . import play
    from .settings import HEADLESS_FRAMES

    editor = args.command == "editor"
    check_flags_apply(args, (game.name,), editor)
    extra = tuple(dict.fromkeys(args.scenes[1:])) if editor else ()
    return play.run_game(args, game, editor, HEADLESS_FRAMES[args.command], extra)


def game_of(args: argparse.Namespace) -> Game | None:
    """The game a `play` or `editor` command line names (its module imported), or None."""
    from .game_module import find_game, is_game_spec

    if args.command == "play":
        return find_game(args.game)
    if args.command == "editor" and args.scenes and is_game_spec(args.scenes[0]):
        return find_game(args.scenes[0])
    return None


class Refused(Exception):
    pass


class FirstReading(OneLineParser):
    """The first reading of a command line, which only looks for the game: what it cannot read
    the second reading reports."""

    def error(self, message: str) -> NoReturn:
        raise Refused(message)


def parse_and_run(argv: Sequence[str] | None) -> int:
    # read once to find the game (its own options are unknown then; --help waits for them), then
    # again with its options
    words = list(sys.argv[1:] if argv is None else argv)
    try:
        args, _ = build_parser(parser_class=FirstReading).parse_known_args([w for w in words if w not in HELP])
    except Refused:
        args = build_parser().parse_args(words)  # says what is wrong, exit 2
    try:
        game = game_of(args)
        args = build_parser(game).parse_args(words)
        return run(args) if game is None else run_game(args, game)
    except (KeyboardInterrupt, BrokenPipeError):
        if args.debug:
            traceback.print_exc()
        raise  # run_command: one line, or quiet
    except (UsageError, EcsError, ValueError, OSError) as exc:
        if args.debug:
            traceback.print_exc()
        print(f"ecs-engine: error: {exc}", file=sys.stderr)
        return 2
    except Exception as exc:
        if args.debug:
            traceback.print_exc()
            print(f"ecs-engine: internal error: {type(exc).__name__}: {exc}", file=sys.stderr)
            return 1
        print(
            f"ecs-engine: internal error: {type(exc).__name__}: {exc} (run with --debug for the traceback)",
            file=sys.stderr,
        )
        return 1


if __name__ == "__main__":
    sys.exit(main())
