//! Safe stop: a fault, the watchdog or a PLC STOP puts the outputs a task drives to their
//! safe values, the other tasks keep running, and each stop is an event.

use plc::task::{ClockReading, StopCause, Stopwatch, TaskConfig, TaskState, TaskStopped};
use plc::{Code, Plc};
use std::cell::Cell;
use std::rc::Rc;

fn plc(src: &str) -> Plc {
    crate::support::plc_of("s.st", src)
}

fn at_ms(ms: i64) -> ClockReading {
    ClockReading {
        monotonic_ns: ms * 1_000_000,
        ..ClockReading::default()
    }
}

fn events(p: &mut Plc) -> Vec<TaskStopped> {
    std::iter::from_fn(|| p.poll_event()).collect()
}

/// Two programs, each with an output bit, a word and a host-bound variable; `Bad` also
/// drives the global `alarm_lamp` and, once `trip` is TRUE, faults with `fault`.
fn two_tasks(fault: &str) -> String {
    format!(
        "
VAR_GLOBAL
    alarm_lamp AT %QX2.0 : BOOL;
    shared AT %QX2.1 : BOOL;
END_VAR
PROGRAM Bad
VAR
    trip : BOOL;
    motor AT %QX0.0 : BOOL;
    speed AT %QW4 : INT;
    valve : BOOL;
    z : INT;
    k : INT := 7;
    i : INT;
    a : ARRAY[1..3] OF INT;
    r : REF_TO INT;
    x : INT;
END_VAR
motor := TRUE;
speed := 1500;
valve := TRUE;
alarm_lamp := TRUE;
IF trip THEN
    {fault}
END_IF
END_PROGRAM
PROGRAM Good
VAR
    n : INT;
    pump AT %QX1.0 : BOOL;
END_VAR
n := n + 1;
pump := TRUE;
shared := TRUE;
END_PROGRAM
"
    )
}

const FAULTS: &[(&str, &str, &str)] = &[
    ("x := 100 / z;", "division by zero", "s.st:24:10"),
    (
        "FOR i := 1 TO k DO a[i] := i; END_FOR",
        "array index 4 out of range 1..3",
        "s.st:24:26",
    ),
    ("x := r^;", "dereference of a NULL reference", "s.st:24:10"),
];

#[test]
fn a_faulted_task_stops_alone_and_its_outputs_go_safe() {
    for (fault, message, position) in FAULTS {
        let mut p = plc(&two_tasks(fault));
        p.add_task(TaskConfig::cyclic("bad", 10_000_000, &["Bad"]))
            .unwrap();
        p.add_task(TaskConfig::cyclic("good", 10_000_000, &["Good"]))
            .unwrap();
        p.bind_output("Bad.valve").unwrap();
        p.bind_output("Good.n").unwrap();
        assert!(p.run_cycle(at_ms(0)).is_empty());
        assert!(events(&mut p).is_empty());
        for out in ["%QX0.0", "%QX1.0", "%QX2.0", "%QX2.1"] {
            assert_eq!(p.get_io(out).unwrap(), 1, "{out}");
        }
        assert_eq!(p.get_io("%QW4").unwrap(), 1500);

        p.write("Bad.trip", "TRUE").unwrap();
        let faults = p.run_cycle(at_ms(10));
        assert_eq!(faults.len(), 1, "{fault}");
        assert!(matches!(p.task_state("bad"), Some(TaskState::Faulted(_))));
        assert_eq!(p.task_state("good"), Some(&TaskState::Running));
        // the outputs of the faulted task: safe (image and variables)
        assert_eq!(p.get_io("%QX0.0").unwrap(), 0, "{fault}");
        assert_eq!(p.get_io("%QW4").unwrap(), 0, "{fault}");
        assert_eq!(p.get_io("%QX2.0").unwrap(), 0, "global it drives");
        assert_eq!(p.read_text("Bad.motor").unwrap(), "FALSE");
        assert_eq!(p.read_text("Bad.valve").unwrap(), "FALSE", "host-bound");
        // the other task's outputs are untouched
        assert_eq!(p.get_io("%QX1.0").unwrap(), 1);
        assert_eq!(p.get_io("%QX2.1").unwrap(), 1);
        assert_eq!(p.read_text("Good.n").unwrap(), "2");

        let ev = events(&mut p);
        assert_eq!(ev.len(), 1, "{ev:?}");
        assert_eq!(ev[0].task, "bad");
        assert_eq!(ev[0].at_ns, 10_000_000);
        let StopCause::Fault(d) = &ev[0].cause else {
            panic!("{:?}", ev[0].cause)
        };
        assert_eq!(d.code, Code::RuntimeFault);
        assert!(d.message.contains(message), "{}", d.message);
        assert_eq!(p.sources().location(d.primary), *position, "{fault}");
        let mut set = ev[0].outputs.clone();
        set.sort();
        assert_eq!(
            set,
            [
                ("%QW4", "0"),
                ("%QX0.0", "FALSE"),
                ("%QX2.0", "FALSE"),
                ("Bad.valve", "FALSE")
            ]
            .map(|(a, b)| (a.to_string(), b.to_string()))
        );

        // the good task keeps its schedule; the faulted one stays stopped and safe
        for k in 2..6 {
            assert!(p.run_cycle(at_ms(k * 10)).is_empty());
        }
        assert_eq!(p.read_text("Good.n").unwrap(), "6");
        assert_eq!(p.stats("bad").unwrap().cycles, 2);
        assert_eq!(p.get_io("%QX0.0").unwrap(), 0);
        assert_eq!(p.get_io("%QX2.0").unwrap(), 0);
        assert!(events(&mut p).is_empty());
    }
}

