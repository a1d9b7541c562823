//! Lighting towers: feedback relay, lamp and fuse failures, stuck contactor, manual switch,
//! pulled module, dusk sensor.

use std::time::Duration;

use plant::{lighting_boards, Action, Fault, Plant, PlantError, Value, VsetinPlant};

use crate::{at, get, ms, s, set};

/// The fault supervision of spec §4.10 as the test's stand-in PLC:
/// `Osv_PorTON(IN := Osv_Zap AND NOT PrRele, PT := 5 s)`, scanned every 10 ms.
fn fault_time(p: &mut VsetinPlant, board: &str, until: Duration) -> Option<Duration> {
    let mut since: Option<Duration> = None;
    while p.now() < until {
        let cmd = get(p, &format!("{board}_OvladanyQ"));
        let fb = p
            .input(&format!("{board}_PrRele"))
            .map(|v| v == Value::Bool(true))
            .unwrap_or(false);
        if cmd && !fb {
            let t0 = *since.get_or_insert(p.now());
            if p.now() >= t0 + s(5) {
                return Some(p.now());
            }
        } else {
            since = None;
        }
        let n = p.now() + ms(10);
        at(p, n);
    }
    None
}

#[test]
fn lamp_failure_drops_feedback_and_fault_timer_sees_it() {
    let mut p = VsetinPlant::new();
    set(&mut p, "ROV03_OvladanyQ", true);
    assert_eq!(fault_time(&mut p, "ROV03", s(60)), None);
    assert!(get(&p, "ROV03_PrRele"));
    p.inject(Fault::LampFailure("ROV03".into())).unwrap();
    assert!(!get(&p, "ROV03_PrRele"));
    assert_eq!(p.real("ROV03_P_kW").unwrap(), 0.0);
    assert_eq!(fault_time(&mut p, "ROV03", s(120)), Some(s(65)));
    // Other towers unaffected.
    assert!(get(&p, "ROV04_Napeti"));
    p.clear(&Fault::LampFailure("ROV03".into())).unwrap();
    at(&mut p, s(121));
    assert!(get(&p, "ROV03_PrRele"));
}

#[test]
fn fuse_blown_cuts_lamps_and_is_indicated() {
    let mut p = VsetinPlant::new();
    set(&mut p, "OR_OvladanyQ", true);
    at(&mut p, s(1));
    assert!(get(&p, "OR_PrRele"));
    p.inject(Fault::FuseBlown("OR_FU1".into())).unwrap();
    assert!(get(&p, "OR_FU1_Pretavena_pojistka"));
    assert!(!get(&p, "OR_PrRele"));
    // A board fuse is indication only.
    p.inject(Fault::FuseBlown("RH2_FU1".into())).unwrap();
    assert!(get(&p, "RH2_P1_FU1_Pretavena_pojistka"));
    assert!(p.bus_live("RH2").unwrap());
}

#[test]
fn stuck_lighting_contactor() {
    let mut p = VsetinPlant::new();
    p.inject(Fault::StuckOpen("ROV07_KM1".into())).unwrap();
    set(&mut p, "ROV07_OvladanyQ", true);
    assert_eq!(fault_time(&mut p, "ROV07", s(30)), Some(s(5)));
    assert!(!get(&p, "ROV07_KM1_Zapnut"));
    p.clear(&Fault::StuckOpen("ROV07_KM1".into())).unwrap();
    at(&mut p, s(31));
    assert!(get(&p, "ROV07_PrRele"));
    // Welded: stays on after the command is removed.
    p.inject(Fault::StuckClosed("ROV07_KM1".into())).unwrap();
    set(&mut p, "ROV07_OvladanyQ", false);
    at(&mut p, s(40));
    assert!(get(&p, "ROV07_PrRele"));
    assert!(p.real("ROV07_P_kW").unwrap() > 0.0);
}

#[test]
fn manual_switch_lights_without_plc() {
    let mut p = VsetinPlant::new();
    p.operate(Action::SetManualSwitch {
        board: "ROV09".into(),
        on: true,
    })
    .unwrap();
    at(&mut p, s(1));
    assert!(get(&p, "ROV09_Rucne_Zap"));
    assert!(get(&p, "ROV09_PrRele"));
    assert!(!get(&p, "ROV09_KM1_Zapnut"));
    p.operate(Action::SetSelector {
        board: "ROV09".into(),
        remote: false,
    })
    .unwrap();
    assert!(!get(&p, "ROV09_Dalkove"));
}

