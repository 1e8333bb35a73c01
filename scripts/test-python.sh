#!/usr/bin/env bash
# The Python bindings' tests and the type stubs checked against the built module (needs .venv: scripts/setup-python.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
.venv/bin/python -m pytest tests/python -q
.venv/bin/python -m mypy.stubtest spectral_skin._core
