//! Timing of each device model, exact to the nanosecond and independent of step size.

use plant::{Fault, GeneratorState, Plant, SafetyKind, VsetinPlant};

use crate::{at, get, ms, real, s, set};

const NS: std::time::Duration = std::time::Duration::from_nanos(1);

#[test]
fn breaker_feedback_exactly_after_operate_time() {
    let mut p = VsetinPlant::new();
    assert!(get(&p, "RH2_QF1_Zapnut"));
    at(&mut p, s(1));
    set(&mut p, "RH2_QF1_Vyp", true);
    assert_eq!(p.next_event(), Some(s(1) + ms(40)));
    at(&mut p, s(1) + ms(40) - NS);
    assert!(get(&p, "RH2_QF1_Zapnut"));
    assert!(p.bus_live("RH2").unwrap());
    at(&mut p, s(1) + ms(40));
    assert!(!get(&p, "RH2_QF1_Zapnut"));
    assert!(!p.bus_live("RH2").unwrap());
    set(&mut p, "RH2_QF1_Vyp", false);
    at(&mut p, s(2));
    set(&mut p, "RH2_QF1_Zap", true);
    at(&mut p, s(2) + ms(60) - NS);
    assert!(!get(&p, "RH2_QF1_Zapnut"));
    at(&mut p, s(2) + ms(60));
    assert!(get(&p, "RH2_QF1_Zapnut"));
    assert!(p.bus_live("RH2").unwrap());
}

#[test]
fn breaker_anti_pumping_and_trip_free() {
    let mut p = VsetinPlant::new();
    set(&mut p, "RZZ_QF1_Vyp", true);
    at(&mut p, s(1));
    assert!(!get(&p, "RZZ_QF1_Zapnut"));
    // Close held while the trip coil is energised: trip-free, nothing closes.
    set(&mut p, "RZZ_QF1_Zap", true);
    at(&mut p, s(2));
    assert!(!get(&p, "RZZ_QF1_Zapnut"));
    assert!(p.safety_log().iter().any(|e| e.kind
        == SafetyKind::BothCoils {
            breaker: "RZZ_QF1".into()
        }));
    // Trip released, close still held: anti-pumping, no re-close without a new edge.
    set(&mut p, "RZZ_QF1_Vyp", false);
    at(&mut p, s(3));
    assert!(!get(&p, "RZZ_QF1_Zapnut"));
    set(&mut p, "RZZ_QF1_Zap", false);
    set(&mut p, "RZZ_QF1_Zap", true);
    at(&mut p, s(3) + ms(60));
    assert!(get(&p, "RZZ_QF1_Zapnut"));
    // A trip during closing aborts it.
    set(&mut p, "RZZ_QF1_Zap", false);
    set(&mut p, "RZZ_QF1_Vyp", true);
    at(&mut p, s(4));
    set(&mut p, "RZZ_QF1_Vyp", false);
    set(&mut p, "RZZ_QF1_Zap", true);
    at(&mut p, s(4) + ms(30));
    set(&mut p, "RZZ_QF1_Vyp", true);
    at(&mut p, s(5));
    assert!(!get(&p, "RZZ_QF1_Zapnut"));
}

#[test]
fn contactor_pickup_dropout_and_short_pulse() {
    let mut p = VsetinPlant::new();
    at(&mut p, s(1));
    set(&mut p, "RDA_KM1_Zap", true);
    at(&mut p, s(1) + ms(30) - NS);
    assert!(!get(&p, "RDA_KM1_Zapnut"));
    at(&mut p, s(1) + ms(30));
    assert!(get(&p, "RDA_KM1_Zapnut"));
    assert!(p.bus_live("RZS").unwrap());
    set(&mut p, "RDA_KM1_Zap", false);
    at(&mut p, s(1) + ms(50) - NS);
    assert!(get(&p, "RDA_KM1_Zapnut"));
    at(&mut p, s(1) + ms(50));
    assert!(!get(&p, "RDA_KM1_Zapnut"));
    // A 10 ms pulse is shorter than the pick-up time.
    at(&mut p, s(2));
    set(&mut p, "RDA_KM1_Zap", true);
    at(&mut p, s(2) + ms(10));
    set(&mut p, "RDA_KM1_Zap", false);
    at(&mut p, s(3));
    assert!(!get(&p, "RDA_KM1_Zapnut"));
}

