#!/usr/bin/env bash
# The timing-sensitive suites, N times in a row (default 10), while a CPU hog keeps every
# core busy: the c104 interoperability tests, the station's IEC 104 suite, the dispatch
# test against the demo, the runtime scenarios, the browser test and the peer selftest.
# A test that needs luck fails here. Stops at the first failure; prints one line per run.
#
#   bash scripts/timing-soak.sh [N]        (after bash scripts/install-test-deps.sh)
set -euo pipefail
cd "$(dirname "$0")/.."
N="${1:-10}"
export STANICE_REQUIRE_PEERS=1

echo "== building the test binaries"
cargo test --locked --no-run -p iec60870 -p station -p stanice -p hmi >/dev/null 2>&1

HOGS=()
stop_hogs() { for pid in "${HOGS[@]}"; do kill "$pid" 2>/dev/null || true; done; }
trap stop_hogs EXIT
# One busy loop per core, for the whole soak (stopped by the trap).
for _ in $(seq "$(nproc)"); do
    ( while :; do :; done ) &
    HOGS+=("$!")
done

suite() {  # suite NAME COMMAND...: runs it quietly, keeps its output on failure
    local name="$1"; shift
    local log
    log="$(mktemp /tmp/timing-soak.XXXXXX)"
    if "$@" >"$log" 2>&1; then
        rm -f "$log"
        return 0
    fi
    echo "FAILED: $name (output in $log)"
    grep -E "panicked|FAILED|FAIL:|failed" "$log" | head -20
    return 1
}

for run in $(seq "$N"); do
    start=$(date +%s)
    suite "iec60870 station + interop" cargo test --locked -q -p iec60870 --test station --test interop_c104
    suite "dispatch against the demo" cargo test --locked -q -p stanice --test dispatch_c104
    suite "runtime scenarios" cargo test --locked -q -p station --test runtime
    suite "browser" cargo test --locked -q -p hmi --test browser
    suite "peer selftest" bash tests/peer/selftest.sh
    echo "run $run/$N green in $(( $(date +%s) - start )) s (under $(nproc) busy loops)"
done
echo "$N passed, 0 failed"
