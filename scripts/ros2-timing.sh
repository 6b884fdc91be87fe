#!/usr/bin/env bash
# The control loop's timing with the ROS 2 node on against off, side by side (issue 47):
#   scripts/ros2-timing.sh [SECONDS] [ROUNDS]
# Each round runs `snaked --emulated` (sidewinding from the start) for WARMUP s (default
# 5) and then SECONDS (default 20) measured, in two arms:
#   off: the recorder, with the live view on a loopback port (0) that nobody watches: the
#        lightest way to run the recorder, which the node hangs from (docs/ros2.md);
#   on:  the same plus `[ros2]`, /joint_states at 1 kHz to one rclpy subscriber
#        (scripts/ros2-timing-listener.py: Fast DDS, sensor-data QoS),
# off first in odd rounds, on first in even ones (drift falls on both), ROUNDS (default
# 3) times. Per arm: `snakectl stats`' wake-up latency p50 / p99 / p99.9 at the end (since
# the daemon's start, warm-up included: stats has no reset or window; the window's mean
# is worked out from mean and count at both ends), overruns in the window, the
# recorder's dropped items; the node's published rate and drops (its /diagnostics); the
# subscriber's rate in the window and message age (receive wall clock − stamp); CPU over the window (utime + stime) of each daemon thread
# (/proc/PID/task/*/stat) summed by name, "bridge" being snaked-ros2, snaked-ros2-spin
# and RustDDS's own threads (RustDDS*), of the whole daemon (/proc/PID/stat) and of the
# subscriber, in % of one core; the 1-min load average (the machine is shared). Prints
# each round, the medians per arm, ON − OFF of p50 and p99 as mean ± standard error over
# rounds, and the CPU per thread name. Everything runs in one loopback-only network
# namespace (scripts/ros2-peers.sh run, which installs the pinned rclpy peers if needed).
# BIN=DIR takes snaked and snakectl from DIR without building. KEEP=1 keeps the work dir.
# NOSUB=1: the on arm without the subscriber (the node publishes to nobody), to tell the
# node's cost from the subscriber's (both share the machine's CPUs with the loop).
# RT=1: the loop under SCHED_FIFO 80 with locked memory on CPU 1 (as loop-timing.sh).
set -euo pipefail
self=$(realpath "$0")
cd "$(dirname "$self")/.."
secs=${1:-20}
rounds=${2:-3}
warm=${WARMUP:-5}

if [ "${ROS2_TIMING_INNER:-}" != 1 ]; then
    if [ -z "${BIN:-}" ]; then
        cargo build --release -q --bin snaked --bin snakectl
        BIN=${CARGO_TARGET_DIR:-target}/release
    fi
    scripts/ros2-peers.sh install > /dev/null
    exec scripts/ros2-peers.sh run env ROS2_TIMING_INNER=1 BIN="$(realpath "$BIN")" \
        WARMUP="$warm" KEEP="${KEEP:-0}" NOSUB="${NOSUB:-0}" RT="${RT:-0}" "$self" "$secs" "$rounds"
fi

# From here on: inside the network namespace, with the peers' environment.
dir=$(mktemp -d)
daemon=""
listener=""
cleanup() {
    # shellcheck disable=SC2086 # either may be empty
    kill $listener $daemon 2> /dev/null || true
    if [ "${KEEP:-0}" = 1 ]; then echo "work dir: $dir" >&2; else rm -rf "$dir"; fi
}
trap cleanup EXIT
ctl() { "$BIN/snakectl" --socket "$dir/snaked.sock" "$@"; }
# One line per thread of PID: tid, name, CPU ticks (utime + stime).
threads() {
    local t
    for t in /proc/"$1"/task/*; do
        printf '%s\t%s\t%s\n' "${t##*/}" "$(cat "$t/comm")" \
            "$(sed 's/.*) //' "$t/stat" | awk '{print $12 + $13}')"
    done 2> /dev/null
}
ticks() { sed 's/.*) //' "/proc/$1/stat" | awk '{print $12 + $13}'; }

