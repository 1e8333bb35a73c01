#!/usr/bin/env bash
# Format and lint checks (CI runs them first): rustfmt, clippy with warnings as errors, ruff, mypy, and the GitHub
# Actions workflows (which cannot run here) against GitHub's workflow schema. Needs .venv with the test tools
# (bash scripts/setup-python.sh --test installs ruff, mypy, check-jsonschema).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo fmt --check
cargo fmt --check --manifest-path fuzz/Cargo.toml
cargo clippy --all-targets --features python -q -- -D warnings
.venv/bin/ruff check python blender_addon scripts tests fuzz
.venv/bin/python -m mypy python/spectral_skin blender_addon
.venv/bin/check-jsonschema --builtin-schema vendor.github-workflows .github/workflows/*.yml
echo "lint: clean"
