//! The slide unit (section 3): step periods, sensors, both directions, overtravel, the
//! alternative sensor positions (LAB-A1) and the example task of section 3.5.

use plant::lab::{ErrLed, ErrorKind};
use plant::{Direction, PlantError, Value};

use super::{assert_no_error, at, flag, get, kinds, model, ms, num, run, s, set, Model};

fn position(m: &Model) -> u8 {
    num(m, "position") as u8
}

fn ks(m: &Model) -> [bool; 4] {
    ["K1", "K2", "K3", "K4"].map(|k| get(m, k))
}

#[test]
fn surface() {
    let m = model("slide", &[]);
    let names: Vec<(&str, Direction)> = m
        .signals()
        .iter()
        .map(|s| (s.name.as_str(), s.direction))
        .collect();
    assert_eq!(
        names,
        [
            ("EM1", Direction::Output),
            ("EM2", Direction::Output),
            ("EM3", Direction::Output),
            ("RESET", Direction::Output),
            ("K1", Direction::Input),
            ("K2", Direction::Input),
            ("K3", Direction::Input),
            ("K4", Direction::Input),
            ("START", Direction::Input),
            ("ERR", Direction::Input),
        ]
    );
    assert_eq!(position(&m), 1);
    assert_eq!(ks(&m), [true, false, false, false]);
    assert_eq!(num(&m, "leds"), 1.0);
    assert!(!flag(&m, "err"));
    assert!(!flag(&m, "err_lit"));
    assert_no_error(&m);
}

#[test]
fn rapid_traverse_steps_every_half_second() {
    let mut m = model("slide", &[]);
    set(&mut m, "EM1", true);
    assert_eq!(m.next_event(), Some(ms(500)));
    at(&mut m, ms(499));
    assert_eq!(position(&m), 1);
    at(&mut m, ms(500));
    assert_eq!(position(&m), 2);
    at(&mut m, ms(999));
    assert_eq!(position(&m), 2);
    at(&mut m, s(1));
    assert_eq!(position(&m), 3);
    assert_eq!(num(&m, "leds"), 4.0);
    at(&mut m, ms(4500));
    assert_eq!(position(&m), 10);
}

#[test]
fn working_feed_steps_every_second_and_the_first_step_waits_a_period() {
    let mut m = model("slide", &[]);
    at(&mut m, ms(300));
    set(&mut m, "EM3", true);
    set(&mut m, "EM1", true);
    at(&mut m, ms(1299));
    assert_eq!(position(&m), 1);
    at(&mut m, ms(1300));
    assert_eq!(position(&m), 2);
    at(&mut m, ms(3300));
    assert_eq!(position(&m), 4);
    // Releasing stops the TON; a new command waits a whole period again.
    at(&mut m, ms(3800));
    set(&mut m, "EM1", false);
    at(&mut m, ms(5000));
    set(&mut m, "EM2", true);
    at(&mut m, ms(5999));
    assert_eq!(position(&m), 4);
    at(&mut m, s(6));
    assert_eq!(position(&m), 3);
}

#[test]
fn em3_changed_mid_run_sets_the_running_period_from_its_start() {
    // Feed started at 0; rapid at 0.7 s: 0.5 s from the start is already over, the step
    // comes at 0.7 s and the next TON runs 0.5 s.
    let mut m = model("slide", &[]);
    set(&mut m, "EM3", true);
    set(&mut m, "EM1", true);
    at(&mut m, ms(700));
    assert_eq!(position(&m), 1);
    set(&mut m, "EM3", false);
    assert_eq!(position(&m), 2);
    at(&mut m, ms(1199));
    assert_eq!(position(&m), 2);
    at(&mut m, ms(1200));
    assert_eq!(position(&m), 3);
    // Rapid started at 1.2 s; feed at 1.5 s: the step comes 1 s after 1.2 s.
    at(&mut m, ms(1500));
    set(&mut m, "EM3", true);
    at(&mut m, ms(2199));
    assert_eq!(position(&m), 3);
    at(&mut m, ms(2200));
    assert_eq!(position(&m), 4);
}

