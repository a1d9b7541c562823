//! Arbitrary bytes as Structured Text: lexing, parsing, checking and compiling must never
//! panic; whatever compiles runs one cycle under a small loop budget without panicking.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data).into_owned();
    let (sources, result) = plc::build(&[("fuzz.st".to_string(), text)]);
    if let Ok(compiled) = result {
        let mut p = plc::Plc::new(compiled, sources);
        p.loop_budget = 10_000;
        for name in ["Main", "MAIN", "main"] {
            if p.add_task(plc::task::TaskConfig::cyclic("t", 1_000_000, &[name])).is_ok() {
                break;
            }
        }
        let _ = p.run_cycle(plc::task::ClockReading::default());
    }
});
