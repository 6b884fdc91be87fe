#!/usr/bin/env bash
# The daemon's per-cycle compute time (cycle start to commands sent: the I/O path plus
# the control step) against snake-emu over UDP in real time, for several builds and
# emulator layouts, alternating in rounds within one run:
#   scripts/io-compare.sh [ROUNDS] [SECONDS] [MODULES] [LABEL=BINDIR[:EMU_ARGS] ...]
# Default variants: this tree's release build with one endpoint per module and with
# `--gateway`. Add e.g. `v1=/path/to/old/target/release` to compare an older build
# (same config format). Prints each round's compute p50 / p99 and the medians.
set -euo pipefail
cd "$(dirname "$0")/.."
# shellcheck source=scripts/emu-config.sh
source scripts/emu-config.sh
rounds=${1:-3}
secs=${2:-10}
n=${3:-18}
shift $(( $# < 3 ? $# : 3 ))
cargo build --release --bins -q
here=$PWD/target/release
variants=("per-module=$here" "gateway=$here:--gateway" "$@")
dir=$(mktemp -d)
trap 'kill $emu $daemon 2>/dev/null || true; rm -rf "$dir"' EXIT
emu=0
daemon=0
for r in $(seq 1 "$rounds"); do
    for v in "${variants[@]}"; do
        label=${v%%=*}
        rest=${v#*=}
        bin=${rest%%:*}
        extra=""
        [[ $rest == *:* ]] && extra=${rest#*:}
        base=$((30000 + RANDOM % 20000))
        # shellcheck disable=SC2086
        "$bin/snake-emu" --modules "$n" --base-port "$base" $extra 2> "$dir/emu.log" &
        emu=$!
        emu_config "$dir/snaked.toml" "$base" "$n" "$dir"
        sleep 0.5
        "$bin/snaked" --config "$dir/snaked.toml" 2> "$dir/snaked.log" &
        daemon=$!
        sleep "$secs"
        "$bin/snakectl" --socket "$dir/snaked.sock" --json stats > "$dir/$label-$r.json"
        kill -TERM $daemon; wait $daemon || true
        kill -TERM $emu; wait $emu || true
        echo "round $r/$rounds: $label done" >&2
    done
done
labels=()
for v in "${variants[@]}"; do labels+=("${v%%=*}"); done
python3 - "$dir" "$rounds" "${labels[@]}" <<'PY'
import json, statistics, sys
d, rounds, labels = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
print(f"{'variant':>12} | compute p50 per round (µs)          | median p50 | median p99")
for l in labels:
    p50, p99 = [], []
    for r in range(1, rounds + 1):
        s = json.load(open(f"{d}/{l}-{r}.json"))["loop"]["compute"]
        p50.append(s["p50_us"]); p99.append(s["p99_us"])
    rs = " ".join(f"{x:6.1f}" for x in p50)
    print(f"{l:>12} | {rs:<36} | {statistics.median(p50):10.1f} | {statistics.median(p99):10.1f}")
PY
