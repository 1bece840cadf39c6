#!/usr/bin/env bash
# The bushing as an FMI 2.0 co-simulation FMU (docs/fmu.md), checked by
# fmpy, a master the FMI community uses:
#   1. the FMU library (crate bushing-fmu) and bushing-sim, release;
#   2. fmpy, pinned, in a virtual environment in the build folder;
#   3. FMUs of a Maxwell bushing (scenes/maxwell4.toml), the composite
#      Maxwell + Iwan + x_f bushing (scenes/hysteresis-triangle.toml) and an
#      STS stack (scenes/sts-triangles.toml) in f64, and of the Maxwell
#      bushing in f32, and of the worked example's identified model
#      (examples/identification/identified/model.toml): fmpy's validation
#      passes, the FMU stepped by fmpy on the displacements of
#      `bushing-sim run`'s trace gives its forces and energies bit for bit, and a rollback (saved state, steps, restored
#      state, the same steps; once through the serialised bytes) repeats
#      the outputs bit for bit;
#   4. every misuse, with the status fmpy sees and the message logged;
#   5. the default bushing at 10 kHz (scenes/default-bushing.toml): time
#      per model step through fmpy's doStep with h = 0.1 s, printed, never
#      asserted.
# Needs python3 with venv (scripts/test.sh installs it when missing).
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/target-dir.sh
step() { printf '\n==> %s\n' "$*"; }
FMPY_VERSION=0.3.32
out="$target/fmu"
rm -rf "$out"
mkdir -p "$out"

step "the FMU library and bushing-sim, release"
cargo build -q --release -p bushing-fmu -p bushing-sim
sim="$target/release/bushing-sim"

step "fmpy $FMPY_VERSION in a virtual environment"
venv="$target/fmu-venv"
py="$venv/bin/python"
[ -x "$py" ] || python3 -m venv "$venv"
if [ "$("$py" -c 'import fmpy; print(fmpy.__version__)' 2>/dev/null)" != "$FMPY_VERSION" ]; then
    "$venv/bin/pip" install -q --disable-pip-version-check "fmpy==$FMPY_VERSION"
fi

for spec in "maxwell4 scenes/maxwell4.toml f64" \
    "hysteresis-triangle scenes/hysteresis-triangle.toml f64" \
    "sts-triangles scenes/sts-triangles.toml f64" \
    "maxwell4 scenes/maxwell4.toml f32" \
    "identified examples/identification/identified/model.toml f64"; do
    read -r name scene number <<<"$spec"
    name="$name-$number"
    step "$name: validation, bit for bit against bushing-sim run, rollback"
    "$sim" fmu "$scene" --number "$number" --out "$out/$name.fmu"
    "$sim" run "$scene" --number "$number" --out "$out/$name-run" >"$out/$name-run.log"
    "$py" scripts/fmu_check.py trace "$out/$name.fmu" "$out/$name-run/trace.csv"
done

step "misuse: the standard's status codes, with the messages logged"
"$py" scripts/fmu_check.py misuse "$out/maxwell4-f64.fmu"

step "the default bushing at 10 kHz through fmpy's doStep (printed, not asserted)"
"$sim" fmu scenes/default-bushing.toml --out "$out/default-bushing.fmu"
"$py" scripts/fmu_check.py time "$out/default-bushing.fmu"
