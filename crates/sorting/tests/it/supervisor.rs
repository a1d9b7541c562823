//! The sorting lab's supervisor blocks (examples/sorting-lab/plc/supervisor.st) against
//! every row of the state tables of the sorting-lab thesis, section 5, on the soft
//! PLC's virtual clock (10-ms scans), and a property: no sequence of student commands
//! keeps a gate on past MaxOnTime or drives two opposed solenoids at once.

use std::path::Path;

use plc::task::{ClockReading, TaskConfig};
use plc::Plc;
use proptest::prelude::*;

const BENCH: &str = "
PROGRAM Bench
VAR
    cmd : BOOL;
    edge : BOOL;
    cmd4 : BOOL;
    cmd5 : BOOL;
    light_cmd : BOOL;
    gate : SingleControl;
    s4 : MultipleControl;
    s5 : MultipleControl;
    light : LightControl;
END_VAR
gate(Command := cmd, MaxOnTime := T#2S, SafetyTime := T#2S, PenaltyTime := T#20S, EdgeRestart := edge);
s4(Command := cmd4, Partner := s5.Output, WorkingTime := T#1S, SafetyTime := T#3S);
s5(Command := cmd5, Partner := s4.Output, WorkingTime := T#1S, SafetyTime := T#3S);
light(Command := light_cmd);
END_PROGRAM
";

const SCAN_MS: i64 = 10;

/// The bench on a PLC, scanned every 10 ms of virtual time.
struct Bench {
    plc: Plc,
    /// Scans run.
    scans: i64,
}

impl Bench {
    fn new() -> Bench {
        let supervisor = std::fs::read_to_string(
            Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../../examples/sorting-lab/plc/supervisor.st"),
        )
        .unwrap();
        let (sources, result) = plc::build(&[
            ("supervisor.st".to_owned(), supervisor),
            ("bench.st".to_owned(), BENCH.to_owned()),
        ]);
        let compiled = result.unwrap_or_else(|d| {
            panic!(
                "{:?}",
                d.iter().map(|d| d.render(&sources)).collect::<Vec<_>>()
            )
        });
        let mut plc = Plc::new(compiled, sources);
        plc.add_task(TaskConfig::cyclic("main", SCAN_MS * 1_000_000, &["Bench"]))
            .unwrap();
        Bench { plc, scans: 0 }
    }

    fn set(&mut self, name: &str, on: bool) {
        self.plc
            .write(&format!("Bench.{name}"), if on { "TRUE" } else { "FALSE" })
            .unwrap();
    }

    fn scan(&mut self) {
        let t = self.scans * SCAN_MS * 1_000_000;
        let faults = self.plc.run_cycle(ClockReading {
            monotonic_ns: t,
            utc_ns: t,
            utc_offset_ns: 0,
        });
        assert!(faults.is_empty());
        self.scans += 1;
    }

    /// Runs `ms` of scans.
    fn run(&mut self, ms: i64) {
        for _ in 0..ms / SCAN_MS {
            self.scan();
        }
    }

    fn int(&self, path: &str) -> i64 {
        self.plc
            .read_text(&format!("Bench.{path}"))
            .unwrap()
            .parse()
            .unwrap()
    }

    fn bool(&self, path: &str) -> bool {
        self.plc.read_text(&format!("Bench.{path}")).unwrap() == "TRUE"
    }

    fn state(&self, block: &str) -> i64 {
        self.int(&format!("{block}.State"))
    }
}

const READY: i64 = 0;
const ON: i64 = 1;
const SAFETY: i64 = 2;
const PENALTY: i64 = 3;

#[test]
fn single_control_rows() {
    let mut b = Bench::new();
    b.scan();
    assert_eq!((b.state("gate"), b.bool("gate.Output")), (READY, false));
    // READY, input 1 -> ON, output on in the same scan
    b.set("cmd", true);
    b.scan();
    assert_eq!((b.state("gate"), b.bool("gate.Output")), (ON, true));
    // ON, input 0 before MaxOnTime -> SAFETY
    b.run(1000);
    b.set("cmd", false);
    b.scan();
    assert_eq!((b.state("gate"), b.bool("gate.Output")), (SAFETY, false));
    // SAFETY, Safety Time (2 s) elapsed -> READY
    b.run(1990);
    assert_eq!(b.state("gate"), SAFETY);
    b.run(20);
    assert_eq!(b.state("gate"), READY);
    // SAFETY, input 1 (any scan) -> timer restarted; held high it stays at zero (BS-A2 level)
    b.set("cmd", true);
    b.scan();
    b.set("cmd", false);
    b.scan();
    assert_eq!(b.state("gate"), SAFETY);
    b.run(1500);
    b.set("cmd", true);
    b.scan();
    assert!(
        b.bool("gate.Refused"),
        "a command during the lock-out is refused"
    );
    b.run(5000);
    assert_eq!(
        (b.state("gate"), b.bool("gate.Output")),
        (SAFETY, false),
        "held high: the lock-out never ends"
    );
    b.set("cmd", false);
    b.run(1990);
    assert_eq!(
        b.state("gate"),
        SAFETY,
        "the whole Safety Time again after the release"
    );
    b.run(20);
    assert_eq!(b.state("gate"), READY);
    // ON, on-time >= MaxOnTime -> PENALTY, output forced 0 regardless of the input
    b.set("cmd", true);
    b.scan();
    assert_eq!(b.state("gate"), ON);
    let on_at = b.scans;
    while b.bool("gate.Output") {
        b.scan();
        assert!(b.scans - on_at <= 201, "still on after MaxOnTime");
    }
    assert_eq!(b.state("gate"), PENALTY);
    assert!(b.bool("gate.LockedOut"));
    assert_eq!(
        (b.scans - on_at) * SCAN_MS,
        2000,
        "off exactly at MaxOnTime"
    );
    // PENALTY, input 1 (still held) -> restarted: it lasts until 20 s after the release
    b.run(30_000);
    assert_eq!(b.state("gate"), PENALTY);
    b.set("cmd", false);
    b.run(19_990);
    assert_eq!(b.state("gate"), PENALTY);
    b.run(20);
    assert_eq!(b.state("gate"), READY);
}

#[test]
fn single_control_edge_option_restarts_only_on_a_rising_edge() {
    let mut b = Bench::new();
    b.set("edge", true);
    b.set("cmd", true);
    b.run(500);
    b.set("cmd", false);
    b.scan();
    assert_eq!(b.state("gate"), SAFETY);
    // held high from here: only the edge restarts the 2 s
    b.set("cmd", true);
    b.run(1990);
    assert_eq!(b.state("gate"), SAFETY);
    b.run(20);
    assert_eq!(b.state("gate"), READY);
    // READY with the command already high: level-controlled, so it switches on
    b.scan();
    assert_eq!(b.state("gate"), ON);
}

#[test]
fn multiple_control_rows() {
    let mut b = Bench::new();
    b.scan();
    // READY, rising edge and partner off -> WORKING for exactly the Working Time
    b.set("cmd4", true);
    b.scan();
    assert_eq!((b.state("s4"), b.bool("s4.Output")), (ON, true));
    let started = b.scans;
    // READY, rising edge and partner on -> READY, edge discarded
    b.set("cmd5", true);
    b.scan();
    assert_eq!((b.state("s5"), b.bool("s5.Output")), (READY, false));
    assert!(b.bool("s5.Refused"));
    // WORKING, further edges ignored
    b.set("cmd4", false);
    b.scan();
    b.set("cmd4", true);
    b.scan();
    assert_eq!(b.state("s4"), ON);
    while b.bool("s4.Output") {
        b.scan();
    }
    assert_eq!(
        (b.scans - started) * SCAN_MS,
        1000,
        "on for the Working Time"
    );
    // WORKING, Working Time elapsed -> SAFETY
    assert_eq!(b.state("s4"), SAFETY);
    // SAFETY, rising edge -> restarted
    b.run(2000);
    b.set("cmd4", false);
    b.scan();
    b.set("cmd4", true);
    b.scan();
    assert!(b.bool("s4.Refused"));
    b.run(2980);
    assert_eq!(b.state("s4"), SAFETY);
    // SAFETY, Safety Time elapsed -> READY
    b.run(20);
    assert_eq!(b.state("s4"), READY);
    // and a new edge with the partner off works again
    b.set("cmd5", false);
    b.scan();
    b.set("cmd5", true);
    b.scan();
    assert_eq!(b.state("s5"), ON);
}

#[test]
fn two_opposed_edges_in_one_scan_move_one_solenoid() {
    let mut b = Bench::new();
    b.scan();
    b.set("cmd4", true);
    b.set("cmd5", true);
    b.scan();
    assert!(b.bool("s4.Output") != b.bool("s5.Output"));
}

#[test]
fn the_light_stays_on_55_minutes_and_ignores_edges_while_lit() {
    let mut b = Bench::new();
    b.set("light_cmd", true);
    b.scan();
    assert!(b.bool("light.Output"));
    b.set("light_cmd", false);
    b.run(60_000);
    b.set("light_cmd", true);
    b.scan();
    b.set("light_cmd", false);
    b.run(3_300_000 - 60_000 - 30);
    assert!(
        b.bool("light.Output"),
        "the edge while lit did not retrigger nor end it"
    );
    b.run(30);
    assert!(!b.bool("light.Output"));
    b.set("light_cmd", true);
    b.scan();
    assert!(b.bool("light.Output"), "a new edge switches it on again");
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn no_command_sequence_keeps_a_gate_on_or_pulls_both_solenoids(
        steps in prop::collection::vec((0u8..8, 1i64..300), 1..60),
    ) {
        let mut b = Bench::new();
        let mut on_since: Option<i64> = None;
        for (bits, scans) in steps {
            b.set("cmd", bits & 1 != 0);
            b.set("cmd4", bits & 2 != 0);
            b.set("cmd5", bits & 4 != 0);
            for _ in 0..scans {
                b.scan();
                let gate = b.bool("gate.Output");
                match (gate, on_since) {
                    (true, None) => on_since = Some(b.scans),
                    (false, _) => on_since = None,
                    _ => {}
                }
                if let Some(since) = on_since {
                    prop_assert!((b.scans - since) * SCAN_MS < 2000, "the gate on past MaxOnTime");
                }
                prop_assert!(!(b.bool("s4.Output") && b.bool("s5.Output")), "both solenoids pulled");
            }
        }
    }
}
