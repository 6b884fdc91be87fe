#!/usr/bin/env bash
# Loop timing against snake-emu over UDP on loopback, in real time:
#   scripts/loop-timing.sh [SECONDS] [MODULES]
# Builds release binaries, runs snake-emu and snaked for SECONDS (default 60) with
# sidewinding, then prints the daemon's `stats` (period error, compute time, feedback
# age, lost and late feedback, overruns) as snakectl shows it, and as JSON.
# RT=1 runs the loop under SCHED_FIFO 80 with locked memory, pinned to CPU 1, and the
# emulator on CPU 0 (needs root or CAP_SYS_NICE; refused settings only warn).
set -euo pipefail
cd "$(dirname "$0")/.."
# shellcheck source=scripts/emu-config.sh
source scripts/emu-config.sh
secs=${1:-60}
n=${2:-18}
cargo build --release --bins -q
dir=$(mktemp -d)
trap 'kill $emu $daemon 2>/dev/null || true; rm -rf "$dir"' EXIT
base=$((30000 + RANDOM % 20000))
emu_cmd=(./target/release/snake-emu --modules "$n" --base-port "$base")
rt_toml=""
if [ "${RT:-0}" = 1 ]; then
    emu_cmd=(taskset -c 0 "${emu_cmd[@]}")
    rt_toml=$'[loop]\nsched_fifo_priority = 80\nlock_memory = true\ncpu = 1'
fi
"${emu_cmd[@]}" &
emu=$!
emu_config "$dir/snaked.toml" "$base" "$n" "$dir" "$rt_toml"
./target/release/snaked --config "$dir/snaked.toml" &
daemon=$!
sleep 1
echo "running $secs s with $n modules..." >&2
sleep "$secs"
./target/release/snakectl --socket "$dir/snaked.sock" stats
./target/release/snakectl --socket "$dir/snaked.sock" --json stats > "$dir/stats.json"
cat "$dir/stats.json"
kill -TERM $daemon; wait $daemon
