#!/usr/bin/env bash
# A snake-lab sweep as a Slurm job array: N tasks each run one shard of the same plan
# into OUT (a directory every node sees), then a job that waits for all of them merges.
#   N=8 OUT=lab-out/sweep scripts/lab-slurm.sh pegboard --layouts 40 [snake-lab options]
# Environment: N (shards, default 4), OUT (default lab-out/sweep), LAB (the snake-lab
# binary, default target/release/snake-lab), THREADS (per task, default 1),
# SBATCH_ARGS (extra sbatch options: partition, time, account...).
# Prints the two job ids. docs/lab.md, "Sweeps on a cluster".
set -euo pipefail
[ $# -ge 1 ] || { echo "usage: N=.. OUT=.. $0 EXPERIMENT [snake-lab options]" >&2; exit 2; }
N=${N:-4}
OUT=${OUT:-lab-out/sweep}
LAB=$(realpath "${LAB:-target/release/snake-lab}")
THREADS=${THREADS:-1}
mkdir -p "$OUT/logs"
args=$(printf ' %q' "$@")
array=$(sbatch --parsable ${SBATCH_ARGS:-} --job-name=snake-lab --array="1-$N" \
    --cpus-per-task="$THREADS" --output="$OUT/logs/shard-%a.log" \
    --wrap="$LAB$args --threads $THREADS --quiet --out $OUT --shard \$SLURM_ARRAY_TASK_ID/$N")
merge=$(sbatch --parsable ${SBATCH_ARGS:-} --job-name=snake-lab-merge \
    --dependency="afterok:${array%%;*}" --output="$OUT/logs/merge.log" \
    --wrap="$LAB merge $OUT --quiet")
echo "shards: job $array (array 1-$N), merge: job $merge; report in $OUT"
