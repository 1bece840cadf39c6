#!/usr/bin/env bash
# The project's test command. On a machine that has only Rust it installs
# what is missing (Cortex-M targets, clippy/rustfmt, QEMU, valgrind, gcc,
# arm-none-eabi-gcc, and python3 with venv for the FMU's validator), then
# runs:
#   1. formatting and lints (host, and the Cortex-M crates for the target);
#   2. core-nostd builds for Cortex-M4F (thumbv7em-none-eabihf) and
#      Cortex-M3 without FPU (thumbv7m-none-eabi), in floating and fixed
#      point;
#   3. the Cortex-M suite under QEMU: M4F debug and release, M3 release,
#      M7 release (mps2-an500, the M4F target built for the Cortex-M7),
#      and the named hard cases on both cores; QEMU's exit code is the
#      verdict, a hang is killed by `timeout`;
#   4. the accuracy-cost report in its quick mode: the kernel-cost firmware
#      on both cores under QEMU, the peer Kalman crates on the host and in
#      QEMU, and the generator (into target/, so that it cannot rot);
#   5. the host tests (unit, integration, doc), the firmware drivers on
#      embedded-hal-mock, and the rig loop of scripts/rig-loop.sh: both
#      firmwares in QEMU against bushing-sim (their defmt logs decoded),
#      and the panic-never link check; then the C API of scripts/c-api.sh
#      (the header, a host C test, the C rig loop in QEMU);
#   6. the core as a crate a firmware engineer picks up: the firmware
#      template run in QEMU from a folder outside the workspace
#      (scripts/template.sh), the package files, `cargo publish --dry-run`,
#      the docs with every feature and no rustdoc warning, the doctests;
#   8. every scene of scenes/ run with the README's command form;
#   9. a scene's cost against its parts in host instructions (callgrind),
#      printed, never asserted.
# Costs and timings are printed, never asserted.
set -euo pipefail
cd "$(dirname "$0")/.."

as_root() {
    if [ "$(id -u)" -eq 0 ]; then "$@"
    elif command -v sudo >/dev/null 2>&1; then sudo "$@"
    else echo "error: need root to run: $*" >&2; return 1
    fi
}

step() { printf '\n==> %s\n' "$*"; }

step "toolchain: Cortex-M targets, clippy, rustfmt, llvm-tools"
installed_targets=$(rustup target list --installed)
for target in thumbv7em-none-eabihf thumbv7m-none-eabi; do
    grep -qx "$target" <<<"$installed_targets" || rustup target add "$target"
done
installed_components=$(rustup component list --installed)
for component in clippy rustfmt llvm-tools; do
    grep -q "^$component" <<<"$installed_components" || rustup component add "$component"
done

