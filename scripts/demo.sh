#!/usr/bin/env bash
# Set up a fresh machine and run the main job on the built-in example: the face-like example parameter map turned into
# Principled texture maps (albedo.exr, radius.exr, specular.exr, skin_maps.json in target/example/maps), plus the
# Caucasian preset's Blender inputs, its radial profile, and the same model through Python.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup-python.sh
cargo build --release --bin spectral-skin
skin=./target/release/spectral-skin
mkdir -p target/example
$skin example --out target/example/face_params.exr --size 512
$skin maps --params target/example/face_params.exr --out target/example/maps
$skin eval --preset caucasian
$skin profile --preset caucasian --csv --count 12
.venv/bin/python -c "import spectral_skin; print(spectral_skin.layered_reflectance([(float('inf'), 0.01, 1.0, 1.4)], [0.5, 1.0]))"
