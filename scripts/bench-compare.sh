#!/usr/bin/env bash
# The controller-step bench (benches/shape_step.rs) of an older revision and of the
# working tree, side by side in one session:
#   scripts/bench-compare.sh OLD_REV [ROUNDS] [FILTER]
# Builds both (OLD_REV in a temporary worktree, sharing the target directory), then
# runs them alternately ROUNDS times (default 3) with criterion's
# `--warm-up-time 1 --measurement-time 2`, and prints each benchmark's median (the
# median over the rounds of criterion's median) before and after, and their ratio.
# Alternating spreads the load of a shared machine over both.
set -euo pipefail
cd "$(dirname "$0")/.."
old_rev=${1:?usage: scripts/bench-compare.sh OLD_REV [ROUNDS] [FILTER]}
rounds=${2:-3}
filter=${3:-}
target=${CARGO_TARGET_DIR:-$PWD/target}
export CARGO_TARGET_DIR=$target
wt=$(mktemp -d)
trap 'git worktree remove --force "$wt" 2>/dev/null || rm -rf "$wt"' EXIT
git worktree add -q --detach "$wt" "$old_rev"
# The bench executable built from the tree in $1, copied to $2. Both trees share the
# target directory and cargo names their artifacts alike (and judges them fresh by
# modification time), so snaked is cleaned before each build.
build() {
    (cd "$1" && cargo clean -q -p snaked --release &&
        cargo bench --bench shape_step --no-run --message-format=json) |
        python3 -c 'import json, sys
for line in sys.stdin:
    m = json.loads(line)
    if m.get("reason") == "compiler-artifact" and m["target"]["name"] == "shape_step" and m.get("executable"):
        print(m["executable"])' | xargs -I{} cp {} "$2"
}
old=$target/shape_step-old
new=$target/shape_step-new
build "$wt" "$old"
build "$PWD" "$new"
if cmp -s "$old" "$new"; then
    echo "$old_rev builds the same bench as the working tree" >&2
    exit 1
fi
for r in $(seq "$rounds"); do
    for side in old new; do
        echo "round $r: $side" >&2
        "${!side}" --bench --warm-up-time 1 --measurement-time 2 --save-baseline "$side-$r" \
            ${filter:+"$filter"} > /dev/null
    done
done
python3 - "$target/criterion/shape_step" "$rounds" <<'PY'
import json, pathlib, statistics, sys
root, rounds = pathlib.Path(sys.argv[1]), int(sys.argv[2])
def median(bench, side):
    runs = [bench / f"{side}-{r}" / "estimates.json" for r in range(1, rounds + 1)]
    ns = [json.loads(p.read_text())["median"]["point_estimate"] for p in runs if p.exists()]
    return statistics.median(ns) if ns else None
def show(ns):
    return f"{ns / 1000:.3g} µs" if ns >= 1000 else f"{ns:.3g} ns"
print("| controller | N | before | after | before / after |")
print("| --- | ---: | ---: | ---: | ---: |")
for name in sorted(p for p in root.iterdir() if p.is_dir() and p.name != "report"):
    for bench in sorted((p for p in name.iterdir() if p.name.isdigit()), key=lambda p: int(p.name)):
        before, after = median(bench, "old"), median(bench, "new")
        if before and after:
            print(f"| {name.name} | {bench.name} | {show(before)} | {show(after)} | {before / after:.2f} |")
PY
