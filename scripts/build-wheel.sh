#!/usr/bin/env bash
# Build the core's abi3 wheel (cp311-abi3: CPython 3.11 and newer, so every Blender from 4.2 on).
#
#   bash scripts/build-wheel.sh                  # this machine's, into target/wheels/
#   bash scripts/build-wheel.sh --target TRIPLE  # cross-compiled on Linux x64, into target/wheels-cross/TRIPLE/:
#                                                # x86_64-pc-windows-gnu, x86_64-apple-darwin, aarch64-apple-darwin
#
# On Linux this machine's wheel is a manylinux2014 wheel (glibc 2.17 and newer: any Linux Blender runs on), linked by
# zig (`maturin build --zig`) and checked by auditwheel; on macOS and Windows maturin's own wheel is portable as built
# (the release workflow, .github/workflows/release.yml, builds those there).
# The cross-compiled wheels: Windows x64 by MinGW-w64's linker (Debian's gcc-mingw-w64-x86-64; Rust links its
# runtime statically, so the .pyd imports only python3.dll and Windows' own DLLs), macOS x86_64 and arm64 by zig
# (macOS 10.12 and 11.0, maturin's defaults; zig signs the arm64 one ad hoc as it links). The rustup target is added
# if missing. scripts/check_wheels.py checks what they link and export (scripts/build_addon.sh runs it).
# The extension (scripts/build_addon.sh) and the Blender test venvs (scripts/setup-blender.sh) both take this
# machine's wheel from target/wheels: the second call finds cargo's build up to date and only repackages.
# Needs .venv with the test tools: bash scripts/setup-python.sh --test (maturin, ziglang, auditwheel).
set -euo pipefail
cd "$(dirname "$0")/.."
target=
case "${1:-}" in
    "") ;;
    --target) target=${2:?"build-wheel: --target needs a target triple"} ;;
    *) echo "usage: bash scripts/build-wheel.sh [--target TRIPLE]" >&2; exit 2 ;;
esac
for tool in maturin auditwheel; do
    [ -x ".venv/bin/$tool" ] || { echo "build-wheel: no .venv/bin/$tool: run bash scripts/setup-python.sh --test" >&2; exit 1; }
done
# The module's own target folder (as in setup-python.sh); a cross-target build lands in a subfolder of it, and shares
# its build scripts and proc-macros.
args=(build --release --target-dir target/python)
if [ -z "$target" ]; then
    out=target/wheels
    args+=(--interpreter .venv/bin/python)
    if [ "$(uname -s)" = Linux ]; then
        echo "build-wheel: manylinux2014 wheel, linked by zig (a release build of its own: minutes the first time)"
        args+=(--zig --compatibility manylinux2014)
    fi
else
    out=target/wheels-cross/$target
    [ "$(uname -s)-$(uname -m)" = Linux-x86_64 ] || { echo "build-wheel: --target is set up for a Linux x64 machine" >&2; exit 1; }
    case "$target" in
        x86_64-pc-windows-gnu)
            command -v x86_64-w64-mingw32-gcc >/dev/null || {
                echo "build-wheel: no x86_64-w64-mingw32-gcc (MinGW-w64, the Windows linker): apt-get install gcc-mingw-w64-x86-64" >&2
                exit 1
            } ;;
        x86_64-apple-darwin | aarch64-apple-darwin) args+=(--zig) ;;
        *) echo "build-wheel: no cross build set up for $target (x86_64-pc-windows-gnu, x86_64-apple-darwin, aarch64-apple-darwin)" >&2; exit 2 ;;
    esac
    if ! rustup target list --installed | grep -qx "$target"; then
        echo "build-wheel: adding the Rust standard library for $target (rustup target add $target)"
        rustup target add "$target"
    fi
    echo "build-wheel: $target wheel (a release build of its own: minutes the first time)"
    args+=(--target "$target")
fi
# Built into a folder of its own and moved into place when whole.
rm -rf "$out.partial"
VIRTUAL_ENV="$PWD/.venv" PATH="$PWD/.venv/bin:$PATH" .venv/bin/maturin "${args[@]}" --out "$out.partial"
wheels=("$out.partial"/spectral_skin-*-cp311-abi3-*.whl)
[ -f "${wheels[0]}" ] && [ ${#wheels[@]} -eq 1 ] || { echo "build-wheel: expected one abi3 wheel, got: ${wheels[*]}" >&2; exit 1; }
if [ -z "$target" ] && [ "$(uname -s)" = Linux ]; then
    # auditwheel reads the libraries and symbol versions the extension needs and names the oldest manylinux policy
    # they satisfy; the wheel must be consistent with manylinux2014 and need no external library.
    report=$(.venv/bin/auditwheel show "${wheels[0]}")
    echo "$report"
    tag=$(tr '\n' ' ' <<<"$report" | sed -n 's/.*consistent with the following platform tag: *"\([^"]*\)".*/\1/p')
    glibc=$(sed -n 's/^manylinux_\([0-9]*\)_\([0-9]*\)_.*/\1 \2/p' <<<"$tag")
    read -r major minor <<<"${glibc:-99 99}"
    if [ "$major" -gt 2 ] || { [ "$major" -eq 2 ] && [ "$minor" -gt 17 ]; }; then
        echo "build-wheel: auditwheel finds the wheel consistent only with '$tag', not with manylinux2014 (glibc 2.17)" >&2
        exit 1
    fi
fi
rm -rf "$out"
mv "$out.partial" "$out"
echo "build-wheel: $out/$(basename "${wheels[0]}")"
