#!/usr/bin/env bash
# Fuzz smoke run (CI): build the libFuzzer targets in fuzz/ (cargo-fuzz) and run each for a few seconds, starting
# from the committed seed corpus (fuzz/seeds/<target>); a crash, panic, failed assertion, out-of-memory or an input
# running over the timeout fails the stage, and libFuzzer leaves the input in fuzz/artifacts/<target>/.
# FUZZ_SECONDS sets the seconds per target (default 10). FUZZ_SANITIZER (default none) is cargo-fuzz's --sanitizer:
# the smoke run checks that the targets build and hold on the seeds and their first mutations, and without a
# sanitizer its build takes about 40 % less CPU; the longer run (docs/robustness.md, "Fuzzing") uses address.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${FUZZ_SECONDS:-10}
sanitizer=${FUZZ_SANITIZER:-none}
# Memory (-rss_limit_mb, the process's resident size): param_map reads images up to MAX_TEXELS, and a few bytes of
# compressed EXR can be a 4096 x 4096 map whose four f32 planes (256 MB) and decompressed blocks (up to 64 at once,
# read_exr_planes) the reader fills, by design (docs/robustness.md, Fuzzing), and glibc's per-thread arenas likely keep
# freed blocks. Measured without a sanitizer: peak 57 to 549 MB in five 10 s runs (370-570 MB in 40-120 s), while
# no input of a 40 s run's corpus (2599) peaks above 53 MB when replayed alone, and LeakSanitizer finds no leak in
# 60 s. At 512 MB one run in five failed on an empty input; 2048 leaves a margin. AddressSanitizer counts every
# (even untouched) allocation and keeps freed memory in quarantine, so it gets 4096.
if [ "$sanitizer" = none ]; then rss_mb=2048; else rss_mb=4096; fi
# cargo-fuzz passes nightly-only flags (-Z sanitizer, -C passes=sancov...); RUSTC_BOOTSTRAP=1 lets the stable
# toolchain accept them, so CI needs no nightly.
export RUSTC_BOOTSTRAP=1
if ! cargo fuzz --version >/dev/null 2>&1; then
    cargo install cargo-fuzz --locked --version 0.13.2
fi
cd fuzz
cargo fuzz build --sanitizer "$sanitizer"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for target in $(cargo fuzz list); do
    mkdir -p "$work/$target"
    # New inputs go to the first (scratch) folder; the seeds are only read.
    if ! cargo fuzz run --sanitizer "$sanitizer" "$target" "$work/$target" "seeds/$target" -- \
        -max_total_time="$seconds" -timeout=60 \
        -rss_limit_mb="$rss_mb" -print_final_stats=1 >"$work/$target.log" 2>&1; then
        tail -n 40 "$work/$target.log"
        echo "fuzz-smoke: $target FAILED (input saved under fuzz/artifacts/$target/)"
        exit 1
    fi
    runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$work/$target.log" | grep -o '[0-9]*$')
    echo "fuzz-smoke: $target ok, $runs executions in ${seconds} s, corpus $(ls "$work/$target" | wc -l) new inputs"
done
