//! Random and mutated source never panics the lexer, parser, checker or compiler.

use proptest::prelude::*;

const SEED: &str =
    "PROGRAM Main\nVAR x : INT := 5; a : ARRAY[1..3] OF REAL; t : TON; s : STRING[10]; END_VAR\n\
IF x > 3 THEN x := x + 1; ELSIF x = 0 THEN x := -x; ELSE x := 0; END_IF;\n\
FOR x := 1 TO 3 DO a[x] := INT_TO_REAL(x) * 1.5; END_FOR;\n\
t(IN := x > 2, PT := T#1s); s := CONCAT('a', 'b');\n\
CASE x OF 1, 2: x := 3; 4..6: x := 7; ELSE x := 0; END_CASE;\n\
WHILE x < 10 DO x := x + 1; END_WHILE; REPEAT x := x - 1; UNTIL x < 0 END_REPEAT;\n\
END_PROGRAM\n";

fn build(text: &str) {
    let (_, r) = plc::build(&[("fuzz.st".to_string(), text.to_string())]);
    if let Ok(c) = r {
        let (sources, _) = plc::build(&[]);
        let mut p = plc::Plc::new(c, sources);
        p.loop_budget = 10_000;
        let _ = p.add_task(plc::task::TaskConfig::cyclic("t", 1, &["Main"]));
        let _ = p.run_cycle(plc::task::ClockReading::default());
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, .. ProptestConfig::default() })]

    #[test]
    fn random_text_never_panics(s in "\\PC{0,200}") {
        build(&s);
    }

    #[test]
    fn token_soup_never_panics(parts in prop::collection::vec(prop::sample::select(vec![
        "PROGRAM", "Main", "END_PROGRAM", "VAR", "END_VAR", "x", ":", "INT", ";", ":=", "(", ")",
        "[", "]", "IF", "THEN", "END_IF", "FOR", "TO", "DO", "END_FOR", "+", "-", "*", "/", "1",
        "T#1s", "'s'", "\"g\"", "#l", "ARRAY", "OF", "..", ",", "CASE", "ELSE", "END_CASE", "NOT",
        "AND", "16#FF", "1.5", "TON", ".", "=>", "FUNCTION", "END_FUNCTION", "TYPE", "END_TYPE",
        "STRUCT", "END_STRUCT", "(*", "*)", "%IX0.0", "AT", "WHILE", "END_WHILE", "EXIT",
        // the newer syntax: references, partial access, typed counters and conversions,
        // time functions, CODESYS parameter names, safe-value pragmas, TYPE initial values
        "REF_TO", "REF", "^", "NULL", ".%B1", ".%W0", ".%D1", ".%L0", "%QX0.0", "CTU_DINT",
        "CTD_UDINT", "RESET", "LOAD", "PV", "CU", "REAL_TRUNC_INT", "BCD_TO_INT",
        "INT_TO_BCD_WORD", "ADD", "ADD_TOD_TIME", "TOD#23:00:00", "LT#1s",
        "{attribute 'safe_value' := 'TRUE'}", "{attribute 'safe_value' := '-1'}", "(0..9)",
    ]), 0..80)) {
        build(&parts.join(" "));
    }

    #[test]
    fn mutated_program_never_panics(pos in 0usize..600, len in 0usize..20, insert in "\\PC{0,10}") {
        let mut s: Vec<char> = SEED.chars().collect();
        let p = pos.min(s.len());
        let e = (p + len).min(s.len());
        s.splice(p..e, insert.chars());
        build(&s.into_iter().collect::<String>());
    }
}

#[test]
fn deep_nesting_is_a_diagnostic_not_a_crash() {
    let deep = format!(
        "PROGRAM Main VAR x : INT; END_VAR x := {}1{}; END_PROGRAM",
        "(".repeat(5000),
        ")".repeat(5000)
    );
    let (_, r) = plc::build(&[("deep.st".into(), deep)]);
    assert!(r.is_err());
    let deep_if = format!(
        "PROGRAM Main VAR x : INT; END_VAR {} END_PROGRAM",
        "IF TRUE THEN ".repeat(3000)
    );
    let (_, r) = plc::build(&[("deep.st".into(), deep_if)]);
    assert!(r.is_err());
    let long = format!(
        "PROGRAM Main VAR x : INT; END_VAR x := 1{}; END_PROGRAM",
        " + 1".repeat(20000)
    );
    let (_, r) = plc::build(&[("long.st".into(), long)]);
    assert!(r.is_err());
    for body in [
        format!("x := y{};", ".a".repeat(20000)),
        format!("x := 2{};", " ** 2".repeat(20000)),
        format!("x := a{};", "[1]".repeat(20000)),
        format!("x := {}1{};", "(1 + ".repeat(60), " + 1)".repeat(60)),
    ] {
        let src = format!("PROGRAM Main VAR x : INT; END_VAR {body} END_PROGRAM");
        let (_, r) = plc::build(&[("chain.st".into(), src)]);
        assert!(r.is_err());
    }
    let ok = format!(
        "PROGRAM Main VAR x : DINT; END_VAR x := 1{}; END_PROGRAM",
        " + 1".repeat(200)
    );
    let (_, r) = plc::build(&[("ok.st".into(), ok)]);
    assert!(r.is_ok());
}
