#!/usr/bin/env bash
# The loop's timing with many Foxglove viewers, side by side (issue 29, point 5):
#   scripts/live-load.sh [SECONDS] [VIEWERS] [SLOW_MS] [ROUNDS]
# Runs `snaked --emulated --foxglove` on flat ground (compliant slithering) for SECONDS
# (default 30), alternately with no viewer and with VIEWERS (default 20) headless
# viewers subscribed to every channel plus one that sleeps SLOW_MS (default 100) after
# each message (it cannot keep up), ROUNDS times (default 2). Prints each run's period
# error and compute time (snakectl stats), the recorder's drops and what each viewer
# received. The viewers run on this machine at nice 19, so what is measured is what
# serving them costs the daemon, as far as two CPUs shared with them allow.
set -euo pipefail
cd "$(dirname "$0")/.."
secs=${1:-30}
viewers=${2:-20}
slow_ms=${3:-100}
rounds=${4:-2}
cargo build --release --bins --example foxglove_viewer -q
dir=$(mktemp -d)
pids=()
trap 'kill "${pids[@]}" 2>/dev/null || true' EXIT
port=$((20000 + RANDOM % 20000))
cat > "$dir/snaked.toml" <<TOML
[gait]
initial = "slithering"
[gait.controllers.slithering]
controller = "a_ws_omega"
[control]
socket = "$dir/snaked.sock"
[foxglove]
enabled = true
port = $port
TOML
summary='
import json, sys
s = json.load(sys.stdin)
l = s["loop"]
pe, c = l["wakeup_latency"], l["compute"]
print("wake-up latency us: p50 %.1f p99 %.1f p999 %.1f max %.1f; compute p99 %.1f; overruns %d; record_dropped %d"
      % (pe["p50_us"], pe["p99_us"], pe["p999_us"], pe["max_us"], c["p99_us"], l["overruns"], s["record_dropped"]))'
run() {
    local label=$1 n=$2
    ./target/release/snaked --config "$dir/snaked.toml" --emulated \
        --world scenarios/flat.toml 2> "$dir/$label.log" &
    local daemon=$!
    pids=("$daemon")
    sleep 1
    for ((k = 0; k < n; k++)); do
        nice -n 19 ./target/release/examples/foxglove_viewer "ws://127.0.0.1:$port" "$((secs - 3))" \
            > "$dir/$label.viewer$k" &
        pids+=($!)
    done
    if ((n > 0)); then
        nice -n 19 ./target/release/examples/foxglove_viewer "ws://127.0.0.1:$port" "$((secs - 3))" \
            "$slow_ms" > "$dir/$label.slow" &
        pids+=($!)
    fi
    sleep "$secs"
    echo "=== $label: $n viewers$( ((n > 0)) && echo " + 1 slow (${slow_ms} ms a message)") ($secs s) ==="
    ./target/release/snakectl --socket "$dir/snaked.sock" --json stats | python3 -c "$summary"
    kill -TERM "$daemon"; wait "$daemon" || true
    for p in "${pids[@]:1}"; do wait "$p" || true; done
    if ((n > 0)); then
        echo -n "idle viewer 0 /joints: "; grep "^/joints " "$dir/$label.viewer0" || echo none
        echo -n "slow viewer /joints: "; grep "^/joints " "$dir/$label.slow" || true
        grep "connection ended" "$dir/$label.slow" || true
    fi
}
for ((r = 1; r <= rounds; r++)); do
    run "none-$r" 0
    run "load-$r" "$viewers"
done
echo "files in $dir"
