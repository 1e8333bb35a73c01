#!/usr/bin/env bash
# Create (or reuse) the project's virtual environment in .venv and build the Python module into it, with the
# `spectral-skin` command it carries, so that `.venv/bin/spectral-skin` and `.venv/bin/python -c "import spectral_skin"`
# work.
#
#   bash scripts/setup-python.sh          # what the main job needs: scripts/pins/requirements.txt (maturin, numpy)
#   bash scripts/setup-python.sh --test   # and the test and lint tools: scripts/pins/requirements-test.txt
#                                         # (pytest, mypy, OpenImageIO) and scripts/pins/requirements-dev.txt (ruff,
#                                         # check-jsonschema, ziglang, auditwheel, bpy 5.0.1, openjd-cli) and Node.js
#                                         # where missing (apt, as root); the module is then the extension's wheel
#
# Needs only the Rust toolchain and Python 3.11+ with pip (PYTHON=... picks the interpreter; default python3).
# The module (cargo features `python` and `cli`) and cargo's own builds (feature `cli`) are compiled with different
# features, so each has its own target folder: maturin builds in target/python, cargo in target/release. Had they
# shared one, every switch between `maturin develop` and `cargo build` would recompile the crate. After editing the
# Rust code: `maturin develop --release --target-dir target/python` (in the activated venv).
set -euo pipefail
cd "$(dirname "$0")/.."
test_tools=0
case "${1:-}" in
    "") ;;
    --test) test_tools=1 ;;
    *) echo "usage: bash scripts/setup-python.sh [--test]" >&2; exit 2 ;;
esac
say() { echo "setup-python: $*"; }
PYTHON=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
    say "creating .venv with $("$PYTHON" --version)"
    "$PYTHON" -m venv .venv
fi
.venv/bin/python -m pip install -q --upgrade pip
say "installing the pinned Python packages"
requirements=(-r scripts/pins/requirements.txt)
[ "$test_tools" -eq 0 ] || requirements+=(-r scripts/pins/requirements-test.txt -r scripts/pins/requirements-dev.txt)
.venv/bin/python -m pip install "${requirements[@]}"
if [ "$test_tools" -eq 1 ] && ! command -v node >/dev/null && ! command -v nodejs >/dev/null; then
    # The farm tests compile the Flamenco job type under Node (tests/python/test_farm_jobs.py).
    say "installing Node.js (Debian's nodejs) for the Flamenco job-type test"
    if [ "$(id -u)" -eq 0 ]; then
        apt-get update -qq && apt-get install -y -qq nodejs >/dev/null
    else
        echo "setup-python: node is missing: install Node.js (e.g. sudo apt-get install nodejs)" >&2; exit 1
    fi
fi

if [ "$test_tools" -eq 0 ]; then
    say "building the Python module into .venv (maturin develop --release; the first build compiles ~85 crates: minutes)"
    VIRTUAL_ENV="$PWD/.venv" .venv/bin/maturin develop --release --target-dir target/python
else
    # The tests run against the wheel the extension ships, built once (scripts/build-wheel.sh; the extension and the
    # Blender venvs reuse it), instead of a second release build by maturin develop.
    say "building the extension's wheel (scripts/build-wheel.sh) and installing it into .venv: the tests test what ships"
    bash scripts/build-wheel.sh
    .venv/bin/python -m pip install --force-reinstall --no-deps target/wheels/spectral_skin-*-cp311-abi3-*.whl
fi

# The module carries the command line (pyproject.toml: features python and cli), and installing it put the
# `spectral-skin` script into .venv/bin, as `pip install` of the wheel does anywhere: no second build for the CLI.
.venv/bin/spectral-skin --version >/dev/null
say "ready: .venv/bin/spectral-skin, .venv/bin/python with spectral_skin (or: source .venv/bin/activate)"
