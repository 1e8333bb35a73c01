#!/usr/bin/env bash
# Set up a fresh machine and run the main job on the built-in example: the Caucasian preset's Blender inputs,
# its RGB radial profile, and the same model through Python.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup-python.sh
cargo build --release --bin spectral-skin
./target/release/spectral-skin eval --preset caucasian
./target/release/spectral-skin profile --preset caucasian --csv --count 12
.venv/bin/python -c "import spectral_skin; print(spectral_skin.layered_reflectance([(float('inf'), 0.01, 1.0, 1.4)], [0.5, 1.0]))"
