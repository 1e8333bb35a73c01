#!/usr/bin/env bash
# Build the Blender extension, one zip per platform: the core's abi3 wheels into a staged copy of blender_addon/, its
# manifest's `wheels` and `platforms` lines set to them, then Blender's own validator and builder (blender_ext.py,
# shipped with Blender and with bpy) validate the folder and build it with --split-platforms ->
# dist/spectral_skin-<version>-<platform>.zip, each holding only its platform's wheel.
#
#   bash scripts/build_addon.sh             # four zips: linux_x64 (this machine's wheel, scripts/build-wheel.sh:
#                                           # manylinux2014) and, cross-compiled here, windows_x64, macos_x64 and
#                                           # macos_arm64 (scripts/build-wheel.sh --target ...); Linux x64 only
#   bash scripts/build_addon.sh --host      # this machine's zip alone (any platform)
#   bash scripts/build_addon.sh WHEEL...    # prebuilt wheels, e.g. one per platform (the release workflow)
#
# Every wheel and every zip is checked by scripts/check_wheels.py (platform tags, abi3, the module's libraries and
# exports, the arm64 code signature; each zip's manifest, files and Blender's validator) before dist/ is touched: the
# zips are built in a staging folder and moved into dist/ when all pass.
# Needs .venv with the test tools (bash scripts/setup-python.sh --test): bpy 5.0.1 brings blender_ext.py, LIEF reads
# the binaries. The cross builds' Rust targets and MinGW-w64 are installed where missing by scripts/setup-cross.sh
# (apt, as root; otherwise it names the command).
set -euo pipefail
cd "$(dirname "$0")/.."
PY=.venv/bin/python
[ -x "$PY" ] || { echo "build_addon: no .venv: run bash scripts/setup-python.sh --test" >&2; exit 1; }
BLENDER_EXT=$("$PY" -c 'import sys; sys.path.insert(0, "scripts"); import check_wheels as c; p = c.find_blender_ext(); print(p or "")')
[ -n "$BLENDER_EXT" ] || { echo "build_addon: blender_ext.py not found: is bpy installed in .venv? (bash scripts/setup-python.sh --test)" >&2; exit 1; }
CROSS_TARGETS=(x86_64-pc-windows-gnu x86_64-apple-darwin aarch64-apple-darwin)
case "${1:-}" in
    --host)
        [ $# -eq 1 ] || { echo "usage: bash scripts/build_addon.sh [--host | WHEEL...]" >&2; exit 2; }
        bash scripts/build-wheel.sh
        wheels=(target/wheels/spectral_skin-*-cp311-abi3-*.whl) ;;
    "")
        if [ "$(uname -s)-$(uname -m)" != Linux-x86_64 ]; then
            echo "build_addon: the four platforms are cross-compiled from Linux x64 only; here: bash scripts/build_addon.sh --host" >&2
            exit 1
        fi
        bash scripts/setup-cross.sh
        bash scripts/build-wheel.sh
        wheels=(target/wheels/spectral_skin-*-cp311-abi3-*.whl)
        for target in "${CROSS_TARGETS[@]}"; do
            start=$SECONDS
            bash scripts/build-wheel.sh --target "$target"
            echo "build_addon: $target wheel in $((SECONDS - start)) s"
            wheels+=(target/wheels-cross/"$target"/spectral_skin-*-cp311-abi3-*.whl)
        done ;;
    -*) echo "usage: bash scripts/build_addon.sh [--host | WHEEL...]" >&2; exit 2 ;;
    *) wheels=("$@") ;;
esac
for w in "${wheels[@]}"; do
    [ -f "$w" ] || { echo "build_addon: no wheel $w" >&2; exit 1; }
done
# The wheels first: a wrong one stops here, before any packaging.
"$PY" scripts/check_wheels.py "${wheels[@]}"

stage=$(mktemp -d "${TMPDIR:-/tmp}/build_addon.XXXXXX")
trap 'rm -rf "$stage"' EXIT
cp -r blender_addon "$stage/spectral_skin"
rm -rf "$stage/spectral_skin/wheels"
mkdir -p "$stage/spectral_skin/wheels" "$stage/dist"
names=()
platforms=()
for w in "${wheels[@]}"; do
    cp "$w" "$stage/spectral_skin/wheels/"
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
manifest=$stage/spectral_skin/blender_manifest.toml
sed -i "s|^wheels = .*|wheels = [$(join "${names[@]}")]|" "$manifest"
sed -i "s|^platforms = .*|platforms = [$(join "${platforms[@]}")]|" "$manifest"
"$PY" "$BLENDER_EXT" validate "$stage/spectral_skin"
"$PY" "$BLENDER_EXT" build --source-dir "$stage/spectral_skin" --output-dir "$stage/dist" --split-platforms
# Each zip: Blender's split name, exactly the add-on's tracked Python files (no render-only script:
# scripts/tools/render_blend.py stays out), the manifest naming its one platform and its one wheel, which passes the
# wheel checks, and Blender's validator on the zip itself.
zips=("$stage"/dist/spectral_skin-*.zip)
[ ${#zips[@]} -eq ${#wheels[@]} ] || { echo "build_addon: ${#wheels[@]} wheels gave ${#zips[@]} zips: ${zips[*]}" >&2; exit 1; }
"$PY" scripts/check_wheels.py --blender-ext "$BLENDER_EXT" "${zips[@]}"
mkdir -p dist
rm -f dist/spectral_skin-*.zip
mv "${zips[@]}" dist/
ls -l dist/spectral_skin-*.zip
