#!/usr/bin/env python3
"""crossing-table.py LABEL=ALL.csv[:CONTROLLER] ...: crossed of the trials (side exits) per
set (family-skin) for each run given, as a markdown table, and the total; then, for each run
after the first, the paired difference in crossed (1/0 per trial) and progress_m against
the first over the trials both have (mean ± standard error). ALL.csv is what
scripts/crossing-sets.sh writes; CONTROLLER picks one controller's rows."""
import csv, math, os, sys
from collections import OrderedDict

SETS = [f"{f}-{s}" for f in ["thesis", "mixed", "rocks"] for s in ["bare", "sleeve"]]


def load(spec):
    label, path = spec.split("=", 1)
    ctrl = None
    if not os.path.exists(path) and ":" in path:
        path, ctrl = path.rsplit(":", 1)
    with open(path) as f:
        rows = [r for r in csv.DictReader(f) if ctrl is None or r["controller"] == ctrl]
    if not rows:
        sys.exit(f"{spec}: no rows")
    return label, {(r["layout"], r["start"], r["repeat"]): r for r in rows}


def paired(a, b, col):
    d = []
    for k, ra in a.items():
        rb = b.get(k)
        if rb is None:
            continue
        if col == "crossed":
            d.append((rb["outcome"] == "crossed") - (ra["outcome"] == "crossed"))
        else:
            d.append(float(rb[col]) - float(ra[col]))
    n = len(d)
    if n < 2:
        return n, float("nan"), float("nan")
    m = sum(d) / n
    se = math.sqrt(sum((x - m) ** 2 for x in d) / (n - 1) / n)
    return n, m, se


def main():
    runs = [load(s) for s in sys.argv[1:]]
    if not runs:
        sys.exit(__doc__)
    print("| set | " + " | ".join(l for l, _ in runs) + " |")
    print("| --- |" + " ---: |" * len(runs))
    totals = OrderedDict((l, [0, 0, 0]) for l, _ in runs)
    for s in SETS:
        cells = []
        for label, rows in runs:
            mine = [r for r in rows.values() if r["set"] == s]
            c = sum(r["outcome"] == "crossed" for r in mine)
            side = sum(r["outcome"] == "side" for r in mine)
            t = totals[label]
            t[0] += c; t[1] += side; t[2] += len(mine)
            cells.append(f"{c}/{len(mine)} ({side})" if mine else "")
        print(f"| {s} | " + " | ".join(cells) + " |")
    print("| **all** | " + " | ".join(
        f"**{c}/{n}** ({side}, {100.0 * c / n:.0f} %)" if n else "" for c, side, n in totals.values()) + " |")
    base_label, base = runs[0]
    for label, rows in runs[1:]:
        n, m, se = paired(base, rows, "crossed")
        n2, m2, se2 = paired(base, rows, "progress_m")
        print(f"\n{label} - {base_label}, paired over {n} trials: crossed {m:+.3f} ± {se:.3f}, "
              f"progress {m2:+.2f} ± {se2:.2f} m")


if __name__ == "__main__":
    main()
