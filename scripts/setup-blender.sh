#!/usr/bin/env bash
# Create (or reuse) one virtual environment per Blender version for the render tests: .venv-blender/<version>, with
# the bpy, numpy, OpenImageIO and pytest pinned in scripts/pins/blender-versions.txt, and the project's Python module.
# The module is the extension's own wheel (scripts/build-wheel.sh: abi3, cp311-abi3, so it loads in Python 3.11 and
# 3.13 alike; manylinux2014 on Linux), built once into target/wheels and installed into every venv.
#
# Usage: bash scripts/setup-blender.sh [VERSION...]     (default: every version in scripts/pins/blender-versions.txt)
# Needs: the Rust toolchain, python3.11, and python3.13 for Blender 5.2+ (found as python3.13, or through pyenv);
# .venv with the test tools (made here by bash scripts/setup-python.sh --test if missing).
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=.venv-blender
PINS=scripts/pins/blender-versions.txt

all_versions() { grep -v '^\s*#' "$PINS" | awk 'NF {print $1}'; }
pin_line() { grep -v '^\s*#' "$PINS" | awk -v v="$1" '$1 == v'; }

python_for() { # the interpreter for a Python version: pythonX.Y on PATH (pyenv shims need PYENV_VERSION)
    local want=$1 exe
    for exe in "python$want" python3; do
        if command -v "$exe" >/dev/null 2>&1 \
            && [ "$("$exe" -c 'import sys; print("%d.%d" % sys.version_info[:2])' 2>/dev/null)" = "$want" ]; then
            echo "$exe"; return 0
        fi
    done
    if command -v pyenv >/dev/null 2>&1; then
        local full
        full=$(pyenv versions --bare | grep -E "^${want//./\\.}\.[0-9]+$" | sort -V | tail -1)
        if [ -n "$full" ]; then echo "$(pyenv root)/versions/$full/bin/python$want"; return 0; fi
    fi
    echo "setup-blender: no Python $want found (needed by the Blender versions pinned to it)" >&2
    return 1
}

if [ $# -gt 0 ]; then versions=("$@"); else mapfile -t versions < <(all_versions); fi
for v in "${versions[@]}"; do
    [ -n "$(pin_line "$v")" ] || { echo "setup-blender: Blender $v is not in $PINS (have: $(all_versions | xargs))" >&2; exit 2; }
done

# 1. The wheel: the extension's (up to date after scripts/build_addon.sh: then cargo has nothing to compile).
[ -x .venv/bin/auditwheel ] || bash scripts/setup-python.sh --test
bash scripts/build-wheel.sh
wheel=$(ls target/wheels/spectral_skin-*-cp311-abi3-*.whl)
mkdir -p "$ROOT"

# 2. One venv per version.
for v in "${versions[@]}"; do
    read -r _ py reqs <<<"$(pin_line "$v")"
    venv="$ROOT/$v"
    if [ ! -x "$venv/bin/python" ]; then
        "$(python_for "$py")" -m venv "$venv"
        "$venv/bin/python" -m pip install -q --upgrade pip
    fi
    # shellcheck disable=SC2086  # reqs is a list of requirement words
    "$venv/bin/python" -m pip install -q $reqs
    "$venv/bin/python" -m pip install -q --force-reinstall --no-deps "$wheel"
    "$venv/bin/python" -c 'import bpy, numpy, OpenImageIO, spectral_skin; print("setup-blender: %s ready: bpy %s, numpy %s, OpenImageIO %s, Python %s" % ("'"$v"'", bpy.app.version_string, numpy.__version__, OpenImageIO.VERSION_STRING, __import__("platform").python_version()))'
done
