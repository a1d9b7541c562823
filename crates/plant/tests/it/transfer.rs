//! RDA transfer driven by a hand-written controller standing in for the PLC: the state
//! machine of spec §5.3 with the default delays, scanned every 10 ms.

use std::time::Duration;

use plant::{Fault, Plant, SafetyKind, VsetinPlant};

use crate::{at, get, ms, real, s, set};

#[derive(Debug, Clone, Copy, PartialEq)]
enum St {
    Mains,
    TransferOut,
    WaitSettle,
    Da,
    Retransfer,
}

/// The controller of spec §5.3 (T_loss 1 s, T_settle 10 s, T_return 60 s). With
/// `interlock = false` it "forgets" rule 1 and closes the diesel contactor without
/// opening the mains one first.
struct Rda {
    st: St,
    since: Duration,
    mains_ok_since: Option<Duration>,
    mains_lost_since: Option<Duration>,
    da_ok_since: Option<Duration>,
    interlock: bool,
    log: Vec<(Duration, St)>,
}

impl Rda {
    fn new(interlock: bool) -> Self {
        Rda {
            st: St::Mains,
            since: Duration::ZERO,
            mains_ok_since: Some(Duration::ZERO),
            mains_lost_since: None,
            da_ok_since: None,
            interlock,
            log: vec![],
        }
    }

    fn go(&mut self, now: Duration, st: St) {
        self.st = st;
        self.since = now;
        self.log.push((now, st));
    }

    fn scan(&mut self, p: &mut VsetinPlant) {
        let now = p.now();
        let mains = get(p, "RDA_KHU1_Napeti_sit");
        let da = get(p, "RDA_KHU2_Napeti_DA");
        let km1 = get(p, "RDA_KM1_Zapnut");
        let km2 = get(p, "RDA_KM2_Zapnut");
        self.mains_ok_since = if mains {
            self.mains_ok_since.or(Some(now))
        } else {
            None
        };
        self.mains_lost_since = if mains {
            None
        } else {
            self.mains_lost_since.or(Some(now))
        };
        self.da_ok_since = if da {
            self.da_ok_since.or(Some(now))
        } else {
            None
        };
        let held = |x: Option<Duration>, d: Duration| x.is_some_and(|t| now >= t + d);
        match self.st {
            St::Mains if held(self.mains_lost_since, s(1)) => self.go(now, St::TransferOut),
            St::TransferOut if da => self.go(now, St::WaitSettle),
            St::WaitSettle if !da => self.go(now, St::TransferOut),
            St::WaitSettle if held(self.da_ok_since, s(10)) && (!km1 || !self.interlock) => {
                self.go(now, St::Da)
            }
            St::Da if held(self.mains_ok_since, s(60)) => self.go(now, St::Retransfer),
            St::Retransfer if !km2 => self.go(now, St::Mains),
            _ => {}
        }
        let (q_mains, q_da, start) = match self.st {
            St::Mains => (true, false, false),
            St::TransferOut => (!self.interlock, false, true),
            St::WaitSettle => (!self.interlock, false, true),
            St::Da => (!self.interlock && get(p, "RDA_KM1_Zapnut"), true, true),
            St::Retransfer => (false, false, false),
        };
        // Rule 1: each close output only while the other contactor is open.
        let q_mains = q_mains && (!self.interlock || !km2);
        let q_da = q_da && (!self.interlock || !km1);
        set(p, "RDA_KM1_Zap", q_mains);
        set(p, "RDA_KM2_Zap", q_da);
        set(p, "RDA_DA_Start", start);
    }
}

fn run(p: &mut VsetinPlant, c: &mut Rda, until: Duration, mut check: impl FnMut(&VsetinPlant)) {
    while p.now() < until {
        c.scan(p);
        check(p);
        let n = p.now() + ms(10);
        at(p, n);
    }
}

