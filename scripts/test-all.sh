#!/usr/bin/env bash
# Set up a fresh machine and run every test: Rust unit and integration tests (release mode: the Monte Carlo
# references need it), then the Python bindings' pytest suite.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup-python.sh
cargo test --release
.venv/bin/python -m pytest tests/python -q
.venv/bin/python -m mypy.stubtest spectral_skin._core
# The map performance report in its reduced form, so the report code cannot rot (the full one: see README).
.venv/bin/python scripts/maps_report.py --quick --out "$(mktemp -d)/maps-performance.md"