# One measured arm: ARM (off or on), ROUND; writes $dir/ARM-ROUND.* for the summary.
measure() {
    local arm=$1 r=$2 out=$dir/$1-$2
    {
        echo $'[foxglove]\nenabled = true\nport = 0'
        echo "[control]"$'\n'"socket = \"$dir/snaked.sock\""
        if [ "$arm" = on ]; then echo $'[ros2]\nenabled = true\njoint_states_rate_hz = 1000.0'; fi
        if [ "$RT" = 1 ]; then echo $'[loop]\nsched_fifo_priority = 80\nlock_memory = true\ncpu = 1'; fi
    } > "$dir/$arm.toml"
    rm -f "$dir/snaked.sock" "$dir/ready"
    # The subscriber first, so that its start (importing rclpy: ~1 s of CPU) is over
    # before the daemon's statistics begin.
    if [ "$arm" = on ] && [ "${NOSUB:-0}" != 1 ]; then
        "$ROS2_PEERS_PYTHON" scripts/ros2-timing-listener.py "$dir/ready" \
            > "$out.listener.json" 2> "$out.listener.log" &
        listener=$!
        for _ in $(seq 1 300); do [ -e "$dir/ready" ] && break; sleep 0.1; done
    fi
    env -u LD_LIBRARY_PATH "$BIN/snaked" --emulated --config "$dir/$arm.toml" \
        > /dev/null 2> "$out.log" &
    daemon=$!
    for _ in $(seq 1 100); do ctl stats > /dev/null 2>&1 && break; sleep 0.1; done
    if ! kill -0 "$daemon" 2> /dev/null; then
        echo "round $r: $arm: snaked exited early: $(tail -n1 "$out.log")" >&2
        exit 1
    fi
    sleep "$warm"
    [ -z "$listener" ] || kill -USR1 "$listener"
    date +%s%N > "$out.t0"
    threads "$daemon" > "$out.cpu0"
    ticks "$daemon" > "$out.proc0"
    if [ -n "$listener" ]; then ticks "$listener" > "$out.lis0"; fi
    ctl --json stats > "$out.stats0.json"
    sleep "$secs"
    [ -z "$listener" ] || kill -USR2 "$listener"
    date +%s%N > "$out.t1"
    threads "$daemon" > "$out.cpu1"
    ticks "$daemon" > "$out.proc1"
    if [ -n "$listener" ]; then ticks "$listener" > "$out.lis1"; fi
    ctl --json stats > "$out.stats1.json"
    cut -d' ' -f1 /proc/loadavg > "$out.load"
    if [ -n "$listener" ]; then wait "$listener" || echo "round $r: the listener failed" >&2; fi
    listener=""
    kill -TERM "$daemon"; wait "$daemon" || true
    daemon=""
    grep -q 'stopped safely' "$out.log" || echo "round $r: $arm did not stop safely" >&2
    if grep -q -E ' (WARN|ERROR) ' "$out.log"; then
        echo "round $r: $arm logged $(grep -c -E ' (WARN|ERROR) ' "$out.log") warnings/errors," \
            "first: $(grep -m1 -E ' (WARN|ERROR) ' "$out.log" | cut -c1-200)" >&2
    fi
}

for r in $(seq 1 "$rounds"); do
    if (( r % 2 )); then order=(off on); else order=(on off); fi
    for arm in "${order[@]}"; do
        measure "$arm" "$r"
        echo "round $r/$rounds: $arm done (${warm} s + ${secs} s)" >&2
    done
done

python3 - "$dir" "$rounds" "$secs" "$warm" "$(getconf CLK_TCK)" <<'PY'
import json, os, re, statistics as st, sys
d, rounds, secs, warm, hz = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4], int(sys.argv[5])
bridge = re.compile(r"^(snaked-ros2|RustDDS)")
med = lambda xs: st.median(xs) if xs else float("nan")
def per_name(f0, f1, wall):
    """CPU % of one core over the window, summed by thread name."""
    rows = lambda f: [l.split("\t") for l in open(f).read().splitlines()]
    before = {tid: int(t) for tid, _, t in rows(f0)}
    out = {}
    for tid, name, t in rows(f1):
        out[name] = out.get(name, 0.0) + 100 * (int(t) - before.get(tid, 0)) / hz / wall
    return out
