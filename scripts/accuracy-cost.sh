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
#    (thumbv7em-none-eabihf), the Cortex-M7 (the same target built for it,
#    in QEMU's mps2-an500) and the Cortex-M3 (thumbv7m-none-eabi, software
#    floating point), with the bushing-qemu-mix plugin recording the
#    instructions each measurement executed; keeps each output, mix, ELF and
#    disassembly (llvm-objdump of rustup's llvm-tools) in
#    target/accuracy-cost/; then the headline kernels alone in a binary of
#    their own (feature headline-only), on the Cortex-M4F, for the spread
#    of the harness between builds;
# 2. runs kalman-peers on the host and on the Cortex-M4F when the firmware
#    crate has that binary;
# 3. runs `bushing-sim accuracy-cost` on those files.
#
# Needs what scripts/test.sh installs (the two targets, llvm-tools, qemu-system-arm;
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

# The executed-instruction mix of each run (estimated cycles): the QEMU
# plugin of qemu-mix/, and the disassembly of the ELF that ran.
cargo build -q --release -p bushing-qemu-mix
plugin="$target/release/libbushing_qemu_mix.so"
objdump="$(rustc --print sysroot)/lib/rustlib/$(rustc -vV | sed -n 's/^host: //p')/bin/llvm-objdump"
[ -x "$objdump" ] || { echo "error: no $objdump (rustup component add llvm-tools)" >&2; exit 1; }

# Runs an ELF of the kernel-cost firmware under QEMU with the plugin:
#   measure ELF LOG MIX MACHINE-ARGS...
# and writes its disassembly beside the ELF (.dis for .elf).
measure() {
    local elf=$1 log=$2 mix=$3
    shift 3
    rm -f "$log" "$mix"
    # The runner of .cargo/config.toml, with the plugin.
    timeout -k 5 300 qemu-system-arm "$@" -nographic \
        -semihosting-config enable=on,target=native -icount shift=0,sleep=off \
        -plugin "$plugin,elf=$elf,out=$mix" -kernel "$elf" >"$log"
    "$objdump" -d --no-show-raw-insn "$elf" >"${elf%.elf}.dis"
}

kernels=()
elfs=()
mixes=()
disassemblies=()
for triple in thumbv7em-none-eabihf thumbv7m-none-eabi; do
    echo "==> kernel-cost on $triple (QEMU, with the instruction-mix plugin)"
    case "$triple" in
        thumbv7em-none-eabihf) machine=(-machine mps2-an386 -cpu cortex-m4) ;;
        thumbv7m-none-eabi) machine=(-machine mps2-an385 -cpu cortex-m3) ;;
    esac
    cargo build -q --release -p bushing-boards --target "$triple" --bin kernel-cost
    # The ELF that printed these lines (for code sizes, footprint and the
    # disassembly the mix is mapped onto).
    elf="$work/kernel-cost-$triple.elf"
    cp "$target/$triple/release/kernel-cost" "$elf"
    log="$work/kernel-cost-$triple.txt"
    mix="$work/mix-$triple.txt"
    measure "$elf" "$log" "$mix" "${machine[@]}"
    grep -c '^kernel ' "$log" | sed "s/^/    kernel lines: /"
    kernels+=("$log")
    elfs+=("$triple=$elf")
    mixes+=("$triple=$mix")
    disassemblies+=("$triple=$work/kernel-cost-$triple.dis")
done

# The Cortex-M7: the M4F target built for it (f64 in hardware), in a build
# folder of its own, on QEMU's mps2-an500. Instructions only: the cycle
# model covers the Cortex-M4 and the Cortex-M3.
echo "==> kernel-cost on the Cortex-M7 (thumbv7em-none-eabihf, target-cpu=cortex-m7; QEMU mps2-an500)"
m7="$work/cortex-m7"
mkdir -p "$m7"
BUSHING_KERNEL_TARGET=m7 CARGO_TARGET_DIR="$m7/target" \
CARGO_TARGET_THUMBV7EM_NONE_EABIHF_RUSTFLAGS="-C target-cpu=cortex-m7" \
    cargo build -q --release -p bushing-boards --target thumbv7em-none-eabihf --bin kernel-cost
cp "$m7/target/thumbv7em-none-eabihf/release/kernel-cost" "$m7/kernel-cost.elf"
measure "$m7/kernel-cost.elf" "$work/kernel-cost-cortex-m7.txt" "$m7/mix.txt" \
    -machine mps2-an500 -cpu cortex-m7
