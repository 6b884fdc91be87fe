#!/usr/bin/env python3
"""Folder-level import cycles of the crate: which top-level folders of src/ name each
other (`crate::FOLDER::` or `use crate::{FOLDER, ..}` in any file under another folder),
and the cycles that makes. Test code is left out (files named *tests.rs and everything
after a file's first `#[cfg(test)]`): tests may reach across. Exits 1 when there is a
cycle (tests/integration/structure.rs runs it). Usage:
scripts/folder-cycles.py [SRC_DIR] (default src)."""
import os, re, sys, itertools

src = sys.argv[1] if len(sys.argv) > 1 else "src"
folders = sorted(d for d in os.listdir(src) if os.path.isdir(os.path.join(src, d)) and d != "bin")
edges = {f: set() for f in folders}
ref = re.compile(r"crate::(\w+)")
group = re.compile(r"crate::\{([^}]*)\}")
for f in folders:
    for root, _, files in os.walk(os.path.join(src, f)):
        for name in files:
            if not name.endswith(".rs") or name.endswith("tests.rs"):
                continue
            text = open(os.path.join(root, name), encoding="utf-8").read()
            text = text.split("#[cfg(test)]")[0]
            # Comments and doc links name folders without depending on them.
            code = "\n".join(l.split("//")[0] for l in text.splitlines())
            named = set(ref.findall(code))
            for g in group.findall(code):
                named |= {p.strip().split("::")[0] for p in g.split(",")}
            edges[f] |= {n for n in named if n in edges and n != f}

# Strongly connected components (Tarjan).
index, low, stack, on, sccs, counter = {}, {}, [], set(), [], itertools.count()
def visit(v):
    index[v] = low[v] = next(counter); stack.append(v); on.add(v)
    for w in edges[v]:
        if w not in index:
            visit(w); low[v] = min(low[v], low[w])
        elif w in on:
            low[v] = min(low[v], index[w])
    if low[v] == index[v]:
        comp = []
        while True:
            w = stack.pop(); on.discard(w); comp.append(w)
            if w == v:
                break
        sccs.append(sorted(comp))
for v in folders:
    if v not in index:
        visit(v)
pairs = sorted({tuple(sorted((a, b))) for a in edges for b in edges[a] if a in edges[b]})
tangled = [c for c in sccs if len(c) > 1]
print(f"{len(folders)} folders, {sum(len(e) for e in edges.values())} folder-to-folder dependencies")
print(f"mutual pairs ({len(pairs)}): " + ", ".join(f"{a} <-> {b}" for a, b in pairs))
print(f"cycles (strongly connected groups of folders, {len(tangled)}): " + "; ".join(" ".join(c) for c in tangled))
sys.exit(1 if tangled else 0)