res = {"off": [], "on": []}
for arm in res:
    for r in range(1, rounds + 1):
        p = f"{d}/{arm}-{r}"
        s0, s1 = json.load(open(p + ".stats0.json")), json.load(open(p + ".stats1.json"))
        pe0, pe1 = s0["loop"]["wakeup_latency"], s1["loop"]["wakeup_latency"]
        wall = (int(open(p + ".t1").read()) - int(open(p + ".t0").read())) / 1e9
        cpu = per_name(p + ".cpu0", p + ".cpu1", wall)
        tick = lambda f: int(open(f).read())
        lis = {}
        if os.path.exists(p + ".listener.json"):
            try:
                lis = json.load(open(p + ".listener.json"))
            except ValueError:
                print(f"round {r}: no answer from the listener ({p}.listener.log)", file=sys.stderr)
        n = pe1["count"] - pe0["count"]
        res[arm].append({
            "p50": pe1["p50_us"], "p99": pe1["p99_us"], "p999": pe1["p999_us"],
            "mean_w": (pe1["mean_us"] * pe1["count"] - pe0["mean_us"] * pe0["count"]) / max(n, 1),
            "overruns_w": s1["loop"]["overruns"] - s0["loop"]["overruns"],
            "dropped": s1["record_dropped"], "rate": lis.get("rate_hz", float("nan")),
            "age50": lis.get("age_ms_p50") or float("nan"), "age99": lis.get("age_ms_p99") or float("nan"),
            "bridge": sum(v for k, v in cpu.items() if bridge.match(k)),
            "daemon": 100 * (tick(p + ".proc1") - tick(p + ".proc0")) / hz / wall,
            "listener": 100 * (tick(p + ".lis1") - tick(p + ".lis0")) / hz / wall if lis else float("nan"),
            "node_hz": lis.get("node_published_hz") or float("nan"),
            "node_drop": (lis.get("node") or {}).get("dropped", float("nan")),
            "load": float(open(p + ".load").read()), "cpu": cpu, "node": lis.get("node"),
        })
cols = [("p50", "p50 µs", 7, 1), ("p99", "p99 µs", 7, 1), ("p999", "p99.9 µs", 8, 1),
        ("mean_w", "mean(win) µs", 12, 1), ("overruns_w", "overruns(win)", 13, 0),
        ("dropped", "rec dropped", 11, 0), ("node_hz", "node pub Hz", 11, 1),
        ("node_drop", "node dropped", 12, 0), ("rate", "recv Hz", 7, 1), ("age50", "age p50 ms", 10, 2),
        ("age99", "age p99 ms", 10, 2), ("bridge", "bridge CPU %", 12, 1),
        ("daemon", "daemon CPU %", 12, 1), ("listener", "rclpy CPU %", 11, 1), ("load", "load", 5, 2)]
head = lambda first: "| " + " | ".join([first] + [t for _, t, _, _ in cols]) + " |"
cell = lambda v, w, p: f"{'–':>{w}}" if v != v else f"{v:{w}.{p}f}"  # nan: not applicable
line = lambda name, row: "| " + " | ".join([name] + [cell(row[k], w, p) for k, _, w, p in cols]) + " |"
sep = lambda: "|" + "|".join(["---"] * (len(cols) + 1)) + "|"
print(f"\nsnaked --emulated, 18 modules, 1 kHz; {warm} s warm-up + {secs} s measured, {rounds} rounds;"
      " wake-up latency since the daemon's start (stats has no window), (win) = the measured window;"
      f" rclpy subscriber in the on arm: {'no' if os.environ.get('NOSUB') == '1' else 'yes'};"
      f" RT: {'SCHED_FIFO 80 on CPU 1' if os.environ.get('RT') == '1' else 'no'}")
print("\nEach round\n"); print(head("arm, round")); print(sep())
for r in range(rounds):
    for arm in ("off", "on"):
        print(line(f"{arm} {r + 1}", res[arm][r]))
print("\nMedians over rounds\n"); print(head("arm")); print(sep())
for arm in ("off", "on"):
    print(line(arm, {k: med([x[k] for x in res[arm]]) for k, *_ in cols}))
for k in ("p50", "p99"):
    diff = [b[k] - a[k] for a, b in zip(res["off"], res["on"])]
    se = st.stdev(diff) / len(diff) ** 0.5 if len(diff) > 1 else float("nan")
    print(f"\nON − OFF wake-up latency {k}: {st.mean(diff):+.1f} ± {se:.1f} µs (mean ± standard error over"
          f" {len(diff)} rounds; per round: {', '.join(f'{x:+.1f}' for x in diff)})")
names = sorted({n for arm in res for x in res[arm] for n in x["cpu"]})
print("\nCPU per thread name, % of one core over the window (median over rounds)\n")
print("| thread | bridge | off | on |"); print("|---|---|---|---|")
for n in names:
    m = {arm: med([x["cpu"][n] for x in res[arm] if n in x["cpu"]]) for arm in res}
    print(f"| {n} | {'yes' if bridge.match(n) else ''} | {cell(m['off'], 0, 2)} | {cell(m['on'], 0, 2)} |")
only_on = {n for x in res["on"] for n in x["cpu"]} - {n for x in res["off"] for n in x["cpu"]}
if only_on - {n for n in only_on if bridge.match(n)}:
    print(f"\nthreads only in the on arm not counted as bridge: {sorted(only_on)}")
node = [x["node"] for x in res["on"] if x["node"]]
print("\nthe node's counters at the last on arm's end (/diagnostics): "
      + (json.dumps(node[-1]) if node else "none (this daemon does not publish them)"))
PY
