//! Diagnostic pages (`docs/diagnostics/CODE.md`): each page's example really produces its
//! code and its fix compiles clean; rendered diagnostics as snapshots.

use plc::task::{ClockReading, TaskConfig};
use plc::{Code, Plc};

/// The first ```st block after the heading that starts with `heading`.
fn example<'a>(page: &'a str, heading: &str) -> &'a str {
    let at = page
        .find(heading)
        .unwrap_or_else(|| panic!("no '{heading}'"));
    let rest = &page[at..];
    let open = rest.find("```st\n").expect("a ```st block") + "```st\n".len();
    let len = rest[open..].find("```").expect("closed block");
    &rest[open..open + len]
}

fn build(code: Code, src: &str) -> (plc::SourceMap, Result<plc::Compiled, Vec<plc::Diagnostic>>) {
    plc::build(&[(format!("{code}.st"), src.to_string())])
}

/// Runs every PROGRAM of `compiled` in one task for a few cycles; the faults.
fn run(compiled: plc::Compiled, sources: plc::SourceMap) -> Vec<plc::Diagnostic> {
    let programs: Vec<String> = compiled
        .checked
        .pous
        .iter()
        .filter(|p| p.kind == plc::syntax::PouKind::Program && !p.stdlib)
        .map(|p| p.name.clone())
        .collect();
    let names: Vec<&str> = programs.iter().map(String::as_str).collect();
    let mut p = Plc::new(compiled, sources);
    p.add_task(TaskConfig::cyclic("main", 10_000_000, &names))
        .unwrap();
    let mut faults = Vec::new();
    for k in 0..3 {
        faults.extend(p.run_cycle(ClockReading {
            monotonic_ns: k * 10_000_000,
            ..ClockReading::default()
        }));
    }
    faults
}

#[test]
fn every_page_example_produces_its_code_and_its_fix_is_clean() {
    for &code in Code::ALL {
        let page = code.page();
        let wrong = example(page, "## Example of the mistake");
        let fixed = example(page, "## How to fix it");
        // the mistake
        let (sources, r) = build(code, wrong);
        let render = |d: &[plc::Diagnostic]| {
            d.iter()
                .map(|d| d.render(&sources))
                .collect::<Vec<_>>()
                .join("\n")
        };
        match (code, r) {
            (Code::RuntimeFault, Ok(c)) => {
                assert!(c.checked.warnings.is_empty(), "{code}");
                let faults = run(c, sources.clone());
                assert_eq!(faults.len(), 1, "{code}: {}", render(&faults));
                assert_eq!(faults[0].code, code);
            }
            (Code::UnusedVariable, Ok(c)) => {
                let codes: Vec<Code> = c.checked.warnings.iter().map(|d| d.code).collect();
                assert_eq!(codes, [code], "{}", render(&c.checked.warnings));
            }
            (_, Ok(_)) => panic!("{code}: the example of the mistake compiles"),
            (_, Err(diags)) => {
                let errors: Vec<&plc::Diagnostic> = diags.iter().filter(|d| d.is_error()).collect();
                // the first error is the page's; a character the lexer skipped may leave
                // the parser a statement it cannot finish, nothing else may follow
                assert_eq!(errors.first().map(|d| d.code), Some(code), "{code}");
                let follow = |d: &&plc::Diagnostic| {
                    d.code == code || (d.code == Code::Syntax && code.as_str() < "E0100")
                };
                assert!(
                    errors.iter().all(follow),
                    "{code}: only {code} expected:\n{}",
                    render(&diags)
                );
            }
        }
        // the fix
        let (sources, r) = build(code, fixed);
        match r {
            Ok(c) => {
                let warnings: Vec<String> = c
                    .checked
                    .warnings
                    .iter()
                    .map(|d| d.render(&sources))
                    .collect();
                assert!(warnings.is_empty(), "{code}: fix warns: {warnings:?}");
                let faults = run(c, sources.clone());
                assert!(faults.is_empty(), "{code}: fix faults: {faults:?}");
            }
            Err(d) => panic!(
                "{code}: the fix does not compile:\n{}",
                d.iter()
                    .map(|d| d.render(&sources))
                    .collect::<Vec<_>>()
                    .join("\n")
            ),
        }
    }
}

