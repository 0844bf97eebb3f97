#!/usr/bin/env bash
# The "no slower" check: the current checkout (working tree, with uncommitted changes) against
# BASE_COMMIT on the paper's 10-body run, Kepler e = 0.6 at T = 200 and T = 20 000, and the
# J2000 and outer-solar-system work–precision points (plus the summary's other fastest points
# and deterministic proxies of the criterion benches), measured side by side in one run.
#
# Usage: scripts/compare-speed.sh [BASE_COMMIT]        (default 9727f8f)
#
# 1. Builds the `gvi` release binary of BASE_COMMIT (a temporary git worktree, built with the
#    persistent target dir target/same-maps-base that scripts/same-maps.sh uses, so that only
#    the crates rebuild) and of the current checkout, and copies both to
#    target/compare-speed/bin/ (so a rebuild by someone else cannot swap a binary mid-run).
# 2. Runs scripts/compare-speed.py on the two binaries. Every scenario is one `gvi run …`
#    (listed in the report), measured two ways:
#    - instructions executed (valgrind --tool=callgrind, whole process): repeatable under load;
#      Kepler T = 20 000 runs 4 000 of its 40 000 steps there (the same for both versions);
#    - wall clock: N interleaved repetitions, old and new alternating (old/new, new/old, …),
#      median of each and their ratio.
#    The bench proxies (the systems and settings of benches/step.rs and benches/nbody.rs run
#    through `gvi run` at two step counts) are measured by callgrind only, per step: the
#    difference of the two counts over the difference of the steps, without the set-up.
# 3. With BENCHES=1, also builds the criterion benches (`--bench step`, `--bench nbody` of
#    galerkin-vi) of both trees and runs each benchmark alone (`--exact`), old and new
#    alternating, with `--warm-up-time 1 --measurement-time 3`; the report gives criterion's
#    point estimates side by side. Takes a few minutes.
# The report (markdown) goes to stdout and to target/compare-speed/report.md; raw numbers to
# target/compare-speed/results.json, callgrind profiles to target/compare-speed/callgrind/.
#
# Exit status: 0 if every instruction ratio new/old is ≤ 1.05; 1 if one is above (or, with
# STRICT_WALL=1, a wall-clock or bench ratio); 2 if a run failed or a build failed.
#
# Environment:
#   REPS=N                 wall-clock repetitions (default 7)
#   STRICT_WALL=1          wall-clock and bench ratios gate too (noisy on a loaded machine)
#   BENCHES=1              also compare the criterion benches (minutes)
#   BENCH_TARGETS          the benches for BENCHES=1, PACKAGE:BENCH words (default
#                          "galerkin-vi:step galerkin-vi:nbody"; the lab's benches are
#                          galerkin-vi-lab:solvers, galerkin-vi-lab:peers,
#                          galerkin-vi-lab:expression)
#   ONLY=a,b               only these scenarios or kinds (required, extra, proxy)
#   NO_CALLGRIND=1         skip the instruction counts; NO_WALL=1 skip the wall clock
#   CALLGRIND_JOBS=N       callgrind runs at a time (default 2; instruction counts do not
#                          depend on the load)
#   LIMIT=1.05             the largest allowed ratio new/old
#   COMPARE_SPEED_BASE_TARGET  cargo target dir of the base build (default
#                          target/same-maps-base of this checkout, shared with same-maps.sh)
set -euo pipefail

base_commit=${1:-9727f8f}
repo=$(git rev-parse --show-toplevel)
cd "$repo"
base_sha=$(git rev-parse --verify --quiet "${base_commit}^{commit}") ||
    { echo "compare-speed: no such commit: $base_commit" >&2; exit 2; }
