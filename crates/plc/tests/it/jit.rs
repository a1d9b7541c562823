//! The loop JIT against the closure compiler: random well-typed loop programs run both
//! ways must leave every variable with the same value and fault the same way at the same
//! position; and the cases the JIT treats specially (registers written back on a fault,
//! cells reached both by name and by index, a global FB instance aliasing its frame).

use plc::task::{ClockReading, TaskConfig};
use plc::{CompileOptions, Plc};
use proptest::prelude::*;

const DECLS: &str = "PROGRAM Main
VAR a, b, c : DINT := 3; s : INT := -7; t : SINT := 100; l : LINT := 1; u : UDINT := 5;
w : WORD := 16#F0F0; x : LREAL := 0.5; r : REAL := 1.25; f, g : BOOL;
arr : ARRAY[1..8] OF DINT; m : ARRAY[0..2, 1..3] OF INT; rr : ARRAY[1..4] OF LREAL;
i0, i1, i2, k : DINT; tm : ARRAY[1..3] OF TON; st : STRUCT_T;
fk : ARRAY[1..2] OF Fk; fk1 : Fk;
END_VAR
";

/// Types, globals and the callees of the random loops: a FUNCTION with every kind of
/// parameter, locals with initial values, a division and RETURN; a FB with state, an
/// indexed array and a nested TON.
const TYPES: &str = "TYPE STRUCT_T : STRUCT p : DINT; q : LREAL; END_STRUCT; END_TYPE
VAR_GLOBAL gc : DINT := 2; ga : ARRAY[1..4] OF DINT; END_VAR
FUNCTION Fx : DINT
VAR_INPUT p : DINT; q : LREAL; END_VAR
VAR_IN_OUT io : DINT; END_VAR
VAR_OUTPUT o : DINT; END_VAR
VAR t : DINT := 4; h : ARRAY[0..2] OF DINT; END_VAR
t := t + p; io := io + t; h[(p MOD 3 + 3) MOD 3] := t;
IF q > 10.0 THEN o := 1; RETURN; END_IF
o := p / (io MOD 5); gc := gc + 1;
Fx := t * 2 + h[0];
END_FUNCTION
FUNCTION_BLOCK Fk
VAR_INPUT p : DINT; END_VAR
VAR_OUTPUT n : DINT; END_VAR
VAR h : ARRAY[0..3] OF DINT; tn : TON; END_VAR
n := n + p; h[n MOD 4] := p;
tn(IN := p > 0, PT := T#20ms);
IF tn.Q THEN n := n - 1; END_IF
END_FUNCTION_BLOCK
";

/// The variables of [`DECLS`] inside a FB, for loops that run on instance frames.
const FB_DECLS: &str = "FUNCTION_BLOCK Work
VAR a, b, c : DINT := 3; s : INT := -7; t : SINT := 100; l : LINT := 1; u : UDINT := 5;
w : WORD := 16#F0F0; x : LREAL := 0.5; r : REAL := 1.25; f, g : BOOL;
arr : ARRAY[1..8] OF DINT; m : ARRAY[0..2, 1..3] OF INT; rr : ARRAY[1..4] OF LREAL;
i0, i1, i2, k : DINT; tm : ARRAY[1..3] OF TON; st : STRUCT_T;
fk : ARRAY[1..2] OF Fk; fk1 : Fk;
END_VAR
";

/// Every variable after `cycles` cycles, and the rendered faults.
fn run(src: &str, jit: bool, cycles: i64) -> (Vec<String>, Vec<String>, usize) {
    let (sources, compiled) =
        crate::support::build_or_fail(&[("p.st".into(), src.into())], CompileOptions { jit });
    let loops = compiled.jit_loops;
    let mut p = Plc::new(compiled, sources);
    p.loop_budget = 20_000;
    p.add_task(TaskConfig::cyclic("main", 10_000_000, &["Main"]))
        .unwrap();
    let mut faults = Vec::new();
    for k in 0..cycles {
        let now = ClockReading {
            monotonic_ns: k * 10_000_000,
            ..ClockReading::default()
        };
        faults.extend(p.run_cycle(now).iter().map(|d| p.render(d)));
    }
    let vars = p
        .leaves()
        .iter()
        .map(|l| {
            let v = p.read_leaf(l).unwrap();
            format!(
                "{} = {}",
                l.path,
                plc::task::format_value(p.checked(), &l.ty, &v)
            )
        })
        .collect();
    (vars, faults, loops)
}

fn assert_same(src: &str, cycles: i64) -> usize {
    let (v1, f1, _) = run(src, false, cycles);
    let (v2, f2, loops) = run(src, true, cycles);
    assert_eq!(f1, f2, "faults differ for\n{src}");
    for (a, b) in v1.iter().zip(v2.iter()) {
        assert_eq!(a, b, "closures vs jit for\n{src}");
    }
    loops
}

// ---- random programs ----------------------------------------------------------------

fn dint_leaf() -> impl Strategy<Value = String> {
    prop_oneof![
        Just("a".to_string()),
        Just("b".to_string()),
        Just("c".to_string()),
        Just("i1".to_string()),
        Just("s".to_string()),
        Just("t".to_string()),
        Just("st.p".to_string()),
        (-40i32..40).prop_map(|v| if v < 0 {
            format!("({v})")
        } else {
            v.to_string()
        }),
        (0i32..10).prop_map(|v| format!("arr[{v} - 1 + 1]")),
        Just("arr[(a MOD 8) + 1]".to_string()),
        Just("arr[c]".to_string()),
        Just("arr[c + 1]".to_string()),
        Just("arr[b - 2]".to_string()),
        Just("arr[i1 + 3]".to_string()),
        Just("arr[i2]".to_string()),
        Just("gc".to_string()),
        Just("ga[(gc MOD 4) + 1]".to_string()),
        Just("m[1, 2]".to_string()),
        Just("m[b MOD 3, 1 + (c MOD 3)]".to_string()),
    ]
}

fn dint_expr() -> impl Strategy<Value = String> {
    dint_leaf().prop_recursive(3, 12, 2, |inner| {
        prop_oneof![
            (
                inner.clone(),
                prop::sample::select(vec!["+", "-", "*", "/", "MOD", "AND", "OR", "XOR"]),
                inner.clone()
            )
                .prop_map(|(x, op, y)| format!("({x} {op} {y})")),
            inner.clone().prop_map(|x| format!("-{x}")),
        ]
    })
}

fn bool_expr() -> impl Strategy<Value = String> {
    let cmp = (
        dint_expr(),
        prop::sample::select(vec!["<", ">", "<=", ">=", "=", "<>"]),
        dint_expr(),
    )
        .prop_map(|(x, op, y)| format!("({x} {op} {y})"));
    let real_cmp = (
        real_expr(),
        prop::sample::select(vec!["<", ">", "=", "<>"]),
        real_expr(),
    )
        .prop_map(|(x, op, y)| format!("({x} {op} {y})"));
    let leaf = prop_oneof![
        cmp,
        real_cmp,
        Just("f".to_string()),
        Just("g".to_string()),
        Just("w.3".to_string()),
        Just("tm[1].Q".to_string()),
    ];
    leaf.prop_recursive(2, 6, 2, |inner| {
        prop_oneof![
            (
                inner.clone(),
                prop::sample::select(vec!["AND", "OR", "XOR"]),
                inner.clone()
            )
                .prop_map(|(x, op, y)| format!("({x} {op} {y})")),
            inner.prop_map(|x| format!("NOT {x}")),
        ]
    })
}

fn real_expr() -> impl Strategy<Value = String> {
    let leaf = prop_oneof![
        Just("x".to_string()),
        Just("r".to_string()),
        Just("rr[2]".to_string()),
        Just("rr[(b MOD 4) + 1]".to_string()),
        Just("st.q".to_string()),
        Just("a".to_string()),
        (-50i32..50).prop_map(|v| format!("({v}.25)")),
    ];
    leaf.prop_recursive(2, 8, 2, |inner| {
        (
            inner.clone(),
            prop::sample::select(vec!["+", "-", "*", "/"]),
            inner,
        )
            .prop_map(|(x, op, y)| format!("({x} {op} {y})"))
    })
}

fn stmt(depth: u32) -> BoxedStrategy<String> {
    let simple = prop_oneof![
        dint_expr().prop_map(|e| format!("a := {e};")),
        dint_expr().prop_map(|e| format!("c := {e};")),
        dint_expr().prop_map(|e| format!("st.p := {e};")),
        dint_expr().prop_map(|e| format!("arr[(b MOD 8) + 1] := {e};")),
        dint_expr().prop_map(|e| format!("arr[0 + {e}] := a;")),
        dint_expr().prop_map(|e| format!("l := l * 3 + {e};")),
        Just("s := s * 3 + 7;".to_string()),
        Just("t := t + 27;".to_string()),
        Just("u := u * 7 - 3;".to_string()),
        Just("w := w XOR 16#FF; w.0 := f;".to_string()),
        Just("m[b MOD 3, 2] := s;".to_string()),
        bool_expr().prop_map(|e| format!("f := {e};")),
        bool_expr().prop_map(|e| format!("g := {e};")),
        real_expr().prop_map(|e| format!("x := {e};")),
        Just("r := r * 1.5 - 0.75;".to_string()),
        real_expr().prop_map(|e| format!("rr[(c MOD 4) + 1] := {e};")),
        real_expr().prop_map(|e| format!("st.q := {e};")),
        bool_expr().prop_map(|e| format!("tm[(a MOD 3) + 1](IN := {e}, PT := T#25ms);")),
        Just("b := b + 1;".to_string()),
        Just("c := c - 1;".to_string()),
        Just("gc := gc + c; ga[(c MOD 4) + 1] := gc;".to_string()),
        Just("arr[c + 1] := arr[c] + arr[i1 + 3];".to_string()),
        Just("IF arr[b] > arr[b + 1] THEN k := arr[b]; arr[b] := arr[b + 1]; arr[b + 1] := k; END_IF;".to_string()),
        Just("IF arr[i1 + 3] > arr[i1 + 4] THEN k := arr[i1 + 3]; arr[i1 + 3] := arr[i1 + 4]; arr[i1 + 4] := k; END_IF;".to_string()),
        Just("arr[i2 + 2] := arr[i2 + 3] - arr[i2 + 2]; rr[i1 + 2] := rr[i1 + 1] * 0.5;".to_string()),
        dint_expr().prop_map(|e| format!("a := a + Fx({e}, x, c);")),
        dint_expr().prop_map(|e| format!("c := Fx(p := {e}, q := r, io := arr[(b MOD 8) + 1], o => b);")),
        real_expr().prop_map(|e| format!("Fx(p := a, q := {e}, io := st.p);")),
        dint_expr().prop_map(|e| format!("fk[(a MOD 2) + 1](p := {e}); b := b + fk[1].n;")),
        Just("fk1(p := Fx(a, x, b) MOD 7); c := c - fk1.n;".to_string()),
    ];
    if depth == 0 {
        return simple.boxed();
    }
    let body = prop::collection::vec(stmt(depth - 1), 1..4).prop_map(|v| v.join(" "));
    let var = format!("i{depth}");
    prop_oneof![
        4 => simple,
        1 => (bool_expr(), body.clone(), body.clone())
            .prop_map(|(c, t, e)| format!("IF {c} THEN {t} ELSE {e} END_IF;")),
        1 => (-3i32..4, -2i32..6, prop::sample::select(vec![1, 2, -1, 3]), body.clone())
            .prop_map(move |(lo, hi, by, b)| format!("FOR {var} := {lo} TO {hi} BY {by} DO {b} END_FOR;")),
        1 => (body.clone(), 1i32..5)
            .prop_map(|(b, n)| format!("k := 0; WHILE k < {n} DO k := k + 1; {b} END_WHILE;")),
        1 => (body.clone(), 1i32..4)
            .prop_map(|(b, n)| format!("k := 0; REPEAT k := k + 1; {b} UNTIL k >= {n} END_REPEAT;")),
        1 => (dint_expr(), body.clone(), body.clone(), body)
            .prop_map(|(e, x, y, z)| format!("CASE {e} OF 0: {x} 1, 2: {y} -5..-1: EXIT; ELSE {z} END_CASE;")),
        1 => bool_expr().prop_map(|c| format!("IF {c} THEN EXIT; END_IF;")),
        1 => bool_expr().prop_map(|c| format!("IF {c} THEN CONTINUE; END_IF;")),
    ]
    .boxed()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 150, .. ProptestConfig::default() })]

    /// Random loops: closures and machine code agree on every variable and fault.
    #[test]
    fn random_loops_agree(body in prop::collection::vec(stmt(2), 1..5)) {
        let src = format!(
            "{TYPES}{DECLS}FOR i0 := 1 TO 3 DO {} END_FOR;\nEND_PROGRAM\n",
            body.join("\n")
        );
        let loops = assert_same(&src, 3);
        prop_assert!(loops >= 1, "the loop did not compile to machine code:\n{}", src);
    }

    /// The same inside a FB: instances in an array, in the program and as a global.
    #[test]
    fn random_loops_in_fb_instances_agree(body in prop::collection::vec(stmt(2), 1..4)) {
        let src = format!(
            "{TYPES}VAR_GLOBAL gw : Work; END_VAR\n{FB_DECLS}FOR i0 := 1 TO 2 DO {} END_FOR;\nEND_FUNCTION_BLOCK\n\
             PROGRAM Main VAR one : Work; many : ARRAY[1..2] OF Work; j : INT; END_VAR\n\
             one(); FOR j := 1 TO 2 DO many[j](); END_FOR; gw();\nEND_PROGRAM\n",
            body.join("\n")
        );
        let loops = assert_same(&src, 2);
        prop_assert!(loops >= 1, "the loop did not compile to machine code:\n{}", src);
    }
}

