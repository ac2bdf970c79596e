#!/bin/bash
# A run on the GPU host (the device tool: no network, Python 3.12 with NumPy, numba and psutil).
# Prepare here, once (both folders are in .git/info/exclude):
#   .gl/   the Vulkan loader, its GL dispatch libraries and the validation layers as .deb files:
#          apt-get download libvulkan1 vulkan-validationlayers libglvnd0 libegl1 libgl1 libglx0
#          libgles2 libopengl0 (per the device README; without the libglvnd ones the NVIDIA
#          driver is refused: VkErrorIncompatibleDriver)
#   .whl/  wheels for Python 3.12 of what the host lacks: vulkan cffi pycparser glfw trimesh
#          imgui-bundle esper fast-simplification miniaudio culverin (and their pure deps;
#          pillow, pytest and hypothesis are there), never numpy (the host's numba is built
#          against its own)
# then `bash scripts/device_run.sh MODE...` with carry [".gl", ".whl"]; results land in $OUT.
# At most 8 files come back: each mode writes one text file and at most one tar of images.
# Modes: tests or tests/K/N (the whole suite, or its K-th shard of N, with validation, from a copy of tests/ outside the checkout),
# parallel/N (all N shards at once),
# demos (every demo scene with --validate), aniso (tests/texture_reference.py: what the driver's
# anisotropic filter does to a magnified texture), bench:NAME:ARGS (a benchmark, e.g.
# bench:schedule:--quick), ab:NAME:ARGS:REPS (old against new, alternated; see below),
# abcli:LABEL:ARGS:REPS (the CLI's perf JSON, old against new), abpar:NAME:ARGS:REPS[:LABEL] (old and new at once),
# same:LABEL:ARGS (old and new in one process, frame blocks alternated: scripts/ab_same_process.py).
set -u
export PYTHONUNBUFFERED=1
for f in .gl/*.deb; do dpkg -x "$f" /; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
export VK_LAYER_PATH=/usr/share/vulkan/explicit_layer.d
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl || exit 1
# (a warm host keeps /tmp/new from the last call: pip --target would keep that one's files)
rm -rf /tmp/new
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
rm -rf /tmp/t && cp -r tests /tmp/t && cp -r README.md Makefile pyproject.toml docs demos bench scripts shaders /tmp/
for mode in "$@"; do
  case $mode in
    tests|tests/*)
      # tests/K/N: the K-th of N shards of the test files (the whole suite passes 10 minutes there)
      shard=${mode#tests}; shard=${shard#/}; k=${shard%/*}; n=${shard#*/}; [ -z "$shard" ] && k=1 n=1
      files=$(ls /tmp/t/test_*.py | awk -v k="$k" -v n="$n" '(NR - 1) % n == k - 1')
      (cd /tmp && timeout 560 python3 -m pytest -q -rfE -p no:cacheprovider --durations=10 $files \
        > "$OUT/gpu_tests.txt" 2>&1; echo "pytest rc=$?" >> "$OUT/gpu_tests.txt")
      grep -v "^\.*s*\.* *\[" "$OUT/gpu_tests.txt" | tail -40 ;;
    parallel/*)
      # parallel/N: the suite's N shards at once (the host has 16 cores; one GPU serves them all),
      # each into gpu_tests_K.txt, 500 s at most
      n=${mode#parallel/}
      for k in $(seq "$n"); do
        files=$(ls /tmp/t/test_*.py | awk -v k="$k" -v n="$n" '(NR - 1) % n == k - 1')
        (cd /tmp && timeout 500 python3 -m pytest -q -rfE -p no:cacheprovider $files \
          > "$OUT/gpu_tests_$k.txt" 2>&1; echo "pytest rc=$?" >> "$OUT/gpu_tests_$k.txt") &
      done
      wait
      for k in $(seq "$n"); do tail -3 "$OUT/gpu_tests_$k.txt"; done ;;
    tests:*)
      files=${mode#tests:}
      (cd /tmp && timeout 560 python3 -m pytest -q -p no:cacheprovider ${files//,/ } \
        > "$OUT/gpu_tests_subset.txt" 2>&1; echo "pytest rc=$?" >> "$OUT/gpu_tests_subset.txt")
      tail -15 "$OUT/gpu_tests_subset.txt" ;;
    demos)
      for scene in cube grid100 model materials lights shadows environment split_screen monitor; do
        mkdir -p /tmp/demos
        (cd /tmp && timeout 120 python3 -m ecs_engine demo $scene --headless --frames 40 --validate \
          --screenshot "/tmp/demos/$scene.png" > /tmp/demos/$scene.txt 2>&1; echo "$scene rc=$?";
          tail -2 /tmp/demos/$scene.txt)
      done 2>&1 | tee "$OUT/demos.txt"
      tar -C /tmp -cf "$OUT/demos.tar" demos ;;
    aniso)
      mkdir -p /tmp/aniso
      (cd /tmp && timeout 200 python3 /tmp/t/texture_reference.py /tmp/aniso --validate 2>&1 | tee "$OUT/aniso.txt")
      tar -C /tmp -cf "$OUT/aniso.tar" aniso ;;
    bench:*)
      spec=${mode#bench:}; name=${spec%%:*}; args=${spec#*:}; [ "$args" = "$spec" ] && args=
      (cd /tmp && timeout 560 python3 -m ecs_engine.bench $name $args --out "$OUT" 2>&1 | tail -20) ;;
    ab:*)
      # ab:NAME:ARGS:REPS[:OLDARGS[:LABEL]]: benchmark NAME with ARGS, this tree ("new") and .ab/base
      # ("old", carried: `git archive REV | tar -x -C .ab/base`; with OLDARGS when its options differ),
      # alternated REPS times in separate processes with the host's core speed (python_loop_ns)
      # beside each; the JSONs in ab-LABEL.tar (LABEL: NAME by default)
      # (a ":" inside ARGS is written "@": culling-methods' --methods indirect@occlusion)
      # (NAME written +NAME: this tree's bench/NAME.py measures the old package too, for options
      # the old benchmark lacks, e.g. +lights with --counts 6,4096)
      IFS=: read -r _ name args reps oldargs label <<< "$mode"; args=${args//@/:}; oldargs=${oldargs//@/:}
      overlay=; [ "${name#+}" != "$name" ] && { overlay=1; name=${name#+}; }
      oldargs=${oldargs:-$args}; label=${label:-$name}
      [ -d /tmp/old ] || python3 -m pip install -q --no-deps --no-build-isolation --no-index --target /tmp/old \
        .ab/base >/dev/null 2>&1 || { echo "install old failed"; continue; }
      [ -n "$overlay" ] && cp "bench/$name.py" /tmp/old/ecs_engine/bench/
      mkdir -p "/tmp/ab-$label"
      for rep in $(seq "${reps:-2}"); do
        if [ $((rep % 2)) = 1 ]; then order="new old"; else order="old new"; fi
        for v in $order; do
          mkdir -p "/tmp/ab-$label/$v$rep"
          if [ $v = old ]; then a=$oldargs; else a=$args; fi
          (cd /tmp && PYTHONPATH=/tmp/$v:/tmp/site timeout 300 python3 -m ecs_engine.bench $name $a \
            --out "/tmp/ab-$label/$v$rep" 2>&1 | tail -3 | sed "s/^/$v$rep: /")
        done
      done 2>&1 | tee "$OUT/ab-$label.txt"
      tar -C /tmp -cf "$OUT/ab-$label.tar" "ab-$label" ;;
    abpar:*)
      # abpar:NAME:ARGS:REPS[:LABEL]: as ab, but each rep runs new and old at the same time (two
      # processes on two of the host's cores), so that both see the host's speed of that moment
      # (it drifts up to 2x between runs; a pair's ratio is then the comparison)
      IFS=: read -r _ name args reps label <<< "$mode"; args=${args//@/:}; label=${label:-$name}
      [ -d /tmp/old ] || python3 -m pip install -q --no-deps --no-build-isolation --no-index --target /tmp/old \
        .ab/base >/dev/null 2>&1 || { echo "install old failed"; continue; }
      mkdir -p "/tmp/abpar-$label"
      for rep in $(seq "${reps:-2}"); do
        for v in new old; do
          mkdir -p "/tmp/abpar-$label/$v$rep"
          (cd /tmp && PYTHONPATH=/tmp/$v:/tmp/site timeout 300 python3 -m ecs_engine.bench $name $args \
            --out "/tmp/abpar-$label/$v$rep" 2>&1 | tail -2 | sed "s/^/$v$rep: /") &
        done
        wait
      done 2>&1 | tee "$OUT/abpar-$label.txt"
      tar -C /tmp -cf "$OUT/abpar-$label.tar" "abpar-$label" ;;
    same:*)
      # same:LABEL:ARGS: scripts/ab_same_process.py ARGS (e.g. "--scene cube"), .ab/base renamed
      # ecs_old beside this tree in one process (a ":" inside ARGS is written "@"); its JSON lines
      # in same-LABEL.jsonl
      IFS=: read -r _ label args <<< "$mode"; args=${args//@/:}
      [ -d /tmp/old ] || python3 -m pip install -q --no-deps --no-build-isolation --no-index --target /tmp/old \
        .ab/base >/dev/null 2>&1 || { echo "install old failed"; continue; }
      if [ ! -d /tmp/renamed/ecs_old ]; then  # (without the old runs' numba caches, which name ecs_engine)
        mkdir -p /tmp/renamed && cp -r /tmp/old/ecs_engine /tmp/renamed/ecs_old
        find /tmp/renamed/ecs_old -name __pycache__ -type d -prune -exec rm -rf {} +
        find /tmp/renamed/ecs_old -name '*.py' -exec sed -i 's/\becs_engine\b/ecs_old/g' {} +
      fi
      (cd /tmp && PYTHONPATH=/tmp/new:/tmp/renamed:/tmp/site timeout 300 python3 "$REPO/scripts/ab_same_process.py" \
        --old ecs_old $args >> "$OUT/same-$label.jsonl" 2> "/tmp/same-$label.err" || tail -3 "/tmp/same-$label.err")
      tail -1 "$OUT/same-$label.jsonl" | cut -c1-400 ;;
    abcli:*)
      # abcli:LABEL:ARGS:REPS: the CLI (`python3 -m ecs_engine ARGS --perf-json`), this tree and
      # .ab/base alternated REPS times (e.g. the editor: abcli:editor:editor grid100 --headless
      # --frames 600:4); every frame's samples in abcli-LABEL.tar
      IFS=: read -r _ label args reps <<< "$mode"
      [ -d /tmp/old ] || python3 -m pip install -q --no-deps --no-build-isolation --no-index --target /tmp/old \
        .ab/base >/dev/null 2>&1 || { echo "install old failed"; continue; }
      mkdir -p "/tmp/abcli-$label"
      for rep in $(seq "${reps:-2}"); do
        if [ $((rep % 2)) = 1 ]; then order="new old"; else order="old new"; fi
        for v in $order; do
          (cd /tmp && PYTHONPATH=/tmp/$v:/tmp/site timeout 300 python3 -m ecs_engine $args \
            --perf-json "/tmp/abcli-$label/$v$rep.json" 2>&1 | tail -1 | sed "s/^/$v$rep: /")
        done
      done 2>&1 | tee "$OUT/abcli-$label.txt"
      tar -C /tmp -cf "$OUT/abcli-$label.tar" "abcli-$label" ;;
    *) echo "unknown mode $mode" ;;
  esac
done
cd "$REPO"
