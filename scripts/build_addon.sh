#!/usr/bin/env bash
# Build the Blender extension, one zip per platform: the core's abi3 wheels into blender_addon/wheels/, the manifest's
# `wheels` and `platforms` lines set to them, then Blender's own validator and builder (blender_ext.py, shipped with
# Blender and with bpy) validate the folder and build it with --split-platforms ->
# dist/spectral_skin-<version>-<platform>.zip, each holding only its platform's wheel.
#
#   bash scripts/build_addon.sh             # this machine's wheel (scripts/build-wheel.sh: manylinux2014 on Linux)
#   bash scripts/build_addon.sh WHEEL...    # prebuilt wheels, e.g. one per platform (the release workflow)
#
# Needs .venv with the test tools (bash scripts/setup-python.sh --test): bpy 5.0.1 brings blender_ext.py.
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
    raise SystemExit("blender_ext.py not found: is bpy installed in .venv? (bash scripts/setup-python.sh --test)")
PYEOF
)
if [ $# -eq 0 ]; then
    bash scripts/build-wheel.sh
    wheels=(target/wheels/spectral_skin-*-cp311-abi3-*.whl)
else
    wheels=("$@")
fi
rm -rf blender_addon/wheels
mkdir -p blender_addon/wheels
names=()
platforms=()
for w in "${wheels[@]}"; do
    [ -f "$w" ] || { echo "build_addon: no wheel $w" >&2; exit 1; }
    cp "$w" blender_addon/wheels/
    name=$(basename "$w")
    names+=("\"./wheels/$name\"")
    # The wheel's platform tag -> Blender's platform name (blender_ext.py's list: linux-x64, linux-arm64, macos-x64,
    # macos-arm64, windows-x64, windows-arm64).
    case "$name" in
        *linux*_x86_64.whl) platforms+=('"linux-x64"') ;;
        *linux*_aarch64.whl) platforms+=('"linux-arm64"') ;;
        *macosx*_x86_64.whl) platforms+=('"macos-x64"') ;;
        *macosx*_arm64.whl) platforms+=('"macos-arm64"') ;;
        *win_amd64.whl) platforms+=('"windows-x64"') ;;
        *win_arm64.whl) platforms+=('"windows-arm64"') ;;
        *) echo "build_addon: unknown platform of wheel $name" >&2; exit 1 ;;
    esac
done
join() { local IFS=, list; list="$*"; echo "${list//,/, }"; }
sed -i "s|^wheels = .*|wheels = [$(join "${names[@]}")]|" blender_addon/blender_manifest.toml
sed -i "s|^platforms = .*|platforms = [$(join "${platforms[@]}")]|" blender_addon/blender_manifest.toml
"$PY" "$BLENDER_EXT" validate blender_addon
mkdir -p dist
rm -f dist/spectral_skin-*.zip
"$PY" "$BLENDER_EXT" build --source-dir blender_addon --output-dir dist --split-platforms
# Each zip holds exactly the add-on's tracked Python files (no render-only script: scripts/tools/render_blend.py stays
# out), the manifest and its one wheel.
for zip in dist/spectral_skin-*.zip; do
    "$PY" - "$zip" <<'PYEOF'
import subprocess, sys, zipfile
names = set(zipfile.ZipFile(sys.argv[1]).namelist())
tracked = subprocess.run(["git", "ls-files", "blender_addon/*.py"], capture_output=True, text=True, check=True).stdout
expected = {path.removeprefix("blender_addon/") for path in tracked.split()}
python = {n for n in names if n.endswith(".py")}
wheels = [n for n in names if n.startswith("wheels/")]
problems = [f"missing {sorted(expected - python)}"] if expected - python else []
problems += [f"unexpected {sorted(python - expected)}"] if python - expected else []
problems += [] if "blender_manifest.toml" in names and len(wheels) == 1 else [f"manifest/wheels: {sorted(names)}"]
if problems:
    raise SystemExit(f"build_addon: {sys.argv[1]}: " + "; ".join(problems))
print(f"{sys.argv[1]}: {len(python)} Python files, {wheels[0]}")
PYEOF
done
ls -l dist/spectral_skin-*.zip