missing=()
command -v qemu-system-arm >/dev/null 2>&1 || missing+=(qemu-system-arm)
command -v gcc >/dev/null 2>&1 || missing+=(gcc)
command -v arm-none-eabi-gcc >/dev/null 2>&1 || missing+=(gcc-arm-none-eabi)
command -v valgrind >/dev/null 2>&1 || missing+=(valgrind)
python3 -c 'import venv, ensurepip' >/dev/null 2>&1 || missing+=(python3 python3-venv)
if [ ${#missing[@]} -gt 0 ]; then
    step "installing ${missing[*]}"
    as_root apt-get update -qq
    as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}" >/dev/null
fi
qemu-system-arm --version | head -n 1
valgrind --version
arm-none-eabi-gcc --version | head -n 1

. scripts/target-dir.sh
echo "cargo builds into $target"
# A test run builds everything once: incremental state would only fill the
# disk (over a gigabyte for the host tests alone).
export CARGO_INCREMENTAL=0
df -h . | tail -n 1 | awk '{print "disk: " $4 " free of " $2}'

step "format"
cargo fmt --all -- --check

step "lints (host, all targets)"
cargo clippy --workspace --all-targets -- -D warnings

step "lints (Cortex-M4F: core, suite, firmware)"
cargo clippy -p bushing --target thumbv7em-none-eabihf -- -D warnings
cargo clippy -p bushing --features micromath --target thumbv7em-none-eabihf -- -D warnings
cargo clippy -p bushing --features fixed --target thumbv7m-none-eabi -- -D warnings
cargo clippy -p bushing --features serde --target thumbv7em-none-eabihf -- -D warnings
cargo clippy -p bushing --features defmt,fixed --target thumbv7m-none-eabi -- -D warnings
cargo clippy -p bushing-c --target thumbv7em-none-eabihf -- -D warnings
cargo clippy -p bushing-c --target thumbv7m-none-eabi -- -D warnings
cargo clippy -p bushing-kernels --target thumbv7em-none-eabihf -- -D warnings
cargo clippy -p bushing-kernels --features fixed --target thumbv7m-none-eabi -- -D warnings
cargo clippy -p bushing-tests --target thumbv7em-none-eabihf --test cortex_m --test hard_cases -- -D warnings
cargo clippy -p bushing-boards --target thumbv7em-none-eabihf --bins -- -D warnings
cargo clippy -p bushing-boards --target thumbv7m-none-eabi --bins -- -D warnings
cargo clippy -p bushing-boards --features peers --bins -- -D warnings
cargo clippy -p bushing-boards --features peers --target thumbv7em-none-eabihf --bins -- -D warnings

step "core-nostd for Cortex-M4F and Cortex-M3 (no FPU)"
cargo build -p bushing --release --target thumbv7em-none-eabihf
cargo build -p bushing --release --target thumbv7m-none-eabi
cargo build -p bushing --release --features fixed --target thumbv7m-none-eabi

step "Cortex-M suite in QEMU: M4F (mps2-an386), debug and release"
cargo test -p bushing-tests --target thumbv7em-none-eabihf --test cortex_m
cargo test -p bushing-tests --target thumbv7em-none-eabihf --test cortex_m --release

step "Cortex-M suite in QEMU: M3 (mps2-an385), soft float, release"
cargo test -p bushing-tests --target thumbv7m-none-eabi --test cortex_m --release

step "Cortex-M suite in QEMU: M7 (mps2-an500, double-precision FPU), release"
# The M4F target built for the Cortex-M7 (f64 in hardware), in a build
# folder of its own, run on QEMU's Cortex-M7 board.
CARGO_TARGET_THUMBV7EM_NONE_EABIHF_RUSTFLAGS="-C target-cpu=cortex-m7" \
CARGO_TARGET_THUMBV7EM_NONE_EABIHF_RUNNER="timeout -k 5 300 qemu-system-arm -machine mps2-an500 -cpu cortex-m7 -nographic -semihosting-config enable=on,target=native -icount shift=0,sleep=off -kernel" \
    cargo test -p bushing-tests --target thumbv7em-none-eabihf --test cortex_m --release \
    --target-dir "$target/m7"

step "named hard cases in QEMU: M4F and M3, release (docs/hard-cases.md)"
cargo test -p bushing-tests --target thumbv7em-none-eabihf --test hard_cases --release
cargo test -p bushing-tests --target thumbv7m-none-eabi --test hard_cases --release

step "accuracy-cost report, quick mode (kernel-cost and kalman-peers in QEMU)"
./scripts/accuracy-cost.sh --quick

step "host tests"
cargo test
cargo test --release -p bushing-tests --test long_run -- --nocapture
cargo test -p bushing-boards --lib

step "rig-loop firmware in QEMU against bushing-sim, panic-never link check"
./scripts/rig-loop.sh

step "C API: header, host C test, the C rig loop in QEMU against the Rust one"
./scripts/c-api.sh

step "FMU: fmpy's validation, bit for bit against bushing-sim, rollback, misuse, time per step"
./scripts/fmu.sh

step "the firmware template, copied outside the workspace, built and run in QEMU"
./scripts/template.sh

step "the core as a published crate: files, publish dry run, docs and doctests with every feature"
cargo package --list -p bushing | tr '\n' ' ' | fold -w 100 -s
echo
cargo publish --dry-run -p bushing
RUSTDOCFLAGS="-D rustdoc::all" cargo doc -p bushing --all-features --no-deps
cargo test --doc -p bushing --all-features

step "fuzz targets build (run them with cargo fuzz: docs/hard-cases.md)"
cargo check --quiet --manifest-path fuzz/Cargo.toml --target-dir "$target/fuzz-check"

step "every scene, with the README's command form (run SCENE --out DIR)"
cargo build -q -p bushing-sim --release
# This step's own folders (an output of an older bushing-sim, from before
# outputs were marked, would be refused rather than replaced).
rm -rf "$target/scenes" "$target/powertrain"
find scenes -name '*.toml' | sort | while read -r scene; do
    name=${scene#scenes/}
    out="$target/scenes/${name%.toml}"
    mkdir -p "$(dirname "$out")"
    "$target/release/bushing-sim" run "$scene" --out "$out" >"$out.log" 2>&1 \
        || { cat "$out.log"; echo "error: $scene failed" >&2; exit 1; }
    printf '%-48s %s\n' "$scene" "$(grep -E '^steps' "$out.log" | tr -s ' ')"
done

step "powertrain on three 6-DOF mounts: modes, stop/start transient, plots (docs/six-dof.md)"
"$target/release/bushing-sim" powertrain --out "$target/powertrain"

step "scene cost against the sum of its parts (host instructions, callgrind)"
cargo run -q -p bushing-sim --release -- cost --instructions scenes/maxwell4.toml
