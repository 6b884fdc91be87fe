#!/usr/bin/env bash
# The loop's timing over the HEBI bus against the UDP bus, in real time, alternating in
# rounds within one run:
#   scripts/hebi-vs-udp.sh [ROUNDS] [SECONDS] [MODULES]
# Each round runs snaked, sidewinding from the start, for SECONDS (default 10) over
#   udp:  snake-emu with MODULES (default 18) modules, one endpoint per module on
#         127.0.0.1 (as io-compare.sh's default), and
#   hebi: `[bus] kind = "hebi"` over HEBI's imitation group of MODULES modules (libhebi
#         echoes each command as feedback; no lookup, no network),
# the two in turn (udp first in odd rounds, hebi first in even ones, so drift over the
# run falls on both), ROUNDS (default 3) times. Prints, per variant, each round's wake-up
# latency, bus_io (time in the bus's receive + send) and compute p50 / p99 (µs), cycles
# and overruns, the medians over the rounds, and the ratio hebi / udp of the medians.
# libhebi comes from scripts/fetch-libhebi.sh (fetched once, into target/hebi/).
# RT=1: the loop under SCHED_FIFO 80 with locked memory on CPU 1 and the emulator on
# CPU 0 (needs root or CAP_SYS_NICE; refused settings only warn), as loop-timing.sh.
# BIN=DIR takes snaked, snake-emu and snakectl from DIR without building.
# Only loopback traffic.
set -euo pipefail
cd "$(dirname "$0")/.."
# shellcheck source=scripts/emu-config.sh
source scripts/emu-config.sh
rounds=${1:-3}
secs=${2:-10}
n=${3:-18}
lib=$(scripts/fetch-libhebi.sh)
if [ -n "${BIN:-}" ]; then
    bins=$BIN
else
    cargo build --release --bins -q
    bins=${CARGO_TARGET_DIR:-target}/release
fi
dir=$(mktemp -d)
emu=""
daemon=""
trap 'kill $emu $daemon 2>/dev/null || true; rm -rf "$dir"' EXIT
emu_pre=()
loop_toml=""
if [ "${RT:-0}" = 1 ]; then
    emu_pre=(taskset -c 0)
    loop_toml=$'[loop]\nsched_fifo_priority = 80\nlock_memory = true\ncpu = 1'
fi
mkdir -p "$dir/udp" "$dir/hebi"
cat > "$dir/hebi.toml" <<TOML
$loop_toml
[bus]
kind = "hebi"
[hebi]
imitation = $n
interfaces = ["127.0.0.1"]
library = "$lib"
[gait]
initial = "sidewinding"
start = "run"
[control]
socket = "$dir/hebi/snaked.sock"
TOML

# One measured run: VARIANT (udp or hebi), ROUND. Starts snaked, waits until its socket
# answers, lets it run SECONDS, then takes its stats and stops it.
measure() {
    local v=$1 r=$2 sock=$dir/$1/snaked.sock
    "$bins/snaked" --config "$dir/$v.toml" > /dev/null 2> "$dir/$v-$r.log" &
    daemon=$!
    for _ in $(seq 1 100); do
        if "$bins/snakectl" --socket "$sock" stats > /dev/null 2>&1; then break; fi
        sleep 0.1
    done
    sleep "$secs"
    "$bins/snakectl" --socket "$sock" --json stats > "$dir/$v-$r.json"
    kill -TERM "$daemon"; wait "$daemon" || true
    daemon=""
    # The gait must have run throughout: any change of mode before the shutdown is told.
    if grep 'state mode=' "$dir/$v-$r.log" | grep -v 'reason=Startup\|reason=Shutdown' >&2; then
        echo "round $r: $v left Running before the end (above)" >&2
    fi
}

udp_round() {
    local r=$1 base=$((30000 + RANDOM % 20000))
    "${emu_pre[@]}" "$bins/snake-emu" --modules "$n" --base-port "$base" 2> "$dir/emu-$r.log" &
    emu=$!
    emu_config "$dir/udp.toml" "$base" "$n" "$dir/udp" "$loop_toml"
    sleep 0.5
    measure udp "$r"
    kill -TERM "$emu"; wait "$emu" || true
    emu=""
}

for r in $(seq 1 "$rounds"); do
    if (( r % 2 )); then order=(udp hebi); else order=(hebi udp); fi
    for v in "${order[@]}"; do
        if [ "$v" = udp ]; then udp_round "$r"; else measure hebi "$r"; fi
        echo "round $r/$rounds: $v done (${secs} s)" >&2
    done
done
python3 - "$dir" "$rounds" "$n" "$secs" <<'PY'
import json, statistics, sys
d, rounds, n, secs = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4]
keys = [("wakeup_latency", "wake-up latency"), ("bus_io", "bus_io"), ("compute", "compute")]
titles = {"udp": f"udp: snake-emu, {n} modules, one endpoint each (127.0.0.1)",
          "hebi": f"hebi: libhebi imitation group of {n}"}
med = {}
for v in ["udp", "hebi"]:
    rows = []
    for r in range(1, rounds + 1):
        s = json.load(open(f"{d}/{v}-{r}.json"))["loop"]
        row = []
        for k, _ in keys:
            row += [s[k]["p50_us"], s[k]["p99_us"]]
        rows.append(row + [s["cycles"], s["overruns"]])
    med[v] = [statistics.median(c) for c in zip(*rows)]
    print(f"{titles[v]}; {secs} s a round; µs")
    print(f"{'round':>6} | " + " | ".join(f"{t:^15}" for _, t in keys) + f" | {'cycles':>7} {'overruns':>8}")
    print(f"{'':>6} | " + " | ".join(f"{'p50':>7} {'p99':>7}" for _ in keys) + " |")
    for name, row in [(str(r + 1), x) for r, x in enumerate(rows)] + [("median", med[v])]:
        cells = " | ".join(f"{row[2 * i]:7.1f} {row[2 * i + 1]:7.1f}" for i in range(len(keys)))
        print(f"{name:>6} | {cells} | {row[6]:7.0f} {row[7]:8.0f}")
    print()
ratio = [h / u if u > 0 else float("inf") for h, u in zip(med["hebi"], med["udp"])]
cells = " | ".join(f"{ratio[2 * i]:7.2f} {ratio[2 * i + 1]:7.2f}" for i in range(len(keys)))
print(f"{'ratio':>6} | {cells} |   (hebi / udp, medians)")
PY
