//! Representative ST programs against the same algorithms in native Rust, side by side.
//! Run: `cargo bench -p plc --bench st_vs_native`. Prints the time per scan of the ST
//! program as compiled (loops as machine code), as closures only, and of native Rust, the
//! ratio ST/native, and what building each program costs with and without the JIT.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::disallowed_methods
)]

use plc::task::{ClockReading, TaskConfig};
use std::hint::black_box;
use std::time::Instant;

const INT_LOOP: &str = "PROGRAM Main VAR i : DINT; acc : DINT; END_VAR
acc := 0;
FOR i := 1 TO 100000 DO acc := acc + (i * i) MOD 7; END_FOR
END_PROGRAM";

fn int_loop() -> i32 {
    let mut acc: i32 = 0;
    for i in 1..=black_box(100_000i32) {
        acc = acc.wrapping_add(i.wrapping_mul(i) % 7);
    }
    acc
}

const REAL_LOOP: &str = "PROGRAM Main VAR i : DINT; x : LREAL; END_VAR
x := 0.0;
FOR i := 1 TO 100000 DO x := x * 0.999999 + 0.5; END_FOR
END_PROGRAM";

fn real_loop() -> f64 {
    let mut x = 0.0f64;
    for _ in 1..=black_box(100_000) {
        x = x * 0.999999 + 0.5;
    }
    x
}

const SORT: &str =
    "PROGRAM Main VAR a : ARRAY[1..200] OF DINT; i, j, t : DINT; seed : DINT := 12345; END_VAR
FOR i := 1 TO 200 DO seed := (seed * 1103 + 12345) MOD 65536; a[i] := seed; END_FOR
FOR i := 1 TO 199 DO
  FOR j := 1 TO 200 - i DO
    IF a[j] > a[j + 1] THEN t := a[j]; a[j] := a[j + 1]; a[j + 1] := t; END_IF
  END_FOR
END_FOR
END_PROGRAM";

/// The seed lives on between calls, as the ST program's `seed` (a PROGRAM variable) does
/// between scans: both sort new data every time. (Restarting it at 12345 gave Rust the
/// same array at every call, whose branches the predictor learns.)
fn sort(seed: &mut i32) -> i32 {
    let mut a = [0i32; 200];
    for x in a.iter_mut() {
        *seed = (*seed * 1103 + 12345) % 65536;
        *x = *seed;
    }
    for i in 1..200 {
        for j in 0..200 - i {
            if a[j] > a[j + 1] {
                a.swap(j, j + 1);
            }
        }
    }
    a[0]
}

const STRINGS: &str = "PROGRAM Main VAR s : STRING[1000]; i : INT; END_VAR
s := '';
FOR i := 1 TO 100 DO s := CONCAT(s, INT_TO_STRING(i)); s := CONCAT(s, ','); END_FOR
END_PROGRAM";

fn strings() -> usize {
    let mut s = String::new();
    for i in 1..=black_box(100) {
        s.push_str(&i.to_string());
        s.push(',');
        s.truncate(1000);
    }
    s.len()
}

