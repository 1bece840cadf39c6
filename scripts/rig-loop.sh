#!/usr/bin/env bash
# The rig-loop firmware under QEMU, checked against bushing-sim:
#   1. the Cortex-M4F build (f32, mps2-an386) and the Cortex-M3 build (Q16,
#      mps2-an385) each run the 10 000 periods of scenes/rig-loop.toml and
#      exit with their verdict (no overrun, no ADC underrun, no transfer
#      error, tracker within 1 %, M4F flash <= 64 KiB and static RAM
#      <= 16 KiB); each logs with defmt, and its log is decoded with the
#      ELF by bushing-defmt-log, which fails on a malformed or truncated
#      log (shown on two damaged copies of the M4F log);
#   2. bushing-sim runs the same scene in f32 and in f64;
#   3. the M4F force trace must equal the f32 host trace bit for bit, and the
#      M3 trace must stay within one DAC step (0.125 N) of the f64 trace;
#   4. the every-model firmware (every public model and tracker of the core,
#      built from black-boxed parameters and stepped) runs on both cores:
#      f32 on the M4F, Q16 on the M3 (the oscillator and the tracker in f32
#      soft float); it fails if a model refuses its parameters or faults;
#   5. the panic-never link check: the release images of the rig loop and of
#      every-model link with `panic-never` on both cores (no panicking
#      branch left), and the M4F rig loop fails to link when a bounds-checked
#      index is added on purpose (feature deliberate-panic).
# Logs and traces go to rig-loop/ in cargo's target folder. Needs the Cortex-M targets and
# qemu-system-arm (scripts/test.sh installs them).
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/target-dir.sh
out="$target/rig-loop"
sim="$target/release/bushing-sim"
mkdir -p "$out"
step() { printf '\n==> %s\n' "$*"; }
summary() { grep -E '^(rig-loop|periods|instructions|memory|tracker|verdict)' "$1"; }
decoder="$target/release/bushing-defmt-log"
cargo build -q --release -p bushing-defmt-log

# rig TARGET NAME: runs the rig loop in QEMU (its defmt bytes into
# NAME.defmt), decodes them into NAME.log and checks what they say.
rig() {
    local status=0
    cargo run -q --release -p bushing-boards --target "$1" --bin rig-loop >"$out/$2.defmt" \
        || status=$?
    rm -f "$out/$2.log"
    if ! "$decoder" "$target/$1/release/rig-loop" "$out/$2.defmt" >"$out/$2.log"; then
        echo "error: the $2 rig loop's defmt log does not decode" >&2
        exit 1
    fi
    if [ "$status" -ne 0 ]; then
        tail -n 8 "$out/$2.log"
        exit 1
    fi
    summary "$out/$2.log"
    # The verdict, the fault flags by name and the tracker's last estimate
    # (the core's defmt::Format of Faults and ModeStatus), as decoded.
    grep -qx 'verdict pass' "$out/$2.log" \
        && grep -Eq '^periods 10000 .* faults NONE$' "$out/$2.log" \
        && grep -Eq ' last Some\(ModeStatus \{ frequency: [0-9.]+, damping: .*faded: false \}\)$' "$out/$2.log" \
        || { echo "error: the $2 log lacks its verdict, fault names or tracker estimate" >&2; exit 1; }
}

step "rig loop on the Cortex-M4F (f32) in QEMU, defmt log decoded"
rig thumbv7em-none-eabihf m4f

step "rig loop on the Cortex-M3 (Q16) in QEMU, defmt log decoded"
rig thumbv7m-none-eabi m3

step "the decoder refuses a damaged log: truncated mid-frame, and a frame inserted"
elf="$target/thumbv7em-none-eabihf/release/rig-loop"
head -c -2 "$out/m4f.defmt" >"$out/m4f-truncated.defmt"
{ head -c 5000 "$out/m4f.defmt"; printf '\377\377\377\000'; tail -c +5001 "$out/m4f.defmt"; } \
    >"$out/m4f-inserted.defmt"
for damaged in truncated inserted; do
    if "$decoder" "$elf" "$out/m4f-$damaged.defmt" >/dev/null 2>"$out/m4f-$damaged.txt"; then
        echo "error: the $damaged log decoded" >&2
        exit 1
    fi
    echo "$damaged: $(cat "$out/m4f-$damaged.txt")"
done

step "the same scene in bushing-sim, f32 and f64"
cargo build -q --release -p bushing-sim
# This script's own folders: an output of an older bushing-sim, from before
# outputs were marked, would be refused rather than replaced.
rm -rf "$out/host-f32" "$out/host-f64"
"$sim" run scenes/rig-loop.toml --out "$out/host-f32" >"$out/host-f32.log"
"$sim" run scenes/rig-loop.toml --out "$out/host-f64" --number f64 >"$out/host-f64.log"

step "M4F force trace against bushing-sim f32: bit for bit"
"$sim" compare-trace "$out/host-f32/trace.csv" "$out/m4f.log"

step "M3 (Q16) force trace against bushing-sim f64: within one DAC step"
"$sim" compare-trace "$out/host-f64/trace.csv" "$out/m3.log" --within 0.125

step "every model and tracker of the core in QEMU (M4F f32, M3 Q16)"
for target in thumbv7em-none-eabihf thumbv7m-none-eabi; do
    log="$out/every-model-$target.log"
    cargo run -q --release -p bushing-boards --target "$target" --bin every-model >"$log" \
        || { grep -Ev 'faults=0x0 not_finite=0$' "$log" | tail -n 20; exit 1; }
    grep -E '^(every-model|models|memory|verdict)' "$log"
    # The UKF with its mode count fixed at compile time steps the same
    # numbers as with it given at run time: the same checksum.
    sums=$(grep -E '^model tracker/modal-ukf(-modes-fixed)? ' "$log" | grep -o 'checksum=[0-9a-f]*' | sort -u)
    [ "$(grep -c . <<<"$sums")" = 1 ] \
        || { echo "error: the two forms of the modal UKF differ on $target:" >&2; echo "$sums" >&2; exit 1; }
    echo "$target: modal UKF, modes at run time and fixed at compile time, the same checksum ($sums)"
done

step "panic-never link check of the release images (rig loop, every model; M4F f32, M3 Q16)"
for target in thumbv7em-none-eabihf thumbv7m-none-eabi; do
    for bin in rig-loop every-model; do
        cargo build -q --release -p bushing-boards --target "$target" --bin "$bin" \
            --features panic-never
        echo "$target $bin: links with panic-never, no panicking branch"
    done
done
if cargo build -q --release -p bushing-boards --target thumbv7em-none-eabihf --bin rig-loop \
    --features panic-never,deliberate-panic 2>"$out/deliberate-panic.txt"; then
    echo "error: the image with a deliberate panic path linked" >&2
    exit 1
fi
grep -o 'error(panic-never): [^"]*' "$out/deliberate-panic.txt" | head -n 1
echo "with a deliberate bounds-checked index: the link fails, as it must"
