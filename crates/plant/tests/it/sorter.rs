//! The sorting lab's ball sorter (`plant::sorter`): the ball path through the gates, the
//! deflectors' cascade, the shutter and the blower, the balance it feeds, the faults of
//! section 13, and runs that do not depend on the step size.

use std::time::Duration;

use plant::sorter::{Place, SorterConfig, SorterPlant, StartState, ACTUATORS};
use plant::{Plant, Value};

use super::{ms, s};

fn sorter(seed: u64) -> SorterPlant {
    SorterPlant::new(SorterConfig {
        seed,
        ..SorterConfig::default()
    })
}

fn set(p: &mut SorterPlant, name: &str, on: bool) {
    p.set_output(name, Value::Bool(on)).unwrap();
}

fn wait(p: &mut SorterPlant, d: Duration) {
    p.advance(d).unwrap();
}

/// Energises `name` for `on_for`, then releases it.
fn pulse(p: &mut SorterPlant, name: &str, on_for: Duration) {
    set(p, name, true);
    wait(p, on_for);
    set(p, name, false);
}

fn sensor(p: &SorterPlant, name: &str) -> bool {
    p.bool(name).unwrap()
}

/// Drives every deflector to `extended` (1 s working time, as the supervisor does).
fn deflectors(p: &mut SorterPlant, extended: [bool; 3]) {
    for (k, on) in extended.iter().enumerate() {
        let solenoid = if *on { 4 + 2 * k } else { 5 + 2 * k };
        pulse(p, &format!("S{solenoid}"), s(1));
    }
    for (k, on) in extended.iter().enumerate() {
        assert_eq!(
            p.deflector_extended(k + 1),
            Some(*on),
            "deflector {}",
            k + 1
        );
    }
}

/// One ball from the upper reservoir onto the pan (S1 1 s, pause, S2 1 s).
fn dose(p: &mut SorterPlant) {
    pulse(p, "S1", s(1));
    wait(p, ms(200));
    pulse(p, "S2", s(1));
}

#[test]
fn power_on_holds_the_balls_above_and_the_deflectors_where_the_seed_put_them() {
    let p = sorter(7);
    assert_eq!(p.upper().len(), 8);
    assert!(sensor(&p, "Sn1"));
    for name in ["Sn2", "Sn3", "Sn4", "Sn5"] {
        assert!(!sensor(&p, name), "{name}");
    }
    assert!(!p.shutter_open());
    let again = sorter(7);
    assert_eq!(p.upper(), again.upper());
    let positions = |p: &SorterPlant| (1..=3).map(|k| p.deflector_extended(k)).collect::<Vec<_>>();
    assert_eq!(positions(&p), positions(&again));
    // Over a few seeds both orders and both positions occur.
    let orders: std::collections::BTreeSet<_> = (0..8).map(|seed| sorter(seed).upper()).collect();
    assert!(orders.len() > 1);
    let extended = (0..16)
        .filter(|seed| sorter(*seed).deflector_extended(1) == Some(true))
        .count();
    assert!((1..16).contains(&extended), "{extended}");
    assert_eq!(p.signals().len(), ACTUATORS.len() * 4 + 5 + 3);
}

