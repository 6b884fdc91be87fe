#!/usr/bin/env python3
"""lab-compare-rows.py PUBLISHED.csv NOW.csv: join two runs' results.csv on the key columns
(controller, layout or pole, start or pose, repeat) and count the rows identical in every column
they share; prints the columns that differ. Used to show a re-run reproduces a published table."""
import csv, sys
KEYS = ["controller", "layout", "pole", "start", "pose", "repeat"]
def load(p):
    with open(p) as f:
        r = csv.DictReader(f)
        rows = list(r)
        return r.fieldnames, rows
fa, a = load(sys.argv[1]); fb, b = load(sys.argv[2])
keys = [k for k in KEYS if k in fa and k in fb]
ka = {tuple(r[k] for k in keys): r for r in a}
kb = {tuple(r[k] for k in keys): r for r in b}
common = [k for k in ka if k in kb]
print(f"keys {keys}; published {len(a)} rows, now {len(b)} rows, joined {len(common)}")
if fa != fb:
    print("columns differ:", set(fa) ^ set(fb))
cols = [c for c in fa if c in fb]
ident = 0; diffcols = {}
diffrows = []
for k in common:
    d = [c for c in cols if ka[k][c] != kb[k][c]]
    if not d: ident += 1
    else:
        diffrows.append((k, d))
        for c in d: diffcols[c] = diffcols.get(c, 0) + 1
print(f"{ident} of {len(common)} joined rows identical (every column)")
if diffcols: print("columns that differ (rows):", diffcols)
per = {}
for k in common:
    c = k[0]; per.setdefault(c, [0, 0]); per[c][1] += 1
    if all(ka[k][x] == kb[k][x] for x in cols): per[c][0] += 1
for c, (i, n) in per.items(): print(f"  {c}: {i}/{n} identical")
for k, d in diffrows[:int(sys.argv[3]) if len(sys.argv) > 3 else 5]:
    print("  diff", k, {c: (ka[k][c], kb[k][c]) for c in d[:6]})
