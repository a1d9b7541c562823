//! The fused closures (inline operands, inline binary operations, stores and branches
//! without inner calls) compute exactly what the generic operators compute: every
//! expression is evaluated twice, once in a fusable shape and once with its operands
//! passed through a function (which defeats fusion), over random and edge values.

use plc::task::{ClockReading, TaskConfig};
use plc::Plc;

/// Integer types with their ranges.
const INTS: &[(&str, i128, i128)] = &[
    ("SINT", -128, 127),
    ("INT", -32768, 32767),
    ("DINT", i32::MIN as i128, i32::MAX as i128),
    ("LINT", i64::MIN as i128, i64::MAX as i128),
    ("USINT", 0, 255),
    ("UINT", 0, 65535),
    ("UDINT", 0, u32::MAX as i128),
    ("ULINT", 0, u64::MAX as i128),
    ("BYTE", 0, 255),
    ("WORD", 0, 65535),
    ("DWORD", 0, u32::MAX as i128),
];

/// Expressions over `x`, `y` (integers); `#` is replaced by the type name.
const INT_EXPRS: &[&str] = &[
    "x + y",
    "x - y",
    "x * y",
    "x + y * 3",
    "(x * y) + (x - y)",
    "x - (y + 1)",
    "x > y",
    "x <= y",
    "x = y",
    "x <> y",
    "(x + 1) > (y - 1)",
    "x < y + 5",
    "x >= y",
];

/// Signed-only expressions (division and remainder by constants).
const SIGNED_EXPRS: &[&str] = &[
    "x MOD 7",
    "x / 3",
    "x / -3",
    "x MOD -7",
    "(x * y) MOD 7",
    "(x - y) / 3",
    "x + (y MOD 5)",
    "(x + y) MOD 2",
];

/// Bit-string-only expressions.
const BIT_EXPRS: &[&str] = &["x XOR y", "x AND y", "x OR y", "(x AND y) XOR x"];

const REAL_EXPRS: &[&str] = &[
    "x * 0.999999 + 0.5",
    "x / y",
    "x - y * 2.0",
    "(x + y) * (x - y)",
    "x * y",
];

const REAL_CMPS: &[&str] = &["x > y", "x <= y", "x = y", "x * 2.0 < y + 1.0"];

struct Gen {
    src: String,
    globals: String,
    body: String,
    vars: String,
    pairs: Vec<(String, String)>,
    n: usize,
}

impl Gen {
    /// `fused` in the fusable shape, `generic` with `x`, `y` through `ID_T`.
    fn case(&mut self, ty: &str, res_ty: &str, expr: &str, x: &str, y: &str, global: bool) {
        self.n += 1;
        let n = self.n;
        let fused = expr.replace('x', x).replace('y', y);
        let generic = expr
            .replace('x', &format!("ID_{ty}({x})"))
            .replace('y', &format!("ID_{ty}({y})"));
        let (r, q) = (format!("r{n}"), format!("q{n}"));
        if global {
            self.globals.push_str(&format!("{r} : {res_ty}; "));
        } else {
            self.vars.push_str(&format!("{r} : {res_ty}; "));
        }
        self.vars.push_str(&format!("{q} : {res_ty}; "));
        self.body
            .push_str(&format!("{r} := {fused};\n{q} := {generic};\n"));
        let path = |v: &str| {
            if global {
                v.to_string()
            } else {
                format!("Main.{v}")
            }
        };
        self.pairs.push((path(&r), format!("Main.{q}")));
        if res_ty == "BOOL" {
            // the same condition as a branch
            self.n += 1;
            let (r, q) = (format!("r{}", self.n), format!("q{}", self.n));
            self.vars.push_str(&format!("{r}, {q} : INT; "));
            self.body.push_str(&format!(
                "IF {fused} THEN {r} := 1; ELSE {r} := 2; END_IF\n\
                 IF {generic} THEN {q} := 1; ELSE {q} := 2; END_IF\n\
                 IF {fused} THEN {r} := {r} + 10; END_IF\n\
                 IF {generic} THEN {q} := {q} + 10; END_IF\n"
            ));
            self.pairs.push((format!("Main.{r}"), format!("Main.{q}")));
        }
    }
}

fn xorshift(s: &mut u64) -> u64 {
    *s ^= *s << 13;
    *s ^= *s >> 7;
    *s ^= *s << 17;
    *s
}

