#!/usr/bin/env python3
"""lab-paired.py BEFORE.csv AFTER.csv COLUMN...: two runs' results.csv joined on the key columns
(controller, layout or pole, start or pose, repeat), per controller: the rows joined, the outcome
(or success) counts before and after, and for each numeric COLUMN the mean before, after, and the paired mean
difference (after - before) ± its standard error. Used where a change (the physics) moves the
figures, to compare over the same worlds.

A file may be given as PATH:CONTROLLER: only that controller's rows, joined with the other
side's (also PATH:CONTROLLER) on the world keys alone, to pair two controllers (a variant
against its base) over the same worlds."""
import os
import csv, math, sys
from collections import Counter

KEYS = ["controller", "layout", "pole", "start", "pose", "repeat"]


def load(spec):
    """(columns, rows, controller or None) of PATH or PATH:CONTROLLER."""
    path, ctrl = spec, None
    if not os.path.exists(spec) and ":" in spec:
        path, ctrl = spec.rsplit(":", 1)
    with open(path) as f:
        r = csv.DictReader(f)
        rows = [x for x in r if ctrl is None or x["controller"] == ctrl]
        if ctrl is not None and not rows:
            sys.exit(f"no rows of controller {ctrl!r} in {path}")
        return r.fieldnames, rows, ctrl


def number(x):
    try:
        v = float(x)
        return v if math.isfinite(v) else None
    except ValueError:
        return None


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    fa, a, ca = load(sys.argv[1])
    fb, b, cb = load(sys.argv[2])
    columns = sys.argv[3:]
    keys = [k for k in KEYS if k in fa and k in fb]
    if ca or cb:
        # Two controllers over the same worlds: join on the world, label by the pair.
        keys = [k for k in keys if k != "controller"]
        for r in a + b:
            r["controller"] = f"{ca} -> {cb}"
        keys = ["controller"] + keys
    ka = {tuple(r[k] for k in keys): r for r in a}
    kb = {tuple(r[k] for k in keys): r for r in b}
    joined = [k for k in kb if k in ka]
    for c in columns:
        if c not in fa or c not in fb:
            sys.exit(f"no column {c!r} in both files")
    by = {}
    for k in joined:
        by.setdefault(k[0], []).append(k)
    print(f"joined on {keys}: {len(joined)} rows")
    for ctrl, ks in by.items():
        oc = next((c for c in ("outcome", "success") if c in fa and c in fb), None)
        before = Counter(ka[k][oc] for k in ks) if oc else {}
        after = Counter(kb[k][oc] for k in ks) if oc else {}
        line = f"{ctrl} ({len(ks)}): {oc} before {dict(before)}, after {dict(after)}"
        for c in columns:
            pairs = [(number(ka[k][c]), number(kb[k][c])) for k in ks]
            pairs = [(x, y) for x, y in pairs if x is not None and y is not None]
            if not pairs:
                continue
            d = [y - x for x, y in pairs]
            n = len(d)
            mean = sum(d) / n
            se = math.sqrt(sum((x - mean) ** 2 for x in d) / (n - 1) / n) if n > 1 else float("nan")
            mb = sum(x for x, _ in pairs) / n
            ma = sum(y for _, y in pairs) / n
            line += f"; {c}: {mb:.3f} -> {ma:.3f}, diff {mean:+.3f} ± {se:.3f} (n {n})"
        print(line)


main()
