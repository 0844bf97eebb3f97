#!/usr/bin/env bash
# The "same maps" regression check: every built-in basis × quadrature × stage solver × scene of
# examples/record_maps/ must give the same map in the current checkout (working tree, with
# uncommitted changes) as at BASE_COMMIT — bit for bit, or within the tolerance (relative).
#
# Usage: scripts/same-maps.sh [BASE_COMMIT]        (default 9727f8f)
#
# Creates a temporary git worktree of BASE_COMMIT, copies the current examples/record_maps/
# into it, runs `cargo run --release --example record_maps -p galerkin-vi` there and here, and
# compares the two recordings with scripts/compare-maps.py. Exits nonzero if a case differs by
# more than the tolerance or changed status (ok/error). The worktree is removed at the end.
#
# Environment:
#   SAME_MAPS_TOL          relative tolerance (default 1e-14)
#   SAME_MAPS_BASE_TARGET  cargo target dir of the base build (default target/same-maps-base
#                          of this checkout: kept, so that later runs rebuild only the crate;
#                          separate from this checkout's target dir, whose fingerprints it
#                          would otherwise churn)
#   SAME_MAPS_VERBOSE=1    list every case that is not bit-identical
# The two recordings are kept in target/same-maps/{base,current}.txt.
set -euo pipefail

base_commit=${1:-9727f8f}
repo=$(git rev-parse --show-toplevel)
cd "$repo"
base_sha=$(git rev-parse --verify --quiet "${base_commit}^{commit}") ||
    { echo "same-maps: no such commit: $base_commit" >&2; exit 2; }
tol=${SAME_MAPS_TOL:-1e-14}
base_target=${SAME_MAPS_BASE_TARGET:-$repo/target/same-maps-base}
out_dir=$repo/target/same-maps
mkdir -p "$out_dir"

tmp=$(mktemp -d "${TMPDIR:-/tmp}/same-maps.XXXXXX")
worktree=$tmp/base
cleanup() {
    git -C "$repo" worktree remove --force "$worktree" >/dev/null 2>&1 || true
    rm -rf "$tmp"
    git -C "$repo" worktree prune >/dev/null 2>&1 || true
}
trap cleanup EXIT

echo "same-maps: base $base_commit (${base_sha:0:12}) in $worktree" >&2
git worktree add --quiet --detach "$worktree" "$base_sha"
# The recorder is examples/record_maps/ (a directory since it was split by case family; before
# that, one file examples/record_maps.rs): the base gets the current one, whatever its shape.
rm -rf "$worktree/examples/record_maps.rs" "$worktree/examples/record_maps"
cp -r "$repo/examples/record_maps" "$worktree/examples/record_maps"

echo "same-maps: recording the base (target dir $base_target)" >&2
(cd "$worktree" && CARGO_TARGET_DIR=$base_target \
    cargo run --quiet --release --example record_maps -p galerkin-vi) >"$out_dir/base.txt"

echo "same-maps: recording the current checkout" >&2
cargo run --quiet --release --example record_maps -p galerkin-vi >"$out_dir/current.txt"

verbose=()
[[ ${SAME_MAPS_VERBOSE:-} == 1 ]] && verbose=(--verbose)
python3 "$repo/scripts/compare-maps.py" "$out_dir/base.txt" "$out_dir/current.txt" \
    --tol "$tol" "${verbose[@]}"
