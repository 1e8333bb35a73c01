#!/usr/bin/env bash
# Format and lint checks (CI runs them first): rustfmt, clippy with warnings as errors, the import graph, ruff, mypy, and the GitHub
# Actions workflows (which cannot run here) against GitHub's workflow schema. Needs .venv with the test tools
# (bash scripts/setup-python.sh --test installs ruff, mypy, check-jsonschema).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo fmt --check
cargo fmt --check --manifest-path fuzz/Cargo.toml
cargo clippy --all-targets --features python -q -- -D warnings
# Imports run one way (no circle in src/ or blender_addon/, no name taken from the crate root).
python3 scripts/check_imports.py
.venv/bin/ruff check python blender_addon scripts tests fuzz
.venv/bin/python -m mypy python/spectral_skin blender_addon
.venv/bin/check-jsonschema --builtin-schema vendor.github-workflows .github/workflows/*.yml
echo "lint: clean"
