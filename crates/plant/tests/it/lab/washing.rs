//! The washing machine (section 6): drum steps, both directions, heating, cooling,
//! temperature and level flags, overheating and overflow, the options of LAB-A7 and
//! LAB-A9, and the example task of section 6.5.

use std::time::Duration;

use plant::lab::{ErrLed, ErrorKind};

use super::{assert_no_error, at, flag, get, kinds, model, ms, num, run, s, set, Model};

fn drum(m: &Model) -> u8 {
    num(m, "drum") as u8
}

fn temps(m: &Model) -> [bool; 4] {
    ["teplota_30", "teplota_40", "teplota_60", "teplota_90"].map(|t| get(m, t))
}

#[test]
fn the_drum_steps_every_half_second_and_every_quarter_with_otacky() {
    let mut m = model("washing", &[]);
    assert_eq!(drum(&m), 0);
    assert!(!flag(&m, "drum_turning"));
    set(&mut m, "buben_vpravo", true);
    assert!(flag(&m, "drum_turning"));
    at(&mut m, ms(499));
    assert_eq!(drum(&m), 0);
    at(&mut m, ms(500));
    assert_eq!(drum(&m), 1);
    at(&mut m, ms(3500));
    assert_eq!(drum(&m), 7);
    at(&mut m, ms(4000));
    assert_eq!(drum(&m), 0);
    // Spin: 0.25 s, from the running TON's start (4.0 s).
    set(&mut m, "otacky", true);
    at(&mut m, ms(4249));
    assert_eq!(drum(&m), 0);
    at(&mut m, ms(4250));
    assert_eq!(drum(&m), 1);
    at(&mut m, ms(5000));
    assert_eq!(drum(&m), 4);
    // Left: decreasing, wrapping.
    set(&mut m, "buben_vpravo", false);
    set(&mut m, "otacky", false);
    set(&mut m, "buben_vlevo", true);
    at(&mut m, ms(7000));
    assert_eq!(drum(&m), 0);
    at(&mut m, ms(7500));
    assert_eq!(drum(&m), 7);
    assert_no_error(&m);
}

#[test]
fn drum_option_4_cycles_four_states() {
    let mut m = model("washing", &[("drum", "4")]);
    set(&mut m, "buben_vpravo", true);
    let mut seen = Vec::new();
    for i in 1..=5 {
        at(&mut m, ms(500 * i));
        seen.push(drum(&m));
    }
    assert_eq!(seen, [1, 2, 3, 0, 1]);
}

#[test]
fn both_directions_blink_err_and_stop_the_drum_until_one_is_released() {
    let mut m = model("washing", &[]);
    set(&mut m, "buben_vpravo", true);
    at(&mut m, ms(1100));
    assert_eq!(drum(&m), 2);
    set(&mut m, "buben_vlevo", true);
    assert_eq!(m.err_led(), ErrLed::Blinking);
    assert!(get(&m, "ERR"));
    assert!(!flag(&m, "drum_turning"));
    assert_eq!(kinds(&m), [(ErrorKind::BothDirections, true, false)]);
    assert_eq!(
        m.errors()[0].detail,
        "buben_vpravo and buben_vlevo together"
    );
    at(&mut m, s(4));
    assert_eq!(drum(&m), 2);
    set(&mut m, "buben_vpravo", false);
    assert_eq!(m.err_led(), ErrLed::Off);
    assert_eq!(m.errors()[0].cleared, Some(s(4)));
    // Turns again, left now.
    at(&mut m, ms(4500));
    assert_eq!(drum(&m), 1);
}

#[test]
fn heating_1_5_degrees_per_second_with_flags_and_overheat_at_61_s() {
    let mut m = model("washing", &[]);
    set(&mut m, "topeni", true);
    at(&mut m, s(1));
    assert_eq!(num(&m, "temperature"), 1.5);
    at(&mut m, s(19));
    assert_eq!(temps(&m), [false; 4]);
    at(&mut m, s(20));
    assert_eq!(num(&m, "temperature"), 30.0);
    assert_eq!(temps(&m), [true, false, false, false]);
    at(&mut m, s(26));
    assert_eq!(temps(&m), [true, false, false, false]);
    at(&mut m, s(27)); // 40.5
    assert_eq!(temps(&m), [true, true, false, false]);
    at(&mut m, s(39));
    assert_eq!(temps(&m), [true, true, false, false]);
    at(&mut m, s(40));
    assert_eq!(temps(&m), [true, true, true, false]);
    at(&mut m, s(59));
    assert_eq!(temps(&m), [true, true, true, false]);
    at(&mut m, s(60));
    assert_eq!(num(&m, "temperature"), 90.0);
    assert_eq!(temps(&m), [true; 4]);
    assert_no_error(&m);
    at(&mut m, ms(60_999));
    assert_no_error(&m);
    at(&mut m, s(61));
    assert_eq!(num(&m, "temperature"), 91.5);
    assert_eq!(m.err_led(), ErrLed::Steady);
    assert_eq!(kinds(&m), [(ErrorKind::Overheat, false, false)]);
    assert_eq!(m.errors()[0].time, s(61));
    assert_eq!(m.errors()[0].detail, "water above 90 °C (91.5 °C)");
    // Frozen: no cooling either.
    set(&mut m, "topeni", false);
    at(&mut m, s(70));
    assert_eq!(num(&m, "temperature"), 91.5);
    m.reset();
    assert_eq!(num(&m, "temperature"), 0.0);
    assert_no_error(&m);
}

