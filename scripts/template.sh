#!/usr/bin/env bash
# The firmware template (templates/firmware) as a new user takes it: copied
# to a temporary folder outside the workspace, its `bushing` dependency
# patched to this checkout's core, then checked with rustfmt and clippy,
# built and run in QEMU (its own runner); the run's summary is checked.
# Needs the Cortex-M4F target and qemu-system-arm (scripts/test.sh installs
# them).
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$(pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cp -r templates/firmware "$tmp/firmware"
cd "$tmp/firmware"
printf '\n# Added by scripts/template.sh: the core of this checkout.\n[patch.crates-io]\nbushing = { path = "%s/core-nostd" }\n' \
    "$repo" >>Cargo.toml
export CARGO_TARGET_DIR="$tmp/target"
cargo fmt --check
cargo clippy -q --release -- -D warnings
timeout -k 5 600 cargo run -q --release >run.log || { cat run.log; exit 1; }
cat run.log
grep -qx 'verdict pass' run.log
grep -Eq '^template periods 5000 peak_force_n [0-9]+ .* faults NONE$' run.log
echo "the template builds and runs from $tmp, outside the workspace"
