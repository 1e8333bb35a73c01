#!/usr/bin/env bash
# Set up a fresh machine and run every test: Rust unit and integration tests (release mode: the Monte Carlo
# references need it), then the Python bindings' pytest suite.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup-python.sh
cargo test --release
.venv/bin/python -m pytest tests/python -q
.venv/bin/python -m mypy.stubtest spectral_skin._core
