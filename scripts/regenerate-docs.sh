#!/usr/bin/env bash
# Regenerate every doc, table and picture that README.md and docs/ show from the model, each stamped with the model's
# version (src/stamp.rs; tests/physics/doc_stamps.rs fails while one is older than the model: docs/tests.md, Stamped
# docs). Run after raising MODEL_VERSION. About an hour and a half on 2 cores, most of it the accuracy report and the
# Blender renders.
#
# Usage: bash scripts/regenerate-docs.sh [--list | --only NAME...]
# Needs: .venv with the test tools (bash scripts/setup-python.sh --test: bpy 5.0) and .venv-blender/5.0 and 5.3
# (bash scripts/setup-blender.sh 5.0 5.3) for the scripts that name them.
set -euo pipefail
cd "$(dirname "$0")/.."

# name|command, in the order they run (the palette first: the presets it writes are what the others render).
JOBS=(
    "palette|cargo run --release --example palette -- --write"
    "transport-albedo|cargo run --release --example transport_albedo"
    "skin-atlas|cargo run --release --example skin_atlas"
    "shader-table|cargo run --release --example shader_table_report"
    "measured-skin|cargo run --release --example measured_skin_report -- --every 16"
    "accuracy|bash scripts/accuracy_report.sh"
    "doc-tables|.venv/bin/python scripts/reports/doc_tables.py"
    "principled-inputs|.venv-blender/5.3/bin/python scripts/reports/principled_inputs.py"
    "preview|.venv/bin/python scripts/tools/render_preview.py"
    "lookdev|.venv/bin/python scripts/reports/lookdev_sheet.py"
    "surface-slices|.venv-blender/5.0/bin/python scripts/reports/surface_slices.py"
    "scene-effects|.venv-blender/5.0/bin/python scripts/reports/scene_effects_report.py"
    "live-mode|.venv-blender/5.0/bin/python scripts/reports/live_mode_report.py"
)

only=()
case "${1:-}" in
    --list) for job in "${JOBS[@]}"; do printf '%-18s %s\n' "${job%%|*}" "${job#*|}"; done; exit 0 ;;
    --only) shift; only=("$@") ;;
    "") ;;
    *) echo "regenerate-docs: unknown argument $1 (--list, --only NAME...)" >&2; exit 2 ;;
esac
for name in "${only[@]}"; do
    printf '%s\n' "${JOBS[@]}" | grep -q "^$name|" || { echo "regenerate-docs: no job $name (--list)" >&2; exit 2; }
done

for job in "${JOBS[@]}"; do
    name=${job%%|*}
    command=${job#*|}
    if [ ${#only[@]} -gt 0 ] && ! printf '%s\n' "${only[@]}" | grep -qx "$name"; then continue; fi
    echo "== $name: $command"
    start=$(date +%s)
    bash -c "$command"
    echo "== $name: $(( $(date +%s) - start )) s"
done