#[test]
fn module_pulled_invalidates_inputs_and_drops_outputs() {
    let mut p = VsetinPlant::new();
    set(&mut p, "ROV05_OvladanyQ", true);
    at(&mut p, s(1));
    assert!(get(&p, "ROV05_PrRele"));
    p.inject(Fault::ModulePulled("ROV05_PLC".into())).unwrap();
    assert!(matches!(
        p.input("ROV05_PrRele"),
        Err(PlantError::ModuleUnavailable { ref module, .. }) if module == "ROV05_PLC"
    ));
    assert!(!p.read("ROV05_Cidlo").unwrap().valid);
    assert!(!p.read("ROV05_OvladanyQ").unwrap().valid);
    assert!(p.read("ROV06_PrRele").unwrap().valid);
    // The output module is dead, so the contactor drops and the lamps go out.
    at(&mut p, s(2));
    assert!(!p.read("ROV05_PrRele").unwrap().value.as_bool().unwrap());
    let invalid: Vec<String> = p
        .inputs()
        .into_iter()
        .filter(|(_, r)| !r.valid)
        .map(|(n, _)| n)
        .collect();
    assert!(invalid.iter().all(|n| n.starts_with("ROV05_")));
    assert_eq!(invalid.len(), 15);
    p.clear(&Fault::ModulePulled("ROV05_PLC".into())).unwrap();
    at(&mut p, s(3));
    assert_eq!(p.input("ROV05_PrRele").unwrap(), Value::Bool(true));
}

#[test]
fn dusk_sensor_follows_the_sun_exactly() {
    // Default start 2024-01-01T00:00Z. Vsetín sunset is about 15:08 UTC that day.
    let mut p = VsetinPlant::new();
    assert!(get(&p, "ROV01_Cidlo"), "dark at midnight");
    at(&mut p, s(12 * 3600));
    assert!(!get(&p, "ROV01_Cidlo"), "light at noon");
    assert!(p.real("ENV_Osvetlenost_lx").unwrap() > 10_000.0);
    let mut t = p.now();
    while !get(&p, "ROV01_Cidlo") {
        t = p.next_event().unwrap();
        at(&mut p, t);
    }
    // Flipped at an event, between 15:00 and 16:00 UTC, every board at the same instant.
    assert!(t > s(15 * 3600) && t < s(16 * 3600), "{t:?}");
    for b in lighting_boards() {
        assert!(get(&p, &format!("{b}_Cidlo")));
    }
    p.advance_to(t - Duration::from_nanos(1)).unwrap_err();
    let lux = p.real("ENV_Osvetlenost_lx").unwrap();
    assert!((lux - 20.0).abs() < 0.01, "{lux}");
    // A forced illuminance overrides the sky.
    p.operate(Action::SetIlluminance(Some(5_000.0))).unwrap();
    assert!(!get(&p, "ROV01_Cidlo"));
    p.operate(Action::SetIlluminance(None)).unwrap();
    assert!(get(&p, "ROV01_Cidlo"));
}

#[test]
fn communication_lost_invalidates_but_the_field_keeps_running() {
    let mut p = VsetinPlant::new();
    set(&mut p, "ROV08_OvladanyQ", true);
    at(&mut p, s(1));
    p.inject(Fault::CommunicationLost("ROV08_PLC".into()))
        .unwrap();
    assert!(!p.read("ROV08_PrRele").unwrap().valid);
    assert!(p.input("ROV08_Cidlo").is_err());
    at(&mut p, s(10));
    // Unlike a pulled module, the outputs stay: the lamps are still lit.
    assert!(p.read("ROV08_PrRele").unwrap().value.as_bool().unwrap());
    let m = p.modules().iter().find(|m| m.name == "ROV08_PLC").unwrap();
    assert!(m.present && !m.linked && !m.valid());
    p.clear(&Fault::CommunicationLost("ROV08_PLC".into()))
        .unwrap();
    assert_eq!(p.input("ROV08_PrRele").unwrap(), Value::Bool(true));
}