#[test]
fn voltage_relay_follows_bus_after_relay_time() {
    let mut p = VsetinPlant::new();
    at(&mut p, s(1));
    assert!(get(&p, "RZZ_P1_KHU1_Napeti_na_privodu"));
    p.inject(Fault::SupplyLoss("T1".into())).unwrap();
    at(&mut p, s(1) + ms(20) - NS);
    assert!(get(&p, "RZZ_P1_KHU1_Napeti_na_privodu"));
    at(&mut p, s(1) + ms(20));
    assert!(!get(&p, "RZZ_P1_KHU1_Napeti_na_privodu"));
}

#[test]
fn generator_start_voltage_build_and_settle_exact() {
    let mut p = VsetinPlant::new();
    let t0 = s(10);
    at(&mut p, t0);
    set(&mut p, "RDA_DA_Start", true);
    assert!(matches!(
        p.generator_state(),
        GeneratorState::Cranking { .. }
    ));
    // Cranking: start delay 5 s.
    at(&mut p, t0 + s(5) - NS);
    assert!(!get(&p, "RDA_DA_Bezi"));
    assert_eq!(real(&p, "RDA_DA_U"), 0.0);
    at(&mut p, t0 + s(5));
    assert!(get(&p, "RDA_DA_Bezi"));
    assert!(!get(&p, "RDA_DA_Pripraven"));
    // Voltage builds linearly to 90 % in 1 s.
    at(&mut p, t0 + s(5) + ms(500));
    assert!((real(&p, "RDA_DA_U") - 180.0).abs() < 1e-9);
    at(&mut p, t0 + s(6));
    assert!((real(&p, "RDA_DA_U") - 360.0).abs() < 1e-9);
    // The voltage relay picks up its relay time after 90 %.
    at(&mut p, t0 + s(6) + ms(20) - NS);
    assert!(!get(&p, "RDA_KHU2_Napeti_DA"));
    at(&mut p, t0 + s(6) + ms(20));
    assert!(get(&p, "RDA_KHU2_Napeti_DA"));
    // Overshoot to 106 % half-way between build and settle (at 5 + 3.5 s).
    at(&mut p, t0 + s(8) + ms(500));
    assert!((real(&p, "RDA_DA_U") - 424.0).abs() < 1e-9);
    // Settled exactly at start delay + settle time.
    at(&mut p, t0 + s(11) - NS);
    assert!(!get(&p, "RDA_DA_Pripraven"));
    at(&mut p, t0 + s(11));
    assert!(get(&p, "RDA_DA_Pripraven"));
    assert_eq!(real(&p, "RDA_DA_U"), 400.0);
}

#[test]
fn generator_cool_down_then_stop() {
    let mut p = VsetinPlant::new();
    set(&mut p, "RDA_DA_Start", true);
    at(&mut p, s(20));
    assert!(get(&p, "RDA_DA_Pripraven"));
    set(&mut p, "RDA_DA_Start", false);
    at(&mut p, s(80) - NS);
    assert!(get(&p, "RDA_DA_Bezi"));
    assert_eq!(real(&p, "RDA_DA_U"), 400.0);
    at(&mut p, s(80));
    assert!(!get(&p, "RDA_DA_Bezi"));
    assert_eq!(real(&p, "RDA_DA_U"), 0.0);
    assert_eq!(p.generator_state(), GeneratorState::Stopped);
    // A start during cool-down keeps it running (no new cranking).
    set(&mut p, "RDA_DA_Start", true);
    at(&mut p, s(100));
    set(&mut p, "RDA_DA_Start", false);
    at(&mut p, s(110));
    set(&mut p, "RDA_DA_Start", true);
    assert!(get(&p, "RDA_DA_Pripraven"));
}

