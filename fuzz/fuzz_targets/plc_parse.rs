//! Arbitrary bytes as Structured Text: lexing and parsing must never panic; input that
//! parses cleanly is also checked, compiled and run for one cycle under a small loop
//! budget, none of which may panic either.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data).into_owned();
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
        let _ = p.run_cycle(plc::task::ClockReading::default());
    }
});
