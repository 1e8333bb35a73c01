#!/usr/bin/env bash
# Run the Blender tests (pytest tests/blender) in each Blender version's venv made by scripts/setup-blender.sh, one
# version after the other, and print one summary line per version at the end.
#
# Usage: bash scripts/test-blender.sh [VERSION...] [-- PYTEST_ARGS...]
#   default: every version in scripts/pins/blender-versions.txt; e.g. bash scripts/test-blender.sh 4.5 5.3 -- -k edge -s
# Exit status: 0 if every version passed, 1 otherwise. Each version's full output: .venv-blender/logs/<version>.log.
set -uo pipefail
cd "$(dirname "$0")/.."
ROOT=.venv-blender
PINS=scripts/pins/blender-versions.txt

versions=()
while [ $# -gt 0 ] && [ "$1" != "--" ]; do versions+=("$1"); shift; done
[ "${1:-}" = "--" ] && shift
[ ${#versions[@]} -gt 0 ] || mapfile -t versions < <(grep -v '^\s*#' "$PINS" | awk 'NF {print $1}')

mkdir -p "$ROOT/logs"
summary=()
status=0
for v in "${versions[@]}"; do
    py="$ROOT/$v/bin/python"
    if [ ! -x "$py" ]; then
        summary+=("Blender $v: NOT SET UP (run: bash scripts/setup-blender.sh $v)")
        status=1
        continue
    fi
    log="$ROOT/logs/$v.log"
    echo "=== Blender $v ($py) ==="
    start=$SECONDS
    # The timeout guards against a bpy that hangs at interpreter exit (seen once in 4.5 after EEVEE; the batch script
    # ends with os._exit, the test process relies on this guard).
    timeout --kill-after=30 "${BLENDER_TEST_TIMEOUT_S:-2400}" "$py" -m pytest tests/blender -q -p no:cacheprovider "$@" 2>&1 | tee "$log"
    rc=${PIPESTATUS[0]}
    secs=$((SECONDS - start))
    last=$(grep -E '(passed|failed|error|skipped|no tests ran)' "$log" | tail -1 | sed 's/=//g; s/^ *//; s/ *$//')
    bpy_version=$("$py" -c 'import importlib.metadata as m; print(m.version("bpy"))' 2>/dev/null || echo "?")
    summary+=("Blender $v (bpy $bpy_version): ${last:-no result} (exit $rc, ${secs} s)")
    [ "$rc" -eq 0 ] || status=1
done
echo
echo "=== Blender test summary ==="
printf '%s\n' "${summary[@]}"
exit $status