#[test]
fn mains_loss_transfer_to_diesel_and_back() {
    let mut p = VsetinPlant::new();
    let mut c = Rda::new(true);
    let mut never_both = |p: &VsetinPlant| {
        assert!(
            !(get(p, "RDA_KM1_Zapnut") && get(p, "RDA_KM2_Zapnut")),
            "both closed at {:?}",
            p.now()
        );
    };
    run(&mut p, &mut c, s(60), &mut never_both);
    assert!(p.bus_live("RZS").unwrap());
    assert_eq!(real(&p, "RZS1_U"), 400.0);

    p.inject(Fault::SupplyLoss("UTILITY".into())).unwrap();
    assert!(!p.bus_live("RZS").unwrap());
    run(&mut p, &mut c, s(200), &mut never_both);
    // Loss seen by KHU1 at 60.02 s, debounced 1 s: transfer out at the first scan >= 61.02 s.
    let t_out = c.log.iter().find(|e| e.1 == St::TransferOut).unwrap().0;
    assert_eq!(t_out, ms(61_020));
    // Start at 61.02 s; running at 66.02; 90 % voltage at 67.02; relay at 67.04.
    let t_ws = c.log.iter().find(|e| e.1 == St::WaitSettle).unwrap().0;
    assert_eq!(t_ws, ms(67_040));
    let t_da = c.log.iter().find(|e| e.1 == St::Da).unwrap().0;
    assert_eq!(t_da, ms(77_040));
    // KM2 closes 30 ms after the command: RZS back, fed by the generator.
    assert!(p.bus_live("RZS").unwrap());
    assert_eq!(real(&p, "RZS1_U"), 400.0);
    assert!(get(&p, "RDA_KM2_Zapnut"));
    assert!(!get(&p, "RH11_KHU1_Napeti_sit"));

    p.clear(&Fault::SupplyLoss("UTILITY".into())).unwrap();
    let t_back = p.now();
    run(&mut p, &mut c, s(500), &mut never_both);
    let t_re = c.log.iter().find(|e| e.1 == St::Retransfer).unwrap().0;
    assert!(
        t_re >= t_back + s(60) && t_re <= t_back + s(60) + ms(40),
        "{t_re:?}"
    );
    assert_eq!(c.st, St::Mains);
    assert!(get(&p, "RDA_KM1_Zapnut"));
    assert!(p.bus_live("RZS").unwrap());
    // Cool-down of 60 s after the start request was removed, then stopped.
    assert!(!get(&p, "RDA_DA_Bezi"));
    assert_eq!(p.source_violations(), 0);
    assert!(p.safety_log().is_empty(), "{:?}", p.safety_log());
}

#[test]
fn wrong_sequence_is_caught_by_the_safety_monitor() {
    let mut p = VsetinPlant::new();
    let mut c = Rda::new(false);
    run(&mut p, &mut c, s(10), |_| {});
    p.inject(Fault::SupplyLoss("UTILITY".into())).unwrap();
    run(&mut p, &mut c, s(60), |_| {});
    // Mains came back while the faulty controller still holds KM1: paralleled.
    p.clear(&Fault::SupplyLoss("UTILITY".into())).unwrap();
    at(&mut p, s(61));
    assert!(p.source_violations() >= 1);
    assert!(p.safety_log().iter().any(|e| matches!(
        &e.kind,
        SafetyKind::SourcesConnected { both_live: true, sources, .. } if sources.contains(&"DA".to_string())
    )));
}

#[test]
fn generator_failure_leaves_rzs_dead() {
    let mut p = VsetinPlant::new();
    let mut c = Rda::new(true);
    p.inject(Fault::GeneratorFailToStart).unwrap();
    run(&mut p, &mut c, s(5), |_| {});
    p.inject(Fault::SupplyLoss("UTILITY".into())).unwrap();
    run(&mut p, &mut c, s(60), |_| {});
    assert_eq!(c.st, St::TransferOut);
    assert!(get(&p, "RDA_DA_Porucha"));
    assert!(!p.bus_live("RZS").unwrap());
    p.clear(&Fault::GeneratorFailToStart).unwrap();
    run(&mut p, &mut c, s(90), |_| {});
    assert_eq!(c.st, St::Da);
    assert!(p.bus_live("RZS").unwrap());
    assert_eq!(p.source_violations(), 0);
}