#[test]
fn k_sensors_sit_at_1_4_7_10() {
    let mut m = model("slide", &[]);
    set(&mut m, "EM1", true);
    for p in 1..=10u8 {
        at(&mut m, ms(500 * u64::from(p - 1)));
        assert_eq!(position(&m), p);
        let expected = [p == 1, p == 4, p == 7, p == 10];
        assert_eq!(ks(&m), expected, "position {p}");
    }
    // And back, falling as the slide leaves.
    set(&mut m, "EM1", false);
    set(&mut m, "EM2", true);
    at(&mut m, ms(5000));
    assert_eq!(position(&m), 9);
    assert_eq!(ks(&m), [false; 4]);
    at(&mut m, ms(6000));
    assert_eq!(position(&m), 7);
    assert_eq!(ks(&m), [false, false, true, false]);
}

#[test]
fn both_directions_blink_err_stop_and_resume_after_release() {
    let mut m = model("slide", &[]);
    set(&mut m, "EM1", true);
    at(&mut m, s(1));
    assert_eq!(position(&m), 3);
    at(&mut m, ms(1200));
    set(&mut m, "EM2", true);
    assert_eq!(m.err_led(), ErrLed::Blinking);
    assert!(get(&m, "ERR"));
    assert!(m.err_lit());
    assert_eq!(kinds(&m), [(ErrorKind::BothDirections, true, false)]);
    assert_eq!(m.errors()[0].time, ms(1200));
    // The LED is dark in the second half of each second; the half-second is an event.
    assert_eq!(m.next_event(), Some(ms(1500)));
    at(&mut m, ms(1500));
    assert!(!m.err_lit());
    assert!(get(&m, "ERR"));
    at(&mut m, s(2));
    assert!(m.err_lit());
    at(&mut m, ms(3000));
    assert_eq!(position(&m), 3);
    set(&mut m, "EM2", false);
    assert_eq!(m.err_led(), ErrLed::Off);
    assert!(!get(&m, "ERR"));
    assert_eq!(m.errors()[0].cleared, Some(s(3)));
    // Resumes to the right with a new TON.
    at(&mut m, ms(3499));
    assert_eq!(position(&m), 3);
    at(&mut m, ms(3500));
    assert_eq!(position(&m), 4);
}

#[test]
fn overtravel_past_k4_locks_until_reset_and_reset_returns_to_k1() {
    let mut m = model("slide", &[]);
    set(&mut m, "EM1", true);
    at(&mut m, ms(4999));
    assert_eq!(position(&m), 10);
    assert_no_error(&m);
    at(&mut m, s(5));
    assert_eq!(position(&m), 10);
    assert_eq!(m.err_led(), ErrLed::Steady);
    assert!(m.err_lit());
    assert!(get(&m, "ERR"));
    assert_eq!(ks(&m), [true; 4]);
    assert_eq!(num(&m, "leds"), (1 | 1 << 3 | 1 << 6 | 1 << 9) as f64);
    assert_eq!(kinds(&m), [(ErrorKind::Overtravel, false, false)]);
    assert_eq!(m.errors()[0].time, s(5));
    assert_eq!(m.errors()[0].detail, "step right past K4 from position 10");
    // Commands are ignored.
    set(&mut m, "EM1", false);
    set(&mut m, "EM2", true);
    at(&mut m, s(20));
    assert_eq!(position(&m), 10);
    assert_eq!(ks(&m), [true; 4]);
    assert_eq!(m.err_led(), ErrLed::Steady);
    assert_eq!(m.errors().len(), 1);
    // RESET: back at K1, record cleared; EM2 still commanded acts from the RESET instant
    // and runs past K1.
    m.reset();
    assert_eq!(position(&m), 1);
    assert_eq!(ks(&m), [true, false, false, false]);
    assert_no_error(&m);
    at(&mut m, ms(20_499));
    assert_no_error(&m);
    at(&mut m, ms(20_500));
    assert_eq!(position(&m), 1);
    assert_eq!(m.err_led(), ErrLed::Steady);
    assert_eq!(m.errors()[0].detail, "step left past K1 from position 1");
    assert_eq!(ks(&m), [true; 4]);
    // The console's reset is the same button.
    set(&mut m, "EM2", false);
    m.console("reset").unwrap();
    assert_no_error(&m);
    assert_eq!(ks(&m), [true, false, false, false]);
}

