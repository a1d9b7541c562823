//! Runtime API: paths, forcing, retain, watchdog, statistics, tasks, I/O image, faults.

use plc::task::{ClockReading, Stopwatch, TaskConfig, TaskState};
use plc::Plc;
use std::cell::Cell;
use std::rc::Rc;

fn plc(src: &str) -> Plc {
    crate::support::plc_of("t.st", src)
}

fn at_ms(ms: i64) -> ClockReading {
    ClockReading {
        monotonic_ns: ms * 1_000_000,
        utc_ns: 1_700_000_000_000_000_000 + ms * 1_000_000,
        utc_offset_ns: 0,
    }
}

const LIGHTS: &str = "
PROGRAM Main
VAR lights : ARRAY[1..4] OF TON; on : BOOL; count : INT; limit : INT := 100; END_VAR
VAR RETAIN starts : INT; END_VAR
VAR PERSISTENT total : DINT; END_VAR
lights[3](IN := on, PT := T#20ms);
count := count + 1;
IF count > limit THEN count := limit; END_IF
total := total + 1;
END_PROGRAM
";

#[test]
fn read_and_write_by_path() {
    let mut p = plc(LIGHTS);
    p.add_task(TaskConfig::cyclic("main", 10_000_000, &["Main"]))
        .unwrap();
    p.write("Main.on", "TRUE").unwrap();
    for k in 0..4 {
        p.run_cycle(at_ms(k * 10));
    }
    assert_eq!(p.read_text("Main.lights[3].Q").unwrap(), "TRUE");
    assert_eq!(p.read_text("Main.lights[3].ET").unwrap(), "T#20ms");
    assert_eq!(p.read_text("main.LIGHTS[3].pt").unwrap(), "T#20ms");
    assert!(p.read_text("Main.lights[5].Q").is_err());
    assert!(p.read_text("Main.nothing").is_err());
    assert!(p.write("Main.count", "'text'").is_err());
    assert!(p.write("Main.count", "70000").is_err());
    let all: Vec<String> = p
        .program_leaves("Main")
        .unwrap()
        .into_iter()
        .map(|l| l.path)
        .collect();
    assert!(all.contains(&"Main.lights[1].IN".to_string()));
    assert!(all.contains(&"Main.total".to_string()));
}

#[test]
fn forcing_holds_a_value_until_released() {
    let mut p = plc(LIGHTS);
    p.add_task(TaskConfig::cyclic("main", 10_000_000, &["Main"]))
        .unwrap();
    p.force("Main.count", "7").unwrap();
    for k in 0..3 {
        p.run_cycle(at_ms(k * 10));
        assert_eq!(p.read_text("Main.count").unwrap(), "7");
    }
    assert_eq!(p.forced(), vec!["Main.count".to_string()]);
    assert!(p.release("Main.count"));
    p.run_cycle(at_ms(30));
    assert_eq!(p.read_text("Main.count").unwrap(), "8");
    // write once: the program takes over in the next cycle
    p.write("Main.count", "50").unwrap();
    p.run_cycle(at_ms(40));
    assert_eq!(p.read_text("Main.count").unwrap(), "51");
}

#[test]
fn warm_start_keeps_retain_cold_start_does_not() {
    let mut p = plc(LIGHTS);
    p.add_task(TaskConfig::cyclic("main", 10_000_000, &["Main"]))
        .unwrap();
    p.write("Main.starts", "5").unwrap();
    for k in 0..3 {
        p.run_cycle(at_ms(k * 10));
    }
    p.warm_start().unwrap();
    assert_eq!(p.read_text("Main.starts").unwrap(), "5");
    assert_eq!(p.read_text("Main.total").unwrap(), "3");
    assert_eq!(p.read_text("Main.count").unwrap(), "0");
    p.cold_start().unwrap();
    assert_eq!(p.read_text("Main.starts").unwrap(), "0");
    assert_eq!(p.read_text("Main.total").unwrap(), "0");
}

#[test]
fn retain_file_is_written_atomically_and_survives_download() {
    let dir = std::env::temp_dir().join(format!("plc-retain-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("retain.txt");
    let mut p = plc(LIGHTS);
    p.add_task(TaskConfig::cyclic("main", 10_000_000, &["Main"]))
        .unwrap();
    p.write("Main.starts", "9").unwrap();
    p.run_cycle(at_ms(0));
    p.run_cycle(at_ms(10));
    p.save_retain(&file).unwrap();
    assert!(!file.with_extension("tmp").exists());
    let text = std::fs::read_to_string(&file).unwrap();
    assert!(text.contains("RETAIN Main.starts = 9"), "{text}");
    assert!(text.contains("PERSISTENT Main.total = 2"), "{text}");
    // a new download of a changed program: PERSISTENT only
    let mut q = plc(&LIGHTS.replace("limit : INT := 100;", "limit : INT := 5; extra : BOOL;"));
    assert_eq!(q.load_retain(&file, true).unwrap(), 1);
    assert_eq!(q.read_text("Main.total").unwrap(), "2");
    assert_eq!(q.read_text("Main.starts").unwrap(), "0");
    assert_eq!(q.load_retain(&file, false).unwrap(), 2);
    assert_eq!(q.read_text("Main.starts").unwrap(), "9");
    std::fs::remove_dir_all(&dir).unwrap();
}

struct Scripted(Rc<Cell<i64>>);
impl Stopwatch for Scripted {
    fn start(&mut self) {}
    fn elapsed_ns(&mut self) -> i64 {
        self.0.get()
    }
}

#[test]
fn watchdog_faults_after_sensitivity_consecutive_overruns() {
    let mut p = plc(LIGHTS);
    let cost = Rc::new(Cell::new(1_000_000));
    p.set_stopwatch(Box::new(Scripted(cost.clone())));
    p.add_task(TaskConfig::cyclic("main", 10_000_000, &["Main"]).with_watchdog(5_000_000, 3))
        .unwrap();
    p.run_cycle(at_ms(0));
    cost.set(8_000_000);
    assert!(p.run_cycle(at_ms(10)).is_empty());
    assert!(p.run_cycle(at_ms(20)).is_empty());
    cost.set(1_000_000);
    assert!(p.run_cycle(at_ms(30)).is_empty()); // resets the consecutive count
    cost.set(8_000_000);
    assert!(p.run_cycle(at_ms(40)).is_empty());
    assert!(p.run_cycle(at_ms(50)).is_empty());
    let faults = p.run_cycle(at_ms(60));
    assert_eq!(faults.len(), 1);
    assert!(
        faults[0].message.contains("watchdog"),
        "{}",
        faults[0].message
    );
    assert!(matches!(p.task_state("main"), Some(TaskState::Faulted(_))));
    let before = p.read_text("Main.count").unwrap();
    p.run_cycle(at_ms(70));
    assert_eq!(
        p.read_text("Main.count").unwrap(),
        before,
        "a faulted task does not run"
    );
    let s = p.stats("main").unwrap();
    assert_eq!(s.cycles, 7);
    assert_eq!(s.overruns, 5);
    assert_eq!(s.min_ns, 1_000_000);
    assert_eq!(s.max_ns, 8_000_000);
    assert_eq!(s.last_ns, 8_000_000);
    p.cold_start().unwrap();
    assert_eq!(p.task_state("main"), Some(&TaskState::Running));
}

#[test]
fn statistics_and_jitter() {
    let mut p = plc(LIGHTS);
    p.add_task(TaskConfig::cyclic("main", 10_000_000, &["Main"]))
        .unwrap();
    p.run_cycle(at_ms(0));
    p.run_cycle(at_ms(5)); // not due
    p.run_cycle(at_ms(13)); // 3 ms late
    p.run_cycle(at_ms(20));
    let s = p.stats("main").unwrap();
    assert_eq!(s.cycles, 3);
    assert_eq!(s.jitter_ns, 3_000_000);
    assert_eq!(p.read_text("Main.count").unwrap(), "3");
    assert_eq!(p.next_due(), Some(30_000_000));
}

#[test]
fn tasks_with_intervals_and_priorities() {
    let src = "
VAR_GLOBAL trace : STRING[200]; END_VAR
PROGRAM Fast VAR n : INT; END_VAR n := n + 1; trace := CONCAT(trace, 'F'); END_PROGRAM
PROGRAM Slow VAR n : INT; END_VAR n := n + 1; trace := CONCAT(trace, 'S'); END_PROGRAM
";
    let mut p = plc(src);
    p.add_task(TaskConfig::cyclic("slow", 30_000_000, &["Slow"]).with_priority(5))
        .unwrap();
    p.add_task(TaskConfig::cyclic("fast", 10_000_000, &["Fast"]).with_priority(1))
        .unwrap();
    for k in 0..6 {
        p.run_cycle(at_ms(k * 10));
    }
    assert_eq!(p.read_text("Fast.n").unwrap(), "6");
    assert_eq!(p.read_text("Slow.n").unwrap(), "2");
    // the higher-priority task runs first when both are due
    assert_eq!(p.read_text("trace").unwrap(), "'FSFFFSFF'");
}

#[test]
fn a_fault_stops_only_its_task() {
    let src = "
PROGRAM Bad VAR z : INT; x : INT; END_VAR x := 1 / z; END_PROGRAM
PROGRAM Good VAR n : INT; END_VAR n := n + 1; END_PROGRAM
";
    let mut p = plc(src);
    p.add_task(TaskConfig::cyclic("bad", 10_000_000, &["Bad"]))
        .unwrap();
    p.add_task(TaskConfig::cyclic("good", 10_000_000, &["Good"]))
        .unwrap();
    let f = p.run_cycle(at_ms(0));
    assert_eq!(f.len(), 1);
    let rendered = p.render(&f[0]);
    assert!(
        rendered.starts_with("t.st:2:48: error: task 'bad' stopped: division by zero"),
        "{rendered}"
    );
    p.run_cycle(at_ms(10));
    assert_eq!(p.read_text("Good.n").unwrap(), "2");
}

#[test]
fn io_image_binds_direct_addresses() {
    let src = "
PROGRAM Main
VAR
    start AT %IX0.0 : BOOL;
    level AT %IW2 : WORD;
    lamp AT %QX1.3 : BOOL;
    setpoint AT %QW4 : WORD;
END_VAR
lamp := start;
setpoint := level + 1;
END_PROGRAM
";
    let mut p = plc(src);
    p.add_task(TaskConfig::cyclic("main", 10_000_000, &["Main"]))
        .unwrap();
    p.set_io("%IX0.0", 1).unwrap();
    p.set_io("%IW2", 1234).unwrap();
    p.run_cycle(at_ms(0));
    assert_eq!(p.get_io("%QX1.3").unwrap(), 1);
    assert_eq!(p.get_io("%QW4").unwrap(), 1235);
    assert_eq!(p.get_io("%QB4").unwrap(), 1235 >> 8, "big-endian words");
    assert!(p.set_io("%ZX0.0", 1).is_err());
    // forcing an input variable overrides the image
    p.force("Main.start", "FALSE").unwrap();
    p.run_cycle(at_ms(10));
    assert_eq!(p.get_io("%QX1.3").unwrap(), 0);
}

#[test]
fn virtual_clock_drives_timers_exactly() {
    let src = "PROGRAM Main VAR t : TON; END_VAR t(IN := TRUE, PT := T#1h); END_PROGRAM";
    let mut p = plc(src);
    p.add_task(TaskConfig::cyclic("main", 0, &["Main"]))
        .unwrap();
    let mut clock = plc::task::VirtualClock::new(0, 0);
    p.run_cycle(clock.now());
    clock.advance(3_600_000_000_000 - 1);
    p.run_cycle(clock.now());
    assert_eq!(p.read_text("Main.t.Q").unwrap(), "FALSE");
    clock.advance(1);
    p.run_cycle(clock.now());
    assert_eq!(p.read_text("Main.t.Q").unwrap(), "TRUE");
    assert_eq!(p.read_text("Main.t.ET").unwrap(), "T#1h");
}

#[test]
fn diagnostics_render_with_file_line_col() {
    let (sources, r) = plc::build(&[(
        "a.st".into(),
        "PROGRAM Main\nVAR x : INT; END_VAR\nx := nope;\nEND_PROGRAM\n".into(),
    )]);
    let d = r.err().unwrap();
    assert_eq!(
        d[0].headline(&sources),
        "a.st:3:6: error: undeclared name 'nope'"
    );
    assert!(d[0].render(&sources).contains("= code: E0101"));
}

/// The native TON/TOF/TP/R_TRIG/F_TRIG bodies agree with their ST reference (the prelude
/// text, compiled under another name) on pseudo-random input sequences.
#[test]
fn native_timers_match_their_st_reference() {
    let prelude = plc::stdlib::PRELUDE;
    let mut copies = String::new();
    for name in ["TON", "TOF", "TP", "R_TRIG", "F_TRIG"] {
        let start = prelude.find(&format!("FUNCTION_BLOCK {name}\n")).unwrap();
        let end = start
            + prelude[start..].find("END_FUNCTION_BLOCK").unwrap()
            + "END_FUNCTION_BLOCK".len();
        copies.push_str(&prelude[start..end].replacen(name, &format!("ST_{name}"), 1));
        copies.push('\n');
    }
    let src = format!(
        "{copies}
PROGRAM Main
VAR a : TON; b : ST_TON; c : TOF; d : ST_TOF; e : TP; f : ST_TP; g : R_TRIG; h : ST_R_TRIG;
    i : F_TRIG; j : ST_F_TRIG; x : BOOL; pt : TIME; same : BOOL := TRUE; END_VAR
a(IN := x, PT := pt); b(IN := x, PT := pt);
c(IN := x, PT := pt); d(IN := x, PT := pt);
e(IN := x, PT := pt); f(IN := x, PT := pt);
g(CLK := x); h(CLK := x); i(CLK := x); j(CLK := x);
same := same AND a.Q = b.Q AND a.ET = b.ET AND c.Q = d.Q AND c.ET = d.ET AND e.Q = f.Q
    AND e.ET = f.ET AND g.Q = h.Q AND i.Q = j.Q;
END_PROGRAM"
    );
    let mut p = plc(&src);
    p.add_task(TaskConfig::cyclic("main", 0, &["Main"]))
        .unwrap();
    let mut seed: u64 = 0x2545_F491_4F6C_DD1D;
    let mut t = 0;
    for _ in 0..5000 {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        if seed % 7 == 0 {
            p.write("Main.x", if seed % 2 == 0 { "TRUE" } else { "FALSE" })
                .unwrap();
        }
        if seed % 97 == 0 {
            p.write("Main.pt", &format!("T#{}ms", seed % 50)).unwrap();
        }
        t += (seed % 13) as i64 * 1_000_000;
        p.run_cycle(at_ms(0).with_mono(t));
        assert_eq!(
            p.read_text("Main.same").unwrap(),
            "TRUE",
            "diverged at t = {t} ns"
        );
    }
}

trait WithMono {
    fn with_mono(self, ns: i64) -> Self;
}
impl WithMono for ClockReading {
    fn with_mono(mut self, ns: i64) -> Self {
        self.monotonic_ns = ns;
        self
    }
}

#[test]
fn standard_timers_have_native_bodies() {
    // the prelude's POUs are compiled when a program names them
    let src =
        "PROGRAM Main VAR a : TON; b : TOF; c : TP; d : R_TRIG; e : F_TRIG; END_VAR END_PROGRAM";
    let (_, r) = plc::build(&[("a.st".into(), src.into())]);
    let c = r.unwrap();
    for name in ["TON", "TOF", "TP", "R_TRIG", "F_TRIG"] {
        let id = c.checked.pou_index[name];
        assert!(
            plc::stdlib::timers::native_body(&c.checked.pous[id.0]).is_some(),
            "{name}"
        );
    }
}

/// SUN_TIME against the Wikipedia "sunrise equation" (Julian-day based, a different
/// algorithm) for every day of 2024 at Vsetín: within 3 minutes.
#[test]
fn sun_time_matches_an_independent_algorithm_over_a_year() {
    let src = "PROGRAM Main VAR s : SUN_TIME; END_VAR s(LATITUDE := 49.3387, LONGITUDE := 17.9962); END_PROGRAM";
    let mut p = plc(src);
    p.add_task(TaskConfig::cyclic("main", 0, &["Main"]))
        .unwrap();
    let (lat, lon) = (49.3387f64, 17.9962f64);
    let day_ns = 86_400_000_000_000i64;
    let start_days = plc::syntax::lexer::days_from_civil(2024, 1, 1);
    let mut worst = 0.0f64;
    for d in 0..366 {
        let days = start_days + d;
        let utc_noon = days * day_ns + 11 * 3_600_000_000_000;
        let offset = 3_600_000_000_000; // a fixed CET offset keeps the comparison simple
        p.run_cycle(ClockReading {
            monotonic_ns: d * day_ns,
            utc_ns: utc_noon,
            utc_offset_ns: offset,
        });
        let tod_min = |path: &str| -> f64 {
            let t = p.read_text(path).unwrap();
            let hms: Vec<f64> = t
                .trim_start_matches("TOD#")
                .split(':')
                .map(|x| x.parse().unwrap())
                .collect();
            hms[0] * 60.0 + hms[1] + hms[2] / 60.0
        };
        // reference
        let jd = (utc_noon as f64 / 1e9) / 86400.0 + 2440587.5;
        let n = (jd - 2451545.0 + 0.0008).ceil();
        let j_star = n - lon / 360.0;
        let m = (357.5291 + 0.98560028 * j_star).rem_euclid(360.0);
        let mr = m.to_radians();
        let c = 1.9148 * mr.sin() + 0.02 * (2.0 * mr).sin() + 0.0003 * (3.0 * mr).sin();
        let lambda = (m + c + 180.0 + 102.9372).rem_euclid(360.0).to_radians();
        let transit = 2451545.0 + j_star + 0.0053 * mr.sin() - 0.0069 * (2.0 * lambda).sin();
        let decl = (lambda.sin() * 23.4397f64.to_radians().sin()).asin();
        let phi = lat.to_radians();
        let w0 = (((-0.833f64).to_radians().sin() - phi.sin() * decl.sin())
            / (phi.cos() * decl.cos()))
        .acos()
        .to_degrees();
        let to_local_min = |jd: f64| ((jd - 2440587.5) * 1440.0 + 60.0).rem_euclid(1440.0);
        let rise = to_local_min(transit - w0 / 360.0);
        let set = to_local_min(transit + w0 / 360.0);
        let (r, s) = (tod_min("Main.s.SUNRISE"), tod_min("Main.s.SUNSET"));
        worst = worst.max((r - rise).abs()).max((s - set).abs());
        assert!(
            (r - rise).abs() < 3.0 && (s - set).abs() < 3.0,
            "day {d}: SUN_TIME {r:.1}/{s:.1} min, reference {rise:.1}/{set:.1}"
        );
    }
    assert!(worst < 3.0, "worst {worst} min");
}

#[test]
fn tasks_declared_in_a_configuration() {
    let src = "
CONFIGURATION Plant
    RESOURCE Cpu ON PLC
        TASK Fast (INTERVAL := T#10ms, PRIORITY := 1);
        TASK Slow (INTERVAL := T#50ms, PRIORITY := 5);
        PROGRAM P1 WITH Fast : Counter;
        PROGRAM P2 WITH Slow : Other;
    END_RESOURCE
END_CONFIGURATION
PROGRAM Counter VAR n : INT; END_VAR n := n + 1; END_PROGRAM
PROGRAM Other VAR n : INT; END_VAR n := n + 1; END_PROGRAM
";
    let mut p = plc(src);
    assert_eq!(p.add_declared_tasks().unwrap(), 2);
    for k in 0..10 {
        p.run_cycle(at_ms(k * 10));
    }
    assert_eq!(p.read_text("Counter.n").unwrap(), "10");
    assert_eq!(p.read_text("Other.n").unwrap(), "2");
}

#[test]
fn type_mismatch_points_at_the_declaration() {
    let (sources, r) = plc::build(&[(
        "m.st".into(),
        "PROGRAM Main\nVAR\n  x : INT;\nEND_VAR\nx := 1.5;\nEND_PROGRAM\n".into(),
    )]);
    let d = r.err().unwrap();
    let text = d[0].render(&sources);
    assert!(
        text.starts_with(
            "m.st:5:6: error: type mismatch: value of type LREAL where INT is expected\n"
        ),
        "{text}"
    );
    assert!(
        text.contains("m.st:3:3: 'x' is declared as INT here"),
        "{text}"
    );
    assert!(
        text.contains("= note: IEC 61131-3 converts implicitly only to wider types"),
        "{text}"
    );
    assert!(plc::Code::TypeMismatch
        .explanation()
        .contains("DINT_TO_INT"));
}

#[test]
fn unused_variables_are_warnings() {
    let (sources, r) = plc::build(&[(
        "w.st".into(),
        "PROGRAM Main\nVAR used : INT; spare : BOOL; _kept : INT; END_VAR\nused := 1;\nEND_PROGRAM\n".into(),
    )]);
    let c = r.unwrap();
    let w: Vec<String> = c
        .checked
        .warnings
        .iter()
        .map(|d| d.headline(&sources))
        .collect();
    assert_eq!(
        w,
        vec!["w.st:2:17: warning: variable 'spare' is declared but never used".to_string()]
    );
}

#[test]
fn download_keeps_persistent_values_and_tasks() {
    let mut p = plc(LIGHTS);
    p.add_task(TaskConfig::cyclic("main", 10_000_000, &["Main"]))
        .unwrap();
    for k in 0..4 {
        p.run_cycle(at_ms(k * 10));
    }
    p.write("Main.starts", "3").unwrap();
    assert_eq!(p.read_text("Main.total").unwrap(), "4");
    let changed = LIGHTS.replace("count := count + 1;", "count := count + 2;");
    let (sources, r) = plc::build(&[("t.st".to_string(), changed)]);
    assert_eq!(p.download(r.unwrap(), sources).unwrap(), 1);
    assert_eq!(
        p.read_text("Main.total").unwrap(),
        "4",
        "PERSISTENT carried over"
    );
    assert_eq!(
        p.read_text("Main.starts").unwrap(),
        "0",
        "RETAIN is not kept by a download"
    );
    p.run_cycle(at_ms(100));
    assert_eq!(p.read_text("Main.count").unwrap(), "2", "new code runs");
    assert_eq!(p.read_text("Main.total").unwrap(), "5");
}

/// The prelude is parsed once per process and only the POUs a program names are checked
/// and compiled (a small program — and every fuzz input — no longer pays for the whole
/// standard library); dependencies among prelude POUs are followed.
#[test]
fn only_the_named_prelude_pous_are_compiled() {
    let (_, r) = plc::build(&[(
        "a.st".into(),
        "PROGRAM Main VAR x : INT; END_VAR x := x + 1; END_PROGRAM".into(),
    )]);
    let c = r.unwrap();
    let stdlib_pous = c.checked.pous.iter().filter(|p| p.stdlib).count();
    assert_eq!(stdlib_pous, 0);
    // types and globals of the prelude are always there
    assert!(c.checked.global_index.contains_key("SYSTEM_S"));
    // a prelude POU and its prelude dependencies
    let (_, r) = plc::build(&[(
        "a.st".into(),
        "PROGRAM Main VAR t : ton; d : DTL; END_VAR d := DT_TO_DTL(DT#2024-01-01-00:00:00); END_PROGRAM"
            .into(),
    )]);
    let c = r.unwrap();
    let names: Vec<&str> = c
        .checked
        .pous
        .iter()
        .filter(|p| p.stdlib)
        .map(|p| p.name.as_str())
        .collect();
    assert_eq!(names, ["TON", "DT_TO_DTL"]);
    // redeclaring a standard FB is still reported as such
    let (sources, r) = plc::build(&[(
        "a.st".into(),
        "FUNCTION_BLOCK TON END_FUNCTION_BLOCK PROGRAM Main END_PROGRAM".into(),
    )]);
    let d = r.err().unwrap();
    assert!(d[0]
        .render(&sources)
        .contains("part of the standard library"));
}

/// The fused fast paths (array element compare/copy, constant divisors) keep the rules:
/// bounds faults with the index, wrapping index arithmetic, truncating division.
#[test]
fn fused_paths_keep_faults_and_semantics() {
    let src = "PROGRAM Main VAR a : ARRAY[1..5] OF DINT := [5, 4, 3, 2, 1]; j, t : DINT;
        m1, m2, d1, d2 : DINT; swapped : BOOL; END_VAR
        FOR j := 1 TO 4 DO
          IF a[j] > a[j + 1] THEN t := a[j]; a[j] := a[j + 1]; a[j + 1] := t; swapped := TRUE; END_IF
        END_FOR
        m1 := -7 MOD 3; m2 := t MOD -3; d1 := -7 / 2; d2 := a[1] / -2;
        IF a[1] = 4 THEN j := 5; t := a[j + 1]; END_IF
        END_PROGRAM";
    let mut p = plc(src);
    p.add_task(TaskConfig::cyclic("main", 0, &["Main"]))
        .unwrap();
    let faults = p.run_cycle(ClockReading::default());
    let read = |p: &Plc, path: &str| p.read_text(path).unwrap();
    assert_eq!(read(&p, "Main.a[1]"), "4");
    assert_eq!(read(&p, "Main.a[5]"), "5");
    assert_eq!(read(&p, "Main.m1"), "-1");
    assert_eq!(read(&p, "Main.m2"), "2");
    assert_eq!(read(&p, "Main.d1"), "-3");
    assert_eq!(read(&p, "Main.d2"), "-2");
    assert_eq!(faults.len(), 1);
    assert!(
        faults[0]
            .message
            .contains("array index 6 out of range 1..5"),
        "{}",
        faults[0].message
    );
}

#[test]
fn a_fault_while_setting_initial_values_is_reported() {
    let src = "PROGRAM Main
VAR n : INT; x : INT (0..10) := 20; END_VAR
n := n + 1;
END_PROGRAM
";
    let build = || plc::build(&[("t.st".to_string(), src.to_string())]);
    let (sources, r) = build();
    let err = Plc::try_new(r.unwrap(), sources).err().expect("init fault");
    let plc::PlcError::Init(d) = &err else {
        panic!("{err}")
    };
    assert_eq!(
        d.message,
        "initialisation stopped: value 20 outside the subrange 0..10 of 'Main.x'"
    );
    let mut p = plc(src);
    let d = p.init_fault().cloned().expect("kept");
    assert!(
        p.render(&d)
            .starts_with("t.st:2:33: error: initialisation stopped: value 20"),
        "{}",
        p.render(&d)
    );
    p.add_task(TaskConfig::cyclic("main", 10_000_000, &["Main"]))
        .unwrap();
    assert_eq!(p.task_state("main"), Some(&TaskState::Faulted(d.clone())));
    // reported once, by the first cycle; the program does not run
    assert_eq!(p.run_cycle(at_ms(0)), vec![d.clone()]);
    assert!(p.run_cycle(at_ms(10)).is_empty());
    assert_eq!(p.read_text("Main.n").unwrap(), "0");
    // a restart faults again
    assert!(p.cold_start().is_err());
    assert!(matches!(p.task_state("main"), Some(TaskState::Faulted(_))));
    // a program whose initial values are fine starts normally
    let (sources, r) = plc::build(&[("t.st".to_string(), LIGHTS.to_string())]);
    let p = Plc::try_new(r.unwrap(), sources).unwrap();
    assert!(p.init_fault().is_none());
}

#[test]
fn forcing_and_writing_by_direct_address() {
    let src = "
PROGRAM Main
VAR
    start AT %IX0.0 : BOOL;
    level AT %IW4 : WORD;
    lamp AT %QX1.3 : BOOL;
    out AT %QW2 : WORD;
    flag AT %MX10.1 : BOOL;
    seen : BOOL;
    mw : WORD;
    md : DWORD;
    n : INT;
END_VAR
n := n + 1;
lamp := FALSE;
out := 7;
seen := start AND flag;
flag := FALSE;
mw := %MW10;
md := %MD20;
%MD20 := 0;
END_PROGRAM
";
    let mut p = plc(src);
    p.add_task(TaskConfig::cyclic("main", 10_000_000, &["Main"]))
        .unwrap();
    p.force("%IX0.0", "TRUE").unwrap();
    p.force("%qx1.3", "TRUE").unwrap();
    p.force("%IW4", "16#BEEF").unwrap();
    p.force("%QW2", "500").unwrap();
    p.force("%MX10.1", "TRUE").unwrap();
    p.force("%MD20", "70000").unwrap();
    assert_eq!(
        p.forced(),
        vec!["%IW4", "%IX0.0", "%MD20", "%MX10.1", "%QW2", "%QX1.3"]
    );
    for k in 0..3 {
        p.set_io("%IX0.0", 0).unwrap(); // the field says FALSE; the force wins
        p.run_cycle(at_ms(10 * k));
        // inputs and markers: the program read the forced values
        assert_eq!(p.read_text("Main.start").unwrap(), "TRUE");
        assert_eq!(p.read_text("Main.level").unwrap(), "48879");
        assert_eq!(p.read_text("Main.seen").unwrap(), "TRUE");
        assert_eq!(p.read_text("Main.mw").unwrap(), "512"); // %MX10.1: bit 1 of %MB10, the high byte
        assert_eq!(p.read_text("Main.md").unwrap(), "70000");
        // outputs: the program wrote other values, the forced ones reach the image
        assert_eq!(p.get_io("%QX1.3").unwrap(), 1);
        assert_eq!(p.read_text("%QX1.3").unwrap(), "TRUE");
        assert_eq!(p.read_text("Main.lamp").unwrap(), "TRUE");
        assert_eq!(p.get_io("%QW2").unwrap(), 500);
        assert_eq!(p.read_text("Main.out").unwrap(), "500");
        assert_eq!(p.read_text("%MD20").unwrap(), "70000");
        assert_eq!(p.read_text("Main.flag").unwrap(), "TRUE");
    }
    assert!(p.release("%QX1.3"));
    assert!(p.release("%qw2"));
    assert!(!p.release("%QW2"));
    assert!(p.release("%IX0.0"));
    // the image keeps the forced value until the field writes the input again
    assert_eq!(p.get_io("%IX0.0").unwrap(), 1);
    p.set_io("%IX0.0", 0).unwrap();
    p.run_cycle(at_ms(30));
    assert_eq!(p.get_io("%QX1.3").unwrap(), 0);
    assert_eq!(p.get_io("%QW2").unwrap(), 7);
    assert_eq!(p.read_text("Main.start").unwrap(), "FALSE");
    assert_eq!(p.read_text("Main.level").unwrap(), "48879");
    assert_eq!(p.forced(), vec!["%IW4", "%MD20", "%MX10.1"]);
    // write once: until the program or the field changes it
    p.write("%IW4", "1").ok(); // forced: overwritten again by the force
    p.release("%IW4");
    p.write("%IW4", "16#12").unwrap();
    p.run_cycle(at_ms(40));
    assert_eq!(p.read_text("Main.level").unwrap(), "18");
    p.write("%QX1.3", "TRUE").unwrap();
    assert_eq!(p.read_text("Main.lamp").unwrap(), "TRUE");
    p.run_cycle(at_ms(50));
    assert_eq!(p.get_io("%QX1.3").unwrap(), 0, "the program overwrites it");
    // errors
    assert!(matches!(
        p.force("%ZX0.0", "TRUE"),
        Err(plc::PlcError::BadAddress(_))
    ));
    assert!(matches!(
        p.write("%QX1.9", "TRUE"),
        Err(plc::PlcError::BadAddress(_))
    ));
    assert!(matches!(
        p.force("%QW2", "70000"),
        Err(plc::PlcError::BadValue { .. })
    ));
    assert!(matches!(
        p.force("%QX1.3", "'on'"),
        Err(plc::PlcError::BadValue { .. })
    ));
}

#[test]
fn null_dereference_faults_at_its_position_both_ways() {
    let src = "PROGRAM Main
VAR r : REF_TO INT; x : INT; i : INT; END_VAR
r := REF(x);
FOR i := 1 TO 3 DO
    IF i = 2 THEN r := NULL; END_IF;
    x := x + r^;
END_FOR;
END_PROGRAM
";
    for jit in [false, true] {
        let files = [("t.st".to_string(), src.to_string())];
        let (sources, r) = plc::build_with(&files, plc::CompileOptions { jit });
        let mut p = Plc::new(r.unwrap(), sources);
        p.add_task(TaskConfig::cyclic("main", 10_000_000, &["Main"]))
            .unwrap();
        let f = p.run_cycle(at_ms(0));
        assert_eq!(f.len(), 1, "jit {jit}");
        let rendered = p.render(&f[0]);
        assert!(
            rendered.starts_with(
                "t.st:6:14: error: task 'main' stopped: dereference of a NULL reference"
            ),
            "jit {jit}: {rendered}"
        );
        assert_eq!(p.read_text("Main.r").unwrap(), "NULL");
        assert_eq!(p.read_text("Main.i").unwrap(), "2");
        // from outside a reference can only be cleared
        assert!(p.write("Main.r", "NULL").is_ok());
        assert!(p.write("Main.r", "5").is_err());
    }
}

#[test]
fn references_start_null_after_a_download_and_keep_their_target_over_a_warm_start() {
    let src = "PROGRAM Main
VAR PERSISTENT r : REF_TO INT; n : INT; END_VAR
VAR x : INT; END_VAR
IF r = NULL THEN r := REF(x); END_IF;
r^ := r^ + 1;
n := x;
END_PROGRAM
";
    let mut p = plc(src);
    p.add_task(TaskConfig::cyclic("main", 10_000_000, &["Main"]))
        .unwrap();
    p.run_cycle(at_ms(0));
    assert_ne!(p.read_text("Main.r").unwrap(), "NULL");
    p.warm_start().unwrap();
    assert_ne!(
        p.read_text("Main.r").unwrap(),
        "NULL",
        "same layout, same target"
    );
    // a variable in front of x moves it: the old address would now be another variable
    let moved = src.replace("VAR x : INT; END_VAR", "VAR y : INT; x : INT; END_VAR");
    let (sources, r) = plc::build(&[("t.st".to_string(), moved)]);
    assert_eq!(
        p.download(r.unwrap(), sources).unwrap(),
        1,
        "only n is carried"
    );
    assert_eq!(p.read_text("Main.r").unwrap(), "NULL");
    p.run_cycle(at_ms(10));
    assert_eq!(p.read_text("Main.x").unwrap(), "1");
    assert_eq!(p.read_text("Main.y").unwrap(), "0");
}

/// Every prelude POU is checked and compiled when named, under the checker's current rules.
#[test]
fn every_prelude_pou_compiles() {
    let names: Vec<String> = plc::stdlib::PRELUDE
        .lines()
        .filter_map(|l| {
            let rest = l
                .strip_prefix("FUNCTION_BLOCK ")
                .or_else(|| l.strip_prefix("FUNCTION "))?;
            Some(rest.split([' ', ':']).next()?.to_string())
        })
        .collect();
    assert!(names.len() > 30, "{names:?}");
    // named as enumeration values: the prelude is included by the names a program uses
    let src = format!(
        "TYPE Named : ({}); END_TYPE\nPROGRAM Main\nVAR x : Named; END_VAR\nEND_PROGRAM\n",
        names.join(", ")
    );
    let (_, compiled) = crate::support::build_one("t.st", &src);
    for n in &names {
        assert!(
            compiled.checked.pou_index.contains_key(n.as_str()),
            "{n} not compiled"
        );
    }
}
