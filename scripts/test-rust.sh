#!/usr/bin/env bash
# Rust unit, integration and property tests (release mode: the Monte Carlo references need it).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo test --release
