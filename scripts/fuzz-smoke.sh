#!/usr/bin/env bash
# A short run of every cargo-fuzz target: builds them (so they keep compiling) and fuzzes
# each for FUZZ_SECONDS (default 8: with eighteen targets the smoke stays a few minutes
# of a CI run that must stay under 30; longer campaigns set it). Any crash fails the run
# and leaves the reproducer in fuzz/artifacts/. Needs the nightly toolchain (preinstalled
# on the project's machine kind); cargo-fuzz is installed from crates.io when missing.
#
#   bash scripts/fuzz-smoke.sh [build|run]     (default: both; CI runs both at nice 19
#                                               while the tests run)
#
# The targets build without a sanitizer (FUZZ_SANITIZER, default none) and with 16 code
# generation units (FUZZ_CODEGEN_UNITS). Measured on the 2-core machine, a clean release
# build of the seventeen targets (the PLC compiler and Cranelift among them): 818 s with
# cargo-fuzz's defaults (AddressSanitizer, one unit), 778 s with 16 units, 462 s without
# the sanitizer; and without it apci_stream runs some 125,000 inputs a second instead of
# 15,000 (an unoptimised `--dev` build: 306 s, 800 a second). The parsers are safe Rust
# (the workspace forbids unsafe code but for the PLC's JIT, whose generated code a
# sanitizer does not instrument anyway): what the smoke finds is a panic, an overflow or
# a failed debug assertion, which need no sanitizer. A long campaign may set
# FUZZ_SANITIZER=address FUZZ_CODEGEN_UNITS=1.
set -euo pipefail
cd "$(dirname "$0")/../fuzz"
seconds="${FUZZ_SECONDS:-8}"
mode="${1:-all}"
build_flags=(--release --codegen-units "${FUZZ_CODEGEN_UNITS:-16}" --sanitizer "${FUZZ_SANITIZER:-none}")

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
if [ "$mode" != "run" ]; then
    echo "fuzz smoke: building $(echo "$targets" | wc -l) targets"
    cargo +nightly fuzz build "${build_flags[@]}"
fi
if [ "$mode" = "build" ]; then
    exit 0
fi
for target in $targets; do
    echo "fuzz smoke: $target for ${seconds}s"
    mkdir -p "corpus/$target"
    extra=()
    case "$target" in
        # start the Structured Text targets from the conformance programs and from the
        # statement fragments that plc_harness wraps in declarations of the newer syntax
        # (references and NULL dereferences, partial access, typed counters, time
        # functions, TYPE initial values, safe-value pragmas), with a dictionary of them
        plc_*)
            cp ../crates/plc/tests/conformance/*.st "corpus/$target/"
            for f in ../crates/plc/tests/fuzz/fragments/*.st; do
                cp "$f" "corpus/$target/fragment_$(basename "$f")"
            done
            extra=(-dict=../crates/plc/tests/fuzz/st.dict) ;;
        # the EKM66 replies of spec §12 (after the config octet and a feed op each)
        ekm66_*)
            printf '\x00\x13\x68\x0e\x0e\x68\x01\x00\x01\x01\x02\x02\x00\x00\x00\x00\x00\x38\x22\x0c\x6d\x16' > "corpus/$target/status"
            printf '\x00\x16\x68\x11\x11\x68\x01\x00\x04\x03\x03\x0a\x00\x07\x2a\x0f\x0e\x03\x16\x3c\x00\x01\x03\xbc\x16' > "corpus/$target/fault"
            printf '\x00\x0b\x68\x06\x06\x68\x01\x00\x04\x05\x00\x00\x0a\x16' > "corpus/$target/empty" ;;
        # the example projects' mimic screens
        mimic_*)
            cp ../examples/*/hmi/*.svg "corpus/$target/" ;;
        # the balance records of spec §7.3 (B1, B3, B4)
        balance_*)
            printf '+   2.345    \r\n' > "corpus/$target/b1"
            printf '+   3.091  g \r\n' > "corpus/$target/b3"
            printf '3.091  g \r\n+   ' > "corpus/$target/b4" ;;
        # a block of two events as the event history packs them (history::codec):
        # version 1, two events (a float with a source time, a text with a key)
        event_*)
            printf '\x01\x02\x14\x01\x02\x01\x00\x04\x00\x00\x00\x00\x00\x00\x24\x40\x00\x01\xd0\x0f\x01\x17\x00\x02\x01\x03\x01\x2b\x06\x02\x6f\x6b\x01\x03\x02\x00\x04\x07' > "corpus/$target/two" ;;
        # the teaching lab's shipped scenarios
        lab_*)
            cp ../examples/lab/scenarios/*.toml "corpus/$target/" ;;
    esac
    cargo +nightly fuzz run "${build_flags[@]}" "$target" "corpus/$target" -- \
        -max_total_time="$seconds" -rss_limit_mb=2048 -print_final_stats=1 ${extra[@]+"${extra[@]}"} 2>&1 \
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
