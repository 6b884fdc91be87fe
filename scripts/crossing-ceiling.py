#!/usr/bin/env python3
"""crossing-ceiling.py RUN_DIR ...: the most any choice among these runs could cross.

Each RUN_DIR holds a crossing run's sets (RUN_DIR/<family>-<skin>/results.csv, what
scripts/crossing-sets.sh writes); every controller of every run is one candidate. For each
trial (set, layout, start, repeat) of the first run, a trial counts as crossable if any
candidate crossed it: the hindsight oracle that picks, per trial, whichever controller and
run did best. No navigator choosing among these controllers can beat it on these worlds, so
a target above it is out of reach of the controllers, not of the steering.
Prints the ceiling per set and per start kind beside the best single candidate."""
import csv, glob, os, sys
from collections import defaultdict

SETS = [f"{f}-{s}" for f in ["thesis", "mixed", "rocks"] for s in ["bare", "sleeve"]]


def load(run_dir):
    """{(run, controller): {trial: (crossed, start_kind)}}"""
    out = defaultdict(dict)
    name = os.path.basename(os.path.normpath(run_dir))
    for path in glob.glob(os.path.join(run_dir, "*", "results.csv")):
        s = os.path.basename(os.path.dirname(path))
        with open(path) as f:
            for r in csv.DictReader(f):
                trial = (s, r["layout"], r["start"], r["repeat"])
                out[(name, r["controller"])][trial] = (r["outcome"] == "crossed", r["start_kind"])
    return out


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    first = load(sys.argv[1])
    if not first:
        sys.exit(f"{sys.argv[1]}: no results.csv")
    # The trials are the first run's; a run on other worlds (a tuning run) is skipped.
    trials = set.intersection(*(set(v) for v in first.values()))
    cands = dict(first)
    for d in sys.argv[2:]:
        for c, rows in load(d).items():
            if trials <= set(rows):
                cands[c] = rows
            else:
                print(f"skipped {c[1]} ({c[0]}): not run on the first run's trials", file=sys.stderr)
    best = max(cands, key=lambda c: sum(cands[c][t][0] for t in trials))
    print(f"{len(cands)} candidates over {len(trials)} shared trials; best single: "
          f"{best[1]} ({best[0]})\n")

    def row(label, ts):
        ceil = sum(any(cands[c][t][0] for c in cands) for t in ts)
        one = sum(cands[best][t][0] for t in ts)
        n = len(ts)
        return f"| {label} | {one}/{n} | {ceil}/{n} ({100.0 * ceil / n:.0f} %) |"

    print("| set | best single | any candidate (ceiling) |\n| --- | ---: | ---: |")
    for s in SETS:
        ts = [t for t in trials if t[0] == s]
        if ts:
            print(row(s, ts))
    kinds = sorted({cands[best][t][1] for t in trials})
    for k in kinds:
        print(row(f"start {k}", [t for t in trials if cands[best][t][1] == k]))
    print(row("**all**", list(trials)))


if __name__ == "__main__":
    main()