struct Scripted(Rc<Cell<i64>>);
impl Stopwatch for Scripted {
    fn start(&mut self) {}
    fn elapsed_ns(&mut self) -> i64 {
        self.0.get()
    }
}

#[test]
fn the_watchdog_stops_its_task_and_puts_its_outputs_safe() {
    let mut p = plc(&two_tasks("x := 1;"));
    let cost = Rc::new(Cell::new(1_000_000));
    p.set_stopwatch(Box::new(Scripted(cost.clone())));
    p.add_task(TaskConfig::cyclic("bad", 10_000_000, &["Bad"]).with_watchdog(5_000_000, 2))
        .unwrap();
    p.add_task(TaskConfig::cyclic("good", 10_000_000, &["Good"]))
        .unwrap();
    assert!(p.run_cycle(at_ms(0)).is_empty());
    // the stopwatch measures every task alike; only `bad` has a watchdog
    cost.set(9_000_000);
    assert!(p.run_cycle(at_ms(10)).is_empty());
    assert!(events(&mut p).is_empty(), "one overrun is tolerated");
    assert_eq!(p.get_io("%QX0.0").unwrap(), 1);
    let faults = p.run_cycle(at_ms(20));
    assert_eq!(faults.len(), 1);
    let ev = events(&mut p);
    assert_eq!(ev.len(), 1);
    assert_eq!(ev[0].task, "bad");
    let StopCause::Watchdog(d) = &ev[0].cause else {
        panic!("{:?}", ev[0].cause)
    };
    assert!(d.message.contains("watchdog"), "{}", d.message);
    assert_eq!(ev[0].cause.kind(), "watchdog");
    assert_eq!(p.get_io("%QX0.0").unwrap(), 0);
    assert_eq!(p.get_io("%QW4").unwrap(), 0);
    assert_eq!(p.get_io("%QX2.0").unwrap(), 0);
    // the other task runs on
    assert_eq!(p.get_io("%QX1.0").unwrap(), 1);
    p.run_cycle(at_ms(30));
    assert_eq!(p.read_text("Good.n").unwrap(), "4");
    assert_eq!(p.get_io("%QX0.0").unwrap(), 0);
    // a cold start restarts it
    p.cold_start().unwrap();
    assert_eq!(p.task_state("bad"), Some(&TaskState::Running));
}

