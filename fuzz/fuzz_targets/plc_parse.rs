//! Arbitrary bytes as Structured Text: lexing and parsing must never panic; input that
//! parses cleanly is also checked, compiled and run for three cycles under a small loop
//! budget, none of which may panic either (a NULL dereference, say, is a fault). Input
//! without a PROGRAM is run as the body of the declarations in `plc_harness`.
#![no_main]

use libfuzzer_sys::fuzz_target;

mod plc_harness;

fuzz_target!(|data: &[u8]| {
    let text = plc_harness::source(data);
    let mut sources = plc::SourceMap::new();
    sources.add("fuzz.st", text.clone());
    let (_, diags) = plc::syntax::parse(&sources);
    if diags.iter().any(plc::Diagnostic::is_error) {
        return;
    }
    let (sources, result) = plc::build(&[("fuzz.st".to_string(), text)]);
    if let Ok(compiled) = result {
        let mut p = plc::Plc::new(compiled, sources);
        p.loop_budget = 10_000;
        for name in ["Main", "MAIN", "main"] {
            if p.add_task(plc::task::TaskConfig::cyclic("t", 1_000_000, &[name]))
                .is_ok()
            {
                break;
            }
        }
        for k in 0..3 {
            let now = plc::task::ClockReading {
                monotonic_ns: k * 1_000_000,
                ..plc::task::ClockReading::default()
            };
            let _ = p.run_cycle(now);
        }
    }
});
