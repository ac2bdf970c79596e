#!/usr/bin/env bash
# Installs everything ecs_engine needs on Debian/Ubuntu, then gets out of the way.
# Safe to run again: apt is skipped when every package is installed, pip when
# pyproject.toml (and the wanted extras) are unchanged since the last successful install.
#
#   scripts/bootstrap.sh [--extras dev,bench] [--venv DIR] [--min-python 3.12]
#   (defaults: --extras dev --venv .venv --min-python 3.11; the physics tests' venv is
#   .venv-physics with Python 3.12+, which its library needs)
#
# Environment: PYTHON=python3.12 picks the interpreter for a new venv (make clean to switch);
#              ECS_ENGINE_APT_EXTRA="pkg ..." adds system packages to check/install.
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")/.."

APT_PACKAGES=(libvulkan1 mesa-vulkan-drivers vulkan-validationlayers glslc xvfb xauth python3-venv)
VENV=.venv
EXTRAS=dev
MIN_PYTHON=3.11

say() { echo "bootstrap: $*"; }
die() { echo "bootstrap: error: $1" >&2; exit "${2:-1}"; }

parse_args() {
  while [ $# -gt 0 ]; do
    case $1 in
      --extras) [ $# -ge 2 ] || die "--extras needs a value, e.g. --extras dev,bench"; EXTRAS=$2; shift 2 ;;
      --extras=*) EXTRAS=${1#--extras=}; shift ;;
      --venv) [ $# -ge 2 ] || die "--venv needs a folder, e.g. --venv .venv-physics"; VENV=$2; shift 2 ;;
      --min-python) [[ ${2:-} =~ ^3\.[0-9]+$ ]] || die "--min-python needs a version such as 3.12"; MIN_PYTHON=$2; shift 2 ;;
      -h|--help) sed -n '2,9p' "$0"; exit 0 ;;
      *) die "unknown argument: $1 (usage: scripts/bootstrap.sh [--extras dev,bench])" ;;
    esac
  done
}

# Prints the first interpreter >= MIN_PYTHON (PYTHON if set), or fails; after the ones on the
# PATH, those pyenv installed (its shims answer only for the version it has selected).
find_python() {
  local cand root candidates=(python3.13 python3.12 python3.11 python3)
  root=$( (command -v pyenv >/dev/null && pyenv root) || echo "$HOME/.pyenv")
  candidates+=($(ls -d "$root"/versions/3.*/bin/python3 2>/dev/null | sort -rV))
  [ -n "${PYTHON:-}" ] && candidates=("$PYTHON")
  for cand in "${candidates[@]}"; do
    if python_ok "$cand"; then
      echo "$cand"; return 0
    fi
  done
  return 1
}

python_ok() { "$1" -c "import sys; sys.exit(sys.version_info < (${MIN_PYTHON/./, }))" >/dev/null 2>&1; }

# a venv made with an older Python than MIN_PYTHON is made again
venv_ok() { [ -x "$VENV/bin/python" ] && [ -x "$VENV/bin/pip" ] && python_ok "$VENV/bin/python"; }

missing_apt_packages() {
  local pkg
  # shellcheck disable=SC2086  # ECS_ENGINE_APT_EXTRA is a space-separated list
  for pkg in "${APT_PACKAGES[@]}" ${ECS_ENGINE_APT_EXTRA:-}; do
    [ "$(dpkg-query -W -f='${db:Status-Status}' "$pkg" 2>/dev/null)" = installed ] || echo "$pkg"
  done
}

ensure_apt_packages() {
  local -a missing as_root=()
  if ! command -v dpkg-query >/dev/null; then
    say "no dpkg here (not Debian/Ubuntu?): make sure these are installed: ${APT_PACKAGES[*]}"; return 0
  fi
  mapfile -t missing < <(missing_apt_packages)
  [ ${#missing[@]} -eq 0 ] && return 0
  if [ "$(id -u)" -eq 0 ]; then as_root=()
  elif command -v sudo >/dev/null && sudo -n true 2>/dev/null; then as_root=(sudo -n)
  else die "missing system packages; install them with: sudo apt-get install -y ${missing[*]}" 2
  fi
  say "apt-get install ${missing[*]}"
  "${as_root[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update -qq
  "${as_root[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}" >/dev/null
}

ensure_venv() {
  venv_ok && return 0
  say "creating $VENV with $1 ($("$1" -c 'import sys; print(sys.version.split()[0])'))"
  rm -rf "$VENV"
  if ! "$1" -m venv "$VENV"; then
    rm -rf "$VENV"
    die "'$1 -m venv' failed; install the venv module, e.g.: sudo apt-get install -y $("$1" -c 'import sys; print("python%d.%d-venv" % sys.version_info[:2])')" 2
  fi
}

# The stamp holds the sha256 of pyproject.toml and the extras installed with it.
ensure_package() {
  local hash old_hash="" old_extras="" want
  hash=$(sha256sum pyproject.toml | cut -d' ' -f1)
  [ -f "$STAMP" ] && { read -r old_hash old_extras < "$STAMP" || true; }
  # Keep extras installed earlier (e.g. bench) so `make bench` then `make test` does not reinstall.
  want=$(tr ', ' '\n' <<< "$EXTRAS,$old_extras" | sed '/^$/d' | sort -u | paste -sd, -)
  [ "$hash" = "$old_hash" ] && [ "$want" = "$old_extras" ] && return 0
  say "pip install -e '.[$want]' into $VENV (can take minutes)"
  rm -f "$STAMP"
  "$VENV/bin/pip" install --quiet --disable-pip-version-check -e ".[$want]"
  echo "$hash $want" > "$STAMP"
}

main() {
  local py=""
  parse_args "$@"
  STAMP=$VENV/.stamp
  if ! venv_ok; then
    py=$(find_python) || die "need Python >= $MIN_PYTHON (tried ${PYTHON:-python3.13 python3.12 python3.11 python3, then pyenv versions}); install one or set PYTHON=/path/to/python$MIN_PYTHON+" 2
  fi
  ensure_apt_packages
  if [ -n "$py" ]; then ensure_venv "$py"; fi
  ensure_package
}

main "$@"