#[test]
fn fused_forms_match_the_generic_operators() {
    let mut g = Gen {
        src: String::new(),
        globals: String::new(),
        body: String::new(),
        vars: String::new(),
        pairs: Vec::new(),
        n: 0,
    };
    let mut inputs: Vec<(String, i128, i128)> = Vec::new();
    for (k, &(ty, lo, hi)) in INTS.iter().enumerate() {
        g.src.push_str(&format!(
            "FUNCTION ID_{ty} : {ty} VAR_INPUT v : {ty}; END_VAR ID_{ty} := v; END_FUNCTION\n"
        ));
        let (x, y) = (format!("x{k}"), format!("y{k}"));
        g.vars.push_str(&format!("{x}, {y} : {ty}; "));
        inputs.push((format!("Main.{x}"), lo, hi));
        inputs.push((format!("Main.{y}"), lo, hi));
        let signed = lo < 0;
        let bits = ty.ends_with("WORD") || ty == "BYTE";
        let mut exprs: Vec<&str> = INT_EXPRS.to_vec();
        if signed {
            exprs.extend(SIGNED_EXPRS);
        }
        if bits {
            exprs.retain(|e| !e.contains('*') && !e.contains('+') && !e.contains('-'));
            exprs.extend(BIT_EXPRS);
        }
        for (i, e) in exprs.iter().enumerate() {
            let cmp = e.contains('>') || e.contains('<') || e.contains('=');
            let res = if cmp { "BOOL" } else { ty };
            g.case(ty, res, e, &x, &y, i % 3 == 0);
        }
    }
    for (k, ty) in ["REAL", "LREAL"].iter().enumerate() {
        g.src.push_str(&format!(
            "FUNCTION ID_{ty} : {ty} VAR_INPUT v : {ty}; END_VAR ID_{ty} := v; END_FUNCTION\n"
        ));
        let (x, y) = (format!("rx{k}"), format!("ry{k}"));
        g.vars.push_str(&format!("{x}, {y} : {ty}; "));
        inputs.push((format!("Main.{x}"), -1000, 1000));
        inputs.push((format!("Main.{y}"), -1000, 1000));
        for (i, e) in REAL_EXPRS.iter().enumerate() {
            g.case(ty, ty, e, &x, &y, i % 2 == 0);
        }
        for (i, e) in REAL_CMPS.iter().enumerate() {
            g.case(ty, "BOOL", e, &x, &y, i % 2 == 0);
        }
    }
    // the identifiers x and y inside names (rx0, ...) must not be replaced twice:
    // every name used above starts with a letter other than x/y or is replaced whole
    let src = format!(
        "{}VAR_GLOBAL {} END_VAR\nPROGRAM Main\nVAR {} END_VAR\n{}END_PROGRAM\n",
        g.src, g.globals, g.vars, g.body
    );
    let (sources, compiled) = crate::support::build_one("t.st", &src);
    let mut p = Plc::new(compiled, sources);
    p.add_task(TaskConfig::cyclic("main", 0, &["Main"]))
        .unwrap();
    let mut seed: u64 = 0x9E37_79B9_7F4A_7C15;
    for round in 0..400 {
        for (path, lo, hi) in &inputs {
            let span = (hi - lo) as u128 + 1;
            let r = xorshift(&mut seed);
            let v: i128 = match (round + r as usize) % 5 {
                0 => *lo,
                1 => *hi,
                2 => 0.clamp(*lo, *hi),
                3 => (r % 7) as i128 - 3,
                _ => lo + (u128::from(r) % span) as i128,
            }
            .clamp(*lo, *hi);
            let text = if path.contains(".r") {
                format!("{:.3}", v as f64 / 7.0)
            } else {
                v.to_string()
            };
            p.write(path, &text).unwrap();
        }
        let faults = p.run_cycle(ClockReading::default());
        assert!(faults.is_empty(), "{faults:?}");
        for (a, b) in &g.pairs {
            let (va, vb) = (p.read_text(a).unwrap(), p.read_text(b).unwrap());
            assert_eq!(va, vb, "{a} vs {b} in round {round}\n{src}");
        }
    }
}

