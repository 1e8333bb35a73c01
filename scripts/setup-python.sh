#!/usr/bin/env bash
# Create (or reuse) the project's virtual environment in .venv and build the Python module into it.
# Needs only the Rust toolchain and Python 3.11+ with pip. numpy<2 because Blender's bpy 5.0.1 needs it;
# OpenImageIO 3.0.x (3.1 requires numpy>=2) to check the written EXRs independently; bpy 5.0.1 (Blender as a Python
# module) for the add-on and the render tests.
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHON=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
    "$PYTHON" -m venv .venv
fi
.venv/bin/python -m pip install -q --upgrade pip
.venv/bin/python -m pip install -q "maturin>=1.5,<2" pytest mypy ruff "numpy<2" "openimageio>=3.0,<3.1" "bpy==5.0.1"
VIRTUAL_ENV="$PWD/.venv" .venv/bin/maturin develop --release -q