// ---- particular cases ------------------------------------------------------------------

#[test]
fn registers_are_written_back_on_a_fault() {
    let src = "PROGRAM Main VAR i, acc, d : DINT; x : LREAL; a : ARRAY[1..5] OF DINT; END_VAR
FOR i := 1 TO 10 DO acc := acc + i; x := x + 0.5; a[i] := acc / (7 - i); END_FOR
END_PROGRAM";
    assert_eq!(assert_same(src, 1), 1);
    let (vars, faults, _) = run(src, true, 1);
    assert!(faults[0].starts_with("p.st:2:53:"), "{faults:?}");
    assert!(
        faults[0].contains("array index 6 out of range 1..5"),
        "{faults:?}"
    );
    assert!(vars.contains(&"Main.acc = 21".to_string()), "{vars:?}");
    assert!(vars.contains(&"Main.x = 3.0".to_string()), "{vars:?}");
    assert!(vars.contains(&"Main.i = 6".to_string()), "{vars:?}");
}

#[test]
fn a_cell_named_and_indexed_stays_in_memory() {
    let src = "PROGRAM Main VAR i : DINT; a : ARRAY[1..4] OF DINT; n : DINT; END_VAR
FOR i := 1 TO 4 DO a[2] := a[2] + 10; a[i] := a[i] + 1; n := n + a[2]; END_FOR
END_PROGRAM";
    assert_eq!(assert_same(src, 2), 1);
    let (vars, _, _) = run(src, true, 1);
    assert!(vars.contains(&"Main.a[2] = 41".to_string()), "{vars:?}");
    assert!(vars.contains(&"Main.n = 103".to_string()), "{vars:?}");
}