#[test]
fn the_program_resets_by_a_rising_edge_only_with_program_err() {
    let mut plain = model("slide", &[]);
    set(&mut plain, "EM2", true);
    at(&mut plain, s(1));
    assert_eq!(plain.err_led(), ErrLed::Steady);
    set(&mut plain, "RESET", true);
    assert_eq!(plain.err_led(), ErrLed::Steady);

    let mut m = model("slide", &[("program-err", "true")]);
    set(&mut m, "EM2", true);
    at(&mut m, s(1));
    assert_eq!(m.err_led(), ErrLed::Steady);
    set(&mut m, "EM2", false);
    set(&mut m, "RESET", true);
    assert_no_error(&m);
    // Held TRUE it does nothing more.
    set(&mut m, "EM2", true);
    at(&mut m, s(2));
    assert_eq!(m.err_led(), ErrLed::Steady);
    set(&mut m, "EM2", false);
    at(&mut m, s(3));
    assert_eq!(m.err_led(), ErrLed::Steady);
    set(&mut m, "RESET", false);
    set(&mut m, "RESET", true);
    assert_no_error(&m);
    assert_eq!(position(&m), 1);
}

#[test]
fn alternative_sensors_make_1_and_10_overtravel_zones() {
    let mut m = model("slide", &[("sensors", "2,4,7,9")]);
    assert_eq!(position(&m), 2);
    assert_eq!(ks(&m), [true, false, false, false]);
    set(&mut m, "EM1", true);
    at(&mut m, ms(3500));
    assert_eq!(position(&m), 9);
    assert_eq!(ks(&m), [false, false, false, true]);
    assert_no_error(&m);
    at(&mut m, s(4));
    assert_eq!(position(&m), 10);
    assert_eq!(kinds(&m), [(ErrorKind::Overtravel, false, false)]);
    assert_eq!(ks(&m), [true; 4]);
    m.reset();
    assert_eq!(position(&m), 2);
    set(&mut m, "EM1", false);
    set(&mut m, "EM2", true);
    at(&mut m, ms(4500));
    assert_eq!(position(&m), 1);
    assert_eq!(m.err_led(), ErrLed::Steady);
}

#[test]
fn outputs_read_back_and_wrong_use_is_an_error() {
    let mut m = model("slide", &[]);
    set(&mut m, "EM3", true);
    assert!(get(&m, "EM3"));
    assert_eq!(
        m.set_output("K1", Value::Bool(true)),
        Err(PlantError::NotAnOutput("K1".into()))
    );
    assert!(matches!(
        m.set_output("EM1", Value::Real(1.0)),
        Err(PlantError::WrongType { .. })
    ));
    assert_eq!(
        m.set_output("EM9", Value::Bool(true)),
        Err(PlantError::UnknownSignal("EM9".into()))
    );
    at(&mut m, s(2));
    assert!(matches!(
        m.advance_to(s(1)),
        Err(PlantError::TimeWentBackwards { .. })
    ));
}

/// Section 3.5: forward to K4 (rapid), back to K3 (rapid), 5 s pause, working feed back
/// to K1, repeat. With K1-K4 at 1, 4, 7, 10: 9 × 0.5 + 3 × 0.5 + 5 + 6 × 1 = 17 s a cycle.
#[test]
fn example_task_runs_100_cycles_without_err() {
    #[derive(Clone, Copy, PartialEq)]
    enum Phase {
        Forward,
        Back,
        Pause(std::time::Duration),
        Feed,
    }
    let mut m = model("slide", &[]);
    let mut phase = Phase::Forward;
    let mut cycle_ends = Vec::new();
    let mut started = false;
    let mut max_err = false;
    run(&mut m, s(17 * 100), |m: &mut Model| {
        max_err |= get(m, "ERR") || !m.errors().is_empty();
        if !started {
            set(m, "EM1", true);
            started = true;
        }
        match phase {
            Phase::Forward if get(m, "K4") => {
                set(m, "EM1", false);
                set(m, "EM2", true);
                phase = Phase::Back;
            }
            Phase::Back if get(m, "K3") => {
                set(m, "EM2", false);
                phase = Phase::Pause(m.now() + s(5));
            }
            Phase::Pause(until) if m.now() >= until => {
                set(m, "EM3", true);
                set(m, "EM2", true);
                phase = Phase::Feed;
            }
            Phase::Feed if get(m, "K1") => {
                set(m, "EM2", false);
                set(m, "EM3", false);
                cycle_ends.push(m.now());
                set(m, "EM1", true);
                phase = Phase::Forward;
            }
            _ => {}
        }
        match phase {
            Phase::Pause(until) => Some(until),
            _ => None,
        }
    });
    assert!(!max_err);
    assert_no_error(&m);
    assert_eq!(cycle_ends.len(), 100);
    for (i, end) in cycle_ends.iter().enumerate() {
        assert_eq!(*end, s(17 * (i as u64 + 1)), "cycle {i}");
    }
}
