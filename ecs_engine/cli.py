"""`ecs-engine` / `python -m ecs_engine`: run demos. Errors a user can cause print one line and
exit 2; other failures exit 1; `--debug` shows the traceback instead."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from .errors import EcsError, UsageError

def positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value <= 0:
        raise argparse.ArgumentTypeError(f"expected a number above 0, got {value}")
    return value


SCENES = ("motion",)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="ecs-engine", description=__doc__)
    parser.add_argument("--debug", action="store_true", help="show tracebacks")
    sub = parser.add_subparsers(dest="command", required=True)
    demo = sub.add_parser("demo", help="run a demo scene")
    demo.add_argument("scene", nargs="?", default="motion", choices=SCENES,
                      help="motion: text-mode ECS scene, N moving entities, no rendering")
    demo.add_argument("--entities", type=positive_int, default=100_000)
    demo.add_argument("--frames", type=positive_int, default=300)
    demo.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help="show tracebacks")
    return parser


def run(args: argparse.Namespace) -> int:
    if args.command == "demo":
        from ecs_engine.demos import motion

        if args.scene == "motion":
            return motion.main(args.entities, args.frames)
    raise UsageError(f"unknown command {args.command!r}")


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return run(args)
    except (UsageError, EcsError, ValueError, OSError) as exc:
        if args.debug:
            raise
        print(f"ecs-engine: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130
    except Exception as exc:  # noqa: BLE001 - last resort: one line unless --debug
        if args.debug:
            raise
        print(f"ecs-engine: internal error: {type(exc).__name__}: {exc} (run with --debug for the traceback)",
              file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
