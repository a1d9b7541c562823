//! Runs every `tests/conformance/*.st` program and checks the expectations written in its
//! comments:
//!
//! - `(* program: Main *)` the program to run (default `Main`);
//! - `(* cycles: 10 *)`, `(* cycle-ms: 100 *)` how long (default 1 cycle of 10 ms);
//! - `(* set: Main.x = 5 *)` write before the first cycle;
//! - `(* expect: Main.x = 42 *)` value after the last cycle (IEC literal syntax);
//! - `(* expect-error: 3:5: undeclared name 'y' *)` a diagnostic at line:col whose message
//!   contains the text; the program must not compile, and every error it reports must be
//!   expected, unless
//! - `(* other-errors: why *)` says why more errors follow (e.g. after a syntax error);
//! - `(* expect-fault: division by zero *)` the task faults with this text.
//!
//! Every program runs twice, with loops compiled to machine code and as closures only
//! ([`plc::CompileOptions::jit`]); both runs must meet the expectations and end with the
//! same value in every variable and the same faults at the same positions.

use plc::task::{ClockReading, TaskConfig};
use std::path::{Path, PathBuf};

#[derive(Default, Debug)]
struct Spec {
    program: Option<String>,
    cycles: u64,
    cycle_ms: i64,
    sets: Vec<(String, String)>,
    expects: Vec<(String, String)>,
    errors: Vec<(usize, usize, String)>,
    /// Errors beyond the expected ones are allowed.
    other_errors: bool,
    fault: Option<String>,
}

fn directives(text: &str) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(start) = rest.find("(*") {
        let Some(end) = rest[start..].find("*)") else {
            break;
        };
        let body = rest[start + 2..start + end].trim();
        if let Some((k, v)) = body.split_once(':') {
            let k = k.trim();
            if [
                "program",
                "cycles",
                "cycle-ms",
                "set",
                "expect",
                "expect-error",
                "expect-fault",
                "other-errors",
            ]
            .contains(&k)
            {
                out.push((k.to_string(), v.trim().to_string()));
            }
        }
        rest = &rest[start + end + 2..];
    }
    out
}

fn spec(text: &str) -> Spec {
    let mut s = Spec {
        cycles: 1,
        cycle_ms: 10,
        ..Spec::default()
    };
    for (k, v) in directives(text) {
        match k.as_str() {
            "program" => s.program = Some(v),
            "cycles" => s.cycles = v.parse().expect("cycles"),
            "cycle-ms" => s.cycle_ms = v.parse().expect("cycle-ms"),
            "set" | "expect" => {
                let (p, val) = v.split_once(" = ").expect("PATH = VALUE");
                let pair = (p.trim().to_string(), val.trim().to_string());
                if k == "set" {
                    s.sets.push(pair)
                } else {
                    s.expects.push(pair)
                }
            }
            "expect-error" => {
                let mut it = v.splitn(3, ':');
                let line = it.next().unwrap().trim().parse().expect("line");
                let col = it.next().unwrap().trim().parse().expect("col");
                s.errors
                    .push((line, col, it.next().unwrap_or("").trim().to_string()));
            }
            "expect-fault" => s.fault = Some(v),
            "other-errors" => s.other_errors = true,
            _ => {}
        }
    }
    s
}

/// What a run leaves behind: every variable (`path = value`), the faults as rendered, and
/// how many loops ran as machine code.
#[derive(Debug, PartialEq, Default)]
struct Outcome {
    variables: Vec<String>,
    faults: Vec<String>,
    jit_loops: usize,
}

