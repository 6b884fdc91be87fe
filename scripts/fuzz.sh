#!/usr/bin/env bash
# Coverage-guided fuzzing (libFuzzer through cargo fuzz) of the packet codec, the control
# socket's request parser and the config parser: docs/fuzzing.md.
#
#   scripts/fuzz.sh [SECONDS_PER_TARGET] [TARGET...]     (default: 60 s, every target)
#
# Runs the targets one after another under `nice -n 19`, each from the committed seeds
# (fuzz/seeds/TARGET) plus what earlier runs found (fuzz/corpus/TARGET, not committed),
# with its dictionary (fuzz/dict/TARGET.dict), then prints executions, coverage and
# corpus per target. A crash is saved under fuzz/artifacts/TARGET/ and makes the script
# exit 1 once every target has run. Not part of the build or of CI.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD

secs=${1:-60}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(codec request config)

if ! command -v cargo-fuzz >/dev/null 2>&1; then
    cargo install cargo-fuzz --version 0.13.2 --locked
fi
# cargo fuzz passes unstable flags (-Z...) to rustc; a stable toolchain accepts them so.
export RUSTC_BOOTSTRAP=1
# Debug assertions and overflow checks on; no sanitizer: the code under test is safe
# Rust, and without one a run is about twice as fast.
flags=(--debug-assertions --sanitizer none)
nice -n 19 cargo fuzz build "${flags[@]}"

declare -A max_len=([codec]=1500 [request]=4096 [config]=8192)
mkdir -p fuzz/logs
failed=()
summary=()
for t in "${targets[@]}"; do
    mkdir -p "fuzz/corpus/$t" "fuzz/artifacts/$t"
    log="fuzz/logs/$t.log"
    echo "== $t: ${secs} s (log: $log)"
    status=0
    nice -n 19 cargo fuzz run "${flags[@]}" "$t" "$root/fuzz/corpus/$t" "$root/fuzz/seeds/$t" -- \
        -dict="$root/fuzz/dict/$t.dict" -max_total_time="$secs" -max_len="${max_len[$t]:-4096}" \
        -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
        >"$log" 2>&1 || status=$?
    execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
    rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -n 1)
    last=$(grep -E '^#[0-9]+.*cov: ' "$log" | tail -n 1 || true)
    cov=$(sed -nE 's/.*cov: ([0-9]+).*/\1/p' <<<"$last")
    ft=$(sed -nE 's/.* ft: ([0-9]+).*/\1/p' <<<"$last")
    corp=$(sed -nE 's/.* corp: ([0-9]+\/[0-9a-zA-Z]+).*/\1/p' <<<"$last")
    # A run that stopped at a crash ran for less than it was given.
    ran=$(sed -nE 's/^Done [0-9]+ runs in ([0-9]+) second.*/\1/p' "$log" | tail -n 1)
    [ -n "$ran" ] || ran=$(( ${execs:-0} / (${rate:-0} > 0 ? ${rate:-1} : 1) ))
    line="$t: ${execs:-?} executions (${rate:-?}/s) in ${ran} s, cov ${cov:-?} edges, ft ${ft:-?} features, corpus ${corp:-?}"
    if [ "$status" -ne 0 ]; then
        line="$line: FAILED (exit $status), see $log and fuzz/artifacts/$t/"
        failed+=("$t")
    fi
    echo "$line"
    summary+=("$line")
done

echo
echo "== summary"
printf '%s\n' "${summary[@]}"
[ ${#failed[@]} -eq 0 ] || {
    echo "failed: ${failed[*]}"
    exit 1
}
