#!/usr/bin/env bash
# Regenerates the accuracy-cost report: docs/accuracy-cost.md, .csv and .svg
# (error against cost of every scheme, order and number type).
#
#   scripts/accuracy-cost.sh           full report into docs/
#   scripts/accuracy-cost.sh --quick   every code path, fewer frequencies,
#                                      steps and repeats, no callgrind, into
#                                      target/accuracy-cost/quick/ (CI)
#
# 1. builds and runs the kernel-cost firmware under QEMU for the Cortex-M4F
#    (thumbv7em-none-eabihf) and the Cortex-M3 (thumbv7m-none-eabi, software
#    floating point); keeps each output and a copy of each ELF in
#    target/accuracy-cost/;
# 2. runs kalman-peers on the host and on the Cortex-M4F when the firmware
#    crate has that binary;
# 3. runs `bushing-sim accuracy-cost` on those files.
#
# Needs what scripts/test.sh installs (the two targets, qemu-system-arm;
# valgrind for the host instruction counts of the full report). Timings are
# printed, never asserted.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/target-dir.sh

mode=()
out=docs
case "${1:-}" in
    --quick) mode=(--quick); out="$target/accuracy-cost/quick" ;;
    "") ;;
    *) echo "usage: scripts/accuracy-cost.sh [--quick]" >&2; exit 2 ;;
esac
[ $# -le 1 ] || { echo "usage: scripts/accuracy-cost.sh [--quick]" >&2; exit 2; }

work="$target/accuracy-cost"
mkdir -p "$work" "$out"

kernels=()
elfs=()
for triple in thumbv7em-none-eabihf thumbv7m-none-eabi; do
    echo "==> kernel-cost on $triple (QEMU)"
    log="$work/kernel-cost-$triple.txt"
    cargo run -q --release -p bushing-boards --target "$triple" --bin kernel-cost >"$log"
    # The ELF that printed these lines (for code sizes and footprint).
    cp "$target/$triple/release/kernel-cost" "$work/kernel-cost-$triple.elf"
    grep -c '^kernel ' "$log" | sed "s/^/    kernel lines: /"
    kernels+=("$log")
    elfs+=("$triple=$work/kernel-cost-$triple.elf")
done

peers=()
if grep -q 'kalman-peers' board-examples/Cargo.toml; then
    echo "==> kalman-peers on the host"
    cargo run -q --release -p bushing-boards --features peers --bin kalman-peers >"$work/kalman-peers-host.txt"
    peers+=("$work/kalman-peers-host.txt")
    echo "==> kalman-peers on thumbv7em-none-eabihf (QEMU)"
    cargo run -q --release -p bushing-boards --features peers --target thumbv7em-none-eabihf \
        --bin kalman-peers \
        >"$work/kalman-peers-m4f.txt"
    peers+=("$work/kalman-peers-m4f.txt")
else
    echo "==> no kalman-peers binary yet: the peer table says so"
fi

echo "==> bushing-sim accuracy-cost ${mode[*]:-} --out $out"
args=(accuracy-cost ${mode[@]+"${mode[@]}"} --kernels "${kernels[@]}" --elf "${elfs[@]}")
if [ ${#peers[@]} -gt 0 ]; then
    args+=(--peers "${peers[@]}")
fi
cargo run -q --release -p bushing-sim -- "${args[@]}" --out "$out"