fn run_one(path: &Path, jit: bool) -> Result<Outcome, String> {
    let text = std::fs::read_to_string(path).map_err(|e| e.to_string())?;
    let spec = spec(&text);
    let name = path.file_name().unwrap().to_string_lossy().to_string();
    let (sources, result) = plc::build_with(&[(name.clone(), text)], plc::CompileOptions { jit });
    if !spec.errors.is_empty() {
        let diags = match result {
            Ok(_) => return Err("compiled, but errors were expected".into()),
            Err(d) => d,
        };
        let rendered: Vec<(usize, usize, String)> = diags
            .iter()
            .filter(|d| d.is_error())
            .map(|d| {
                let lc = sources.line_col(d.primary);
                (lc.line, lc.col, d.message.clone())
            })
            .collect();
        for (line, col, msg) in &spec.errors {
            if !rendered
                .iter()
                .any(|(l, c, m)| l == line && c == col && m.contains(msg.as_str()))
            {
                return Err(format!(
                    "expected error {line}:{col}: {msg}\n got:\n{}",
                    diags
                        .iter()
                        .map(|d| d.headline(&sources))
                        .collect::<Vec<_>>()
                        .join("\n")
                ));
            }
        }
        let unexpected: Vec<String> = rendered
            .iter()
            .filter(|(l, c, m)| {
                !spec
                    .errors
                    .iter()
                    .any(|(line, col, msg)| l == line && c == col && m.contains(msg.as_str()))
            })
            .map(|(l, c, m)| format!("{l}:{c}: {m}"))
            .collect();
        if !unexpected.is_empty() && !spec.other_errors {
            return Err(format!("unexpected errors:\n{}", unexpected.join("\n")));
        }
        return Ok(Outcome::default());
    }
    let compiled = result.map_err(|d| {
        d.iter()
            .map(|d| d.render(&sources))
            .collect::<Vec<_>>()
            .join("\n")
    })?;
    let jit_loops = compiled.jit_loops;
    let mut plc = plc::Plc::new(compiled, sources);
    plc.loop_budget = 1_000_000;
    let program = spec.program.clone().unwrap_or_else(|| "Main".into());
    plc.add_task(TaskConfig::cyclic(
        "main",
        spec.cycle_ms * 1_000_000,
        &[&program],
    ))
    .map_err(|e| e.to_string())?;
    for (p, v) in &spec.sets {
        plc.write(p, v).map_err(|e| format!("set {p}: {e}"))?;
    }
    let mut faults = Vec::new();
    for k in 0..spec.cycles {
        let t = k as i64 * spec.cycle_ms * 1_000_000;
        let now = ClockReading {
            monotonic_ns: t,
            utc_ns: 1_714_521_600_000_000_000 + t,
            utc_offset_ns: 7_200_000_000_000,
        };
        faults.extend(plc.run_cycle(now));
    }
    match (&spec.fault, faults.first()) {
        (Some(f), Some(d)) if d.message.contains(f.as_str()) => {}
        (Some(f), other) => return Err(format!("expected fault '{f}', got {other:?}")),
        (None, Some(d)) => return Err(format!("unexpected fault: {}", plc.render(d))),
        (None, None) => {}
    }
    let mut errs = Vec::new();
    for (p, want) in &spec.expects {
        match plc.read_text(p) {
            Ok(got) if &got == want => {}
            Ok(got) => errs.push(format!("{p}: expected {want}, got {got}")),
            Err(e) => errs.push(format!("{p}: {e}")),
        }
    }
    if !errs.is_empty() {
        return Err(errs.join("\n"));
    }
    let variables = plc
        .leaves()
        .iter()
        .map(|l| match plc.read_leaf(l) {
            Ok(v) => format!(
                "{} = {}",
                l.path,
                plc::task::format_value(plc.checked(), &l.ty, &v)
            ),
            Err(e) => format!("{}: {e}", l.path),
        })
        .collect();
    Ok(Outcome {
        variables,
        faults: faults.iter().map(|d| plc.render(d)).collect(),
        jit_loops,
    })
}

/// Runs a program both ways and compares the outcomes.
fn run_both(path: &Path) -> Result<usize, String> {
    let closures = run_one(path, false).map_err(|e| format!("closures: {e}"))?;
    let mut jit = run_one(path, true).map_err(|e| format!("jit: {e}"))?;
    let loops = jit.jit_loops;
    jit.jit_loops = 0;
    if closures != jit {
        let diff: Vec<String> = closures
            .variables
            .iter()
            .zip(jit.variables.iter())
            .filter(|(a, b)| a != b)
            .map(|(a, b)| format!("closures {a} / jit {b}"))
            .collect();
        return Err(format!(
            "the two runs differ:\n{}\nfaults: {:?} / {:?}",
            diff.join("\n"),
            closures.faults,
            jit.faults
        ));
    }
    Ok(loops)
}

#[test]
fn conformance_suite() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/conformance");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "st"))
        .collect();
    files.sort();
    let filter = std::env::var("PLC_CONFORMANCE").ok();
    let mut failed = Vec::new();
    let mut passed = 0;
    let mut jit_loops = 0;
    for f in &files {
        if let Some(flt) = &filter {
            if !f.to_string_lossy().contains(flt.as_str()) {
                continue;
            }
        }
        match std::panic::catch_unwind(|| run_both(f)) {
            Ok(Ok(loops)) => {
                passed += 1;
                jit_loops += loops;
            }
            Ok(Err(e)) => failed.push(format!("{}: {e}", f.display())),
            Err(_) => failed.push(format!("{}: PANIC", f.display())),
        }
    }
    eprintln!(
        "conformance: {passed} passed, {} failed; {jit_loops} loops compiled to machine code",
        failed.len()
    );
    assert!(
        failed.is_empty(),
        "{} conformance program(s) failed:\n{}",
        failed.len(),
        failed.join("\n\n")
    );
    assert!(passed >= 1);
    if filter.is_none() {
        // the suite's loops are in the JIT subset: most of them must really run as code
        assert!(
            jit_loops >= 30,
            "only {jit_loops} loops compiled to machine code"
        );
    }
}