#[test]
fn a_plc_stop_puts_every_output_safe_and_start_resumes() {
    let mut p = plc(&two_tasks("x := 1;"));
    p.add_task(TaskConfig::cyclic("bad", 10_000_000, &["Bad"]))
        .unwrap();
    p.add_task(TaskConfig::cyclic("good", 10_000_000, &["Good"]))
        .unwrap();
    p.bind_output("Good.n").unwrap();
    p.run_cycle(at_ms(0));
    p.run_cycle(at_ms(10));
    assert_eq!(p.read_text("Good.n").unwrap(), "2");
    p.stop(at_ms(15));
    assert_eq!(p.task_state("bad"), Some(&TaskState::Stopped));
    assert_eq!(p.task_state("good"), Some(&TaskState::Stopped));
    for out in ["%QX0.0", "%QX1.0", "%QX2.0", "%QX2.1", "%QW4"] {
        assert_eq!(p.get_io(out).unwrap(), 0, "{out}");
    }
    assert_eq!(p.read_text("Good.n").unwrap(), "0", "host-bound output");
    let ev = events(&mut p);
    let tasks: Vec<&str> = ev.iter().map(|e| e.task.as_str()).collect();
    assert_eq!(tasks, ["bad", "good"]);
    assert!(ev
        .iter()
        .all(|e| e.cause == StopCause::Stop && e.at_ns == 15_000_000));
    let good: Vec<&str> = ev[1].outputs.iter().map(|(o, _)| o.as_str()).collect();
    assert_eq!(good, ["%QX2.1", "%QX1.0", "Good.n"]);
    // stopped tasks do not run
    p.run_cycle(at_ms(20));
    assert_eq!(p.get_io("%QX1.0").unwrap(), 0);
    assert_eq!(p.next_due(), None);
    // a second stop records nothing
    p.stop(at_ms(25));
    assert!(events(&mut p).is_empty());
    p.start();
    p.run_cycle(at_ms(30));
    assert_eq!(p.get_io("%QX1.0").unwrap(), 1);
    assert_eq!(p.get_io("%QX0.0").unwrap(), 1);
    assert_eq!(p.read_text("Good.n").unwrap(), "1");
}

const DECLARED: &str = "
VAR_GLOBAL
    {attribute 'safe_value' := 'TRUE'}
    brake_n AT %QX3.0 : BOOL;
END_VAR
PROGRAM Main
VAR
    trip : BOOL;
    z : INT;
    x : INT;
    {attribute 'safe_value' := '-1'}
    {attribute 'hide'}
    speed AT %QW4 : INT;
    lamp AT %QX0.0 : BOOL;
    {attribute 'safe_value' := 'TRUE'} door AT %QX0.1 : BOOL;
    flap1, {attribute 'safe_value' := 'TRUE'} flap2 : BOOL;
    {attribute 'safe_value' := 'TRUE'}
    vent1, vent2 : BOOL;
    (* not an output: no safe value applies *)
    {attribute 'safe_value' := 'TRUE'}
    memo : BOOL;
    {attribute 'safe_value' := '2.5'}
    setpoint : REAL;
    {attribute 'safe_value' := 'T#3s'}
    delay : TIME;
END_VAR
brake_n := FALSE;
speed := 1200;
lamp := TRUE;
door := FALSE;
flap1 := TRUE; flap2 := FALSE; vent1 := FALSE; vent2 := FALSE;
memo := FALSE;
setpoint := 7.0;
delay := T#1s;
IF trip THEN x := 1 / z; END_IF
END_PROGRAM
";

