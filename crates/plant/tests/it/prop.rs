//! Random command and fault sequences: never a panic, and energisation always agrees with
//! an independent reachability check over the published topology.

use std::collections::VecDeque;
use std::time::Duration;

use plant::{Action, Direction, Fault, Plant, TopologySnapshot, Value, VsetinPlant};
use proptest::prelude::*;

#[derive(Debug, Clone)]
enum Op {
    Out(usize, bool),
    Inject(usize),
    Clear(usize),
    Act(usize),
    Advance(u64),
    Read(usize),
}

fn faults() -> Vec<Fault> {
    let mut v = vec![Fault::GeneratorFailToStart];
    for d in ["TNS_USTI", "TNS_VALMEZ", "UTILITY", "T1", "T2", "T9"] {
        v.push(Fault::SupplyLoss(d.into()));
    }
    for d in [
        "RH2_QF1",
        "RZZ_QF1",
        "RDA_KM1",
        "RDA_KM2",
        "ROV01_KM1",
        "RH11_QF1",
        "RH2_FA1.1",
    ] {
        v.push(Fault::StuckClosed(d.into()));
        v.push(Fault::StuckOpen(d.into()));
        v.push(Fault::BreakerTripped(d.into()));
    }
    for d in ["RH2", "RZZ", "RDA", "RZS1"] {
        v.push(Fault::EmergencyOff(d.into()));
    }
    for d in ["ROV01", "OR"] {
        v.push(Fault::LampFailure(d.into()));
    }
    for d in ["RH2_LOGO", "RDA_LOGO", "ROV01_PLC", "RZS1_DI"] {
        v.push(Fault::ModulePulled(d.into()));
    }
    v.push(Fault::FuseBlown("ROV01_FU1".into()));
    v
}

fn actions() -> Vec<Action> {
    vec![
        Action::SetSelector {
            board: "RH2".into(),
            remote: false,
        },
        Action::SetSelector {
            board: "RH2".into(),
            remote: true,
        },
        Action::SetSelector {
            board: "RZZ".into(),
            remote: false,
        },
        Action::Close("RH2_QF1".into()),
        Action::Open("RH2_QF1".into()),
        Action::Close("RZZ_QF1".into()),
        Action::Open("RH11_QF1".into()),
        Action::Close("RH11_QF1".into()),
        Action::Open("RH2_FA1".into()),
        Action::Close("RH2_FA1".into()),
        Action::SetManualSwitch {
            board: "ROV01".into(),
            on: true,
        },
        Action::SetManualSwitch {
            board: "ROV01".into(),
            on: false,
        },
        Action::SetIlluminance(Some(1.0)),
        Action::SetIlluminance(Some(f64::NAN)),
        Action::SetIlluminance(None),
        Action::Close("NOPE".into()),
    ]
}

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        4 => (0usize..64, any::<bool>()).prop_map(|(i, v)| Op::Out(i, v)),
        1 => (0usize..64).prop_map(Op::Inject),
        1 => (0usize..64).prop_map(Op::Clear),
        1 => (0usize..64).prop_map(Op::Act),
        3 => prop_oneof![0u64..100, 0u64..20_000, 0u64..200_000].prop_map(Op::Advance),
        1 => (0usize..1000).prop_map(Op::Read),
    ]
}

/// Live iff reachable from a live source through closed links, computed here from scratch.
fn check_energisation(t: &TopologySnapshot) -> Result<(), String> {
    let n = t.buses.len();
    let mut live = vec![false; n];
    let mut q: VecDeque<usize> = t.sources.iter().filter(|s| s.live).map(|s| s.bus).collect();
    for &b in &q {
        live[b] = true;
    }
    while let Some(b) = q.pop_front() {
        for l in t.links.iter().filter(|l| l.closed) {
            let other = if l.a == b {
                l.b
            } else if l.b == b {
                l.a
            } else {
                continue;
            };
            if !live[other] {
                live[other] = true;
                q.push_back(other);
            }
        }
    }
    for (i, bus) in t.buses.iter().enumerate() {
        if bus.live != live[i] {
            return Err(format!(
                "bus {} live={} but reachable={}",
                bus.name, bus.live, live[i]
            ));
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 128, ..ProptestConfig::default() })]

    #[test]
    fn random_sequences_never_panic_and_energisation_is_sound(ops in prop::collection::vec(op(), 1..120)) {
        let mut p = VsetinPlant::new();
        let outs: Vec<String> = p.signals().iter().filter(|s| s.direction == Direction::Output).map(|s| s.name.clone()).collect();
        let names: Vec<String> = p.signals().iter().map(|s| s.name.clone()).collect();
        let faults = faults();
        let actions = actions();
        for op in ops {
            match op {
                Op::Out(i, v) => { p.set_output(&outs[i % outs.len()], Value::Bool(v)).unwrap(); }
                Op::Inject(i) => { let _ = p.inject(faults[i % faults.len()].clone()); }
                Op::Clear(i) => { let _ = p.clear(&faults[i % faults.len()]); }
                Op::Act(i) => { let _ = p.operate(actions[i % actions.len()].clone()); }
                Op::Advance(ms) => {
                    let t = p.now() + Duration::from_millis(ms);
                    p.advance_to(t).unwrap();
                    prop_assert_eq!(p.now(), t);
                    prop_assert!(p.next_event().is_none_or(|e| e > t));
                }
                Op::Read(i) => {
                    let r = p.read(&names[i % names.len()]).unwrap();
                    if let Value::Real(x) = r.value { prop_assert!(x.is_finite()); }
                }
            }
            check_energisation(p.topology()).map_err(TestCaseError::fail)?;
            // The monitor's "joined" flag agrees with the topology.
            let t = p.topology();
            let mixed = t.sources.iter().any(|a| t.sources.iter().any(|b| a.group != b.group && connected(t, a.bus, b.bus)));
            prop_assert_eq!(mixed, p.sources_joined());
        }
    }
}

fn connected(t: &TopologySnapshot, a: usize, b: usize) -> bool {
    let mut seen = vec![false; t.buses.len()];
    let mut q = VecDeque::from([a]);
    seen[a] = true;
    while let Some(x) = q.pop_front() {
        if x == b {
            return true;
        }
        for l in t.links.iter().filter(|l| l.closed) {
            let o = if l.a == x {
                l.b
            } else if l.b == x {
                l.a
            } else {
                continue;
            };
            if !seen[o] {
                seen[o] = true;
                q.push_back(o);
            }
        }
    }
    false
}
