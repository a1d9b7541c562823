#!/usr/bin/env bash
# The full test suite, as CI runs it: installs what the tests need (tshark, the c104
# peer), then formatting, lints, unit/property/state-machine tests, interoperability
# tests against c104 with tshark capture checks, and a short fuzz smoke run.
set -euo pipefail
cd "$(dirname "$0")/.."
# Each section says when it starts ([N s] since the start): where a slow run spends its time.
# A clean clone builds once: incremental caches would only double the target folder's size.
if [ "${CI:-}" = "true" ]; then export CARGO_INCREMENTAL=0; fi

echo "== installing test dependencies [${SECONDS} s]"
bash scripts/install-test-deps.sh

echo "== formatting [${SECONDS} s]"
cargo fmt --all -- --check

echo "== lints [${SECONDS} s]"
cargo clippy --workspace --all-targets --locked -- -D warnings
# The protocol cores build without tokio (for serial adapters, other runtimes, fuzzers).
cargo clippy -p iec60870 --no-default-features --locked -- -D warnings

echo "== tests (unit, property, state machine, interoperability with c104, tshark) [${SECONDS} s]"
# The interoperability tests refuse to skip when STANICE_REQUIRE_PEERS=1.
export STANICE_REQUIRE_PEERS=1
bash scripts/with-postgres.sh cargo test --workspace --locked

echo "== the peer tooling checks itself (c104 against c104; the capture checker must reject broken frames) [${SECONDS} s]"
bash tests/peer/selftest.sh

echo "== fuzz smoke [${SECONDS} s]"
bash scripts/fuzz-smoke.sh
echo "== done [${SECONDS} s]"
