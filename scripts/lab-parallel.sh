#!/usr/bin/env bash
# A snake-lab sweep with GNU parallel: N shards of the same plan, as many at once as
# parallel runs (one per core by default; -j in PARALLEL_ARGS; hosts over ssh with
# PARALLEL_ARGS="-S h1,h2 --return $OUT/shard-{}-of-$N.cbor"), the first failure
# stopping the rest, then the merge.
#   N=4 OUT=lab-out/sweep scripts/lab-parallel.sh pegboard --layouts 8 [snake-lab options]
# OUT must be new or empty (shards of an earlier run would be merged as this run's).
# Environment: N (default: the cores), OUT (default lab-out/sweep), LAB (default
# target/release/snake-lab), PARALLEL_ARGS. docs/lab.md, "Sweeps on a cluster".
set -euo pipefail
[ $# -ge 1 ] || { echo "usage: N=.. OUT=.. $0 EXPERIMENT [snake-lab options]" >&2; exit 2; }
N=${N:-$(nproc)}
OUT=${OUT:-lab-out/sweep}
case $N in '' | *[!0-9]* | 0) echo "$0: N must be a positive integer, not '$N'" >&2; exit 2 ;; esac
LAB=$(realpath "${LAB:-target/release/snake-lab}")
if [ -e "$OUT" ] && [ -n "$(ls -A "$OUT" 2>/dev/null)" ]; then
    echo "$0: OUT=$OUT is not empty: give a new directory (an earlier run's shards would be merged with this one's)" >&2
    exit 2
fi
mkdir -p "$OUT"
# shellcheck disable=SC2086
seq 1 "$N" | parallel ${PARALLEL_ARGS:-} --line-buffer --halt now,fail=1 \
    "$LAB" "$@" --threads 1 --out "$OUT" --shard "{}/$N"
"$LAB" merge "$OUT" --expect "$N"
