#!/usr/bin/env bash
# Set up a fresh machine and run every test: Rust tests, the Python bindings' tests, the Blender extension build (four
# platforms) and its checks, the Windows command line under wine, the add-on and render tests in every supported Blender version (one venv each), and the reduced reports.
# Each stage is a script of its own and can be run alone.
set -euo pipefail
cd "$(dirname "$0")/.."
stage() { echo; echo "=== $* ($(date -u +%H:%M:%S))"; }
# Every temporary file of the run (pytest's, the Blender sessions' blender_* folders, the reports') goes into one
# folder, removed at the end; a failed run keeps it and says where.
run_tmp=$(mktemp -d)
export TMPDIR=$run_tmp
cleanup() { if [ $? -eq 0 ]; then rm -rf "$run_tmp"; else echo "test-all: temporary files kept in $run_tmp" >&2; fi; }
trap cleanup EXIT
stage setup; bash scripts/setup-python.sh --test
# The Rust targets of the Windows and macOS builds (lint's clippy and the extension stage need them), MinGW-w64 and
# wine (apt, as root) where missing.
bash scripts/setup-cross.sh --wine
stage lint; bash scripts/lint.sh
stage rust; bash scripts/test-rust.sh
# libFuzzer smoke run: each fuzz target for a few seconds from the committed seed corpus (cargo-fuzz, installed if
# missing).
stage fuzz; bash scripts/fuzz-smoke.sh
stage python; bash scripts/test-python.sh
# The Blender extension (built and validated by Blender's own validator), then the add-on and render tests via bpy in
# each version of scripts/pins/blender-versions.txt.
stage extension; bash scripts/build_addon.sh
# The builds for other platforms: scripts/check_wheels.py's rules on fixtures and every check on the four zips and
# their wheels; the Windows command line (cargo, x86_64-pc-windows-gnu) under wine writes the Linux one's maps.
stage cross; .venv/bin/python -m pytest tests/build -q
stage blender; bash scripts/setup-blender.sh && bash scripts/test-blender.sh
# The map performance report in its reduced form, so the report code cannot rot (the full one: docs/maps-performance.md).
stage reports
.venv/bin/python scripts/reports/maps_report.py --quick --out "$run_tmp/maps-performance.md"
# The Live-mode cost report, reduced (the full one: .venv-blender/5.0/bin/python scripts/reports/live_mode_report.py).
.venv-blender/5.0/bin/python scripts/reports/live_mode_report.py --quick --out "$run_tmp/live-mode.md"
# The look-dev sheet, reduced (the full one: .venv/bin/python scripts/reports/lookdev_sheet.py).
.venv-blender/5.0/bin/python scripts/reports/lookdev_sheet.py --out "$run_tmp/lookdev" --width 240 --samples 2
# The accuracy-vs-time report, reduced (the full one: bash scripts/accuracy_report.sh).
bash scripts/accuracy_report.sh --quick
stage done
