# `make demo` and `make test` install everything (scripts/bootstrap.sh) and then run.
# Variables: PYTEST_ARGS="-k world", DEMO_ARGS="...", BENCH="...", PYTHON=python3.12 (new .venv only).
PY      := .venv/bin/python
SHADERS := $(wildcard shaders/*.vert shaders/*.frag shaders/*.comp)
PYTEST_ARGS ?=
DEMO_ARGS   ?=
BENCH       ?=
# Without a display (CI, ssh) run under xvfb-run -a; decided when the recipe runs, i.e. after setup.
HEADLESS = $$([ -z "$$DISPLAY" ] && command -v xvfb-run >/dev/null && echo xvfb-run -a)

.PHONY: setup test demo shaders bench clean

setup:
	@bash scripts/bootstrap.sh

test: setup
	$(HEADLESS) $(PY) -m pytest $(PYTEST_ARGS)

demo: setup
	.venv/bin/ecs-engine demo $(DEMO_ARGS)

# The compiled .spv files are committed (a test fails when one is stale); this rebuilds them.
shaders: $(SHADERS:=.spv)

shaders/%.spv: shaders/% | setup
	glslc $< -o $@

bench:
	@bash scripts/bootstrap.sh --extras dev,bench
	$(PY) -m bench $(BENCH)

clean:
	rm -rf .venv *.egg-info

$(SHADERS:=.spv): shaders/common.glsl