#[test]
fn a_global_instance_naming_itself_runs_as_closures() {
    let src = "FUNCTION_BLOCK Loop VAR_INPUT i : INT; END_VAR VAR_OUTPUT n : INT; END_VAR
n := 0; FOR i := 1 TO 10 DO g.i := 20; n := n + 1; END_FOR
END_FUNCTION_BLOCK
VAR_GLOBAL g : Loop; h : Loop; END_VAR
PROGRAM Main VAR n, m : INT; END_VAR g(); n := g.n; h(); m := h.n; END_PROGRAM";
    assert_same(src, 1);
    let (vars, _, loops) = run(src, true, 1);
    assert_eq!(loops, 1);
    assert!(vars.contains(&"Main.n = 1".to_string()), "{vars:?}");
    assert!(vars.contains(&"Main.m = 10".to_string()), "{vars:?}");
}

#[test]
fn loop_budget_and_return_inside_compiled_loops() {
    let src = "FUNCTION Find : DINT VAR_INPUT v : DINT; END_VAR VAR i : DINT; END_VAR
Find := -1; FOR i := 1 TO 100 DO IF i * i >= v THEN Find := i; RETURN; END_IF END_FOR
END_FUNCTION
PROGRAM Main VAR r, k : DINT; END_VAR
r := Find(v := 50);
WHILE TRUE DO k := k + 1; END_WHILE
END_PROGRAM";
    assert_same(src, 1);
    let (vars, faults, loops) = run(src, true, 1);
    assert_eq!(loops, 2);
    assert!(vars.contains(&"Main.r = 8".to_string()), "{vars:?}");
    // 8 iterations in Find, the rest of the budget in the WHILE loop
    assert!(vars.contains(&"Main.k = 19992".to_string()), "{vars:?}");
    assert!(faults[0].contains("loop iteration budget"), "{faults:?}");
    assert!(faults[0].starts_with("p.st:6:1:"), "{faults:?}");
}