base_target=${COMPARE_SPEED_BASE_TARGET:-$repo/target/same-maps-base}
new_target=${CARGO_TARGET_DIR:-$repo/target}
out_dir=$repo/target/compare-speed
bin_dir=$out_dir/bin
mkdir -p "$bin_dir"
rm -f "$bin_dir"/*
command -v valgrind >/dev/null || [[ ${NO_CALLGRIND:-} == 1 ]] ||
    { echo "compare-speed: valgrind not found (apt-get install valgrind, or NO_CALLGRIND=1)" >&2
      exit 2; }
bench_targets=${BENCH_TARGETS:-galerkin-vi:step galerkin-vi:nbody}
t0=$SECONDS

tmp=$(mktemp -d "${TMPDIR:-/tmp}/compare-speed.XXXXXX")
worktree=$tmp/base
cleanup() {
    git -C "$repo" worktree remove --force "$worktree" >/dev/null 2>&1 || true
    rm -rf "$tmp"
    git -C "$repo" worktree prune >/dev/null 2>&1 || true
}
trap cleanup EXIT

# Builds the bench targets (`cargo bench --no-run`) and copies each executable to
# $bin_dir/SIDE-bench-PACKAGE-BENCH. $1 = old|new.
build_benches() {
    local side=$1 t exe
    for t in $bench_targets; do
        exe=$(cargo bench --no-run --message-format=json -p "${t%%:*}" --bench "${t#*:}" |
            python3 -c '
import json, sys
for line in sys.stdin:
    try: m = json.loads(line)
    except ValueError: continue
    if m.get("reason") == "compiler-artifact" and m.get("executable") and \
       "bench" in m["target"]["kind"] and m["target"]["name"] == sys.argv[1]:
        print(m["executable"])
' "${t#*:}") || { echo "compare-speed: bench $t does not build ($side)" >&2; continue; }
        if [[ -n $exe ]]; then
            cp "$exe" "$bin_dir/$side-bench-${t/:/-}"
        else
            echo "compare-speed: no executable for bench $t ($side)" >&2
        fi
    done
}

echo "compare-speed: base $base_commit (${base_sha:0:12}) in $worktree" >&2
git worktree add --quiet --detach "$worktree" "$base_sha"

echo "compare-speed: building the base (target dir $base_target)" >&2
(cd "$worktree" && CARGO_TARGET_DIR=$base_target cargo build --quiet --release -p galerkin-vi-lab) ||
    { echo "compare-speed: the base does not build" >&2; exit 2; }
cp "$base_target/release/gvi" "$bin_dir/old-gvi"
if [[ ${BENCHES:-} == 1 ]]; then
    echo "compare-speed: building the base's benches" >&2
    (cd "$worktree" && export CARGO_TARGET_DIR=$base_target && build_benches old)
fi

head_sha=$(git rev-parse HEAD)
dirty=$(git status --porcelain --untracked-files=no | wc -l)
untracked=$(git status --porcelain | grep -c '^??' || true)
echo "compare-speed: building the current checkout (target dir $new_target)" >&2
cargo build --quiet --release -p galerkin-vi-lab ||
    { echo "compare-speed: the current checkout does not build" >&2; exit 2; }
cp "$new_target/release/gvi" "$bin_dir/new-gvi"
if [[ ${BENCHES:-} == 1 ]]; then
    echo "compare-speed: building the current checkout's benches" >&2
    build_benches new
fi
t_build=$((SECONDS - t0))
cleanup
trap - EXIT

header="## Speed: current checkout against ${base_commit} (${base_sha:0:12})

- old: \`${base_sha:0:12}\` ($(git log -1 --format=%s "$base_sha" | cut -c1-80)…)
- new: the working tree at \`${head_sha:0:12}\` with ${dirty} modified tracked and ${untracked} untracked files
- $(date -u '+%Y-%m-%d %H:%M UTC'); $(nproc) CPUs ($(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')); $(rustc --version); $(valgrind --version 2>/dev/null || echo 'no valgrind')
- builds: ${t_build} s"

args=(--old "$bin_dir/old-gvi" --new "$bin_dir/new-gvi" --out "$out_dir"
      --reps "${REPS:-7}" --limit "${LIMIT:-1.05}" --callgrind-jobs "${CALLGRIND_JOBS:-2}"
      --header "$header")
[[ ${STRICT_WALL:-} == 1 ]] && args+=(--strict-wall)
[[ ${NO_CALLGRIND:-} == 1 ]] && args+=(--no-callgrind)
[[ ${NO_WALL:-} == 1 ]] && args+=(--no-wall)
[[ -n ${ONLY:-} ]] && args+=(--only "$ONLY")
if [[ ${BENCHES:-} == 1 ]]; then
    for t in $bench_targets; do
        f=${t/:/-}
        if [[ -x $bin_dir/old-bench-$f && -x $bin_dir/new-bench-$f ]]; then
            args+=(--bench "$t=$bin_dir/old-bench-$f:$bin_dir/new-bench-$f")
        else
            echo "compare-speed: bench $t not built on both sides, skipped" >&2
        fi
    done
fi

status=0
python3 "$repo/scripts/compare-speed.py" "${args[@]}" || status=$?
echo "compare-speed: total $((SECONDS - t0)) s; report in $out_dir/report.md" >&2
exit $status
