//! Energisation through the topology and its faults.

use std::time::Duration;

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

/// RS602 by-passes the 6 kV switchroom R6: with R6 out of service (its transformer feeder
/// Q3 open) the transformers stay fed from the line from TNS Ústí; the by-pass and Q3
/// lock each other out.
#[test]
fn rs602_bypasses_r6_for_maintenance() {
    let mut p = VsetinPlant::new();
    assert!(!get(&p, "RS602_Zapnut") && get(&p, "R6_Q3_Zapnut"));
    assert_eq!(
        p.operate(Action::Close("RS602".into())),
        Err(PlantError::Refused(
            "RS602: interlocked while R6_Q3 is closed; open it first".into()
        ))
    );
    // R6 out: the transformers lose their supply until the by-pass closes.
    p.operate(Action::Open("R6_Q3".into())).unwrap();
    at(&mut p, ms(100));
    assert!(!p.bus_live("T1_LV").unwrap() && !p.bus_live("T2_LV").unwrap());
    assert_eq!(real(&p, "R6_T_U"), 0.0);
    assert_eq!(real(&p, "R6_U"), 6000.0);
    p.operate(Action::Close("RS602".into())).unwrap();
    at(&mut p, ms(200));
    assert!(get(&p, "RS602_Zapnut"));
    assert_eq!(real(&p, "R6_T_U"), 6000.0);
    for bus in ["T1_LV", "T2_LV", "RZZ", "RH2", "ROV01"] {
        assert!(p.bus_live(bus).unwrap(), "{bus}");
    }
    // The switchroom itself can now go dead (both incomers open) and the station runs on.
    p.operate(Action::Open("R6_Q1".into())).unwrap();
    p.operate(Action::Open("R6_Q2".into())).unwrap();
    at(&mut p, ms(300));
    assert_eq!(real(&p, "R6_U"), 0.0);
    assert!(p.bus_live("RH2").unwrap());
    // On the by-pass only TNS Ústí feeds the station: losing it is losing the 6 kV level.
    p.inject(Fault::SupplyLoss("TNS_VALMEZ".into())).unwrap();
    assert!(p.bus_live("T1_LV").unwrap());
    p.inject(Fault::SupplyLoss("TNS_USTI".into())).unwrap();
    assert!(!p.bus_live("T1_LV").unwrap());
    p.clear_all();
    // Back: R6_Q3 is locked out until the by-pass opens.
    p.operate(Action::Close("R6_Q1".into())).unwrap();
    assert!(matches!(
        p.operate(Action::Close("R6_Q3".into())),
        Err(PlantError::Refused(m)) if m.contains("RS602")
    ));
    p.operate(Action::Open("RS602".into())).unwrap();
    p.operate(Action::Close("R6_Q3".into())).unwrap();
    at(&mut p, ms(400));
    assert_eq!(real(&p, "R6_T_U"), 6000.0);
    assert!(p.safety_log().is_empty(), "{:?}", p.safety_log());
}