#[test]
fn cooling_3_degrees_per_second_with_flags_falling_and_clamped_at_0() {
    let mut m = model("washing", &[]);
    set(&mut m, "topeni", true);
    at(&mut m, s(40));
    assert_eq!(num(&m, "temperature"), 60.0);
    set(&mut m, "topeni", false);
    at(&mut m, s(41));
    assert_eq!(num(&m, "temperature"), 57.0);
    assert_eq!(temps(&m), [true, true, false, false]);
    at(&mut m, s(46)); // 42
    assert_eq!(temps(&m), [true, true, false, false]);
    at(&mut m, s(47)); // 39
    assert_eq!(temps(&m), [true, false, false, false]);
    at(&mut m, s(50)); // 30
    assert_eq!(num(&m, "temperature"), 30.0);
    assert_eq!(temps(&m), [true, false, false, false]);
    at(&mut m, s(51)); // 27
    assert_eq!(temps(&m), [false; 4]);
    at(&mut m, s(60));
    assert_eq!(num(&m, "temperature"), 0.0);
    at(&mut m, s(65));
    assert_eq!(num(&m, "temperature"), 0.0);
    assert_no_error(&m);
}

#[test]
fn level_fills_and_drains_5_percent_per_second_and_overflows_beyond_100() {
    let mut m = model("washing", &[]);
    set(&mut m, "napousteni", true);
    at(&mut m, s(9));
    assert_eq!(num(&m, "level"), 45.0);
    assert!(!get(&m, "voda_50"));
    at(&mut m, s(10));
    assert!(get(&m, "voda_50"));
    // Both: net nothing.
    set(&mut m, "cerpadlo", true);
    at(&mut m, s(15));
    assert_eq!(num(&m, "level"), 50.0);
    set(&mut m, "cerpadlo", false);
    at(&mut m, s(24));
    assert_eq!(num(&m, "level"), 95.0);
    assert!(!get(&m, "voda_100"));
    at(&mut m, s(25));
    assert_eq!(num(&m, "level"), 100.0);
    assert!(get(&m, "voda_100"));
    assert_no_error(&m);
    at(&mut m, s(26));
    assert_eq!(num(&m, "level"), 100.0);
    assert_eq!(m.err_led(), ErrLed::Steady);
    assert_eq!(kinds(&m), [(ErrorKind::Overflow, false, false)]);
    assert_eq!(m.errors()[0].detail, "tub filled beyond 100 % (105 %)");
    // Frozen: the drum ignores its commands.
    set(&mut m, "buben_vpravo", true);
    at(&mut m, s(30));
    assert_eq!(drum(&m), 0);
    assert!(!flag(&m, "drum_turning"));
    // After RESET: empty, and draining an empty tub stays at 0.
    set(&mut m, "napousteni", false);
    set(&mut m, "buben_vpravo", false);
    m.reset();
    assert_eq!(num(&m, "level"), 0.0);
    set(&mut m, "cerpadlo", true);
    at(&mut m, s(33));
    assert_eq!(num(&m, "level"), 0.0);
    assert_no_error(&m);
}

#[test]
fn level_dependent_heating_option() {
    let mut m = model("washing", &[("heating", "level")]);
    // Empty tub: the heater does nothing.
    set(&mut m, "topeni", true);
    at(&mut m, s(3));
    assert_eq!(num(&m, "temperature"), 0.0);
    set(&mut m, "topeni", false);
    set(&mut m, "napousteni", true);
    at(&mut m, s(13));
    set(&mut m, "napousteni", false);
    assert_eq!(num(&m, "level"), 50.0);
    set(&mut m, "topeni", true);
    at(&mut m, s(14));
    assert_eq!(num(&m, "temperature"), 3.0);
    at(&mut m, s(20));
    assert_eq!(num(&m, "temperature"), 21.0);
}

