#!/usr/bin/env bash
# Set up a fresh machine and run every test: Rust unit and integration tests (release mode: the Monte Carlo
# references need it), the Python bindings' pytest suite, and the Blender add-on and render tests (bpy, Cycles CPU).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup-python.sh
cargo test --release
.venv/bin/python -m pytest tests/python -q
.venv/bin/python -m mypy.stubtest spectral_skin._core
# The Blender extension (built and validated by Blender's own validator), then the add-on and render tests via bpy.
bash scripts/build_addon.sh
.venv/bin/python -m pytest tests/blender -q
# The map performance report in its reduced form, so the report code cannot rot (the full one: see README).
.venv/bin/python scripts/maps_report.py --quick --out "$(mktemp -d)/maps-performance.md"
# The accuracy-vs-time report, reduced (the full one: bash scripts/accuracy_report.sh).
bash scripts/accuracy_report.sh --quick
