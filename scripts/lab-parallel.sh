#!/usr/bin/env bash
# A snake-lab sweep with GNU parallel: N shards of the same plan, as many at once as
# parallel runs (local cores by default; hosts over ssh with PARALLEL_ARGS="-S h1,h2
# --return $OUT/shard-{}-of-$N.cbor"), then the merge.
#   N=4 OUT=lab-out/sweep scripts/lab-parallel.sh pegboard --layouts 8 [snake-lab options]
# Environment: N (default: the cores), OUT (default lab-out/sweep), LAB (default
# target/release/snake-lab), PARALLEL_ARGS. docs/lab.md, "Sweeps on a cluster".
set -euo pipefail
[ $# -ge 1 ] || { echo "usage: N=.. OUT=.. $0 EXPERIMENT [snake-lab options]" >&2; exit 2; }
N=${N:-$(nproc)}
OUT=${OUT:-lab-out/sweep}
LAB=$(realpath "${LAB:-target/release/snake-lab}")
mkdir -p "$OUT"
# shellcheck disable=SC2086
seq 1 "$N" | parallel ${PARALLEL_ARGS:-} --line-buffer --halt now,fail=1 \
    "$LAB" "$@" --threads 1 --out "$OUT" --shard "{}/$N"
"$LAB" merge "$OUT"
