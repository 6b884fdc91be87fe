#!/usr/bin/env bash
# The crossing experiment on every family (thesis, mixed, rocks) and skin (bare, sleeve):
# six `snake-lab crossing` runs into OUT/<family>-<skin>/, then OUT/all.csv, every row
# with its set in front of the layout (thesis-bare/seed1000), for scripts/lab-paired.py
# and scripts/crossing-table.py. The sleeve runs slithering at the thesis's sleeve
# nominal (docs/measurements/crossing.md).
#   OUT=lab-out/x LAYOUTS=5 scripts/crossing-sets.sh --controllers navigator --pose-source lab
# Environment: OUT (default lab-out/crossing-sets), LAYOUTS (5), SEED_BASE (default: each
# family's own seeds, the published worlds), THREADS (nproc), LAB (target/release/snake-lab).
set -euo pipefail
OUT=${OUT:-lab-out/crossing-sets}
LAYOUTS=${LAYOUTS:-5}
THREADS=${THREADS:-$(nproc)}
LAB=${LAB:-target/release/snake-lab}
SLEEVE_NOMINAL='{"amplitude_lat_rad":1.1,"spatial_freq_rad":6.283185307179586}'
seed=()
[ -n "${SEED_BASE:-}" ] && seed=(--seed-base "$SEED_BASE")
mkdir -p "$OUT"
for family in thesis mixed rocks; do
    for skin in bare sleeve; do
        set_dir="$OUT/$family-$skin"
        nominal=()
        [ "$skin" = sleeve ] && nominal=(--nominal "$SLEEVE_NOMINAL")
        echo "$(date +%T) $family $skin -> $set_dir" >&2
        "$LAB" crossing --family "$family" --skin "$skin" --layouts "$LAYOUTS" "${seed[@]}" \
            "${nominal[@]}" --threads "$THREADS" --quiet --out "$set_dir" "$@" >/dev/null
    done
done
python3 - "$OUT" <<'PY'
import csv, os, sys
out = sys.argv[1]
rows, fields = [], None
for family in ["thesis", "mixed", "rocks"]:
    for skin in ["bare", "sleeve"]:
        with open(os.path.join(out, f"{family}-{skin}", "results.csv")) as f:
            r = csv.DictReader(f)
            fields = ["set"] + r.fieldnames
            for row in r:
                row["layout"] = f"{family}-{skin}/{row['layout']}"
                rows.append({"set": f"{family}-{skin}", **row})
with open(os.path.join(out, "all.csv"), "w", newline="") as f:
    w = csv.DictWriter(f, fieldnames=fields)
    w.writeheader()
    w.writerows(rows)
print(f"{len(rows)} trials in {out}/all.csv", file=sys.stderr)
PY