#[test]
fn one_ball_is_dosed_weighed_and_routed_by_the_deflector_cascade() {
    let mut p = sorter(1);
    let first = p.upper()[0];
    pulse(&mut p, "S1", s(1));
    assert_eq!(p.balls_at(Place::BeforeS2), vec![first]);
    assert!(sensor(&p, "Sn2"));
    assert_eq!(
        p.upper().len(),
        7,
        "S1 lets one ball through while S2 is shut"
    );
    wait(&mut p, ms(200));
    pulse(&mut p, "S2", s(1));
    assert_eq!(p.balls_at(Place::Pan), vec![first]);
    assert!(sensor(&p, "Sn5"));
    wait(&mut p, s(3));
    let ball = p.balls().iter().find(|b| b.name == first).unwrap();
    let weight = p.real("Balance_g").unwrap();
    assert!((weight - ball.mean_3s).abs() < 0.3, "{weight} for {first}");
    assert!(
        !sensor(&p, "Balance_stable"),
        "never stable with a ball on the pan"
    );

    deflectors(&mut p, [false, true, false]);
    set(&mut p, "S3", true);
    wait(&mut p, ms(250));
    assert!(sensor(&p, "Sn3"), "Sn3 sees the ball fall");
    wait(&mut p, ms(750));
    set(&mut p, "S3", false);
    assert!(!sensor(&p, "Sn3"));
    assert_eq!(p.shaft(2), vec![first]);
    assert_eq!(p.arrivals().len(), 1);
    assert_eq!(p.arrivals()[0].shaft, 2);
    // The empty pan settles: stable within 10 s.
    wait(&mut p, s(10));
    assert!(sensor(&p, "Balance_stable"));
    assert!(p.real("Balance_g").unwrap().abs() < 0.001);

    // All retracted: shaft 4; the first extended wins over the later ones.
    dose(&mut p);
    deflectors(&mut p, [false, false, false]);
    pulse(&mut p, "S3", s(1));
    assert_eq!(p.shaft(4).len(), 1);
    dose(&mut p);
    deflectors(&mut p, [true, true, true]);
    pulse(&mut p, "S3", s(1));
    assert_eq!(p.shaft(1).len(), 1);
}

#[test]
fn s1_and_s2_open_together_dose_two_balls() {
    let mut p = sorter(2);
    let expected: f64 = p.upper()[..2]
        .iter()
        .map(|name| p.balls().iter().find(|b| b.name == *name).unwrap().mean_3s)
        .sum();
    set(&mut p, "S1", true);
    set(&mut p, "S2", true);
    wait(&mut p, s(1));
    set(&mut p, "S1", false);
    set(&mut p, "S2", false);
    wait(&mut p, s(3));
    assert_eq!(p.balls_at(Place::Pan).len(), 2);
    assert!((p.mass_on_pan() - expected).abs() < 1e-9);
    assert!((p.real("Balance_g").unwrap() - expected).abs() < 0.4);
}

#[test]
fn a_deflector_moves_only_for_its_whole_stroke_and_never_against_its_partner() {
    let mut p = sorter(3);
    deflectors(&mut p, [false, false, false]);
    // 0.5 s is shorter than the stroke.
    wait(&mut p, s(1));
    pulse(&mut p, "S4", ms(500));
    assert_eq!(p.deflector_extended(1), Some(false));
    // Both solenoids of a pair: nothing moves.
    set(&mut p, "S4", true);
    set(&mut p, "S5", true);
    wait(&mut p, s(1));
    set(&mut p, "S4", false);
    set(&mut p, "S5", false);
    assert_eq!(p.deflector_extended(1), Some(false));
    pulse(&mut p, "S4", s(1));
    assert_eq!(p.deflector_extended(1), Some(true));
}

#[test]
fn the_shutter_empties_the_shafts_and_the_blower_lifts_only_through_a_closed_shutter() {
    let mut p = SorterPlant::new(SorterConfig {
        seed: 4,
        start: StartState::Shafts,
        ..SorterConfig::default()
    });
    for shaft in 1..=4 {
        assert_eq!(p.shaft(shaft).len(), 2);
    }
    assert!(!sensor(&p, "Sn1"));
    // The blower cannot lift balls that are in the shafts.
    pulse(&mut p, "Blower", s(4));
    assert!(p.upper().is_empty());
    pulse(&mut p, "SL2", ms(1500));
    wait(&mut p, s(1));
    assert!(p.shutter_open());
    assert_eq!(p.balls_at(Place::Lower).len(), 8);
    assert!(sensor(&p, "Sn4"));
    // Through an open shutter the air escapes: nothing is lifted.
    pulse(&mut p, "Blower", s(4));
    assert!(p.upper().is_empty());
    pulse(&mut p, "SL1", ms(1500));
    assert!(!p.shutter_open());
    // 1.5 s of blowing is too short; 4 s lifts them all.
    pulse(&mut p, "Blower", ms(1500));
    assert!(p.upper().is_empty());
    wait(&mut p, s(1));
    pulse(&mut p, "Blower", s(4));
    assert_eq!(p.upper().len(), 8);
    assert!(sensor(&p, "Sn1"));
    assert!(!sensor(&p, "Sn4"));
    // The run-down air disturbs the balance for 30 s.
    wait(&mut p, s(20));
    assert!(!sensor(&p, "Balance_stable"));
    wait(&mut p, s(11));
    assert!(sensor(&p, "Balance_stable"));
}

