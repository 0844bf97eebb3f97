#!/bin/bash
# Bad-input sweep of the gvi command line (issue 32): every case must fail with a typed error
# (exit status 1 or 2) within 60 s, without a panic, and leave the input files intact; each
# case runs twice, with stdout on /dev/null and on /dev/full. Prints the counts the guide
# quotes (docs/guide/command-line.md, "Outputs, warnings and --strict").
#
#   cargo build -p galerkin-vi-lab && scripts/bad_input_sweep.sh [path/to/gvi]
set -u
ROOT=$(cd "$(dirname "$0")/.." && pwd)
G=$(realpath "${1:-$ROOT/target/debug/gvi}")
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
cd "$WORK"
cp "$ROOT/scenes/two-body.toml" s.toml
cp "$ROOT/scenes/figure-eight.toml" f8.toml
sed 's/^modes = 60/modes = 1000000/' f8.toml > big.toml
LONG=$(printf 'X%.0s' $(seq 1 245)).csv
cat > cases.txt <<CASES
run s.toml --steps 5 --output nope/../s.toml
run s.toml --steps 5 --plot a/../s.toml
run kepler --steps 5 --output x.csv --plot x.csv
run kepler --steps 100000000 --plot m.svg
run kepler --steps 100000000 --format json
run kepler --steps 3 --plot x.png
run kepler --steps 3 --retraction cayley
run rigid-body --steps 3 --solver modal
run kepler --steps 3 --tol 1e-6 --n 12
run kepler --steps 3 --tol 1e-6 --economical
run kepler --q0 0,0 --steps 3
run kepler --p0 0,1e300 --steps 3
run kepler --h -2
run kepler --n 1
run kepler --steps 3 --output /proc/version
run kepler --steps 3 --output /
run kepler --steps 3 --output $LONG
run nosuchscene
run /tmp
check kepler --steps 100000000
check kepler --q0 0,0
check kepler --retraction exp
periodic f8.toml --output f8.toml
periodic f8.toml --output o.json --plot o.json
periodic f8.toml --plot o.png
periodic big.toml
periodic figure-eight --modes 4096
periodic figure-eight --modes 0
periodic figure-eight --periods 100000000
periodic kepler
work-precision s.toml --write-reference s.toml
work-precision kepler --quick --repeats 0
work-precision kepler --quick --write-reference r.csv --ns 8
work-precision kepler --quick --horizon 1e300
work-precision kepler --quick --external nosuch.csv
refine kepler --vary n --range 4:8:x1.00001
refine kepler --vary n --range 1000:2000:500
refine kepler --vary n --range 4:8:2 --steps 100000000
refine kepler --vary n --range 4:8:2 --n 5
compare-bases kepler --steps 100000000
compare-refinement kepler --quick --steps 10000000
stability kepler --cell-steps 100000000
stability kepler --q0 0,0 --quick
stability kepler --h 1
tolerance-study kepler --steps 10000000
tolerance-study harmonic --steps 4 --tols 1e-3 --ladder 8,4
tolerance-study kepler --eccentricity 2
nbody-report two-body --steps 100000000
nbody-report kepler
nbody-report two-body --substeps 0
ensemble solar-system --count 10000000 --perturb 0
ensemble kepler --count 3 --perturb 1e300 --steps 3
ensemble kepler --count 0 --perturb 0
ensemble kepler --count 3 --perturb -1
ensemble kepler --count 3 --perturb 0 --threads 0
ensemble s.toml --count 2 --perturb 0 --output no/../s.toml
solver-scaling --out /proc/x
reproduce --out /proc/x
scenes --bogus
CASES
tried=0; panics=0; hangs=0; silent=0; lost=0
sum0=$(md5sum s.toml f8.toml | md5sum)
while IFS= read -r line; do
  [ -z "$line" ] && continue
  for out in /dev/null /dev/full; do
    tried=$((tried+1))
    # shellcheck disable=SC2086
    timeout 60 "$G" $line > "$out" 2> err.txt; rc=$?
    if [ $rc = 124 ]; then hangs=$((hangs+1)); echo "HANG: $line > $out"; fi
    if [ $rc = 101 ] || grep -q panicked err.txt; then panics=$((panics+1)); echo "PANIC: $line > $out"; fi
    if [ $rc = 0 ]; then silent=$((silent+1)); echo "EXIT 0: $line > $out"; fi
    if [ "$(md5sum s.toml f8.toml | md5sum)" != "$sum0" ]; then
      lost=$((lost+1)); echo "LOST: $line > $out"
      cp "$ROOT/scenes/two-body.toml" s.toml; cp "$ROOT/scenes/figure-eight.toml" f8.toml
    fi
  done
done < cases.txt
echo "cases tried: $tried; panics: $panics; hangs: $hangs; silent exit 0: $silent; data lost: $lost"
