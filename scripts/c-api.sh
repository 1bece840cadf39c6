#!/usr/bin/env bash
# The C API (crate bushing-c, header c-api/include/bushing.h):
#   1. the committed header is cbindgen's output (cargo test --test header);
#   2. the host C test (c-api/tests/c/api_test.c), built with gcc -Wall
#      -Wextra -Werror against the host static library, runs every entry
#      point and every status code;
#   3. the C rig loop (c-api/examples/rig-loop), built with
#      arm-none-eabi-gcc against the Cortex-M static libraries, runs the
#      ADC codes of the Rust rig loop's run of scenes/rig-loop.toml in QEMU:
#      its force trace must equal the Rust rig loop's line for line on the
#      M4F (f32) and on the M3 (Q16), and bushing-sim's f32 trace bit for
#      bit (M4F) or its f64 trace within one DAC step (M3).
# Needs gcc, arm-none-eabi-gcc and QEMU (scripts/test.sh installs them),
# and the logs of scripts/rig-loop.sh, which runs first.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/target-dir.sh
out="$target/c-api"
mkdir -p "$out"
step() { printf '\n==> %s\n' "$*"; }

step "bushing.h is cbindgen's output"
cargo test -q -p bushing-c --test header

step "host C test: every entry point and status code"
cargo build -q -p bushing-c
# The libraries a Rust staticlib needs on the host, as rustc names them.
native=$(cargo rustc -q -p bushing-c --lib --crate-type staticlib -- --print native-static-libs 2>&1 \
    | sed -n 's/.*native-static-libs: //p' | tail -n 1)
gcc -std=c11 -Wall -Wextra -Werror -O1 -I c-api/include -I c-api/examples \
    c-api/tests/c/api_test.c "$target/debug/libbushing_c.a" $native -lm -o "$out/api_test"
"$out/api_test"
# Every function the header declares is called by the C test.
declared=$(grep -E '^[a-z].*[ *]bushing_[a-z0-9_]+\(' c-api/include/bushing.h \
    | grep -oE 'bushing_[a-z0-9_]+\(' | tr -d '(')
uncalled=$(for f in $declared; do grep -q "$f(" c-api/tests/c/api_test.c || echo "$f"; done)
if [ -n "$uncalled" ]; then
    echo "error: bushing.h functions the C test never calls: $uncalled" >&2
    exit 1
fi
echo "the C test calls all $(wc -w <<<"$declared") functions of bushing.h"

step "C rig loop on the Cortex-M static libraries, in QEMU, against the Rust rig loop"
rig="$target/rig-loop"
for f in m4f.log m3.log host-f32/trace.csv host-f64/trace.csv; do
    [ -f "$rig/$f" ] || { echo "error: $rig/$f missing: run scripts/rig-loop.sh first" >&2; exit 1; }
done
# The ADC codes of the Rust run, periods 1 to 10 000 (period 0, the
# start, is at code 0: the sweep starts at rest).
codes=$(awk '/^step /{print $3}' "$rig/m4f.log")
{
    echo "/* ADC codes of the Rust rig loop's run of scenes/rig-loop.toml. */"
    echo "#define RIG_PERIODS $(wc -l <<<"$codes")"
    echo "static const int16_t rig_codes[RIG_PERIODS] = {"
    paste -sd, <<<"$codes"
    echo "};"
} >"$out/codes.h"
src=c-api/examples/rig-loop
sim="$target/release/bushing-sim"
for core in m4f m3; do
    case $core in
        m4f) triple=thumbv7em-none-eabihf; machine=mps2-an386; cpu=cortex-m4
             cflags="-mcpu=cortex-m4 -mthumb -mfloat-abi=hard -mfpu=fpv4-sp-d16" ;;
        m3) triple=thumbv7m-none-eabi; machine=mps2-an385; cpu=cortex-m3
            cflags="-mcpu=cortex-m3 -mthumb -mfloat-abi=soft" ;;
    esac
    cargo build -q --release -p bushing-c --target "$triple"
    elf="$out/rig-loop-$core.elf"
    # shellcheck disable=SC2086
    arm-none-eabi-gcc $cflags -std=c11 -O2 -ffreestanding -nostdlib -Wall -Wextra -Werror \
        -ffunction-sections -fdata-sections -Wl,--gc-sections -Wl,-z,noexecstack \
        -I c-api/include -I c-api/examples -I "$out" -T "$src/mps2.ld" \
        "$src/main.c" "$src/startup.c" "$src/semihost.c" \
        "$target/$triple/release/libbushing_c.a" -lgcc -o "$elf"
    arm-none-eabi-size "$elf" | tail -n 1 | awk -v c="$core" '{print c " image: text " $1 " B, data " $2 " B, bss " $3 " B"}'
    timeout -k 5 300 qemu-system-arm -machine "$machine" -cpu "$cpu" -nographic \
        -semihosting-config enable=on,target=native -icount shift=0,sleep=off \
        -kernel "$elf" >"$out/rig-loop-$core.log" \
        || { tail -n 5 "$out/rig-loop-$core.log"; echo "error: the C rig loop failed on the $core" >&2; exit 1; }
    grep -E '^(periods|refused|step_instructions|model_bytes|state_bytes|spec_bytes|verdict)' "$out/rig-loop-$core.log" \
        | paste -sd' ' | sed "s/^/$core: /"
    if ! cmp -s <(grep '^step ' "$rig/$core.log") <(grep '^step ' "$out/rig-loop-$core.log"); then
        echo "error: the C rig loop's trace differs from the Rust rig loop's on the $core" >&2
        diff <(grep '^step ' "$rig/$core.log") <(grep '^step ' "$out/rig-loop-$core.log") | head -n 5 >&2
        exit 1
    fi
    echo "$core: every one of $(grep -c '^step ' "$out/rig-loop-$core.log") forces equals the Rust rig loop's, bit for bit"
    if [ "$core" = m4f ]; then
        "$sim" compare-trace "$rig/host-f32/trace.csv" "$out/rig-loop-$core.log" | grep -E '^(identical|result)'
    else
        "$sim" compare-trace "$rig/host-f64/trace.csv" "$out/rig-loop-$core.log" --within 0.125 \
            | grep -E '^(max|result)'
    fi
done
