//! Energisation through the topology and its faults.

use plant::{Action, Fault, PlantError, SafetyKind, VsetinPlant};

use crate::{at, get, ms, real, s, set};

#[test]
fn initial_energisation() {
    let p = VsetinPlant::new();
    for bus in [
        "R6", "T1_LV", "T2_LV", "RZZ", "RZZ_A", "RH2", "RH2_V1", "RH11", "RH11_AB", "ROV01",
        "ROV12", "OR",
    ] {
        assert!(p.bus_live(bus).unwrap(), "{bus}");
    }
    // RZS waits for the RDA logic to close a contactor; the generator is stopped.
    assert!(!p.bus_live("RZS").unwrap());
    assert!(!p.bus_live("DA").unwrap());
    assert_eq!(real(&p, "RH2_U"), 400.0);
    assert_eq!(real(&p, "R6_U"), 6000.0);
    assert_eq!(real(&p, "RZS1_U"), 0.0);
    assert!(p.bus_live("nope").is_err());
}

#[test]
fn mains_loss_on_t1_kills_rzz_not_rh2() {
    let mut p = VsetinPlant::new();
    at(&mut p, s(1));
    p.inject(Fault::SupplyLoss("T1".into())).unwrap();
    at(&mut p, s(2));
    assert!(!p.bus_live("RZZ").unwrap());
    assert!(!p.bus_live("RZZ_A").unwrap());
    assert!(p.bus_live("RH2").unwrap());
    assert!(p.bus_live("ROV01").unwrap());
    assert!(!get(&p, "RZZ_P1_KHU1_Napeti_na_privodu"));
    assert!(!get(&p, "RZZ_P1_KHU3_Napeti_na_pripojeni"));
    assert!(get(&p, "RH2_P1_KHU1_Napeti_na_privodu"));
    assert!(get(&p, "RH2_P1_KHU3_Napeti_na_pripojeni"));
    // The breaker stays closed: loss of voltage is not a trip.
    assert!(get(&p, "RZZ_QF1_Zapnut"));
    assert_eq!(real(&p, "RZZ_U"), 0.0);
    p.clear(&Fault::SupplyLoss("T1".into())).unwrap();
    assert!(p.bus_live("RZZ").unwrap());
    // And T2 the other way round.
    p.inject(Fault::SupplyLoss("T2".into())).unwrap();
    assert!(p.bus_live("RZZ").unwrap());
    assert!(!p.bus_live("RH2").unwrap());
    assert!(!p.bus_live("ROV07").unwrap());
}

#[test]
fn both_traction_feeds_needed_to_lose_r6() {
    let mut p = VsetinPlant::new();
    p.inject(Fault::SupplyLoss("TNS_USTI".into())).unwrap();
    assert!(p.bus_live("R6").unwrap());
    p.inject(Fault::SupplyLoss("TNS_VALMEZ".into())).unwrap();
    for bus in ["R6", "T1_LV", "T2_LV", "RZZ", "RH2"] {
        assert!(!p.bus_live(bus).unwrap(), "{bus}");
    }
    // The utility side is independent.
    assert!(p.bus_live("RH11").unwrap());
}

#[test]
fn branch_breaker_trip_cuts_its_towers_only() {
    let mut p = VsetinPlant::new();
    p.inject(Fault::BreakerTripped("RH2_FA1.2".into())).unwrap();
    at(&mut p, ms(40));
    assert!(!get(&p, "RH2_V1_FA1.2"));
    for b in ["ROV04", "ROV05", "ROV06"] {
        assert!(!p.bus_live(b).unwrap(), "{b}");
    }
    assert!(p.bus_live("ROV03").unwrap());
    assert!(p.bus_live("ROV07").unwrap());
    // Cannot be reclosed by hand while the fault is active; clearing recloses it.
    assert!(matches!(
        p.operate(Action::Close("RH2_FA1.2".into())),
        Err(PlantError::Refused(_))
    ));
    p.clear(&Fault::BreakerTripped("RH2_FA1.2".into())).unwrap();
    assert!(get(&p, "RH2_V1_FA1.2"));
    assert!(p.bus_live("ROV05").unwrap());
    // Manual breakers open and close by hand at once.
    p.operate(Action::Open("RH2_FA1".into())).unwrap();
    assert!(!get(&p, "RH2_V1_FA1_Zapnut"));
    assert!(!p.bus_live("OR").unwrap());
    p.operate(Action::Close("RH2_FA1".into())).unwrap();
    assert!(p.bus_live("OR").unwrap());
}

