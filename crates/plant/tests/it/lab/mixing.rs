//! The mixing unit (section 5): the initial blinking, filling and overflow, sensor
//! thresholds both ways (LAB-A5), SV4 and SV5 rates, the vessel's overflow and the
//! example task of section 5.5.

use std::time::Duration;

use plant::lab::{ErrLed, ErrorKind};

use super::{assert_no_error, at, flag, get, kinds, model, ms, num, run, s, set, Model};

fn levels(m: &Model) -> [f64; 4] {
    ["tank1", "tank2", "tank3", "vessel"].map(|k| num(m, k))
}

#[test]
fn err_blinks_from_power_on_until_the_first_solenoid() {
    let mut m = model("mixing", &[]);
    assert_eq!(m.err_led(), ErrLed::Blinking);
    assert!(get(&m, "ERR"));
    assert!(flag(&m, "err"));
    assert!(m.err_lit());
    assert!(m.errors().is_empty());
    assert_eq!(m.next_event(), Some(ms(500)));
    at(&mut m, ms(700));
    assert!(!m.err_lit());
    assert!(!flag(&m, "err_lit"));
    at(&mut m, ms(1200));
    assert!(m.err_lit());
    // The mixer is no solenoid.
    set(&mut m, "MIX", true);
    assert!(flag(&m, "mixing"));
    assert_eq!(m.err_led(), ErrLed::Blinking);
    at(&mut m, ms(3200));
    set(&mut m, "SV5", true);
    assert_eq!(m.err_led(), ErrLed::Off);
    assert!(!get(&m, "ERR"));
    // Closing it again does not bring the blinking back.
    set(&mut m, "SV5", false);
    at(&mut m, s(5));
    assert_no_error(&m);
    // RESET does.
    m.reset();
    assert_eq!(m.err_led(), ErrLed::Blinking);
    assert!(m.errors().is_empty());
}

#[test]
fn a_tank_fills_in_14_s_and_overflows_in_the_15th() {
    let mut m = model("mixing", &[]);
    set(&mut m, "SV1", true);
    for t in 1..=14u64 {
        at(&mut m, s(t) - ms(1));
        assert_eq!(num(&m, "tank1"), 6.0 * (t - 1) as f64);
        at(&mut m, s(t));
        assert_eq!(num(&m, "tank1"), 6.0 * t as f64);
    }
    assert!(get(&m, "H1"));
    assert_no_error(&m);
    at(&mut m, ms(14_999));
    assert_no_error(&m);
    at(&mut m, s(15));
    assert_eq!(num(&m, "tank1"), 90.0);
    assert_eq!(m.err_led(), ErrLed::Steady);
    assert_eq!(kinds(&m), [(ErrorKind::Overflow, false, false)]);
    assert_eq!(m.errors()[0].time, s(15));
    assert_eq!(m.errors()[0].detail, "tank 1 above 84 L (90 L)");
    // Frozen: nothing moves, whatever is commanded.
    set(&mut m, "SV1", false);
    set(&mut m, "SV4", true);
    at(&mut m, s(30));
    assert_eq!(levels(&m), [90.0, 0.0, 0.0, 0.0]);
    assert_eq!(m.err_led(), ErrLed::Steady);
    m.reset();
    assert_eq!(levels(&m), [0.0; 4]);
    assert!(m.errors().is_empty());
    // SV4 still open at RESET ends the initial blinking at once.
    assert_eq!(m.err_led(), ErrLed::Off);
}

#[test]
fn a_valve_opened_within_a_second_counts_at_the_next_edge() {
    let mut m = model("mixing", &[]);
    at(&mut m, ms(900));
    set(&mut m, "SV2", true);
    at(&mut m, s(1));
    assert_eq!(num(&m, "tank2"), 6.0);
    at(&mut m, ms(1500));
    set(&mut m, "SV2", false);
    at(&mut m, s(3));
    assert_eq!(num(&m, "tank2"), 6.0);
}