#[test]
fn wrapping_division_and_conversions_match() {
    let src = "PROGRAM Main VAR i : INT; a : DINT := -2147483648; q, m : DINT; s : SINT;
u : ULINT := 16#FFFFFFFFFFFFFFFF; v : ULINT; x : LREAL; r : REAL; d : DINT; END_VAR
FOR i := -1 TO -1 DO q := a / i; m := a MOD i; s := s + 100; v := u / 3; x := i;
r := r / 3.0 + 1.0; d := (a + 1) / 65536; END_FOR
END_PROGRAM";
    assert_eq!(assert_same(src, 2), 1);
}

#[test]
fn an_index_changed_in_a_branch_is_checked_again() {
    let src =
        "PROGRAM Main VAR i, j, x, y : DINT; a : ARRAY[1..5] OF DINT := [1, 2, 3, 4, 5]; END_VAR
j := 2;
FOR i := 1 TO 3 DO
  x := x + a[j];
  IF i = 2 THEN j := 9; END_IF
  y := y + a[j];
END_FOR
END_PROGRAM";
    assert_eq!(assert_same(src, 1), 1);
    let (vars, faults, _) = run(src, true, 1);
    assert!(
        faults[0].contains("array index 9 out of range 1..5"),
        "{faults:?}"
    );
    assert!(faults[0].starts_with("p.st:6:14:"), "{faults:?}");
    assert!(vars.contains(&"Main.x = 4".to_string()), "{vars:?}");
    assert!(vars.contains(&"Main.y = 2".to_string()), "{vars:?}");
}

