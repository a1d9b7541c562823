//! The RH2 LOGO! breaker logic of spec §5.1, written in the test as the PLC would run it,
//! against the plant: emergency off dominates, no effect in local, never both coils.

use plant::{Action, Fault, Plant, SafetyKind, VsetinPlant};

use crate::{at, get, ms, set};

/// `QF1_OFF := HavarijniVyp OR (SA1_Dalkove AND Cmd_Vyp)`,
/// `QF1_ON := SA1_Dalkove AND Cmd_Zap AND NOT QF1_OFF`.
fn scan(p: &mut VsetinPlant, cmd_off: bool, cmd_on: bool) {
    let estop = get(p, "RH2_P1_KHVRH2_Havarijni_vypnuti");
    let remote = get(p, "RH2_P1_SA1_Dalkove");
    let off = estop || (remote && cmd_off);
    let on = remote && cmd_on && !off;
    set(p, "RH2_QF1_Vyp", off);
    set(p, "RH2_QF1_Zap", on);
}

fn run(p: &mut VsetinPlant, cmd_off: bool, cmd_on: bool, scans: u32) {
    for _ in 0..scans {
        scan(p, cmd_off, cmd_on);
        let n = p.now() + ms(10);
        at(p, n);
    }
}

#[test]
fn rh2_breaker_logic_truth_table_against_the_plant() {
    let mut p = VsetinPlant::new();
    // Remote open, then remote close.
    run(&mut p, true, false, 10);
    assert!(!get(&p, "RH2_QF1_Zapnut"));
    assert!(!p.bus_live("RH2").unwrap());
    run(&mut p, false, false, 2);
    run(&mut p, false, true, 10);
    assert!(get(&p, "RH2_QF1_Zapnut"));
    // Both commands at once: open wins, and the LOGO! never energises both coils.
    run(&mut p, false, false, 2);
    run(&mut p, true, true, 10);
    assert!(!get(&p, "RH2_QF1_Zapnut"));
    // Local: remote commands do nothing.
    run(&mut p, false, false, 2);
    p.operate(Action::SetSelector {
        board: "RH2".into(),
        remote: false,
    })
    .unwrap();
    run(&mut p, false, true, 10);
    assert!(!get(&p, "RH2_QF1_Zapnut"));
    // Door pushbutton in local works.
    p.operate(Action::Close("RH2_QF1".into())).unwrap();
    run(&mut p, false, false, 10);
    assert!(get(&p, "RH2_QF1_Zapnut"));
    // Emergency off dominates even in local and with a close command held.
    p.inject(Fault::EmergencyOff("RH2".into())).unwrap();
    p.operate(Action::SetSelector {
        board: "RH2".into(),
        remote: true,
    })
    .unwrap();
    run(&mut p, false, true, 10);
    assert!(!get(&p, "RH2_QF1_Zapnut"));
    assert!(!p
        .safety_log()
        .iter()
        .any(|e| matches!(e.kind, SafetyKind::BothCoils { .. })));
}
