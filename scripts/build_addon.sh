#!/usr/bin/env bash
# Build the Blender extension: the core's abi3 wheel (maturin, features from pyproject.toml) into
# blender_addon/wheels/, the manifest's wheels line set to that wheel and its platforms line to the wheel's platform
# (one zip per platform: the core is compiled code), then validate and zip it with the validator that
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
# The wheel's platform tag -> Blender's platform name (blender_ext.py's list: linux-x64, linux-arm64, macos-x64,
# macos-arm64, windows-x64, windows-arm64).
case "$wheel" in
    *manylinux*_x86_64.whl | *linux_x86_64.whl) platform=linux-x64 ;;
    *manylinux*_aarch64.whl | *linux_aarch64.whl) platform=linux-arm64 ;;
    *macosx*_x86_64.whl) platform=macos-x64 ;;
    *macosx*_arm64.whl) platform=macos-arm64 ;;
    *win_amd64.whl) platform=windows-x64 ;;
    *win_arm64.whl) platform=windows-arm64 ;;
    *) echo "unknown platform of wheel $wheel" >&2; exit 1 ;;
esac
sed -i "s|^wheels = .*|wheels = [\"./wheels/$wheel\"]|" blender_addon/blender_manifest.toml
sed -i "s|^platforms = .*|platforms = [\"$platform\"]|" blender_addon/blender_manifest.toml
"$PY" "$BLENDER_EXT" validate blender_addon
mkdir -p dist
"$PY" "$BLENDER_EXT" build --source-dir blender_addon --output-dir dist
ls -l dist/spectral_skin-*.zip
