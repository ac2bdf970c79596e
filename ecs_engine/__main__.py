import sys

try:
    from .app.cli import main
except KeyboardInterrupt:  # Ctrl-C while Python imports the CLI: one line, as later (app/entry_point.py)
    print("ecs-engine: interrupted", file=sys.stderr)
    sys.exit(130)

sys.exit(main())
