#!/usr/bin/env bash
# The loop's period error against the machine's floor, under the same load:
#   scripts/jitter-vs-cyclictest.sh [ROUNDS] [SECONDS] [MODULES]
# Starts snake-emu (MODULES, default 18) over UDP on loopback, then alternates ROUNDS
# (default 3) times: cyclictest (rt-tests; one thread, 1 ms interval, SECONDS, default
# 30) and snaked at 1 kHz against the emulator for SECONDS. Prints both period-error
# distributions (p50, p99, p99.9, max, µs) per round and the ratio snaked / cyclictest
# of the medians over the rounds. RT=1 runs both under SCHED_FIFO 80 with locked memory
# on CPU 1 (the emulator on CPU 0); needs root or CAP_SYS_NICE.
# cyclictest measures wake-up latency; snaked's period error is |cycle start - deadline|
# (docs/architecture.md): the same quantity for a loop on absolute deadlines.
set -euo pipefail
cd "$(dirname "$0")/.."
# shellcheck source=scripts/emu-config.sh
source scripts/emu-config.sh
rounds=${1:-3}
secs=${2:-30}
n=${3:-18}
command -v cyclictest >/dev/null || { apt-get install -y -qq rt-tests >/dev/null || {
    apt-get update -qq && apt-get install -y -qq rt-tests >/dev/null; }; }
cargo build --release --bins -q
dir=$(mktemp -d)
trap 'kill $emu 2>/dev/null || true' EXIT
base=$((30000 + RANDOM % 20000))
emu_cmd=(./target/release/snake-emu --modules "$n" --base-port "$base")
ct_rt=()
rt_toml=""
if [ "${RT:-0}" = 1 ]; then
    emu_cmd=(taskset -c 0 "${emu_cmd[@]}")
    ct_rt=(-p 80 -m -a 1)
    rt_toml=$'[loop]\nsched_fifo_priority = 80\nlock_memory = true\ncpu = 1'
fi
"${emu_cmd[@]}" 2> "$dir/emu.log" &
emu=$!
emu_config "$dir/snaked.toml" "$base" "$n" "$dir" "$rt_toml"
sleep 1
for r in $(seq 1 "$rounds"); do
    echo "round $r/$rounds: cyclictest ${secs} s" >&2
    cyclictest -t1 -i 1000 -D "${secs}s" -q -h 100000 "${ct_rt[@]}" > "$dir/ct-$r.txt"
    echo "round $r/$rounds: snaked ${secs} s" >&2
    ./target/release/snaked --config "$dir/snaked.toml" 2> "$dir/snaked-$r.log" &
    daemon=$!
    sleep "$secs"
    ./target/release/snakectl --socket "$dir/snaked.sock" --json stats > "$dir/sd-$r.json"
    kill -TERM $daemon; wait $daemon || true
done
python3 - "$dir" "$rounds" <<'PY'
import json, statistics, sys
d, rounds = sys.argv[1], int(sys.argv[2])
def ct(path):
    hist = []
    for line in open(path):
        parts = line.split()
        if len(parts) == 2 and parts[0].isdigit():
            hist.append((int(parts[0]), int(parts[1])))
    total = sum(c for _, c in hist)
    def q(p):
        acc = 0
        for us, c in hist:
            acc += c
            if acc >= p * total:
                return float(us)
        return float(hist[-1][0])
    mx = max((us for us, c in hist if c), default=0)
    return {"p50": q(0.5), "p99": q(0.99), "p999": q(0.999), "max": float(mx), "n": total}
rows = []
print(f"{'round':>5} | {'cyclictest p50':>14} {'p99':>8} {'p99.9':>8} {'max':>8} | {'snaked p50':>10} {'p99':>8} {'p99.9':>8} {'max':>8}  (µs)")
for r in range(1, rounds + 1):
    c = ct(f"{d}/ct-{r}.txt")
    s = json.load(open(f"{d}/sd-{r}.json"))["loop"]["period_error"]
    sd = {"p50": s["p50_us"], "p99": s["p99_us"], "p999": s["p999_us"], "max": s["max_us"]}
    rows.append((c, sd))
    print(f"{r:>5} | {c['p50']:>14.1f} {c['p99']:>8.1f} {c['p999']:>8.1f} {c['max']:>8.1f} | "
          f"{sd['p50']:>10.1f} {sd['p99']:>8.1f} {sd['p999']:>8.1f} {sd['max']:>8.1f}")
for k in ["p50", "p99", "p999"]:
    cm = statistics.median(c[k] for c, _ in rows)
    sm = statistics.median(s[k] for _, s in rows)
    ratio = sm / cm if cm > 0 else float("inf")
    print(f"median {k}: cyclictest {cm:.1f} µs, snaked {sm:.1f} µs, ratio {ratio:.2f}")
PY
