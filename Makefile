# `make demo` and `make test` install everything (scripts/bootstrap.sh) and then run.
# Variables: PYTEST_ARGS="-k world", DEMO_ARGS="...", BENCH="ecs --quick", PYTHON=python3.12 (new .venv only).
PY      := .venv/bin/python
PYTEST_ARGS ?=
DEMO_ARGS   ?=
BENCH       ?=
# Without a display (CI, ssh) the tests run under xvfb-run -a; decided when the recipe runs, after
# setup installed it. The recipe prints the command it runs, not this shell test.
HEADLESS = $$([ -z "$$DISPLAY" ] && command -v xvfb-run >/dev/null && echo "xvfb-run -a ")

.PHONY: setup test test-slow test-physics demo shaders bench clean

setup:
	@bash scripts/bootstrap.sh

# lint, format and type checks first (seconds), then the suite
test: setup
	$(PY) -m ruff check .
	$(PY) -m ruff format --check .
	$(PY) -m mypy
	@run="$(HEADLESS)$(PY) -m pytest $(PYTEST_ARGS)"; echo "$$run"; $$run

# the long cases (marked slow: the 20,000-frame soak, 300 random parallel schedules), a CI step of
# their own after `make test`, so the main suite stays under CI's 15 minutes
test-slow: setup
	@run="$(HEADLESS)$(PY) -m pytest -m slow $(PYTEST_ARGS)"; echo "$$run"; $$run

# physics (ecs_engine.physics) binds culverin, which has wheels for CPython 3.12+ only: its tests
# run in a venv of their own, .venv-physics, made with the newest Python 3.12+ found (on the PATH
# or installed by pyenv; PYTHON=... to choose); in `make test` they are skipped on 3.11
test-physics:
	@bash scripts/bootstrap.sh --venv .venv-physics --min-python 3.12 --extras dev,physics
	@run="$(HEADLESS).venv-physics/bin/python -m pytest tests/test_physics*.py tests/test_bench_physics.py tests/test_editor_physics.py $(PYTEST_ARGS)"; echo "$$run"; $$run

demo: setup
	.venv/bin/ecs-engine editor $(DEMO_ARGS)

# The compiled .spv files and shaders/manifest.json are committed; tests/test_shaders.py fails
# when a source changed without them. This rebuilds them all.
shaders: setup
	$(PY) scripts/compile_shaders.py

# `make bench` lists the benchmarks (installs nothing; any python3 can print the list);
# `make bench BENCH="ecs --quick"` installs the bench extras, then runs one. Results go to
# ~/.cache/ecs_engine/bench-results (printed) unless BENCH has --out, e.g. --out bench/results.
ifeq ($(strip $(BENCH)),)
bench:
	@$(if $(wildcard $(PY)),$(PY),python3) -m bench --help
else
bench:
	@bash scripts/bootstrap.sh --extras dev,bench
	$(PY) -m bench $(BENCH)
endif

clean:
	rm -rf .venv .venv-physics *.egg-info

