#!/usr/bin/env bash
# Format and lint checks (CI runs them first): rustfmt, clippy with warnings as errors (for Linux, and for the Windows
# and macOS targets), the import graph, ruff, mypy, and the GitHub Actions workflows (which cannot run here) against
# GitHub's workflow schema. Needs .venv with the test tools (bash scripts/setup-python.sh --test installs ruff, mypy,
# check-jsonschema).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo fmt --check
cargo fmt --check --manifest-path fuzz/Cargo.toml
cargo clippy --all-targets --features python -q -- -D warnings
# The code only the other platforms compile (cfg(windows), cfg(not(unix)), aarch64): clippy of the library and the CLI
# for each target the extension ships for (the Rust targets: bash scripts/setup-cross.sh). The tests, benches and
# examples run on Linux only (and a dev-dependency's C code would need a C compiler for macOS).
for target in x86_64-pc-windows-gnu x86_64-apple-darwin aarch64-apple-darwin; do
    cargo clippy --target "$target" --lib --bins --features python -q -- -D warnings
done
# Imports run one way (no circle in src/ or blender_addon/, no name taken from the crate root).
python3 scripts/check_imports.py
.venv/bin/ruff check python blender_addon scripts tests fuzz
.venv/bin/python -m mypy python/spectral_skin blender_addon
.venv/bin/check-jsonschema --builtin-schema vendor.github-workflows .github/workflows/*.yml
echo "lint: clean"
