//! The sorting lab on the simulated clock: the reference sorting program behind the
//! supervisor, driving the mechanism (`sorting::rig`).

use std::time::Duration;

use lab::program::Program;
use plant::sorter::{Place, SorterConfig};
use plant::Plant;
use sorting::rig::{Rig, RigSettings, SupervisorAction};

fn supervisor() -> Program {
    sorting::programs::supervisor().unwrap()
}

fn reference_sorter() -> Program {
    sorting::programs::reference_sorter().unwrap()
}

fn rig(seed: u64) -> Rig {
    Rig::new(
        reference_sorter(),
        supervisor(),
        RigSettings {
            mechanism: SorterConfig {
                seed,
                ..SorterConfig::default()
            },
            ..RigSettings::default()
        },
    )
    .unwrap()
}

#[test]
fn the_reference_program_sorts_the_eight_balls_by_colour_without_a_single_refusal() {
    let mut rig = rig(1);
    let outcome = rig
        .automatic_sorting([1, 2, 3, 4], Duration::from_secs(600))
        .unwrap();
    assert!(outcome.finished, "{outcome:?}");
    assert!(outcome.events.is_empty(), "{:?}", outcome.events);
    for (ball, shaft) in &outcome.shafts {
        let colour = ["red", "yellow", "blue", "green"]
            .iter()
            .position(|c| ball.starts_with(c))
            .unwrap();
        assert_eq!(usize::from(*shaft), colour + 1, "{outcome:?}");
    }
    // Initialisation (2.8 + 2 + 4 + 30 s) and eight balls of about 7.4 s, and a last
    // round that finds the pan empty.
    let took = outcome.took.as_secs_f64();
    assert!((90.0..130.0).contains(&took), "{took} s");
    assert_eq!(rig.value("Sorted"), 8.0, "balls sorted");
    assert_eq!(
        [1, 2, 3, 4].map(|k| rig.value(&format!("Shaft{k}"))),
        [2.0; 4],
        "balls counted per shaft"
    );
    assert_eq!(rig.value("StateOut"), 0.0, "idle again");

    // Another colour assignment: the next sorting starts without blowing (the balls
    // are in the shafts, so the program initialises again only when told).
    rig.set("InitCmd", "TRUE").unwrap();
    let initialised = rig
        .run_until(Duration::from_secs(60), |rig| {
            rig.plant().upper().len() == 8 && rig.value("StateOut") == 0.0
        })
        .unwrap();
    assert!(initialised);
    let outcome = rig
        .automatic_sorting([4, 3, 2, 1], Duration::from_secs(600))
        .unwrap();
    assert!(outcome.finished);
    for (ball, shaft) in &outcome.shafts {
        let colour = ["green", "blue", "yellow", "red"]
            .iter()
            .position(|c| ball.starts_with(c))
            .unwrap();
        assert_eq!(usize::from(*shaft), colour + 1, "{outcome:?}");
    }
}

/// A student's program that holds gate S1 open and pulls both solenoids of deflector 1.
const ABUSIVE: &str = "
PROGRAM Abuse
VAR
    cS1 AT %QX0.0 : BOOL;
    cS4 AT %QX0.3 : BOOL;
    cS5 AT %QX0.4 : BOOL;
    t : TON;
