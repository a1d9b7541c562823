#!/usr/bin/env bash
# A short run of every cargo-fuzz target: builds them (so they keep compiling) and fuzzes
# each for FUZZ_SECONDS (default 30). Any crash fails the run and leaves the reproducer
# in fuzz/artifacts/. Needs the nightly toolchain (preinstalled on the project's machine
# kind); cargo-fuzz is installed from crates.io when missing.
set -euo pipefail
cd "$(dirname "$0")/../fuzz"
seconds="${FUZZ_SECONDS:-30}"

if ! rustup toolchain list | grep -q '^nightly'; then
    echo "fuzz smoke: no nightly toolchain on this machine; the stable random-input tests ran instead" >&2
    if [ "${CI:-}" = "true" ]; then exit 1; fi
    exit 0
fi
if ! command -v cargo-fuzz >/dev/null 2>&1; then
    echo "fuzz smoke: installing cargo-fuzz"
    cargo install cargo-fuzz --locked --quiet
fi

targets=$(cargo +nightly fuzz list)
echo "fuzz smoke: building $(echo "$targets" | wc -l) targets"
cargo +nightly fuzz build --release
for target in $targets; do
    echo "fuzz smoke: $target for ${seconds}s"
    mkdir -p "corpus/$target"
    case "$target" in
        # start the Structured Text targets from the conformance programs
        plc_*) cp ../crates/plc/tests/conformance/*.st "corpus/$target/" ;;
    esac
    cargo +nightly fuzz run --release "$target" "corpus/$target" -- \
        -max_total_time="$seconds" -rss_limit_mb=2048 -print_final_stats=1 2>&1 \
        | grep -E 'stat::number_of_executed_units|Done|ERROR|panicked|SUMMARY' || true
    # cargo fuzz run exits non-zero on a crash; the pipeline above hides that, so check
    # for artifacts instead.
    if compgen -G "artifacts/$target/crash-*" >/dev/null || compgen -G "artifacts/$target/oom-*" >/dev/null; then
        echo "fuzz smoke: $target found a failure:" >&2
        ls "artifacts/$target" >&2
        exit 1
    fi
done
echo "fuzz smoke: no crash"
