#!/usr/bin/env bash
# Set up a fresh machine for the main job (bash scripts/setup-python.sh: .venv with the module and the CLI, nothing
# for tests) and run the main job on the built-in example: the face-like example parameter map turned into Principled
# texture maps (albedo.exr, radius.exr, specular.exr, skin_maps.json in target/example/maps), plus the Caucasian
# preset's Blender inputs, its radial profile, and the same model through Python.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup-python.sh
skin=.venv/bin/spectral-skin
say() { echo; echo "demo: $*"; }
mkdir -p target/example
say "the example parameter map (spectral-skin example) -> target/example/face_params.exr"
$skin example --out target/example/face_params.exr --size 512
say "the main job: parameter map -> texture maps (spectral-skin maps) -> target/example/maps"
$skin maps --params target/example/face_params.exr --out target/example/maps
say "one material: the Caucasian preset's Blender inputs (spectral-skin eval --preset caucasian)"
$skin eval --preset caucasian
say "its radial profile (spectral-skin profile --preset caucasian --csv --count 12)"
$skin profile --preset caucasian --csv --count 12
say "the same model through Python (spectral_skin.layered_reflectance)"
.venv/bin/python -c "import spectral_skin; print(spectral_skin.layered_reflectance([(float('inf'), 0.01, 1.0, 1.4)], [0.5, 1.0]))"