const TONS: &str = "PROGRAM Main VAR t : ARRAY[1..1000] OF TON; i : INT; n : INT; END_VAR
n := 0;
FOR i := 1 TO 1000 DO t[i](IN := TRUE, PT := T#1h); IF t[i].Q THEN n := n + 1; END_IF END_FOR
END_PROGRAM";

#[derive(Clone, Copy, Default)]
struct Ton {
    q: bool,
    et: i64,
    running: bool,
    start: i64,
}

fn tons(ts: &mut [Ton], now: i64) -> i32 {
    let mut n = 0;
    for t in ts.iter_mut() {
        let (inp, pt) = (black_box(true), 3_600_000_000_000i64);
        if inp {
            if !t.running {
                t.running = true;
                t.start = now;
            }
            if !t.q {
                t.et = now - t.start;
                if t.et >= pt {
                    t.et = pt;
                    t.q = true;
                }
            }
        } else {
            t.running = false;
            t.q = false;
            t.et = 0;
        }
        if t.q {
            n += 1;
        }
    }
    n
}

const CALLS: &str = "FUNCTION Mix : DINT
VAR_INPUT a, b : DINT; END_VAR
Mix := (a * 31 + b) MOD 1000;
END_FUNCTION
FUNCTION Clamp : DINT
VAR_INPUT x, lo, hi : DINT; END_VAR
IF x < lo THEN Clamp := lo; ELSIF x > hi THEN Clamp := hi; ELSE Clamp := x; END_IF
END_FUNCTION
FUNCTION_BLOCK Smooth
VAR_INPUT x : DINT; END_VAR
VAR_IN_OUT sum : DINT; END_VAR
VAR_OUTPUT y : DINT; END_VAR
VAR prev : DINT; END_VAR
y := (x + prev) / 2;
prev := x;
sum := sum + y;
END_FUNCTION_BLOCK
PROGRAM Main VAR f : Smooth; i, v, total : DINT; END_VAR
total := 0;
FOR i := 1 TO 10000 DO
  v := Clamp(Mix(i, v), 100, 900);
  f(x := v, sum := total);
END_FOR
END_PROGRAM";

/// `Main` of [`CALLS`]: `v` and the block's `prev` keep their values from scan to scan.
#[derive(Default)]
struct Calls {
    v: i32,
    prev: i32,
}

fn mix(a: i32, b: i32) -> i32 {
    a.wrapping_mul(31).wrapping_add(b) % 1000
}

fn clamp(x: i32, lo: i32, hi: i32) -> i32 {
    if x < lo {
        lo
    } else if x > hi {
        hi
    } else {
        x
    }
}

/// The function block: `sum` is the VAR_IN_OUT, `prev` its state; returns `y`.
fn smooth(prev: &mut i32, x: i32, sum: &mut i32) -> i32 {
    let y = x.wrapping_add(*prev) / 2;
    *prev = x;
    *sum = sum.wrapping_add(y);
    y
}

fn calls(st: &mut Calls) -> i32 {
    let mut total = 0;
    for i in 1..=black_box(10_000i32) {
        st.v = clamp(mix(i, st.v), 100, 900);
        black_box(smooth(&mut st.prev, st.v, &mut total));
    }
    total
}

/// The ST program and its Rust twin compute the same `total` over three scans (with and
/// without the JIT): the two sides of a row run the same algorithm.
fn check_calls() {
    let mut native = Calls::default();
    let want: Vec<String> = (0..3).map(|_| calls(&mut native).to_string()).collect();
    for jit in [false, true] {
        let (sources, r) = plc::build_with(
            &[("bench.st".into(), CALLS.into())],
            plc::CompileOptions { jit },
        );
        let mut p = plc::Plc::new(r.unwrap_or_else(|d| panic!("{d:?}")), sources);
        p.add_task(TaskConfig::cyclic("t", 0, &["Main"])).unwrap();
        let mut now = ClockReading::default();
        let got: Vec<String> = (0..3)
            .map(|_| {
                now.monotonic_ns += 1_000_000;
                assert!(p.run_cycle(now).is_empty());
                p.read_text("Main.total").unwrap()
            })
            .collect();
        assert_eq!(got, want, "ST (jit {jit}) and Rust disagree");
    }
}

fn time_st(src: &str, scans: u32, jit: bool) -> f64 {
    let (sources, r) = plc::build_with(
        &[("bench.st".into(), src.into())],
        plc::CompileOptions { jit },
    );
    let compiled = r.unwrap_or_else(|d| panic!("{d:?}"));
    if !jit {
        assert_eq!(compiled.jit_loops, 0, "closures only");
    }
    let mut p = plc::Plc::new(compiled, sources);
    p.add_task(TaskConfig::cyclic("t", 0, &["Main"])).unwrap();
    let mut now = ClockReading::default();
    p.run_cycle(now);
    let start = Instant::now();
    for _ in 0..scans {
        now.monotonic_ns += 1_000_000;
        assert!(p.run_cycle(now).is_empty());
    }
    start.elapsed().as_secs_f64() / f64::from(scans)
}

fn time_native(mut f: impl FnMut() -> i64, scans: u32) -> f64 {
    black_box(f());
    let start = Instant::now();
    for _ in 0..scans {
        black_box(f());
    }
    start.elapsed().as_secs_f64() / f64::from(scans)
}

fn main() {
    if let Ok(only) = std::env::var("ST_BENCH_ONLY") {
        let (src, scans) = match only.as_str() {
            "ton" => (TONS, 20000),
            "sort" => (SORT, 500),
            "real" => (REAL_LOOP, 200),
            "string" => (STRINGS, 20000),
            "calls" => (CALLS, 500),
            _ => (INT_LOOP, 200),
        };
        println!("{:.1}us", time_st(src, scans, true) * 1e6);
        return;
    }
    check_calls();
    let mut ts = vec![Ton::default(); 1000];
    let mut now = 0i64;
    let mut calls_state = Calls::default();
    let rows: Vec<(&str, f64, f64, f64)> = vec![
        (
            "integer loop (100k)",
            time_st(INT_LOOP, 20, true),
            time_st(INT_LOOP, 20, false),
            time_native(|| i64::from(int_loop()), 200),
        ),
        (
            "REAL loop (100k)",
            time_st(REAL_LOOP, 20, true),
            time_st(REAL_LOOP, 20, false),
            time_native(|| real_loop() as i64, 200),
        ),
        (
            "bubble sort (200)",
            time_st(SORT, 50, true),
            time_st(SORT, 20, false),
            {
                let mut seed = black_box(12345);
                time_native(move || i64::from(sort(&mut seed)), 500)
            },
        ),
        (
            "string building (100) *",
            time_st(STRINGS, 200, true),
            time_st(STRINGS, 200, false),
            time_native(|| strings() as i64, 2000),
        ),
        (
            "1000 TON per scan",
            time_st(TONS, 500, true),
            time_st(TONS, 200, false),
            time_native(
                || {
                    now += 1_000_000;
                    i64::from(tons(&mut ts, now))
                },
                5000,
            ),
        ),
        (
            "FUNCTION/FB calls (10k)",
            time_st(CALLS, 50, true),
            time_st(CALLS, 20, false),
            time_native(|| i64::from(calls(&mut calls_state)), 2000),
        ),
    ];
    println!(
        "{:<24} {:>12} {:>12} {:>12} {:>8}",
        "program", "ST/scan", "closures", "native/scan", "ratio"
    );
    for (name, st, closures, native) in rows {
        println!(
            "{name:<24} {:>10.1}us {:>10.1}us {:>10.1}us {:>7.1}x",
            st * 1e6,
            closures * 1e6,
            native * 1e6,
            st / native
        );
    }
    println!("* strings are outside the JIT subset: that loop runs as closures either way");
    let calls_jit_loops = {
        let (_, r) = plc::build(&[("bench.st".into(), CALLS.into())]);
        r.unwrap_or_else(|d| panic!("{d:?}")).jit_loops
    };
    println!("FUNCTION/FB calls: {calls_jit_loops} loop(s) compiled to machine code");
    // what the JIT costs when a program is built (every program above, best of 5)
    let all = [INT_LOOP, REAL_LOOP, SORT, STRINGS, TONS, CALLS];
    for jit in [false, true] {
        let best = (0..5)
            .map(|_| {
                let start = Instant::now();
                for src in all {
                    let (_, r) = plc::build_with(
                        &[("bench.st".into(), src.into())],
                        plc::CompileOptions { jit },
                    );
                    black_box(r.is_ok());
                }
                start.elapsed().as_secs_f64() / all.len() as f64
            })
            .fold(f64::MAX, f64::min);
        println!(
            "build per program ({}): {:.2} ms",
            if jit { "with JIT" } else { "closures only" },
            best * 1e3
        );
    }
}