#[test]
fn sensors_follow_thresholds_rising_and_falling() {
    let mut m = model("mixing", &[]);
    for v in ["SV1", "SV2", "SV3"] {
        set(&mut m, v, true);
    }
    let all = |m: &Model| ["H1", "H2", "H3", "H4", "H5", "H6", "H7", "H8"].map(|h| get(m, h));
    //          H1     H2     H3     H4     H5     H6     H7     H8
    let none = [false; 8];
    let min = [false, false, true, false, true, false, false, true];
    let half = [false, true, true, false, true, false, true, true];
    let full = [true; 8];
    assert_eq!(all(&m), none);
    at(&mut m, s(1)); // 6 L
    assert_eq!(all(&m), none);
    at(&mut m, s(2)); // 12 L
    assert_eq!(all(&m), min);
    at(&mut m, s(6)); // 36 L
    assert_eq!(all(&m), min);
    at(&mut m, s(7)); // 42 L
    assert_eq!(all(&m), half);
    at(&mut m, s(13)); // 78 L
    assert_eq!(all(&m), half);
    at(&mut m, s(14)); // 84 L
    assert_eq!(all(&m), full);
    for v in ["SV1", "SV2", "SV3"] {
        set(&mut m, v, false);
    }
    set(&mut m, "SV4", true);
    at(&mut m, s(15)); // 78 L
    assert_eq!(all(&m), half);
    at(&mut m, s(21)); // 42 L
    assert_eq!(all(&m), half);
    at(&mut m, s(22)); // 36 L
    assert_eq!(all(&m), min);
    at(&mut m, s(26)); // 12 L
    assert_eq!(all(&m), min);
    at(&mut m, s(27)); // 6 L
    assert_eq!(all(&m), none);
    at(&mut m, s(28)); // 0 L
    assert_eq!(levels(&m), [0.0, 0.0, 0.0, 252.0]);
    assert_no_error(&m);
}

#[test]
fn sv4_moves_6_l_per_second_from_each_tank_that_holds_liquid() {
    let mut m = model("mixing", &[]);
    set(&mut m, "SV1", true);
    set(&mut m, "SV2", true);
    at(&mut m, s(2));
    set(&mut m, "SV1", false);
    at(&mut m, s(5));
    set(&mut m, "SV2", false);
    assert_eq!(levels(&m), [12.0, 30.0, 0.0, 0.0]);
    set(&mut m, "SV4", true);
    let mut vessel = Vec::new();
    for t in 6..=11 {
        at(&mut m, s(t));
        vessel.push(num(&m, "vessel"));
    }
    // 12 L/s while two tanks hold liquid, then 6 L/s, then nothing.
    assert_eq!(vessel, [12.0, 24.0, 30.0, 36.0, 42.0, 42.0]);
    assert_eq!(levels(&m), [0.0, 0.0, 0.0, 42.0]);
}

#[test]
fn sv5_drains_the_vessel_18_l_per_second() {
    let mut m = model("mixing", &[]);
    set(&mut m, "SV1", true);
    at(&mut m, s(14));
    set(&mut m, "SV1", false);
    set(&mut m, "SV4", true);
    at(&mut m, s(28));
    set(&mut m, "SV4", false);
    assert_eq!(levels(&m), [0.0, 0.0, 0.0, 84.0]);
    set(&mut m, "SV5", true);
    let mut vessel = Vec::new();
    for t in 29..=34 {
        at(&mut m, s(t));
        vessel.push(num(&m, "vessel"));
    }
    assert_eq!(vessel, [66.0, 48.0, 30.0, 12.0, 0.0, 0.0]);
    assert_no_error(&m);
}

