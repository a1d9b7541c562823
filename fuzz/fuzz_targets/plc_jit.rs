//! Arbitrary bytes as Structured Text, differentially: a program that builds runs three
//! cycles with its loops compiled to machine code and three as closures only; every
//! variable and every fault must be the same both ways (the closures are the reference
//! semantics of the JIT). Input without a PROGRAM is run as the body of the declarations
//! in `plc_harness`, whose FUNCTIONs (`Sq`, `Per` with an output and a division) and FB
//! (`Acc` with a VAR_IN_OUT) the compiled loops inline where they are called; the seeds
//! `calls_in_loop.st` and `call_fault_in_loop.st` call them in loops.
#![no_main]

use libfuzzer_sys::fuzz_target;

mod plc_harness;
use plc::task::{ClockReading, TaskConfig};

fn run(text: &str, jit: bool) -> Option<(Vec<String>, Vec<String>)> {
    let (sources, result) = plc::build_with(
        &[("fuzz.st".to_string(), text.to_string())],
        plc::CompileOptions { jit },
    );
    let mut p = plc::Plc::new(result.ok()?, sources);
    p.loop_budget = 10_000;
    let added = ["Main", "MAIN", "main"].iter().any(|name| {
        p.add_task(TaskConfig::cyclic("t", 1_000_000, &[name]))
            .is_ok()
    });
    if !added {
        return None;
    }
    let mut faults = Vec::new();
    for k in 0..3 {
        let now = ClockReading {
            monotonic_ns: k * 1_000_000,
            ..ClockReading::default()
        };
        faults.extend(p.run_cycle(now).iter().map(|d| p.render(d)));
    }
    let vars = p
        .leaves()
        .iter()
        .map(|l| match p.read_leaf(l) {
            Ok(v) => format!(
                "{} = {}",
                l.path,
                plc::task::format_value(p.checked(), &l.ty, &v)
            ),
            Err(e) => format!("{}: {e}", l.path),
        })
        .collect();
    Some((vars, faults))
}

fuzz_target!(|data: &[u8]| {
    let text = plc_harness::source(data);
    let mut sources = plc::SourceMap::new();
    sources.add("fuzz.st", text.clone());
    let (_, diags) = plc::syntax::parse(&sources);
    if diags.iter().any(plc::Diagnostic::is_error) {
        return;
    }
    let closures = run(&text, false);
    let jit = run(&text, true);
    assert_eq!(closures, jit, "closures and machine code differ");
});
