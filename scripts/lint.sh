#!/usr/bin/env bash
# Format and lint checks (CI runs them first): rustfmt, clippy with warnings as errors, ruff and mypy.
# Needs .venv (bash scripts/setup-python.sh installs ruff and mypy there).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo fmt --check
cargo fmt --check --manifest-path fuzz/Cargo.toml
cargo clippy --all-targets --features python -q -- -D warnings
.venv/bin/ruff check python blender_addon scripts tests fuzz
.venv/bin/python -m mypy python/spectral_skin blender_addon
echo "lint: clean"
