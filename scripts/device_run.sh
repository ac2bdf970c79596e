#!/bin/bash
# A run on the GPU host (the device tool: no network, Python 3.12 with NumPy, numba and psutil).
# Prepare here, once (both folders are in .git/info/exclude):
#   .gl/   the Vulkan loader and validation layers as .deb files (apt-get download libvulkan1
#          vulkan-validationlayers, per the device README)
#   .whl/  wheels for Python 3.12 of what the host lacks: vulkan cffi pycparser glfw trimesh
#          imgui-bundle esper fast-simplification pillow pytest hypothesis (and their pure deps),
#          never numpy (the host's numba is built against its own)
# then `bash scripts/device_run.sh MODE...` with carry [".gl", ".whl"]; results land in $OUT.
# Modes: tests (the whole suite with validation, from a copy of tests/ outside the checkout),
# demos (every demo scene with --validate), aniso (tests/texture_reference.py: what the driver's
# anisotropic filter does to a magnified texture), bench:NAME:ARGS (a benchmark, e.g.
# bench:schedule:--quick).
set -u
export PYTHONUNBUFFERED=1
for f in .gl/*.deb; do dpkg -x "$f" /; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
export VK_LAYER_PATH=/usr/share/vulkan/explicit_layer.d
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --target /tmp/site .whl/*.whl || exit 1
python3 -m pip install -q --no-deps --no-build-isolation --no-index --target /tmp/new . >/dev/null 2>&1 || {
  echo "install failed"; exit 1; }
export PYTHONPATH=/tmp/new:/tmp/site
{ nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; nproc; date -u +%FT%TZ; python3 --version;
  git log -1 --format=%h 2>/dev/null; } > "$OUT/machine.txt"
cat "$OUT/machine.txt"
REPO=$PWD
# tests and demos run from a copy outside the checkout: in its root, `ecs_engine` would be the
# source folder, not the installed package (whose components/ and systems/ live inside it)
# (the tests read README.md, docs/, demos/, bench/, scripts/ and shaders/ beside tests/)
rm -rf /tmp/t && cp -r tests /tmp/t && cp -r README.md pyproject.toml docs demos bench scripts shaders /tmp/
for mode in "$@"; do
  case $mode in
    tests)
      (cd /tmp && timeout 560 python3 -m pytest -q -p no:cacheprovider -x --durations=15 /tmp/t \
        > "$OUT/gpu_tests.txt" 2>&1; echo "pytest rc=$?" >> "$OUT/gpu_tests.txt")
      tail -25 "$OUT/gpu_tests.txt" ;;
    tests:*)
      files=${mode#tests:}
      (cd /tmp && timeout 560 python3 -m pytest -q -p no:cacheprovider ${files//,/ } \
        > "$OUT/gpu_tests_subset.txt" 2>&1; echo "pytest rc=$?" >> "$OUT/gpu_tests_subset.txt")
      tail -15 "$OUT/gpu_tests_subset.txt" ;;
    demos)
      for scene in cube grid100 model materials lights shadows environment; do
        (cd /tmp && timeout 120 python3 -m ecs_engine demo $scene --headless --frames 40 --validate \
          --screenshot "$OUT/demo-$scene.png" 2>&1 | tail -1 | sed "s/^/$scene: /")
        echo "$scene rc=${PIPESTATUS[0]}"
      done 2>&1 | tee "$OUT/demos.txt" ;;
    aniso)
      (cd /tmp && timeout 200 python3 /tmp/t/texture_reference.py "$OUT" --validate 2>&1 | tee "$OUT/aniso.txt") ;;
    bench:*)
      spec=${mode#bench:}; name=${spec%%:*}; args=${spec#*:}; [ "$args" = "$spec" ] && args=
      (cd /tmp && timeout 560 python3 -m ecs_engine.bench $name $args --out "$OUT" 2>&1 | tail -20) ;;
    *) echo "unknown mode $mode" ;;
  esac
done
cd "$REPO"