/// Wrong programs, each rendered as `plc check` prints them.
const WRONG: &[(&str, &str)] = &[
    (
        "lexer",
        "PROGRAM Main\nVAR a : INT; b : BOOL; END_VAR\nb := a ! 1;\na := 16#G1;\nEND_PROGRAM\n(* never closed\n",
    ),
    (
        "syntax",
        "PROGRAM Main\nVAR a : INT; END_VAR\nIF a > 1\n  a := 2;\nEND_IF\na := a +;\nEND_PROGRAM\n",
    ),
    (
        "names",
        "TYPE Mode : (Off, On); END_TYPE\nPROGRAM Main\nVAR a : INT; A : DINT; m : Modes; END_VAR\na := missing + 1;\nEND_PROGRAM\n",
    ),
    (
        "types",
        "PROGRAM Main\nVAR\n  small : INT;\n  big : DINT := 70000;\n  flag : BOOL;\nEND_VAR\nsmall := big;\nflag := small;\nIF small THEN small := 0; END_IF\nEND_PROGRAM\n",
    ),
    (
        "calls",
        "PROGRAM Main\nVAR t : TON; go : BOOL; done : BOOL; x : INT; END_VAR\nt(IN := go, PT := T#1s, Q := done);\nx := LIMIT(0, x);\nx := ABS(x, 1);\nEND_PROGRAM\n",
    ),
    (
        "constants",
        "PROGRAM Main\nVAR CONSTANT max : INT := 5; END_VAR\nVAR n : INT := 3; buf : ARRAY[1..n] OF INT; END_VAR\nmax := 6;\n3 := n;\nbuf[1] := max;\nEND_PROGRAM\n",
    ),
    (
        "recursion",
        "FUNCTION F : INT\nVAR_INPUT n : INT; END_VAR\nF := G(n);\nEND_FUNCTION\nFUNCTION G : INT\nVAR_INPUT n : INT; END_VAR\nG := F(n - 1);\nEND_FUNCTION\nPROGRAM Main\nVAR_GLOBAL g : INT; END_VAR\nVAR r : INT; END_VAR\nr := F(3);\nEND_PROGRAM\n",
    ),
    (
        "warnings",
        "PROGRAM Main\nVAR used : INT; spare : BOOL; other : REAL; END_VAR\nused := used + 1;\nEND_PROGRAM\n",
    ),
];

#[test]
fn rendered_diagnostics() {
    for (name, src) in WRONG {
        let (sources, r) = plc::build(&[(format!("{name}.st"), src.to_string())]);
        let diags = match r {
            Ok(c) => c.checked.warnings,
            Err(d) => d,
        };
        assert!(!diags.is_empty(), "{name}");
        let text = diags
            .iter()
            .map(|d| d.render(&sources))
            .collect::<Vec<_>>()
            .join("\n");
        insta::assert_snapshot!(*name, text);
    }
}

#[test]
fn rendered_runtime_faults() {
    let src = "PROGRAM Main\nVAR z : INT; x : INT; a : ARRAY[1..3] OF INT; i : INT := 7; r : REF_TO INT; END_VAR\nx := 10 / z;\nEND_PROGRAM\nPROGRAM Idx\nVAR a : ARRAY[1..3] OF INT; i : INT := 7; END_VAR\na[i] := 1;\nEND_PROGRAM\nPROGRAM Deref\nVAR r : REF_TO INT; x : INT; END_VAR\nx := r^;\nEND_PROGRAM\n";
    let (sources, r) = plc::build(&[("faults.st".to_string(), src.to_string())]);
    let mut p = Plc::new(r.unwrap(), sources);
    for (task, program) in [("div", "Main"), ("idx", "Idx"), ("deref", "Deref")] {
        p.add_task(TaskConfig::cyclic(task, 10_000_000, &[program]))
            .unwrap();
    }
    let faults = p.run_cycle(ClockReading::default());
    let text = faults
        .iter()
        .map(|d| p.render(d))
        .collect::<Vec<_>>()
        .join("\n");
    insta::assert_snapshot!("runtime_faults", text);
}
