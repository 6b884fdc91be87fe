#!/usr/bin/env bash
# The loop's period error against the machine's floor, under the same load:
#   scripts/jitter-vs-cyclictest.sh [ROUNDS] [SECONDS] [MODULES]
# Starts snake-emu (MODULES, default 18) over UDP on loopback, then alternates ROUNDS
# (default 3) times: cyclictest (rt-tests; one thread, 1 ms interval, SECONDS, default
# 30) and snaked at 1 kHz against the emulator for SECONDS (and up to two more snaked
# variants after it, below). Prints the period-error distributions (p50, p99,
# p99.9, max, µs) per round and, per snaked variant, the medians over the rounds and
# their ratio to cyclictest's.
#
# The same load: during the cyclictest rounds a second snaked, the load daemon (same
# binary, same configuration), drives the emulator, so the emulator does the same work
# (commands decoded, plant stepped, feedback sent at 1 kHz) and loopback carries the same
# datagrams as in the snaked rounds. Only the load daemon's loop is not measured, and
# it is kept off the measured CPU: with RT=1 the whole load daemon runs on CPU 0 beside
# the emulator (its loop under the same SCHED_FIFO as the measured one), so CPU 1 holds
# what it holds in a snaked round minus snaked itself, which is what a floor is. Its
# cost (2-5 % of one CPU) is the one thing CPU 0 carries on top. Without RT=1 nothing is
# pinned, the load daemon included. LOAD=0 leaves the
# emulator idle during cyclictest (the earlier, quieter comparison).
#
# RT=1: cyclictest and the measured loop under SCHED_FIFO 80 with locked memory on CPU 1,
# the emulator on CPU 0; needs root or CAP_SYS_NICE. GATEWAY=1: the emulator serves
# every module from one endpoint (`snake-emu --gateway`, one datagram per cycle each
# way) instead of one endpoint per module.
# Variants, measured in the same run, one round of each after each cyclictest round:
#   B=PATH      a second snaked binary (e.g. built from another commit);
#   B_LOOP=TOML extra `[loop]` lines for it (e.g. 'busy_wait_s = 0.00005'; the first
#               binary when B is not set);
#   C=PATH, C_LOOP=TOML a third variant, likewise;
#   A_LOOP=TOML extra `[loop]` lines for the first variant (and the load daemon).
#   A key given there replaces RT=1's (e.g. B_LOOP='lock_memory = false').
#   A_PREFIX, B_PREFIX, C_PREFIX: a command the variant runs under (e.g. 'taskset -c 1': every
#               thread of the daemon on the loop's CPU).
# BG=N: N busy loops at nice 19 run throughout (cyclictest's rounds and snaked's): the
# loaded machine. The per-thread minor page faults of the loop thread (snaked-rt) from
# 2 s after start to the end are printed for each snaked round.
# cyclictest holds /dev/cpu_dma_latency at 0 while it runs (idle CPUs poll instead of
# halting); so does snaked under SCHED_FIFO (RT=1) unless `cpu_dma_latency_s` says
# otherwise (B_LOOP='cpu_dma_latency_s = 0.1': let the CPUs halt).
# CT_ARGS="--laptop" runs cyclictest without it.
# CT_IDLE=1 adds a cyclictest round with the emulator idle to each round (what the load
# changes). BIN=DIR takes snaked, snake-emu and snakectl from DIR without building.
# cyclictest measures wake-up latency against an absolute schedule; so does snaked's
# `wakeup_latency` (cycle start - deadline, docs/architecture.md), in the same 1 µs
# buckets below 200 µs, truncated as cyclictest's histogram counts them, so the ratios
# compare like with like. snaked's period error (the jitter between successive cycle
# starts) and its compute time are printed beside it.
set -euo pipefail
cd "$(dirname "$0")/.."
# shellcheck source=scripts/emu-config.sh
source scripts/emu-config.sh
rounds=${1:-3}
secs=${2:-30}
n=${3:-18}
command -v cyclictest >/dev/null || { apt-get install -y -qq rt-tests >/dev/null || {
    apt-get update -qq && apt-get install -y -qq rt-tests >/dev/null; }; }
if [ -n "${BIN:-}" ]; then
    bins=$BIN
else
    cargo build --release --bins -q
    bins=${CARGO_TARGET_DIR:-target}/release
fi
a_bin=$bins/snaked
b_bin=${B:-}
if [ -z "$b_bin" ] && [ -n "${B_LOOP:-}${B_PREFIX:-}" ]; then b_bin=$a_bin; fi
c_bin=${C:-}
if [ -z "$c_bin" ] && [ -n "${C_LOOP:-}${C_PREFIX:-}" ]; then c_bin=$a_bin; fi
snakectl=$bins/snakectl
dir=$(mktemp -d)
emu=""
load=""
bg=()
trap 'kill $emu $load ${bg[*]} 2>/dev/null || true' EXIT
for _ in $(seq 1 "${BG:-0}"); do
    nice -n 19 sh -c 'while :; do :; done' &
    bg+=($!)
