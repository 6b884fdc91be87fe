#!/usr/bin/env bash
# The loop's timing with and without recording and with a live viewer, side by side:
#   scripts/record-timing.sh [SECONDS] [WORLD]
# Builds release binaries, then runs `snaked --emulated --world WORLD` (default
# scenarios/peg-board-40.toml, compliant slithering) three times for SECONDS (default
# 60) each: plain; with --record; with --record --foxglove and a headless viewer
# (examples/foxglove_viewer.rs) subscribed to every channel. Prints each run's period
# error and compute time (snakectl stats), the recorder's dropped items, the viewer's
# message rates, and the recording read back by Python's mcap package
# (scripts/mcap-summary.py) when it is installed.
set -euo pipefail
cd "$(dirname "$0")/.."
secs=${1:-60}
world=${2:-scenarios/peg-board-40.toml}
cargo build --release --bins --example foxglove_viewer -q
dir=$(mktemp -d)
trap 'kill $daemon $viewer 2>/dev/null || true' EXIT
port=$((20000 + RANDOM % 20000))
cat > "$dir/snaked.toml" <<TOML
[gait]
initial = "slithering"
[gait.controllers.slithering]
controller = "a_ws_omega"
[control]
socket = "$dir/snaked.sock"
[foxglove]
port = $port
TOML
run() {
    local label=$1; shift
    viewer=""
    ./target/release/snaked --config "$dir/snaked.toml" --emulated --world "$world" "$@" \
        2> "$dir/$label.log" &
    daemon=$!
    if [[ " $* " == *" --foxglove "* ]]; then
        ./target/release/examples/foxglove_viewer "ws://127.0.0.1:$port" "$((secs - 2))" \
            > "$dir/$label.viewer" &
        viewer=$!
    fi
    sleep "$secs"
    echo "=== $label ($secs s) ==="
    ./target/release/snakectl --socket "$dir/snaked.sock" stats | sed -n 1,8p
    ./target/release/snakectl --socket "$dir/snaked.sock" --json stats \
        | python3 -c 'import json,sys; s=json.load(sys.stdin); print("record_dropped", s["record_dropped"], " cycles", s["cycles"])'
    kill -TERM $daemon; wait $daemon || true
    if [ -n "$viewer" ]; then wait $viewer || true; echo "viewer:"; cat "$dir/$label.viewer"; fi
}
run plain
run record --record "$dir/record.mcap"
run record+viewer --record "$dir/viewer.mcap" --foxglove
grep -h "recording finished" "$dir"/*.log || true
if python3 -c 'import mcap' 2>/dev/null; then
    python3 scripts/mcap-summary.py "$dir/record.mcap"
fi
echo "files in $dir"