#[test]
fn tare_zeroes_only_a_stable_balance() {
    let mut p = sorter(5);
    p.console("dust 0.01").unwrap();
    wait(&mut p, s(60));
    let dusty = p.real("Balance_g").unwrap();
    assert!(dusty > 0.005, "{dusty}");
    pulse(&mut p, "Tare", s(1));
    wait(&mut p, s(1));
    assert!(p.real("Balance_g").unwrap().abs() < 0.001);
    dose(&mut p);
    wait(&mut p, s(1));
    let loaded = p.real("Balance_g").unwrap();
    pulse(&mut p, "Tare", s(1));
    wait(&mut p, s(1));
    assert!(
        (p.real("Balance_g").unwrap() - loaded).abs() < 0.2,
        "tare refused with a ball on the pan"
    );
    let notes = p.status().into_iter().find(|l| l.label == "notes").unwrap();
    assert!(
        notes.items.iter().any(|n| n.contains("tare refused")),
        "{notes:?}"
    );
}

#[test]
fn the_faults_of_section_13() {
    let mut p = sorter(6);
    // A light barrier that misses the ball; the weight still tells.
    p.console("miss Sn5").unwrap();
    dose(&mut p);
    wait(&mut p, s(3));
    assert!(!sensor(&p, "Sn5"));
    assert!(p.real("Balance_g").unwrap() > 2.0);
    p.console("clear miss Sn5").unwrap();
    assert!(sensor(&p, "Sn5"));
    pulse(&mut p, "S3", s(1));

    // Two balls dosed at once, once.
    p.console("double-dose").unwrap();
    dose(&mut p);
    assert_eq!(p.balls_at(Place::Pan).len(), 2);
    pulse(&mut p, "S3", s(1));
    dose(&mut p);
    assert_eq!(p.balls_at(Place::Pan).len(), 1);
    pulse(&mut p, "S3", s(1));

    // A stuck deflector.
    deflectors(&mut p, [false, false, false]);
    p.console("stuck D2").unwrap();
    pulse(&mut p, "S6", s(1));
    assert_eq!(p.deflector_extended(2), Some(false));
    p.console("clear stuck D2").unwrap();

    // The DP exchange: a command reaches the supervisor's input; a pulse marked lost
    // does not, the next one does; the actuator comes back as driven.
    set(&mut p, "Cmd_S3", true);
    assert!(sensor(&p, "DP_S3"));
    set(&mut p, "Cmd_S3", false);
    p.console("lose-pulse S3").unwrap();
    set(&mut p, "Cmd_S3", true);
    assert!(!sensor(&p, "DP_S3"), "lost");
    set(&mut p, "Cmd_S3", false);
    set(&mut p, "Cmd_S3", true);
    assert!(sensor(&p, "DP_S3"));
    set(&mut p, "Cmd_S3", false);
    set(&mut p, "S3", true);
    assert!(sensor(&p, "Fb_S3"));
    set(&mut p, "S3", false);
    p.console("dp-link-loss").unwrap();
    assert!(!p.read("DP_S3").unwrap().valid);
    assert!(!p.read("Fb_S3").unwrap().valid);
    p.console("clear dp-link-loss").unwrap();
    assert!(p.read("Fb_S3").unwrap().valid);

    // The gateway to the balance falls silent: its values turn invalid.
    p.console("balance-link-loss").unwrap();
    assert!(!p.read("Balance_g").unwrap().valid);
    assert!(p.input("Balance_g").is_err());
    p.console("clear all").unwrap();
    assert!(p.read("Balance_g").unwrap().valid);

    // Unknown names are refused with what is allowed.
    let error = p.console("stuck D4").unwrap_err().to_string();
    assert!(error.contains("D1, D2, D3"), "{error}");
    assert!(p.console("sing").is_err());
    assert!(p.set_output("Sn1", Value::Bool(true)).is_err());
    assert!(p.set_output("S1", Value::Real(1.0)).is_err());
}

