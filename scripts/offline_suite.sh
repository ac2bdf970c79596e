#!/usr/bin/env bash
# Run the benchmark suite on a GPU server without network access.
#
#   scripts/offline_suite.sh fetch DIR [PYTHON_VERSION]   on a connected Debian/Ubuntu machine:
#       wheels for this package, its dependencies and the bench extra (for PYTHON_VERSION of the
#       server, default 3.12, manylinux x86_64) into DIR/wheels, and the Vulkan loader,
#       validation layers and GL/EGL libraries as .deb files into DIR/debs. Copy DIR over.
#   scripts/offline_suite.sh run DIR [BENCH ...]          on the server, from the repository:
#       unpack the .debs (into / as root, else into DIR/root with the library and layer paths
#       set), install the wheels into DIR/site, and run the benchmarks (default: seed-tables
#       scaling numerics ecs), writing bench/results/<name>-<slug>.json and .png.
#
# DRY_RUN=1 prints the commands instead of running them. Safe to run twice.
set -euo pipefail

DEBS=(libvulkan1 vulkan-validationlayers libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2)
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

usage() {
    sed -n '2,14p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'
    exit "${1:-2}"
}

say() { echo "offline_suite: $*" >&2; }

do_run() {
    if [[ "${DRY_RUN:-0}" == 1 ]]; then
        printf '%q ' "$@"
        echo
    else
        "$@"
    fi
}

fetch() {
    local dir="$1" py="${2:-3.12}"
    mkdir -p "$dir/wheels" "$dir/debs"
    command -v apt-get >/dev/null || { say "apt-get not found: fetch runs on Debian or Ubuntu"; exit 2; }
    say "wheels for Python $py into $dir/wheels"
    do_run python3 -m pip wheel --no-deps --wheel-dir "$dir/wheels" "$ROOT"
    # the dependencies as pyproject.toml lists them, resolved as wheels for the server's Python
    local deps
    mapfile -t deps < <(python3 - "$ROOT/pyproject.toml" <<'PY'
import sys, tomllib
project = tomllib.load(open(sys.argv[1], "rb"))["project"]
print("\n".join(project["dependencies"] + project["optional-dependencies"]["bench"]))
PY
)
    do_run python3 -m pip download --dest "$dir/wheels" --only-binary=:all: --python-version "$py" \
        --implementation cp --platform manylinux2014_x86_64 --platform manylinux_2_17_x86_64 \
        --platform manylinux_2_28_x86_64 --platform any \
        "${deps[@]}"
    say ".debs into $dir/debs"
    (cd "$dir/debs" && do_run apt-get download "${DEBS[@]}")
    say "done: copy $dir to the server and run: scripts/offline_suite.sh run $dir"
}

run() {
    local dir="$1"
    shift
    local benches=("$@")
    [[ ${#benches[@]} -gt 0 ]] || benches=(seed-tables scaling numerics ecs)
    [[ -d "$dir/wheels" && -d "$dir/debs" ]] || { say "$dir has no wheels/ and debs/: run fetch first"; exit 2; }
    local prefix=/
    if [[ $(id -u) -ne 0 ]]; then
        prefix="$dir/root"
        mkdir -p "$prefix"
    fi
    say "unpacking $(ls "$dir"/debs/*.deb | wc -l) .debs into $prefix"
    for deb in "$dir"/debs/*.deb; do
        do_run dpkg -x "$deb" "$prefix"
    done
    if [[ "$prefix" == / ]]; then
        do_run ldconfig
    else
        export LD_LIBRARY_PATH="$prefix/usr/lib/x86_64-linux-gnu${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
        export VK_ADD_LAYER_PATH="$prefix/usr/share/vulkan/explicit_layer.d"
    fi
    say "installing into $dir/site"
    do_run python3 -m pip install --quiet --no-index --find-links "$dir/wheels" --target "$dir/site" --upgrade \
        "ecs_engine[bench]"
    export PYTHONPATH="$dir/site${PYTHONPATH:+:$PYTHONPATH}"
    if [[ -z "${VK_DRIVER_FILES:-}" && -f /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json ]]; then
        export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
    fi
    for bench in "${benches[@]}"; do
        say "benchmark $bench"
        # from outside the checkout, so the installed package is the one imported
        (cd "$dir" && do_run python3 -m ecs_engine.bench "$bench" --out "$ROOT/bench/results")
    done
}

case "${1:-}" in
    -h|--help) usage 0 ;;
esac
[[ $# -ge 2 ]] || usage
case "$1" in
    fetch) shift; fetch "$@" ;;
    run) shift; run "$@" ;;
    *) say "unknown command $1"; usage ;;
esac
