#!/usr/bin/env python3
"""Paired comparison of two snake-lab runs (or two controllers of one run), world by world.

    scripts/lab-paired.py A.csv[:CONTROLLER] B.csv[:CONTROLLER] [--metric COLUMN ...]

Trials are paired by (layout, start, repeat) - the same world and sensor-noise seed - and
for each metric the script prints the mean of A and of B, the mean of B - A with its
standard error, and in how many worlds B is above A. Columns that are not numbers
(outcome) are compared as "through" shares. Only the standard library is used.
"""
import argparse
import csv
import math
import sys


def load(spec):
    path, _, controller = spec.partition(":")
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if controller:
        rows = [r for r in rows if r["controller"] == controller]
    if not rows:
        sys.exit(f"{spec}: no trials")
    names = {r["controller"] for r in rows}
    if len(names) > 1:
        sys.exit(f"{spec}: several controllers ({', '.join(sorted(names))}): name one with :NAME")
    start = "start" if "start" in rows[0] else "pose"
    key = lambda r: (r["layout"], r[start], r.get("repeat", "0"))
    return {key(r): r for r in rows}


def value(row, metric):
    v = row[metric]
    if metric == "outcome":
        return 1.0 if v == "through" else 0.0
    if metric == "success":
        return 1.0 if v == "true" else 0.0
    return float(v) if v not in ("", "NaN", "nan") else math.nan


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("a")
    p.add_argument("b")
    p.add_argument("--metric", action="append", help="a results.csv column (repeatable)")
    args = p.parse_args()
    a, b = load(args.a), load(args.b)
    keys = sorted(set(a) & set(b))
    if not keys:
        sys.exit("no world in common")
    metrics = args.metric or ["seconds"]
    print(f"{len(keys)} paired worlds; A = {args.a}, B = {args.b}")
    for m in metrics:
        pairs = [(value(a[k], m), value(b[k], m)) for k in keys]
        pairs = [(x, y) for x, y in pairs if not (math.isnan(x) or math.isnan(y))]
        n = len(pairs)
        if n < 2:
            print(f"{m}: fewer than two finite pairs")
            continue
        d = [y - x for x, y in pairs]
        mean = sum(d) / n
        sd = math.sqrt(sum((x - mean) ** 2 for x in d) / (n - 1))
        ma = sum(x for x, _ in pairs) / n
        mb = sum(y for _, y in pairs) / n
        above = sum(1 for x in d if x > 0)
        below = sum(1 for x in d if x < 0)
        print(
            f"{m}: A {ma:.4g}, B {mb:.4g}, B - A {mean:+.4g} ± {sd / math.sqrt(n):.2g} (se), "
            f"B above in {above}, below in {below} of {n}"
        )


if __name__ == "__main__":
    main()