#[test]
fn declared_safe_values_override_the_default() {
    let mut p = plc(DECLARED);
    p.add_task(TaskConfig::cyclic("main", 10_000_000, &["Main"]))
        .unwrap();
    p.bind_output("Main.setpoint").unwrap();
    p.bind_output("Main.delay").unwrap();
    for v in ["flap1", "flap2", "vent1", "vent2"] {
        p.bind_output(&format!("Main.{v}")).unwrap();
    }
    p.run_cycle(at_ms(0));
    assert_eq!(p.get_io("%QX3.0").unwrap(), 0);
    assert_eq!(p.get_io("%QW4").unwrap(), 1200);
    p.write("Main.trip", "TRUE").unwrap();
    assert_eq!(p.run_cycle(at_ms(10)).len(), 1);
    assert_eq!(p.get_io("%QX3.0").unwrap(), 1, "declared TRUE");
    assert_eq!(p.read_text("brake_n").unwrap(), "TRUE");
    assert_eq!(p.read_text("Main.speed").unwrap(), "-1");
    assert_eq!(p.get_io("%QW4").unwrap(), 0xFFFF);
    assert_eq!(p.get_io("%QX0.0").unwrap(), 0, "default");
    assert_eq!(p.get_io("%QX0.1").unwrap(), 1, "pragma on the same line");
    // before one name of `a, b`: that name; before the declaration: every name
    assert_eq!(p.read_text("Main.flap1").unwrap(), "FALSE");
    assert_eq!(p.read_text("Main.flap2").unwrap(), "TRUE");
    assert_eq!(p.read_text("Main.vent1").unwrap(), "TRUE");
    assert_eq!(p.read_text("Main.vent2").unwrap(), "TRUE");
    assert_eq!(p.read_text("Main.setpoint").unwrap(), "2.5");
    assert_eq!(p.read_text("Main.delay").unwrap(), "T#3s");
    assert_eq!(p.read_text("Main.memo").unwrap(), "FALSE", "not an output");
    let ev = events(&mut p);
    assert_eq!(ev.len(), 1);
    let mut set = ev[0].outputs.clone();
    set.sort();
    let want = [
        ("%QW4", "-1"),
        ("%QX0.0", "FALSE"),
        ("%QX0.1", "TRUE"),
        ("%QX3.0", "TRUE"),
        ("Main.delay", "T#3s"),
        ("Main.flap1", "FALSE"),
        ("Main.flap2", "TRUE"),
        ("Main.setpoint", "2.5"),
        ("Main.vent1", "TRUE"),
        ("Main.vent2", "TRUE"),
    ]
    .map(|(a, b)| (a.to_string(), b.to_string()));
    assert_eq!(set, want);
}

#[test]
fn a_safe_value_that_does_not_fit_stops_the_plc_at_the_pragma() {
    let src = "PROGRAM Main\nVAR\n  {attribute 'safe_value' := '70000'}\n  speed AT %QW4 : INT;\nEND_VAR\nspeed := 1;\nEND_PROGRAM\n";
    let (sources, r) = plc::build(&[("bad.st".to_string(), src.to_string())]);
    let compiled = r.unwrap();
    let Err(plc::PlcError::Init(d)) = Plc::try_new(compiled, sources.clone()) else {
        panic!("a bad safe value is accepted")
    };
    assert_eq!(d.code, Code::BadLiteral);
    assert_eq!(sources.location(d.primary), "bad.st:3:3");
    assert!(d.message.contains("'70000'"), "{}", d.message);
    // host-bound: refused when bound
    let src = "PROGRAM Main\nVAR\n  {attribute 'safe_value' := 'maybe'}\n  on : BOOL;\nEND_VAR\non := TRUE;\nEND_PROGRAM\n";
    let mut p = plc(src);
    assert!(matches!(
        p.bind_output("Main.on"),
        Err(plc::PlcError::Init(d)) if d.code == Code::BadLiteral
    ));
}

#[test]
fn forced_outputs_stay_forced_and_bound_outputs_survive_a_download() {
    let src = two_tasks("x := 100 / z;");
    let mut p = plc(&src);
    p.add_task(TaskConfig::cyclic("bad", 10_000_000, &["Bad"]))
        .unwrap();
    p.bind_output("Bad.valve").unwrap();
    p.force("%QX0.0", "TRUE").unwrap();
    p.run_cycle(at_ms(0));
    p.write("Bad.trip", "TRUE").unwrap();
    assert_eq!(p.run_cycle(at_ms(10)).len(), 1);
    assert_eq!(
        p.get_io("%QX0.0").unwrap(),
        1,
        "a forced output stays forced"
    );
    assert_eq!(p.get_io("%QW4").unwrap(), 0);
    assert_eq!(events(&mut p).len(), 1);

    // a new build of the same program: the host binding is kept
    let (sources, r) = plc::build(&[("s.st".to_string(), src.clone())]);
    p.download(r.unwrap(), sources).unwrap();
    p.run_cycle(at_ms(20));
    assert_eq!(p.read_text("Bad.valve").unwrap(), "TRUE");
    p.write("Bad.trip", "TRUE").unwrap();
    assert_eq!(p.run_cycle(at_ms(30)).len(), 1);
    assert_eq!(p.read_text("Bad.valve").unwrap(), "FALSE");
    let ev = events(&mut p);
    assert_eq!(ev.len(), 1);
    assert!(
        ev[0].outputs.iter().any(|(o, _)| o == "Bad.valve"),
        "{ev:?}"
    );
}