grep -c '^kernel ' "$work/kernel-cost-cortex-m7.txt" | sed "s/^/    kernel lines: /"
kernels+=("$work/kernel-cost-cortex-m7.txt")

# The headline kernels again, in a binary of their own (feature
# headline-only): the harness's spread between two builds.
echo "==> kernel-cost, headline kernels alone, on thumbv7em-none-eabihf (QEMU, with the plugin)"
cargo build -q --release -p bushing-boards --target thumbv7em-none-eabihf --bin kernel-cost \
    --features headline-only
alone="$work/kernel-cost-headline.elf"
cp "$target/thumbv7em-none-eabihf/release/kernel-cost" "$alone"
measure "$alone" "$work/kernel-cost-headline.txt" "$work/mix-headline.txt" \
    -machine mps2-an386 -cpu cortex-m4
headline=(--headline-kernels "$work/kernel-cost-headline.txt"
    --headline-mix "$work/mix-headline.txt" --headline-disassembly "$work/kernel-cost-headline.dis")

peers=()
peers_mix=()
if grep -q 'kalman-peers' board-examples/Cargo.toml; then
    echo "==> kalman-peers on the host"
    cargo run -q --release -p bushing-boards --features peers --bin kalman-peers >"$work/kalman-peers-host.txt"
    peers+=("$work/kalman-peers-host.txt")
    echo "==> kalman-peers on thumbv7em-none-eabihf (QEMU, with the plugin)"
    cargo build -q --release -p bushing-boards --features peers --target thumbv7em-none-eabihf \
        --bin kalman-peers
    cp "$target/thumbv7em-none-eabihf/release/kalman-peers" "$work/kalman-peers-m4f.elf"
    measure "$work/kalman-peers-m4f.elf" "$work/kalman-peers-m4f.txt" "$work/mix-peers.txt" \
        -machine mps2-an386 -cpu cortex-m4
    peers+=("$work/kalman-peers-m4f.txt")
    peers_mix=(--peers-mix "$work/mix-peers.txt" --peers-disassembly "$work/kalman-peers-m4f.dis")
else
    echo "==> no kalman-peers binary yet: the peer table says so"
fi

# The full report compares the M4F build with the generic ARMv7E-M one (no
# target-cpu, as the flags of .cargo/config.toml are chosen on estimated
# cycles), measured the same way in a build folder of its own.
other=()
if [ ${#mode[@]} -eq 0 ]; then
    echo "==> kernel-cost on thumbv7em-none-eabihf, target-cpu=generic (QEMU, with the plugin)"
    generic="$work/generic-cpu"
    mkdir -p "$generic"
    RUSTFLAGS="-C target-cpu=generic" CARGO_TARGET_DIR="$generic/target" \
        cargo build -q --release -p bushing-boards --target thumbv7em-none-eabihf --bin kernel-cost
    cp "$generic/target/thumbv7em-none-eabihf/release/kernel-cost" "$generic/kernel-cost.elf"
    measure "$generic/kernel-cost.elf" "$generic/kernel-cost.txt" "$generic/mix.txt" \
        -machine mps2-an386 -cpu cortex-m4
    other=(--other-build "target-cpu=generic" --other-kernels "$generic/kernel-cost.txt"
        --other-mix "$generic/mix.txt" --other-disassembly "$generic/kernel-cost.dis")
fi

# The full report checks the cycle model against llvm-mca (Debian's llvm
# package) where it is installed.
if [ ${#mode[@]} -eq 0 ] && command -v llvm-mca >/dev/null 2>&1; then
    mca=(--llvm-mca "$(command -v llvm-mca)")
else
    mca=()
    [ ${#mode[@]} -gt 0 ] || echo "==> no llvm-mca: the report's cross-check says it did not run"
fi

echo "==> bushing-sim accuracy-cost ${mode[*]:-} --out $out"
args=(accuracy-cost ${mode[@]+"${mode[@]}"} --kernels "${kernels[@]}" --elf "${elfs[@]}"
    --mix "${mixes[@]}" --disassembly "${disassemblies[@]}" ${mca[@]+"${mca[@]}"}
    ${other[@]+"${other[@]}"} "${headline[@]}")
if [ ${#peers[@]} -gt 0 ]; then
    args+=(--peers "${peers[@]}" ${peers_mix[@]+"${peers_mix[@]}"})
fi
cargo run -q --release -p bushing-sim -- "${args[@]}" --out "$out"
