#!/usr/bin/env bash
# The rig-loop firmware under QEMU, checked against bushing-sim:
#   1. the Cortex-M4F build (f32, mps2-an386) and the Cortex-M3 build (Q16,
#      mps2-an385) each run the 10 000 periods of scenes/rig-loop.toml and
#      exit with their verdict (no overrun, no ADC underrun, no transfer
#      error, tracker within 1 %, M4F flash <= 64 KiB and static RAM
#      <= 16 KiB);
#   2. bushing-sim runs the same scene in f32 and in f64;
#   3. the M4F force trace must equal the f32 host trace bit for bit, and the
#      M3 trace must stay within one DAC step (0.125 N) of the f64 trace;
#   4. the panic-never link check: both release images link with
#      `panic-never` (no panicking branch left), and the M4F image fails to
#      link when a bounds-checked index is added on purpose (feature
#      deliberate-panic).
# Logs and traces go to target/rig-loop/. Needs the Cortex-M targets and
# qemu-system-arm (scripts/test.sh installs them).
set -euo pipefail
cd "$(dirname "$0")/.."
out=target/rig-loop
mkdir -p "$out"
step() { printf '\n==> %s\n' "$*"; }
summary() { grep -E '^(rig-loop|periods|instructions|memory|tracker|verdict)' "$1"; }

step "rig loop on the Cortex-M4F (f32) in QEMU"
cargo run -q --release -p bushing-boards --target thumbv7em-none-eabihf --bin rig-loop >"$out/m4f.log" \
    || { tail -n 8 "$out/m4f.log"; exit 1; }
summary "$out/m4f.log"

step "rig loop on the Cortex-M3 (Q16) in QEMU"
cargo run -q --release -p bushing-boards --target thumbv7m-none-eabi --bin rig-loop >"$out/m3.log" \
    || { tail -n 8 "$out/m3.log"; exit 1; }
summary "$out/m3.log"

step "the same scene in bushing-sim, f32 and f64"
cargo build -q --release -p bushing-sim
./target/release/bushing-sim run scenes/rig-loop.toml --out "$out/host-f32" >"$out/host-f32.log"
./target/release/bushing-sim run scenes/rig-loop.toml --out "$out/host-f64" --number f64 >"$out/host-f64.log"

step "M4F force trace against bushing-sim f32: bit for bit"
./target/release/bushing-sim compare-trace "$out/host-f32/trace.csv" "$out/m4f.log"

step "M3 (Q16) force trace against bushing-sim f64: within one DAC step"
./target/release/bushing-sim compare-trace "$out/host-f64/trace.csv" "$out/m3.log" --within 0.125

step "panic-never link check of the release images (M4F f32, M3 Q16)"
for target in thumbv7em-none-eabihf thumbv7m-none-eabi; do
    cargo build -q --release -p bushing-boards --target "$target" --bin rig-loop \
        --features panic-never
    echo "$target: links with panic-never, no panicking branch"
done
if cargo build -q --release -p bushing-boards --target thumbv7em-none-eabihf --bin rig-loop \
    --features panic-never,deliberate-panic 2>"$out/deliberate-panic.txt"; then
    echo "error: the image with a deliberate panic path linked" >&2
    exit 1
fi
grep -o 'error(panic-never): [^"]*' "$out/deliberate-panic.txt" | head -n 1
echo "with a deliberate bounds-checked index: the link fails, as it must"
