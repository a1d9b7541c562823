#!/usr/bin/env bash
# A short run of every cargo-fuzz target: builds them (so they keep compiling) and fuzzes
# each for FUZZ_SECONDS (default 12: with seventeen targets the smoke stays a few minutes
# of a CI run that must stay under 30; longer campaigns set it). Any crash fails the run
# and leaves the reproducer in fuzz/artifacts/. Needs the nightly toolchain (preinstalled
# on the project's machine kind); cargo-fuzz is installed from crates.io when missing.
#
#   bash scripts/fuzz-smoke.sh [build|run]     (default: both; CI builds while other
#                                               checks run, then runs)
#
# The targets build with 16 code generation units instead of cargo-fuzz's default of one:
# a clean release build of the seventeen targets (the PLC compiler and Cranelift among
# them, every crate instrumented for coverage and AddressSanitizer) took 818 s with one
# unit and 778 s with 16 on the 2-core machine, so the units are not where the time goes
# (an unoptimised `--dev` build took 306 s, but ran some 800 inputs a second of
# apci_stream where the release build runs about 15,000). A long campaign may set
# FUZZ_CODEGEN_UNITS=1.
set -euo pipefail
cd "$(dirname "$0")/../fuzz"
seconds="${FUZZ_SECONDS:-12}"
mode="${1:-all}"
build_flags=(--release --codegen-units "${FUZZ_CODEGEN_UNITS:-16}")

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