/// Section 6.5 with the proposals: the drum turns right while washing, "empty" is
/// `voda_50` FALSE plus 10 s, filling and heating run together; the heater is a
/// thermostat on the 30 °C sensor, then on the 60 °C sensor until the main wash is
/// drained.
#[test]
fn example_task_runs_without_err() {
    #[derive(Clone, Copy, PartialEq, Debug)]
    enum Phase {
        Fill,
        PreWash(Duration),
        Drain(Option<Duration>),
        MainFill,
        MainWash(Duration),
        MainDrain(Option<Duration>),
        RinseFill,
        RinseDrain(Option<Duration>),
        Spin(Duration),
    }
    /// Drains until `voda_50` has been FALSE for 10 s; the next phase when done.
    fn draining(m: &Model, since: Option<Duration>) -> Result<Option<Duration>, ()> {
        match since {
            None if !get(m, "voda_50") => Ok(Some(m.now())),
            Some(t) if m.now() >= t + s(10) => Err(()),
            other => Ok(other),
        }
    }
    let mut m = model("washing", &[]);
    let mut phase = Phase::Fill;
    let mut thermostat = Some(30u32);
    let mut max_temperature: f64 = 0.0;
    let mut max_level: f64 = 0.0;
    let mut cycle_ends = Vec::new();
    let mut any_err = false;
    let mut started = false;
    run(&mut m, s(3000), |m: &mut Model| {
        let now = m.now();
        if !started {
            set(m, "napousteni", true);
            started = true;
        }
        phase = match phase {
            Phase::Fill if get(m, "voda_100") => {
                set(m, "napousteni", false);
                set(m, "buben_vpravo", true);
                Phase::PreWash(now + s(5))
            }
            Phase::PreWash(t) if now >= t => {
                set(m, "buben_vpravo", false);
                set(m, "cerpadlo", true);
                Phase::Drain(None)
            }
            Phase::Drain(since) => match draining(m, since) {
                Ok(since) => Phase::Drain(since),
                Err(()) => {
                    set(m, "cerpadlo", false);
                    set(m, "napousteni", true);
                    thermostat = Some(60);
                    Phase::MainFill
                }
            },
            Phase::MainFill if get(m, "voda_100") || !get(m, "napousteni") => {
                set(m, "napousteni", false);
                if get(m, "teplota_60") {
                    set(m, "buben_vpravo", true);
                    Phase::MainWash(now + s(5))
                } else {
                    Phase::MainFill
                }
            }
            Phase::MainWash(t) if now >= t => {
                set(m, "buben_vpravo", false);
                set(m, "cerpadlo", true);
                Phase::MainDrain(None)
            }
            Phase::MainDrain(since) => match draining(m, since) {
                Ok(since) => Phase::MainDrain(since),
                Err(()) => {
                    thermostat = None;
                    set(m, "cerpadlo", false);
                    set(m, "napousteni", true);
                    Phase::RinseFill
                }
            },
            Phase::RinseFill if get(m, "voda_100") => {
                set(m, "napousteni", false);
                set(m, "cerpadlo", true);
                Phase::RinseDrain(None)
            }
            Phase::RinseDrain(since) => match draining(m, since) {
                Ok(since) => Phase::RinseDrain(since),
                Err(()) => {
                    set(m, "cerpadlo", false);
                    set(m, "buben_vpravo", true);
                    set(m, "otacky", true);
                    Phase::Spin(now + s(5))
                }
            },
            Phase::Spin(t) if now >= t => {
                set(m, "buben_vpravo", false);
                set(m, "otacky", false);
                cycle_ends.push(now);
                thermostat = Some(30);
                set(m, "napousteni", true);
                Phase::Fill
            }
            p => p,
        };
        let heat = match thermostat {
            Some(30) => !get(m, "teplota_30"),
            Some(60) => !get(m, "teplota_60"),
            _ => false,
        };
        set(m, "topeni", heat);
        max_temperature = max_temperature.max(num(m, "temperature"));
        max_level = max_level.max(num(m, "level"));
        any_err |= get(m, "ERR") || !m.errors().is_empty();
        match phase {
            Phase::PreWash(t) | Phase::MainWash(t) | Phase::Spin(t) => Some(t),
            Phase::Drain(Some(t)) | Phase::MainDrain(Some(t)) | Phase::RinseDrain(Some(t)) => {
                Some(t + s(10))
            }
            _ => None,
        }
    });
    assert!(!any_err);
    assert_no_error(&m);
    assert!(max_temperature <= 61.5, "{max_temperature}");
    assert!(max_temperature >= 60.0, "{max_temperature}");
    assert_eq!(max_level, 100.0);
    assert!(cycle_ends.len() >= 10, "{cycle_ends:?}");
    // Every cycle takes the same time (139 s).
    assert_eq!(cycle_ends[0], s(139));
    let lengths: Vec<Duration> = cycle_ends.windows(2).map(|w| w[1] - w[0]).collect();
    assert!(lengths.windows(2).all(|w| w[0] == w[1]), "{lengths:?}");
}
