#!/usr/bin/env bash
# The full test suite, as CI runs it: installs what the tests need (tshark, the c104
# peer), then formatting, lints, unit/property/state-machine tests, interoperability
# tests against c104 with tshark capture checks, and a short fuzz smoke run.
set -euo pipefail
cd "$(dirname "$0")/.."
# Each section says when it starts ([N s] since the start): where a slow run spends its time.
# A clean clone builds once: incremental caches would only double the target folder's size.
if [ "${CI:-}" = "true" ]; then export CARGO_INCREMENTAL=0; fi

# finish_background WHAT PID LOG: waits for a step started in the background, shows what it
# printed, and ends the run with its exit status when it failed.
finish_background() {
    local status=0
    wait "$2" || status=$?
    cat "$3"
    rm -f "$3"
    if [ "$status" -ne 0 ]; then
        echo "$1 failed (exit $status)" >&2
        exit "$status"
    fi
}

# The test dependencies (Debian and Python packages: mostly downloads) install in the
# background while formatting and lints keep the cores busy; the tests wait for them.
deps_log="$(mktemp /tmp/stanice-test-deps.XXXXXX)"
echo "== installing test dependencies, in the background [${SECONDS} s]"
bash scripts/install-test-deps.sh >"$deps_log" 2>&1 &
deps_pid=$!

echo "== formatting [${SECONDS} s]"
cargo fmt --all -- --check

echo "== lints [${SECONDS} s]"
cargo clippy --workspace --all-targets --locked -- -D warnings
# The protocol cores build without tokio (for serial adapters, other runtimes, fuzzers).
cargo clippy -p iec60870 --no-default-features --locked -- -D warnings

echo "== building the tests [${SECONDS} s]"
cargo test --workspace --locked --no-run

# The fuzz targets build (the nightly compiler) and then run their smoke in the
# background, at the lowest CPU priority, while the tests run (they wait on sockets,
# pseudo-terminals, browsers and timeouts much of the time, and must pass on a busy
# machine) and while the peer tooling, which runs no Stanice code, checks itself. (Run
# after the tests, the smoke alone took about 170 s of a 30-minute budget; each target
# runs for its seconds either way, with fewer inputs when the machine is busy.)
fuzz_log="$(mktemp /tmp/stanice-fuzz.XXXXXX)"
echo "== building the fuzz targets and running their smoke, in the background [${SECONDS} s]"
nice -n 19 bash -c 'bash scripts/fuzz-smoke.sh build && bash scripts/fuzz-smoke.sh run' \
    >"$fuzz_log" 2>&1 &
fuzz_pid=$!

echo "== waiting for the test dependencies [${SECONDS} s]"
finish_background "installing the test dependencies" "$deps_pid" "$deps_log"

echo "== tests (unit, property, state machine, interoperability with c104, tshark) [${SECONDS} s]"
# The interoperability tests refuse to skip when STANICE_REQUIRE_PEERS=1.
export STANICE_REQUIRE_PEERS=1
bash scripts/with-postgres.sh cargo test --workspace --locked

echo "== the peer tooling checks itself (c104 against c104; the capture checker must reject broken frames) [${SECONDS} s]"
selftest_status=0
bash tests/peer/selftest.sh || selftest_status=$?

echo "== waiting for the fuzz targets and their smoke [${SECONDS} s]"
finish_background "the fuzz smoke" "$fuzz_pid" "$fuzz_log"
if [ "$selftest_status" -ne 0 ]; then
    echo "the peer selftest failed (exit $selftest_status)" >&2
    exit "$selftest_status"
fi
echo "== done [${SECONDS} s]"
