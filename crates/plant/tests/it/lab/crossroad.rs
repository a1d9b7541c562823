//! The crossroad (section 4): the lights follow the outputs; conflicting greens are
//! recorded (ERR stays dark); the example task of section 4.3 never conflicts.

use plant::lab::{ErrLed, ErrorKind};
use plant::Direction;

use super::{assert_no_error, at, get, kinds, model, ms, run, s, set, Model};

const LIGHTS: [&str; 8] = [
    "cerv_spodek",
    "oran_spodek",
    "zel_spodek",
    "cerv_vrch",
    "oran_vrch",
    "zel_vrch",
    "cerv_chodci",
    "zel_chodci",
];

#[test]
fn surface_and_lights_follow_the_outputs() {
    let mut m = model("crossroad", &[]);
    assert_eq!(m.model(), "crossroad");
    let outputs: Vec<&str> = m
        .signals()
        .iter()
        .filter(|s| s.direction == Direction::Output)
        .map(|s| s.name.as_str())
        .collect();
    assert_eq!(&outputs[..8], LIGHTS);
    assert_eq!(outputs[8], "RESET");
    let inputs: Vec<&str> = m
        .signals()
        .iter()
        .filter(|s| s.direction == Direction::Input)
        .map(|s| s.name.as_str())
        .collect();
    assert_eq!(inputs, ["tlacitko_chodci", "START", "ERR"]);
    assert_eq!(m.modules().len(), 1);
    assert_eq!(m.modules()[0].name, "crossroad");
    for light in LIGHTS {
        set(&mut m, light, true);
        assert!(get(&m, light));
        let t = m.now() + ms(100);
        at(&mut m, t);
        set(&mut m, light, false);
        assert!(!get(&m, light));
    }
    m.console("press tlacitko_chodci").unwrap();
    assert!(get(&m, "tlacitko_chodci"));
    m.console("release tlacitko_chodci").unwrap();
    assert!(!get(&m, "tlacitko_chodci"));
    assert_no_error(&m);
    // Only ERR and err_lit in the state.
    let keys: Vec<&str> = m.state().iter().map(|(k, _)| *k).collect();
    assert_eq!(keys, ["err", "err_lit"]);
}

#[test]
fn conflicting_greens_are_recorded_but_err_stays_dark() {
    let mut m = model("crossroad", &[]);
    set(&mut m, "zel_spodek", true);
    at(&mut m, s(2));
    set(&mut m, "zel_vrch", true);
    assert_eq!(kinds(&m), [(ErrorKind::ConflictingGreens, true, false)]);
    assert_eq!(m.errors()[0].time, s(2));
    assert_eq!(m.errors()[0].detail, "zel_spodek with zel_vrch");
    assert_eq!(m.err_led(), ErrLed::Off);
    assert!(!get(&m, "ERR"));
    at(&mut m, s(3));
    set(&mut m, "zel_vrch", false);
    assert_eq!(m.errors()[0].cleared, Some(s(3)));
    // The pedestrians' green conflicts too.
    at(&mut m, s(4));
    set(&mut m, "zel_chodci", true);
    assert_eq!(m.errors().len(), 2);
    assert_eq!(m.errors()[1].detail, "zel_spodek with zel_chodci");
    set(&mut m, "zel_spodek", false);
    // Cleared at the instant it began: two writes in one scan are no conflict.
    assert_eq!(m.errors().len(), 1);
    // Upper and pedestrian green together are no conflict of this kind.
    set(&mut m, "zel_vrch", true);
    assert_eq!(m.errors().len(), 1);
    m.reset();
    assert!(m.errors().is_empty());
}

#[test]
fn a_broken_lamp_does_not_hide_a_conflict() {
    let mut m = model("crossroad", &[]);
    m.console("broken zel_vrch").unwrap();
    set(&mut m, "zel_spodek", true);
    set(&mut m, "zel_vrch", true);
    assert_eq!(kinds(&m), [(ErrorKind::ConflictingGreens, true, false)]);
}

/// Section 4.3 with the phase durations of LAB-A4: green 5 s, amber 2 s, all-red 1 s,
/// pedestrian green 5 s.
#[test]
fn example_task_never_shows_conflicting_greens() {
    let mut m = model("crossroad", &[]);
    // (lights on, duration s)
    let phases: [(&[&str], u64); 8] = [
        (&["zel_spodek", "cerv_vrch", "cerv_chodci"], 5),
        (&["oran_spodek", "cerv_vrch", "cerv_chodci"], 2),
        (&["cerv_spodek", "cerv_vrch", "cerv_chodci"], 1),
        (&["cerv_spodek", "zel_vrch", "cerv_chodci"], 5),
        (&["cerv_spodek", "oran_vrch", "cerv_chodci"], 2),
        (&["cerv_spodek", "cerv_vrch", "cerv_chodci"], 1),
        (&["cerv_spodek", "cerv_vrch", "zel_chodci"], 5),
        (&["cerv_spodek", "cerv_vrch", "cerv_chodci"], 1),
    ];
    let cycle: u64 = phases.iter().map(|(_, d)| d).sum();
    let mut phase = 0usize;
    let mut phase_end = s(0);
    let mut cycles = 0;
    run(&mut m, s(cycle * 50), |m: &mut Model| {
        if m.now() >= phase_end {
            if m.now() > s(0) {
                phase = (phase + 1) % phases.len();
                if phase == 0 {
                    cycles += 1;
                }
            }
            let (on, duration) = phases[phase];
            // Off first, then on: the program writes its outputs in one scan.
            for light in LIGHTS {
                if !on.contains(&light) {
                    set(m, light, false);
                }
            }
            for light in on {
                set(m, light, true);
            }
            phase_end = m.now() + s(duration);
        }
        Some(phase_end)
    });
    assert_eq!(cycles, 50);
    assert_no_error(&m);
}