/// A whole sorting by hand: init, then each ball to the shaft of its colour.
fn script(p: &mut SorterPlant, step: Duration) -> Vec<(String, u8)> {
    let run = |p: &mut SorterPlant, name: &str, on: bool, then: Duration| {
        p.set_output(name, Value::Bool(on)).unwrap();
        let until = p.now() + then;
        while p.now() < until {
            let next = (p.now() + step).min(until);
            p.advance_to(next).unwrap();
        }
    };
    for _ in 0..8 {
        run(p, "S1", true, s(1));
        run(p, "S1", false, ms(200));
        run(p, "S2", true, s(1));
        run(p, "S2", false, s(3));
        let weight = p.real("Balance_g").unwrap();
        let shaft = match weight {
            w if w < 2.505 => 1,
            w if w < 2.915 => 2,
            w if w < 3.305 => 3,
            _ => 4,
        };
        for k in 1..=3usize {
            let extend = k == shaft;
            let solenoid = if extend { 2 + 2 * k } else { 3 + 2 * k };
            run(p, &format!("S{solenoid}"), true, s(1));
            run(p, &format!("S{solenoid}"), false, ms(100));
        }
        run(p, "S3", true, s(1));
        run(p, "S3", false, ms(500));
    }
    p.arrivals()
        .iter()
        .map(|a| (a.ball.to_owned(), a.shaft))
        .collect()
}

#[test]
fn a_run_does_not_depend_on_the_step_size() {
    let reference = script(&mut sorter(11), ms(1));
    assert_eq!(reference.len(), 8);
    for step in [ms(7), ms(100), s(3)] {
        assert_eq!(script(&mut sorter(11), step), reference, "step {step:?}");
    }
    // Sorted by the balance's weight, most balls land in the shaft of their colour.
    let right = reference
        .iter()
        .filter(|(ball, shaft)| {
            let colour = ["red", "yellow", "blue", "green"]
                .iter()
                .position(|c| ball.starts_with(c))
                .unwrap();
            usize::from(*shaft) == colour + 1
        })
        .count();
    assert!(right >= 6, "{reference:?}");
}

#[test]
fn the_balance_port_carries_the_records_the_gateway_reads_and_falls_silent_with_the_link() {
    use devices::balance::record::{parse, RECORD_LEN};
    use plant::sorter::BALANCE_PORT;

    let mut p = sorter(5);
    let ports = p.serial_ports();
    assert_eq!(ports.len(), 1);
    assert_eq!(ports[0].name, BALANCE_PORT);
    assert_eq!(ports[0].line.baud, 1200);
    dose(&mut p);
    wait(&mut p, s(5));
    let octets = p.take_serial_output(BALANCE_PORT);
    // A reader that fell behind gets the newest records only, whole.
    assert_eq!(octets.len(), 4 * RECORD_LEN, "{octets:?}");
    let last = octets.chunks(RECORD_LEN).last().unwrap();
    let reading = parse(last.try_into().unwrap()).unwrap();
    assert_eq!(reading.weight_g, p.real("Balance_g").unwrap());
    assert_eq!(reading.stable, p.bool("Balance_stable").unwrap());
    assert!(reading.weight_g > 2.0, "a ball on the pan: {reading:?}");
    // Taken: nothing until the next record.
    assert!(p.take_serial_output(BALANCE_PORT).is_empty());
    wait(&mut p, s(1));
    let octets = p.take_serial_output(BALANCE_PORT);
    assert!(!octets.is_empty() && octets.len() % RECORD_LEN == 0);
    // The link lost: the port is silent.
    p.console("balance-link-loss").unwrap();
    p.take_serial_output(BALANCE_PORT);
    wait(&mut p, s(3));
    assert!(p.take_serial_output(BALANCE_PORT).is_empty());
    p.console("clear balance-link-loss").unwrap();
    wait(&mut p, s(1));
    assert!(!p.take_serial_output(BALANCE_PORT).is_empty());
    // Octets to the balance go nowhere; an unknown port is an error naming the ports.
    assert!(p.serial_input(BALANCE_PORT, b"T\r\n").is_ok());
    let error = p.serial_input("printer", b"x").unwrap_err();
    assert!(error.to_string().contains("balance"), "{error}");
}