#[test]
fn emergency_off_trips_feeder_and_blocks_closing() {
    let mut p = VsetinPlant::new();
    at(&mut p, s(1));
    p.inject(Fault::EmergencyOff("RH2".into())).unwrap();
    assert!(get(&p, "RH2_P1_KHVRH2_Havarijni_vypnuti"));
    at(&mut p, s(1) + ms(40));
    assert!(!get(&p, "RH2_QF1_Zapnut"));
    set(&mut p, "RH2_QF1_Zap", true);
    at(&mut p, s(2));
    assert!(!get(&p, "RH2_QF1_Zapnut"));
    p.clear(&Fault::EmergencyOff("RH2".into())).unwrap();
    set(&mut p, "RH2_QF1_Zap", false);
    set(&mut p, "RH2_QF1_Zap", true);
    at(&mut p, s(3));
    assert!(get(&p, "RH2_QF1_Zapnut"));
}

#[test]
fn rda_emergency_off_drops_both_contactors() {
    let mut p = VsetinPlant::new();
    set(&mut p, "RDA_KM1_Zap", true);
    at(&mut p, s(1));
    assert!(p.bus_live("RZS").unwrap());
    p.inject(Fault::EmergencyOff("RDA".into())).unwrap();
    at(&mut p, s(2));
    assert!(!get(&p, "RDA_KM1_Zapnut"));
    assert!(!p.bus_live("RZS").unwrap());
    p.clear(&Fault::EmergencyOff("RDA".into())).unwrap();
    at(&mut p, s(3));
    assert!(get(&p, "RDA_KM1_Zapnut"));
}

#[test]
fn door_pushbuttons_only_in_local() {
    let mut p = VsetinPlant::new();
    assert!(get(&p, "RH2_P1_SA1_Dalkove"));
    assert!(!get(&p, "RH2_P1_SA1_Mistne"));
    assert!(matches!(
        p.operate(Action::Open("RH2_QF1".into())),
        Err(PlantError::Refused(_))
    ));
    p.operate(Action::SetSelector {
        board: "RH2".into(),
        remote: false,
    })
    .unwrap();
    assert!(get(&p, "RH2_P1_SA1_Mistne"));
    assert!(!get(&p, "RH2_P1_SA1_Dalkove"));
    p.operate(Action::Open("RH2_QF1".into())).unwrap();
    at(&mut p, ms(40));
    assert!(!get(&p, "RH2_QF1_Zapnut"));
    p.operate(Action::Close("RH2_QF1".into())).unwrap();
    at(&mut p, ms(100));
    assert!(get(&p, "RH2_QF1_Zapnut"));
}

#[test]
fn stuck_breaker_ignores_coils() {
    let mut p = VsetinPlant::new();
    p.inject(Fault::StuckClosed("RZZ_QF1".into())).unwrap();
    set(&mut p, "RZZ_QF1_Vyp", true);
    at(&mut p, s(1));
    assert!(get(&p, "RZZ_QF1_Zapnut"));
    assert!(p.bus_live("RZZ").unwrap());
    p.clear(&Fault::StuckClosed("RZZ_QF1".into())).unwrap();
    at(&mut p, s(1) + ms(40));
    assert!(!get(&p, "RZZ_QF1_Zapnut"));
    p.inject(Fault::StuckOpen("RH2_QF1".into())).unwrap();
    assert!(!get(&p, "RH2_QF1_Zapnut"));
    set(&mut p, "RH2_QF1_Zap", true);
    at(&mut p, s(3));
    assert!(!get(&p, "RH2_QF1_Zapnut"));
}

#[test]
fn closing_both_rda_contactors_is_recorded() {
    let mut p = VsetinPlant::new();
    set(&mut p, "RDA_KM1_Zap", true);
    set(&mut p, "RDA_KM2_Zap", true);
    at(&mut p, s(1));
    assert!(p.sources_joined());
    let first = p
        .safety_log()
        .iter()
        .find_map(|e| match &e.kind {
            SafetyKind::SourcesConnected {
                sources,
                both_live,
                buses,
            } => Some((e.at, sources.clone(), *both_live, buses.clone())),
            _ => None,
        })
        .unwrap();
    // Both contactors closed at 30 ms; the generator is stopped: back-feed, not parallel.
    assert_eq!(first.0, ms(30));
    assert_eq!(first.1, vec!["DA".to_string(), "UTILITY".to_string()]);
    assert!(!first.2);
    assert!(first.3.contains(&"RZS".to_string()));
    // The generator starts into the joined network: now a true paralleling.
    set(&mut p, "RDA_DA_Start", true);
    at(&mut p, s(10));
    assert!(p.safety_log().iter().any(|e| matches!(
        &e.kind,
        SafetyKind::SourcesConnected {
            both_live: true,
            ..
        }
    ) && e.at == s(6)));
    set(&mut p, "RDA_KM2_Zap", false);
    at(&mut p, s(11));
    assert!(!p.sources_joined());
    assert!(matches!(
        p.safety_log().last().unwrap().kind,
        SafetyKind::SourcesSeparated { .. }
    ));
    assert_eq!(p.source_violations(), 2);
}