END_VAR
    t(IN := TRUE, PT := T#1H);
    cS1 := t.ET < T#5S;
    cS4 := t.ET >= T#6S;
    cS5 := t.ET >= T#6S;
END_PROGRAM
";

#[test]
fn the_supervisor_stands_between_a_student_program_and_the_actuators() {
    let abusive = Program::compile(&[("abuse.st".to_owned(), ABUSIVE.to_owned())], None).unwrap();
    let mut rig = Rig::new(abusive, supervisor(), RigSettings::default()).unwrap();
    rig.run_until(Duration::from_secs(10), |_| false).unwrap();
    // S1 was cut off at its MaxOnTime of 2 s: one ball passed, the gate is locked out.
    let events = rig.events();
    let lock_out = events
        .iter()
        .find(|e| e.actuator == "S1" && e.action == SupervisorAction::LockedOut)
        .unwrap_or_else(|| panic!("{events:?}"));
    let at = lock_out.at.as_secs_f64();
    assert!((2.0..2.1).contains(&at), "{at}");
    assert!(lock_out.rule.contains("MaxOnTime"));
    assert_eq!(rig.actuator_state(0), 3, "S1 in PENALTY");
    assert!(!rig.plant().bool("S1").unwrap());
    assert_eq!(rig.plant().balls_at(Place::BeforeS2).len(), 1);
    // S4 and S5 rose together: S4 moved, S5's edge was discarded.
    let partner = events
        .iter()
        .find(|e| e.actuator == "S5" && e.action == SupervisorAction::Refused)
        .unwrap_or_else(|| panic!("{events:?}"));
    assert!(partner.rule.contains("opposed"), "{}", partner.rule);
    assert_eq!(rig.plant().deflector_extended(1), Some(true));
}

/// A pulse of 20 ms (two scans of the sorting PLC) falls between the supervisor's
/// 30-ms scans and is lost, as section 4.5 warns; 100 ms always arrives.
#[test]
fn a_pulse_shorter_than_two_supervisor_scans_can_be_lost() {
    let pulses = |on_ms: u32| {
        format!(
            "PROGRAM Pulses
VAR
    cS8 AT %QX0.7 : BOOL;
    cS9 AT %QX1.0 : BOOL;
    t : TON;
END_VAR
    t(IN := TRUE, PT := T#1H);
    (* S8 then S9, 4 s apart (over the 3-s safety time), pulses of {on_ms} ms from 5 ms into a
       10-ms scan grid offset against the supervisor's 30-ms one *)
    cS8 := (t.ET >= T#10MS AND t.ET < T#{}MS) OR (t.ET >= T#8010MS AND t.ET < T#{}MS);
    cS9 := t.ET >= T#4010MS AND t.ET < T#{}MS;
END_PROGRAM",
            10 + on_ms,
            8010 + on_ms,
            4010 + on_ms
        )
    };
    let run = |on_ms: u32, for_ms: u64| {
        let program = Program::compile(&[("pulses.st".to_owned(), pulses(on_ms))], None).unwrap();
        let mut rig = Rig::new(program, supervisor(), RigSettings::default()).unwrap();
        let before = rig.plant().deflector_extended(3);
        rig.run_until(Duration::from_millis(for_ms), |_| false)
            .unwrap();
        (before, rig)
    };
    // 100 ms: S8, S9, S8 all carried out; the deflector ends extended.
    let (_, rig) = run(100, 12_000);
    assert_eq!(rig.plant().deflector_extended(3), Some(true));
    assert!(rig.events().is_empty(), "{:?}", rig.events());
    // 20 ms at 10 ms..30 ms: the supervisor scans at 0 and 30 ms and never sees it.
    let (before, rig) = run(20, 2000);
    assert_eq!(
        rig.plant().deflector_extended(3),
        before,
        "the 20-ms pulse was lost"
    );
    assert_eq!(rig.actuator_state(7), 0, "S8 never worked");
}

#[test]
fn fifty_seeded_sortings_beat_the_theses_ninety_percent() {
    let build = || Ok((reference_sorter(), supervisor()));
    let report = sorting::rig::mechanism_reliability(50, 100, build).unwrap();
    assert_eq!(report.unfinished, 0);
    assert_eq!(report.supervisor_events, 0);
    assert_eq!(report.confusion.total(), 400);
    assert!(
        report.confusion.reliability() > 0.95,
        "{}",
        report.confusion.table()
    );
}

#[test]
fn the_program_sorts_on_through_the_faults_of_section_13() {
    // The balance's light barrier misses every ball: the weight alone carries the loop.
    let mut blind = rig(3);
    blind.plant_mut().console("miss Sn5").unwrap();
    let outcome = blind
        .automatic_sorting([1, 2, 3, 4], Duration::from_secs(600))
        .unwrap();
    assert!(outcome.finished);
    assert_eq!(
        outcome
            .shafts
            .iter()
            .filter(|(_, shaft)| *shaft != 0)
            .count(),
        8
    );

    // Two balls dosed at once weigh more than any colour: FC1 gives 0 and the pair
    // goes to shaft 4; every other ball is sorted.
    let mut doubled = rig(4);
    doubled.plant_mut().console("double-dose").unwrap();
    let outcome = doubled
        .automatic_sorting([1, 2, 3, 4], Duration::from_secs(600))
        .unwrap();
    assert!(outcome.finished);
    let in_shaft_4 = outcome
        .shafts
        .iter()
        .filter(|(_, shaft)| *shaft == 4)
        .count();
    assert!(in_shaft_4 >= 3, "{outcome:?}");
    assert_eq!(
        outcome
            .shafts
            .iter()
            .filter(|(_, shaft)| *shaft != 0)
            .count(),
        8
    );

    // Lost pulses to every deflector solenoid: the program sees that the supervisor's
    // output never came on, waits out the safety time and moves the deflector again.
    let mut lossy = rig(5);
    for solenoid in ["S4", "S5", "S6", "S7", "S8", "S9"] {
        lossy.lose_next_pulse(solenoid).unwrap();
    }
    let outcome = lossy
        .automatic_sorting([1, 2, 3, 4], Duration::from_secs(600))
        .unwrap();
    assert!(outcome.finished);
    let right = outcome
        .shafts
        .iter()
        .filter(|(ball, shaft)| {
            let colour = ["red", "yellow", "blue", "green"]
                .iter()
                .position(|c| ball.starts_with(c))
                .unwrap();
            usize::from(*shaft) == colour + 1
        })
        .count();
    assert_eq!(right, 8, "{outcome:?}");
    assert!(
        outcome.events.is_empty(),
        "the retry waits out the safety time"
    );
}
