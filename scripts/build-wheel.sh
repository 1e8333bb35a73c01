#!/usr/bin/env bash
# Build the core's abi3 wheel (cp311-abi3: CPython 3.11 and newer, so every Blender from 4.2 on) for this machine into
# target/wheels/. On Linux it is a manylinux2014 wheel (glibc 2.17 and newer: any Linux Blender runs on), linked by zig
# (`maturin build --zig`) and checked by auditwheel; on macOS and Windows maturin's own wheel is portable as built
# (the release workflow, .github/workflows/release.yml, builds those there).
# The extension (scripts/build_addon.sh) and the Blender test venvs (scripts/setup-blender.sh) both take the wheel
# from here: the second call finds cargo's build up to date and only repackages.
# Needs .venv with the test tools: bash scripts/setup-python.sh --test (maturin, ziglang, auditwheel).
set -euo pipefail
cd "$(dirname "$0")/.."
out=target/wheels
for tool in maturin auditwheel; do
    [ -x ".venv/bin/$tool" ] || { echo "build-wheel: no .venv/bin/$tool: run bash scripts/setup-python.sh --test" >&2; exit 1; }
done
rm -rf "$out"
# The module's own target folder (as in setup-python.sh); the cross-target build lands in a subfolder of it.
args=(build --release --interpreter .venv/bin/python --target-dir target/python --out "$out")
if [ "$(uname -s)" = Linux ]; then
    echo "build-wheel: manylinux2014 wheel, linked by zig (a release build of its own: minutes the first time)"
    VIRTUAL_ENV="$PWD/.venv" PATH="$PWD/.venv/bin:$PATH" .venv/bin/maturin "${args[@]}" --zig --compatibility manylinux2014
else
    VIRTUAL_ENV="$PWD/.venv" .venv/bin/maturin "${args[@]}"
fi
wheels=("$out"/spectral_skin-*-cp311-abi3-*.whl)
[ -f "${wheels[0]}" ] && [ ${#wheels[@]} -eq 1 ] || { echo "build-wheel: expected one abi3 wheel in $out, got: ${wheels[*]}" >&2; exit 1; }
if [ "$(uname -s)" = Linux ]; then
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
echo "build-wheel: ${wheels[0]}"