#[test]
fn generator_fails_to_start_and_restarts_after_clear() {
    let mut p = VsetinPlant::new();
    p.inject(Fault::GeneratorFailToStart).unwrap();
    set(&mut p, "RDA_DA_Start", true);
    at(&mut p, s(5) - NS);
    assert!(!get(&p, "RDA_DA_Porucha"));
    at(&mut p, s(5));
    assert!(get(&p, "RDA_DA_Porucha"));
    assert!(!get(&p, "RDA_DA_Bezi"));
    at(&mut p, s(100));
    assert!(!get(&p, "RDA_KHU2_Napeti_DA"));
    p.clear(&Fault::GeneratorFailToStart).unwrap();
    assert!(!get(&p, "RDA_DA_Porucha"));
    at(&mut p, s(105));
    assert!(get(&p, "RDA_DA_Bezi"));
    at(&mut p, s(111));
    assert!(get(&p, "RDA_DA_Pripraven"));
}

#[test]
fn lamp_feedback_and_warm_up() {
    let mut p = VsetinPlant::new();
    at(&mut p, s(1));
    set(&mut p, "ROV01_OvladanyQ", true);
    // contactor 30 ms, then feedback relay 50 ms.
    at(&mut p, s(1) + ms(80) - NS);
    assert!(!get(&p, "ROV01_PrRele"));
    at(&mut p, s(1) + ms(80));
    assert!(get(&p, "ROV01_PrRele"));
    // warm-up 3 s from energisation (t = 1.030 s).
    at(&mut p, s(1) + ms(30) + ms(1500));
    assert!((real(&p, "ROV01_Svit_pct") - 50.0).abs() < 1e-9);
    at(&mut p, s(1) + ms(30) + s(3));
    assert_eq!(real(&p, "ROV01_Svit_pct"), 100.0);
    assert_eq!(real(&p, "ROV01_P_kW"), 2.4);
    // 2.4 kW three-phase at 400 V.
    assert!((real(&p, "ROV01_I_A") - 3.464_101_6).abs() < 1e-6);
    // Off: contactor drops after 20 ms, feedback at once with it.
    set(&mut p, "ROV01_OvladanyQ", false);
    at(&mut p, s(5) + ms(20));
    assert!(!get(&p, "ROV01_PrRele"));
    assert_eq!(real(&p, "ROV01_Svit_pct"), 0.0);
}

/// The same command script stepped coarsely, finely and by events gives identical inputs
/// at every check point.
#[test]
fn results_do_not_depend_on_step_size() {
    fn run(
        step: Option<std::time::Duration>,
    ) -> Vec<std::collections::BTreeMap<String, plant::Reading>> {
        let script: Vec<(u64, &str, bool)> = vec![
            (1_000, "RDA_KM1_Zap", true),
            (1_013, "ROV02_OvladanyQ", true),
            (2_000, "RDA_DA_Start", true),
            (3_333, "RH2_QF1_Vyp", true),
            (3_400, "RH2_QF1_Vyp", false),
            (4_001, "RH2_QF1_Zap", true),
            (9_999, "RDA_KM1_Zap", false),
            (14_000, "RDA_KM2_Zap", true),
            (20_000, "RDA_DA_Start", false),
        ];
        let checks: Vec<u64> = (0..100).map(|i| i * 777).collect();
        let mut p = VsetinPlant::new();
        let mut out = Vec::new();
        let mut events: Vec<(u64, Option<(&str, bool)>)> = script
            .iter()
            .map(|&(t, n, v)| (t, Some((n, v))))
            .chain(checks.iter().map(|&t| (t, None)))
            .collect();
        events.sort_by_key(|e| (e.0, e.1.is_none()));
        for (t, what) in events {
            let target = ms(t);
            match step {
                Some(dt) => {
                    while p.now() + dt < target {
                        let n = p.now() + dt;
                        p.advance_to(n).unwrap();
                    }
                    p.advance_to(target).unwrap();
                }
                None => {
                    while let Some(e) = p.next_event().filter(|e| *e < target) {
                        p.advance_to(e).unwrap();
                    }
                    p.advance_to(target).unwrap();
                }
            }
            match what {
                Some((n, v)) => set(&mut p, n, v),
                None => out.push(p.inputs()),
            }
        }
        out
    }
    let coarse = run(None);
    assert_eq!(coarse, run(Some(ms(1))));
    assert_eq!(coarse, run(Some(ms(7))));
    assert_eq!(coarse, run(Some(s(3))));
}
