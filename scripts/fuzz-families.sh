#!/usr/bin/env bash
# Runs every model-family fuzz target of fuzz/ (each family of the core on
# its own: backbone, maxwell, fractional, iwan, xf, stack, friction,
# viscous, oscillator, six_dof, tracker, fixed_point) for SECONDS each, one
# after the other, and prints per family the runs libFuzzer made and the
# result. Exits non-zero if any target failed; the crash input is kept in
# fuzz/artifacts/<family>/ and the whole log in fuzz-families/ of cargo's
# target folder.
#
#   scripts/fuzz-families.sh [SECONDS] [FAMILY...]
#
# SECONDS defaults to 600 (the 10 minutes per family of the release
# check); FAMILY defaults to every family target. Uses cargo-fuzz
# (installed if missing) with the stable toolchain (RUSTC_BOOTSTRAP=1) and
# no sanitizer. The `step_models` target (any family) and `scene_parser`
# are not run here.
set -euo pipefail
cd "$(dirname "$0")/.."

seconds=${1:-600}
shift || true
if ! [[ $seconds =~ ^[0-9]+$ ]] || [ "$seconds" -eq 0 ]; then
    echo "usage: $0 [SECONDS] [FAMILY...]" >&2
    exit 2
fi

export RUSTC_BOOTSTRAP=1
command -v cargo-fuzz >/dev/null 2>&1 || cargo install --locked cargo-fuzz

if [ $# -gt 0 ]; then
    families=("$@")
else
    mapfile -t families < <(cargo fuzz list | grep -vx -e scene_parser -e step_models)
fi

echo "building the fuzz targets"
cargo fuzz build --sanitizer none

. scripts/target-dir.sh
logs="$target/fuzz-families"
mkdir -p "$logs"
failed=()
printf '%-12s %14s %9s  %s\n' family runs seconds result
for family in "${families[@]}"; do
    log="$logs/$family.log"
    if cargo fuzz run --sanitizer none "$family" -- -max_total_time="$seconds" >"$log" 2>&1; then
        result=ok
    else
        result="FAILED ($(grep -o 'Test unit written to .*' "$log" | tail -n 1 | sed 's/Test unit written to //' || true))"
        failed+=("$family")
    fi
    done_line=$(grep -E '^Done [0-9]+ runs in [0-9]+ second' "$log" | tail -n 1 || true)
    runs=$(sed -E 's/^Done ([0-9]+) runs.*/\1/' <<<"$done_line")
    secs=$(sed -E 's/.* in ([0-9]+) second.*/\1/' <<<"$done_line")
    if [ -z "$done_line" ]; then
        runs=$(grep -oE '^#[0-9]+' "$log" | tail -n 1 | tr -d '#' || true)
        secs=-
    fi
    printf '%-12s %14s %9s  %s\n' "$family" "${runs:--}" "${secs:--}" "$result"
done

if [ ${#failed[@]} -gt 0 ]; then
    echo "failed: ${failed[*]} (logs in $logs/)" >&2
    exit 1
fi
echo "every family ran ${seconds} s with no failure"