#[test]
fn the_vessel_overflows_above_253_l() {
    let mut m = model("mixing", &[]);
    for v in ["SV1", "SV2", "SV3"] {
        set(&mut m, v, true);
    }
    at(&mut m, s(14));
    for v in ["SV2", "SV3"] {
        set(&mut m, v, false);
    }
    // Tank 1 keeps filling while SV4 drains it: 6 L in, 6 L out, no tank overflow.
    set(&mut m, "SV4", true);
    at(&mut m, s(27));
    assert_eq!(levels(&m), [84.0, 6.0, 6.0, 234.0]);
    assert_no_error(&m);
    at(&mut m, s(28));
    assert_eq!(levels(&m), [84.0, 0.0, 0.0, 252.0]);
    assert_no_error(&m);
    at(&mut m, s(29));
    assert_eq!(num(&m, "vessel"), 258.0);
    assert_eq!(kinds(&m), [(ErrorKind::Overflow, false, false)]);
    assert_eq!(m.errors()[0].detail, "mixing vessel above 253 L (258 L)");
    assert_eq!(m.err_led(), ErrLed::Steady);
}

/// Section 5.5 with the proposals: SV4 closed at the end of step 4, SV5 open 15 s. A cycle
/// is 5 + 14 + 13 + 2 + 5 + 15 = 54 s.
#[test]
fn example_task_runs_without_err_after_the_first_solenoid() {
    #[derive(Clone, Copy, PartialEq, Debug)]
    enum Phase {
        Pause(Duration),
        Fill,
        Transfer,
        Overrun(Duration),
        Mix(Duration),
        Empty(Duration),
    }
    let mut m = model("mixing", &[]);
    let mut phase = Phase::Pause(s(5));
    let mut full_at = Vec::new();
    let mut cycle_ends = Vec::new();
    let mut max_vessel: f64 = 0.0;
    let mut err_after_first = false;
    let mut blinked_before = true;
    run(&mut m, s(54 * 10), |m: &mut Model| {
        let now = m.now();
        max_vessel = max_vessel.max(num(m, "vessel"));
        if now < s(5) {
            blinked_before &= m.err_led() == ErrLed::Blinking;
        }
        phase = match phase {
            Phase::Pause(until) if now >= until => {
                for v in ["SV1", "SV2", "SV3"] {
                    set(m, v, true);
                }
                Phase::Fill
            }
            Phase::Fill if get(m, "H1") && get(m, "H4") && get(m, "H6") => {
                full_at.push(now);
                for v in ["SV1", "SV2", "SV3"] {
                    set(m, v, false);
                }
                set(m, "SV4", true);
                Phase::Transfer
            }
            Phase::Transfer if !get(m, "H3") && !get(m, "H5") && !get(m, "H8") => {
                Phase::Overrun(now + s(2))
            }
            Phase::Overrun(until) if now >= until => {
                set(m, "SV4", false);
                set(m, "MIX", true);
                Phase::Mix(now + s(5))
            }
            Phase::Mix(until) if now >= until => {
                set(m, "MIX", false);
                set(m, "SV5", true);
                Phase::Empty(now + s(15))
            }
            Phase::Empty(until) if now >= until => {
                set(m, "SV5", false);
                cycle_ends.push(now);
                Phase::Pause(now + s(5))
            }
            p => p,
        };
        // After this scan's outputs: from the first solenoid on, never an ERR.
        if now >= s(5) {
            err_after_first |= get(m, "ERR") || !m.errors().is_empty();
        }
        match phase {
            Phase::Pause(t) | Phase::Overrun(t) | Phase::Mix(t) | Phase::Empty(t) => Some(t),
            Phase::Fill | Phase::Transfer => None,
        }
    });
    assert!(blinked_before);
    assert!(!err_after_first);
    assert_no_error(&m);
    assert_eq!(max_vessel, 252.0);
    assert_eq!(full_at.first(), Some(&s(19)));
    assert_eq!(cycle_ends.len(), 10);
    for (i, end) in cycle_ends.iter().enumerate() {
        assert_eq!(*end, s(54 * (i as u64 + 1)), "cycle {i}");
    }
}
