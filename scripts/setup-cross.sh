#!/usr/bin/env bash
# What the cross builds of scripts/build_addon.sh and the Windows test under wine (tests/build) need on a Linux x64
# machine, installed where missing: the Rust standard library for x86_64-pc-windows-gnu, x86_64-apple-darwin and
# aarch64-apple-darwin (rustup), and Debian's MinGW-w64 (gcc-mingw-w64-x86-64: the Windows linker) and, with --wine,
# wine (wine, wine64: Debian 12's wine 8) through apt, as root. The macOS wheels need only zig, from .venv
# (scripts/pins/requirements-dev.txt).
#
#   bash scripts/setup-cross.sh          # Rust targets and MinGW-w64 (scripts/build_addon.sh runs this)
#   bash scripts/setup-cross.sh --wine   # and wine (scripts/test-all.sh runs this before tests/build)
set -euo pipefail
cd "$(dirname "$0")/.."
wine=0
case "${1:-}" in
    "") ;;
    --wine) wine=1 ;;
    *) echo "usage: bash scripts/setup-cross.sh [--wine]" >&2; exit 2 ;;
esac
say() { echo "setup-cross: $*"; }
[ "$(uname -s)-$(uname -m)" = Linux-x86_64 ] || { echo "setup-cross: the cross builds are set up for Linux x64" >&2; exit 1; }
command -v rustup >/dev/null || { echo "setup-cross: no rustup: the Rust toolchain is installed with rustup (https://rustup.rs)" >&2; exit 1; }
installed=$(rustup target list --installed)
for target in x86_64-pc-windows-gnu x86_64-apple-darwin aarch64-apple-darwin; do
    if ! grep -qx "$target" <<<"$installed"; then
        say "adding the Rust standard library for $target"
        rustup target add "$target"
    fi
done
packages=()
command -v x86_64-w64-mingw32-gcc >/dev/null || packages+=(gcc-mingw-w64-x86-64)
if [ "$wine" -eq 1 ] && ! command -v wine >/dev/null; then
    packages+=(wine wine64)
fi
if [ ${#packages[@]} -gt 0 ]; then
    if [ "$(id -u)" -ne 0 ]; then
        echo "setup-cross: missing ${packages[*]}: sudo apt-get install ${packages[*]}" >&2
        exit 1
    fi
    say "installing ${packages[*]} (apt)"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${packages[@]}" >/dev/null
fi
ready="$(x86_64-w64-mingw32-gcc --version | head -1)"
[ "$wine" -eq 0 ] || ready+=", $(wine --version 2>/dev/null)"
say "ready: $ready"