done
base=$((30000 + RANDOM % 20000))
emu_cmd=("$bins/snake-emu" --modules "$n" --base-port "$base")
if [ "${GATEWAY:-0}" = 1 ]; then emu_cmd+=(--gateway); fi
read -r -a ct_rt <<< "${CT_ARGS:-}"
loop_toml=$'[loop]'
load_toml=$'[loop]'
load_cmd=()
if [ "${RT:-0}" = 1 ]; then
    emu_cmd=(taskset -c 0 "${emu_cmd[@]}")
    ct_rt+=(-p 80 -m -a 1)
    rt=$'\nsched_fifo_priority = 80\nlock_memory = true'
    loop_toml+="$rt"$'\ncpu = 1'
    load_toml+="$rt"$'\ncpu = 0'
    load_cmd=(taskset -c 0)
fi
"${emu_cmd[@]}" 2> "$dir/emu.log" &
emu=$!
# BASE's `[loop]` lines with EXTRA's after them, a key in EXTRA replacing BASE's.
merge_loop() {
    local base=$1 extra=$2 line key out=""
    while IFS= read -r line; do
        key=${line%%=*}
        key=${key// /}
        if [ "$line" != "[loop]" ] && [ -n "$key" ] \
            && printf '%s\n' "$extra" | grep -q "^ *$key *="; then
            continue
        fi
        out+="$line"$'\n'
    done <<< "$base"
    printf '%s%s' "$out" "$extra"
}
emu_config "$dir/a.toml" "$base" "$n" "$dir/a" "$(merge_loop "$loop_toml" "${A_LOOP:-}")"
emu_config "$dir/b.toml" "$base" "$n" "$dir/b" "$(merge_loop "$loop_toml" "${B_LOOP:-}")"
emu_config "$dir/c.toml" "$base" "$n" "$dir/c" "$(merge_loop "$loop_toml" "${C_LOOP:-}")"
emu_config "$dir/load.toml" "$base" "$n" "$dir/load" "$(merge_loop "$load_toml" "${A_LOOP:-}")"
mkdir -p "$dir/a" "$dir/b" "$dir/c" "$dir/load"
sleep 1

# Starts a snaked (BIN, CONFIG, LOG, then a command prefix) and waits until its
# socket answers; its pid in $started.
start_daemon() {
    local bin=$1 cfg=$2 log=$3 sock
    shift 3
    sock=$(dirname "$cfg")/$(basename "$cfg" .toml)/snaked.sock
    "$@" "$bin" --config "$cfg" > /dev/null 2> "$log" &
    started=$!
    for _ in $(seq 1 100); do
        if "$snakectl" --socket "$sock" stats > /dev/null 2>&1; then break; fi
        sleep 0.1
    done
}

# Minor page faults of the loop thread (snaked-rt) of process PID.
loop_minflt() {
    local t
    for t in /proc/"$1"/task/*; do
        if [ "$(cat "$t/comm" 2>/dev/null)" = snaked-rt ]; then
            # Field 10 of stat, after the parenthesised name.
            sed 's/.*) //' "$t/stat" | awk '{print $8}'
            return
        fi
    done
    echo 0
}

# One measured snaked round: VARIANT (a or b), BIN, ROUND, then a command prefix.
snaked_round() {
    local v=$1 bin=$2 r=$3 f0 pid
    shift 3
    echo "round $r/$rounds: snaked ($v) ${secs} s" >&2
    start_daemon "$bin" "$dir/$v.toml" "$dir/snaked-$v-$r.log" "$@"
    # With a prefix (taskset) the daemon is its child or the exec'd process itself.
    pid=$(pgrep -n -f -- "--config $dir/$v.toml" || echo "$started")
    sleep 2
    f0=$(loop_minflt "$pid")
    sleep "$((secs - 2))"
    "$snakectl" --socket "$dir/$v/snaked.sock" --json stats > "$dir/sd-$v-$r.json"
    echo $(( $(loop_minflt "$pid") - f0 )) > "$dir/minflt-$v-$r.txt"
    kill -TERM "$started"; wait "$started" || true
}

read -r -a a_pre <<< "${A_PREFIX:-}"
read -r -a b_pre <<< "${B_PREFIX:-}"
read -r -a c_pre <<< "${C_PREFIX:-}"
for r in $(seq 1 "$rounds"); do
    if [ "${CT_IDLE:-0}" = 1 ]; then
        echo "round $r/$rounds: cyclictest ${secs} s (emulator idle)" >&2
        cyclictest -t1 -i 1000 -D "${secs}s" -q -h 100000 "${ct_rt[@]}" > "$dir/ct-idle-$r.txt"
    fi
    if [ "${LOAD:-1}" = 1 ]; then
        start_daemon "$a_bin" "$dir/load.toml" "$dir/load-$r.log" "${load_cmd[@]}"
        load=$started
    fi
    echo "round $r/$rounds: cyclictest ${secs} s (load: ${LOAD:-1})" >&2
    cyclictest -t1 -i 1000 -D "${secs}s" -q -h 100000 "${ct_rt[@]}" > "$dir/ct-$r.txt"
    if [ -n "$load" ]; then
        "$snakectl" --socket "$dir/load/snaked.sock" --json stats > "$dir/load-$r.json"
        kill -TERM "$load"; wait "$load" || true
        load=""
    fi
    snaked_round a "$a_bin" "$r" "${a_pre[@]}"
    if [ -n "$b_bin" ]; then snaked_round b "$b_bin" "$r" "${b_pre[@]}"; fi
    if [ -n "$c_bin" ]; then snaked_round c "$c_bin" "$r" "${c_pre[@]}"; fi
done
python3 - "$dir" "$rounds" <<'PY'
import json, os, statistics, sys
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

def sd(path):
    s = json.load(open(path))["loop"]
    w, e, c = s["wakeup_latency"], s["period_error"], s["compute"]
    return {"p50": w["p50_us"], "p99": w["p99_us"], "p999": w["p999_us"], "max": w["max_us"],
            "e99": e["p99_us"], "c50": c["p50_us"], "c99": c["p99_us"], "over": s["overruns"],
            "flt": int(open(path.replace("sd-", "minflt-").replace(".json", ".txt")).read())}

variants = [v for v in "abc" if os.path.exists(f"{d}/sd-{v}-1.json")]
rows = []
head = f"{'round':>5} | {'cyclictest p50':>14} {'p99':>6} {'p99.9':>6} {'max':>6}"
for v in variants:
    head += (f" | snaked {v} p50 {'p99':>6} {'p99.9':>6} {'max':>7}"
             " (period error p99; compute p50/p99; overruns; minor faults)")
print("wake-up latency, µs")
print(head)
for r in range(1, rounds + 1):
    c = ct(f"{d}/ct-{r}.txt")
    ss = {v: sd(f"{d}/sd-{v}-{r}.json") for v in variants}
    rows.append((c, ss))
    line = f"{r:>5} | {c['p50']:>14.1f} {c['p99']:>6.1f} {c['p999']:>6.1f} {c['max']:>6.1f}"
    for v in variants:
        s = ss[v]
        line += (f" | {s['p50']:>14.1f} {s['p99']:>6.1f} {s['p999']:>6.1f} {s['max']:>7.1f}"
                 f" ({s['e99']:.1f}; {s['c50']:.1f}/{s['c99']:.1f}; {s['over']}; {s['flt']})")
    print(line)
if os.path.exists(f"{d}/ct-idle-1.txt"):
    idle = [ct(f"{d}/ct-idle-{r}.txt") for r in range(1, rounds + 1)]
    print("cyclictest, emulator idle: " + "; ".join(
        f"round {r + 1} {c['p50']:.0f} / {c['p99']:.0f} / {c['p999']:.0f} / {c['max']:.0f}"
        for r, c in enumerate(idle)) + " (p50 / p99 / p99.9 / max)")
    print("  medians: " + ", ".join(
        f"{k} {statistics.median(c[k] for c in idle):.1f}" for k in ["p50", "p99", "p999"]))
# Each round's snaked beside the cyclictest round just before it: the geometric mean of
# those paired ratios and its standard error (the machine's drift falls on both sides).
import math
for v in variants:
    for k in ["p50", "p99"]:
        logs = [math.log(max(s[v][k], 1.0) / max(c[k], 1.0)) for c, s in rows]
        m = statistics.mean(logs)
        se = statistics.stdev(logs) / math.sqrt(len(logs)) if len(logs) > 1 else float("nan")
        print(f"paired by round, snaked {v} / cyclictest {k}: {math.exp(m):.2f}× "
              f"(±1 SE {math.exp(m - se):.2f}–{math.exp(m + se):.2f}, {len(logs)} rounds)")
for k in ["p50", "p99", "p999"]:
    cm = statistics.median(c[k] for c, _ in rows)
    line = f"median {k}: cyclictest {cm:.1f} µs"
    for v in variants:
        sm = statistics.median(s[v][k] for _, s in rows)
        ratio = sm / cm if cm > 0 else float("inf")
        line += f"; snaked {v} {sm:.1f} µs, ratio {ratio:.2f}"
    print(line)
PY
echo "raw output: $dir" >&2
