#!/usr/bin/env bash
# Build the Blender extension: the core's abi3 wheel (maturin, features from pyproject.toml) into
# blender_addon/wheels/, the manifest's wheels line set to that wheel, then validate and zip it with the validator that
# ships with Blender (blender_ext.py) -> dist/spectral_skin-<version>.zip.
# Needs .venv (bash scripts/setup-python.sh): maturin and bpy 5.0.1 come from it.
set -euo pipefail
cd "$(dirname "$0")/.."
PY=.venv/bin/python
BLENDER_EXT=$("$PY" - <<'PYEOF'
import pathlib, site
for p in site.getsitepackages():
    hits = sorted(pathlib.Path(p).glob("bpy/*/scripts/addons_core/bl_pkg/cli/blender_ext.py"))
    if hits:
        print(hits[-1])
        break
else:
    raise SystemExit("blender_ext.py not found: is bpy installed in .venv? (bash scripts/setup-python.sh)")
PYEOF
)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
VIRTUAL_ENV="$PWD/.venv" .venv/bin/maturin build --release --interpreter "$PY" --out "$tmp" -q
wheels=("$tmp"/spectral_skin-*-abi3-*.whl)
[ -f "${wheels[0]}" ] && [ ${#wheels[@]} -eq 1 ] || { echo "expected one abi3 wheel in $tmp, got: ${wheels[*]}" >&2; exit 1; }
wheel=$(basename "${wheels[0]}")
rm -rf blender_addon/wheels
mkdir -p blender_addon/wheels
cp "${wheels[0]}" blender_addon/wheels/
sed -i "s|^wheels = .*|wheels = [\"./wheels/$wheel\"]|" blender_addon/blender_manifest.toml
"$PY" "$BLENDER_EXT" validate blender_addon
mkdir -p dist
"$PY" "$BLENDER_EXT" build --source-dir blender_addon --output-dir dist
ls -l dist/spectral_skin-*.zip