/// `s := CONCAT(s, ...)` appends in place; the same text as the generic CONCAT (whose
/// first argument is not the target), with truncation at the declared length counted
/// in characters, multi-byte characters, literal and computed parts.
#[test]
fn in_place_concat_matches_the_generic_concat() {
    let src = "PROGRAM Main
VAR a, b : STRING[7]; c, d : STRING[7]; e, f : WSTRING[5]; g, h : STRING[30]; i : INT; END_VAR
a := CONCAT(a, 'é');           b := CONCAT(CONCAT(b, ''), 'é');
c := CONCAT(c, 'x', INT_TO_STRING(i), 'žž');
d := CONCAT(CONCAT(d, ''), 'x', INT_TO_STRING(i), 'žž');
e := CONCAT(e, \"ab\");       f := CONCAT(CONCAT(f, \"\"), \"ab\");
g := CONCAT(g, g, 'é');        h := CONCAT(CONCAT(h, ''), h, 'é');
i := i + 1;
END_PROGRAM";
    let (sources, r) = plc::build(&[("t.st".to_string(), src.to_string())]);
    let mut p = Plc::new(r.unwrap(), sources);
    p.add_task(TaskConfig::cyclic("main", 0, &["Main"]))
        .unwrap();
    for round in 0..12 {
        assert!(p.run_cycle(ClockReading::default()).is_empty());
        for (x, y) in [("a", "b"), ("c", "d"), ("e", "f"), ("g", "h")] {
            let (vx, vy) = (
                p.read_text(&format!("Main.{x}")).unwrap(),
                p.read_text(&format!("Main.{y}")).unwrap(),
            );
            assert_eq!(vx, vy, "{x} vs {y} in round {round}");
        }
    }
    assert_eq!(p.read_text("Main.a").unwrap(), "'ééééééé'");
}

/// A FOR loop reads its counter back after the body unless the body cannot write it; every
/// way of writing it is seen: assignment, VAR_IN_OUT, `=>`, through the program's name,
/// through a global instance's name, from a user function's body.
#[test]
fn for_counter_written_by_the_body_is_read_back() {
    let src = "
FUNCTION Bump : INT VAR_IN_OUT x : INT; END_VAR x := x + 1; Bump := 0; END_FUNCTION
FUNCTION Poke : INT VAR_INPUT v : INT; END_VAR Main.k := v; Poke := 0; END_FUNCTION
FUNCTION_BLOCK Out VAR_OUTPUT o : INT; END_VAR o := 100; END_FUNCTION_BLOCK
FUNCTION_BLOCK Loop VAR_INPUT i : INT; END_VAR VAR_OUTPUT n : INT; END_VAR
n := 0; FOR i := 1 TO 10 DO g.i := 20; n := n + 1; END_FOR
END_FUNCTION_BLOCK
VAR_GLOBAL g : Loop; END_VAR
PROGRAM Main
VAR i, j, k, m, n1, n2, n3, n4, n5, n6, d : INT; f : Out; END_VAR
FOR i := 1 TO 10 DO d := Bump(x := i); n1 := n1 + 1; END_FOR
FOR j := 1 TO 10 DO f(o => j); n2 := n2 + 1; END_FOR
FOR k := 1 TO 10 DO d := Poke(v := 40); n3 := n3 + 1; END_FOR
FOR m := 1 TO 10 DO Main.m := 30; n4 := n4 + 1; END_FOR
g(); n5 := g.n;
FOR m := 1 TO 10 DO IF m = 2 THEN m := 8; END_IF n6 := n6 + 1; END_FOR
END_PROGRAM";
    let (sources, r) = plc::build(&[("t.st".to_string(), src.to_string())]);
    let compiled = match r {
        Ok(c) => c,
        Err(d) => panic!(
            "{}",
            d.iter()
                .map(|d| d.render(&sources))
                .collect::<Vec<_>>()
                .join("\n")
        ),
    };
    let mut p = Plc::new(compiled, sources);
    p.add_task(TaskConfig::cyclic("main", 0, &["Main"]))
        .unwrap();
    assert!(p.run_cycle(ClockReading::default()).is_empty());
    let read = |path: &str| p.read_text(path).unwrap();
    // i: 1 (bumped to 2), 3, 5, 7, 9 -> 5 rounds, ends at 11
    assert_eq!((read("Main.n1"), read("Main.i")), ("5".into(), "11".into()));
    assert_eq!(
        (read("Main.n2"), read("Main.j")),
        ("1".into(), "101".into())
    );
    assert_eq!((read("Main.n3"), read("Main.k")), ("1".into(), "41".into()));
    assert_eq!(read("Main.n4"), "1");
    assert_eq!(read("Main.n5"), "1");
    // 1, 2 (set to 8), 9, 10
    assert_eq!((read("Main.n6"), read("Main.m")), ("4".into(), "11".into()));
}

/// A FOR loop whose body cannot touch the budget counts it down locally: the fault comes
/// at the same iteration, and the next loop of the cycle sees what is left.
#[test]
fn leaf_for_loops_share_the_cycle_budget() {
    let src = "PROGRAM Main VAR i : DINT; x, y : DINT; END_VAR
x := 0; y := 0;
FOR i := 1 TO 600 DO x := x + 1; END_FOR
FOR i := 1 TO 600 DO y := y + 1; END_FOR
END_PROGRAM";
    let (sources, r) = plc::build(&[("t.st".to_string(), src.to_string())]);
    let mut p = Plc::new(r.unwrap(), sources);
    p.loop_budget = 1000;
    p.add_task(TaskConfig::cyclic("main", 0, &["Main"]))
        .unwrap();
    let faults = p.run_cycle(ClockReading::default());
    assert_eq!(faults.len(), 1);
    assert!(
        faults[0].message.contains("loop iteration budget"),
        "{}",
        faults[0].message
    );
    assert!(
        p.render(&faults[0]).starts_with("t.st:4:1:"),
        "{}",
        p.render(&faults[0])
    );
    assert_eq!(p.read_text("Main.x").unwrap(), "600");
    assert_eq!(p.read_text("Main.y").unwrap(), "400");
}