/// The signalling equipment's universal source: from RZZ (TZ1) while it is live, from
/// RZS1 while it is not, never from both (RZS may run on the diesel set while RZZ is on
/// the grid).
#[test]
fn signalling_supply_changes_over_to_rzs1_and_back() {
    let mut p = VsetinPlant::new();
    assert!(get(&p, "UZ_K1_Zapnut") && !get(&p, "UZ_K2_Zapnut") && get(&p, "UZ_Vystup"));
    assert_eq!(real(&p, "SZZ_P_kW"), 4.0);
    // RZS on the mains (RDA's KM1), as the RDA logic holds it.
    set(&mut p, "RDA_KM1_Zap", true);
    at(&mut p, ms(100));
    assert!(p.bus_live("RZS").unwrap() && get(&p, "UZ_Napeti_RZS1"));
    let mut t = ms(100);
    let mut step = |p: &mut VsetinPlant, until: Duration| {
        while t < until {
            t += ms(5);
            at(p, t);
            assert!(
                !(get(p, "UZ_K1_Zapnut") && get(p, "UZ_K2_Zapnut")),
                "both inputs closed at {t:?}"
            );
        }
    };
    p.inject(Fault::SupplyLoss("T1".into())).unwrap();
    assert!(!p.bus_live("SZZ").unwrap(), "no break-less changeover");
    step(&mut p, ms(300));
    assert!(!get(&p, "UZ_K1_Zapnut") && get(&p, "UZ_K2_Zapnut"));
    assert!(p.bus_live("SZZ").unwrap() && get(&p, "UZ_Vystup"));
    p.clear(&Fault::SupplyLoss("T1".into())).unwrap();
    step(&mut p, ms(500));
    assert!(get(&p, "UZ_K1_Zapnut") && !get(&p, "UZ_K2_Zapnut"));
    // Both inputs dead: the equipment is unsupplied and says so.
    p.inject(Fault::SupplyLoss("T1".into())).unwrap();
    p.inject(Fault::SupplyLoss("UTILITY".into())).unwrap();
    step(&mut p, ms(800));
    assert!(!get(&p, "UZ_Vystup") && !get(&p, "UZ_K1_Zapnut") && !get(&p, "UZ_K2_Zapnut"));
    assert_eq!(real(&p, "SZZ_P_kW"), 0.0);
    assert_eq!(p.source_violations(), 0);
}

/// RH1.2, RZS2 and the boards in DT hang off RH1.1 and RZS: they follow their feeders,
/// and RH1.2/RZS2's QF1 obey their LOGO! coils as RH2's does.
#[test]
fn rh12_rzs2_and_the_dt_boards_follow_their_feeders() {
    let mut p = VsetinPlant::new();
    for b in ["RH12", "RHDT"] {
        assert!(p.bus_live(b).unwrap(), "{b}");
    }
    assert_eq!(real(&p, "RHDT_U"), 400.0);
    assert_eq!(real(&p, "RHDT_P_kW"), 20.0);
    assert!(get(&p, "RH12_P1_KHU1_Napeti_na_privodu") && get(&p, "RHDT_KHU1_Napeti"));
    // RZS2 and RZS in DT wait for RZS, as RZS1 does.
    assert!(!p.bus_live("RZS2").unwrap() && !p.bus_live("RZSDT").unwrap());
    set(&mut p, "RDA_KM1_Zap", true);
    at(&mut p, ms(100));
    assert!(p.bus_live("RZS2").unwrap() && p.bus_live("RZSDT").unwrap());
    assert!(get(&p, "RZSDT_KHU1_Napeti") && get(&p, "RZS2_P1_KHU3_Napeti_na_pripojeni"));
    // RH1.2's feeder breaker: the trip coil opens it, a close-coil edge recloses it.
    set(&mut p, "RH12_QF1_Vyp", true);
    at(&mut p, ms(200));
    assert!(!get(&p, "RH12_QF1_Zapnut") && !p.bus_live("RH12").unwrap());
    assert!(p.bus_live("RH11").unwrap());
    set(&mut p, "RH12_QF1_Vyp", false);
    set(&mut p, "RH12_QF1_Zap", true);
    at(&mut p, ms(300));
    assert!(get(&p, "RH12_QF1_Zapnut") && p.bus_live("RH12").unwrap());
    // The utility lost: everything on RH1.1 goes dark, the DT board included.
    p.inject(Fault::SupplyLoss("UTILITY".into())).unwrap();
    at(&mut p, ms(400));
    for b in ["RH12", "RHDT", "RZS2", "RZSDT"] {
        assert!(!p.bus_live(b).unwrap(), "{b}");
    }
    assert!(!get(&p, "RHDT_KHU1_Napeti"));
    // The DT board's incomer by hand.
    p.clear_all();
    p.operate(Action::Open("RHDT_QF1".into())).unwrap();
    at(&mut p, ms(500));
    assert!(!get(&p, "RHDT_QF1_Zapnut") && !p.bus_live("RHDT").unwrap());
}
