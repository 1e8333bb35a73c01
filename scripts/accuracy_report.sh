#!/usr/bin/env bash
# Regenerate docs/accuracy-vs-time.md: Cycles samples through bpy (docs/data/cycles_samples.json), then every accuracy
# knob of the core measured and timed (examples/accuracy_report). About 35 minutes on 2 cores shared with other jobs.
#   bash scripts/accuracy_report.sh            # the full report, written to docs/
#   bash scripts/accuracy_report.sh --quick    # the reduced run CI does, written to a temporary folder
set -euo pipefail
cd "$(dirname "$0")/.."
# The Cycles samples measurement needs bpy, one of the test tools.
.venv/bin/python -c 'import bpy' 2>/dev/null || bash scripts/setup-python.sh --test
if [ "${1:-}" = "--quick" ]; then
    out="$(mktemp -d)"
    .venv/bin/python scripts/reports/cycles_samples.py --quick --out "$out/data/cycles_samples.json"
    cargo run --release --example accuracy_report -- --quick --out-dir "$out" --cycles-json "$out/data/cycles_samples.json"
    echo "reduced report: $out/accuracy-vs-time.md"
else
    .venv/bin/python scripts/reports/cycles_samples.py --out docs/data/cycles_samples.json
    cargo run --release --example accuracy_report
fi