/// The seeds of the `plc_*` fuzz targets in `tests/fuzz/fragments`, each put into
/// `tests/fuzz/harness.st` as the targets do: every one builds, runs the same as closures
/// and as machine code for three cycles, and faults as its first line says (a NULL
/// dereference, also inside a loop, is a fault and stops the task, never a panic).
#[test]
fn fuzz_fragments_build_agree_and_fault_as_declared() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz");
    let harness = std::fs::read_to_string(dir.join("harness.st")).unwrap();
    assert!(harness.contains("(* BODY *)"));
    let mut names: Vec<_> = std::fs::read_dir(dir.join("fragments"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    names.sort();
    assert!(names.len() >= 10, "fragments: {names:?}");
    let mut with_jit_loops = 0;
    for path in names {
        let body = std::fs::read_to_string(&path).unwrap();
        assert!(
            !body.to_ascii_uppercase().contains("PROGRAM"),
            "{path:?} would not be wrapped"
        );
        let first = body.lines().next().unwrap();
        let expected = first
            .strip_prefix("(* fault: ")
            .and_then(|f| f.strip_suffix(" *)"));
        assert!(
            expected.is_some() || first == "(* no fault *)",
            "{path:?}: first line says neither '(* fault: ... *)' nor '(* no fault *)'"
        );
        let src = harness.replacen("(* BODY *)", &body, 1);
        let (v1, f1, _) = run(&src, false, 3);
        let (v2, f2, loops) = run(&src, true, 3);
        assert_eq!(f1, f2, "faults differ for {path:?}");
        assert_eq!(v1, v2, "closures vs jit for {path:?}");
        with_jit_loops += usize::from(loops > 0);
        match expected {
            Some(text) => {
                assert_eq!(
                    f1.len(),
                    1,
                    "{path:?}: one fault, then the task stays stopped: {f1:?}"
                );
                assert!(f1[0].contains(text), "{path:?}: {f1:?}");
            }
            None => assert!(f1.is_empty(), "{path:?}: {f1:?}"),
        }
    }
    assert!(
        with_jit_loops > 0,
        "no fragment has a loop compiled to machine code"
    );
}

/// The conformance programs with calls in loops (`tests/conformance/call_in_loop_*.st`,
/// run both ways by the suite): their loops compile to machine code, calls of FUNCTIONs
/// and FB instances (VAR_IN_OUT, outputs, arrays of instances, nested calls) included.
/// A nested loop is part of the loop around it; the one loop left to the closures is
/// `Fill`'s own, which indexes its own VAR_IN_OUT (it runs inlined where it is called).
#[test]
fn loops_with_calls_compile_to_machine_code() {
    let expected = [
        ("exit_continue", 4),
        ("fault_div", 1),
        ("fault_index", 1),
        ("fault_range", 1),
        ("fb_array", 2),
        ("fb_outputs", 1),
        ("function_params", 1),
        ("inout_sort", 4),
        ("locals_reinit", 2),
        ("nested", 1),
    ];
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/conformance");
    for (name, loops) in expected {
        let path = dir.join(format!("call_in_loop_{name}.st"));
        let text = std::fs::read_to_string(&path).unwrap();
        let (_, compiled) =
            crate::support::build_or_fail(&[("p.st".into(), text)], CompileOptions { jit: true });
        assert_eq!(compiled.jit_loops, loops, "{path:?}");
    }
}

/// An index check made in an inlined callee after a RETURN it may take does not stand
/// for the same index after the call: `a[j]` is checked again and faults at its own
/// position, as with closures.
#[test]
fn an_index_checked_in_a_callee_after_its_return_is_checked_again() {
    let src = "FUNCTION_BLOCK Peek
VAR_INPUT skip : BOOL; END_VAR
VAR_IN_OUT idx : DINT; arr : ARRAY[1..5] OF DINT; END_VAR
VAR_OUTPUT v : DINT; END_VAR
IF skip THEN RETURN; END_IF
v := arr[idx];
END_FUNCTION_BLOCK
PROGRAM Main VAR p : Peek; a : ARRAY[1..5] OF DINT := [1, 2, 3, 4, 5]; j, s : DINT; END_VAR
FOR j := 1 TO 9 DO p(skip := j > 3, idx := j, arr := a); s := s + a[j]; END_FOR
END_PROGRAM";
    assert_eq!(assert_same(src, 1), 1);
    let (vars, faults, _) = run(src, true, 1);
    assert!(faults[0].starts_with("p.st:9:69:"), "{faults:?}");
    assert!(
        faults[0].contains("array index 6 out of range 1..5"),
        "{faults:?}"
    );
    assert!(vars.contains(&"Main.s = 15".to_string()), "{vars:?}");
    assert!(vars.contains(&"Main.p.v = 3".to_string()), "{vars:?}");
}

/// The `jit_*` conformance programs (branch-free swaps, elements carried between
/// iterations, their faults, EXIT, RETURN, budget, VAR_IN_OUT, REF, wrapping indices):
/// their loops compile to machine code and agree with the closures.
#[test]
fn jit_conformance_programs_compile_and_agree() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/conformance");
    let mut seen = 0;
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        if !name.starts_with("jit_") || !name.ends_with(".st") {
            continue;
        }
        let src = std::fs::read_to_string(&path).unwrap();
        let loops = assert_same(&src, 2);
        assert!(loops >= 1, "{name}: no loop compiled to machine code");
        seen += 1;
    }
    assert!(seen >= 6, "jit_ programs found: {seen}");
}
