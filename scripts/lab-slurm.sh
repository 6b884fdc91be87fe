#!/usr/bin/env bash
# A snake-lab sweep as a Slurm job array: N tasks each run one shard of the same plan
# into OUT, then a merge job writes the report. The merge waits for every task to end
# however it ended (afterany), so a failed, killed or cancelled shard does not leave it
# pending for ever: `snake-lab merge --expect N` then exits non-zero naming the missing
# shards, and the merge's log points at their logs.
#   N=8 OUT=/shared/lab-out/sweep scripts/lab-slurm.sh pegboard --layouts 40 [snake-lab options]
# OUT must be new or empty (shards of an earlier run would be merged as this run's) and
# on a file system every node mounts at the same path, as must LAB and any scenario
# file named. Environment: N (shards, default 4), OUT (default lab-out/sweep), LAB (the
# snake-lab binary, default target/release/snake-lab), THREADS (per task, default 1),
# SBATCH_ARGS (extra sbatch options: partition, time, account...).
# Prints the two job ids. docs/lab.md, "Sweeps on a cluster".
set -euo pipefail
[ $# -ge 1 ] || { echo "usage: N=.. OUT=.. $0 EXPERIMENT [snake-lab options]" >&2; exit 2; }
N=${N:-4}
OUT=${OUT:-lab-out/sweep}
THREADS=${THREADS:-1}
case $N in '' | *[!0-9]* | 0) echo "$0: N must be a positive integer, not '$N'" >&2; exit 2 ;; esac
LAB=$(realpath "${LAB:-target/release/snake-lab}")
[ -x "$LAB" ] || { echo "$0: no snake-lab at $LAB (build it: cargo build --release)" >&2; exit 2; }
OUT=$(realpath -m "$OUT")
if [ -e "$OUT" ] && [ -n "$(ls -A "$OUT" 2>/dev/null)" ]; then
    echo "$0: OUT=$OUT is not empty: give a new directory (an earlier run's shards would be merged with this one's)" >&2
    exit 2
fi
mkdir -p "$OUT/logs"
q() { printf '%q' "$1"; }
args=$(printf ' %q' "$@")
array=$(sbatch --parsable ${SBATCH_ARGS:-} --job-name=snake-lab --array="1-$N" \
    --cpus-per-task="$THREADS" --output="$OUT/logs/shard-%a.log" \
    --wrap="$(q "$LAB")$args --threads $THREADS --quiet --out $(q "$OUT") --shard \$SLURM_ARRAY_TASK_ID/$N")
array=${array%%;*}
# The merge: after every task, whatever its end; on failure, the missing shards' logs.
merge_script="status=0
$(q "$LAB") merge $(q "$OUT") --expect $N --quiet || status=\$?
if [ \$status -ne 0 ]; then
    for k in \$(seq 1 $N); do
        [ -e $(q "$OUT")/shard-\$k-of-$N.cbor ] ||
            echo \"snake-lab-merge: shard \$k/$N wrote no file: see $(q "$OUT")/logs/shard-\$k.log (job ${array}_\$k)\" >&2
    done
fi
exit \$status"
merge=$(sbatch --parsable ${SBATCH_ARGS:-} --job-name=snake-lab-merge \
    --dependency="afterany:$array" --kill-on-invalid-dep=yes --output="$OUT/logs/merge.log" \
    --wrap="$merge_script")
merge=${merge%%;*}
echo "shards: job $array (array 1-$N), merge: job $merge; report in $OUT (logs in $OUT/logs)"
