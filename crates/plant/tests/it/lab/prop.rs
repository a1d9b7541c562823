//! Random console lines and output sequences never panic any lab model, and its state
//! stays within the model's physics.

use std::time::Duration;

use plant::lab::{open, LabModel, LabOptions, MODELS};
use plant::Value;
use proptest::prelude::*;

#[derive(Debug, Clone)]
enum Op {
    Out(usize, bool),
    Console(String),
    Advance(u64),
    Reset,
    Read(usize),
}

const WORDS: &[&str] = &[
    "stuck",
    "wire-open",
    "broken",
    "clear",
    "all",
    "reset",
    "press",
    "release",
    "on",
    "off",
    "K1",
    "k4",
    "EM1",
    "EM3",
    "START",
    "ERR",
    "RESET",
    "tlacitko_chodci",
    "zel_vrch",
    "SV4",
    "H5",
    "MIX",
    "topeni",
    "otacky",
    "voda_100",
    "teplota_90",
    "nope",
    "",
];

fn line() -> impl Strategy<Value = String> {
    prop_oneof![
        4 => prop::collection::vec(prop::sample::select(WORDS), 0..4).prop_map(|w| w.join(" ")),
        1 => "\\PC{0,24}",
    ]
}

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        5 => (0usize..64, any::<bool>()).prop_map(|(i, v)| Op::Out(i, v)),
        2 => line().prop_map(Op::Console),
        4 => prop_oneof![0u64..300, 0u64..3_000, 0u64..40_000].prop_map(Op::Advance),
        1 => Just(Op::Reset),
        1 => (0usize..64).prop_map(Op::Read),
    ]
}

fn options() -> impl Strategy<Value = Vec<(String, String)>> {
    prop::sample::select(vec![
        vec![],
        vec![("program-err", "true")],
        vec![("sensors", "2,4,7,9")],
        vec![("drum", "4"), ("heating", "level")],
    ])
    .prop_map(|pairs| {
        pairs
            .into_iter()
            .map(|(k, v)| (k.to_owned(), v.to_owned()))
            .collect()
    })
}

fn real(m: &dyn LabModel, key: &str) -> Option<f64> {
    m.state()
        .into_iter()
        .find(|(k, _)| *k == key)
        .and_then(|(_, v)| v.as_real())
}

/// The hottest a washer may get: one heating step past 90 °C, the step +1.5 °C, or with
/// `heating=level` 1.5 x 100 / 5 = 30 °C at the lowest level that heats (5 %).
fn check(m: &dyn LabModel, hottest: f64) -> Result<(), TestCaseError> {
    let now = m.now();
    prop_assert!(m.next_event().is_some_and(|e| e > now));
    for (key, value) in m.state() {
        if let Value::Real(x) = value {
            prop_assert!(x.is_finite() && x >= 0.0, "{} = {}", key, x);
        }
    }
    if let Some(p) = real(m, "position") {
        prop_assert!((1.0..=10.0).contains(&p));
    }
    if let Some(d) = real(m, "drum") {
        prop_assert!(d < 8.0);
    }
    if let Some(l) = real(m, "level") {
        prop_assert!(l <= 100.0);
    }
    if let Some(t) = real(m, "temperature") {
        prop_assert!(t <= hottest, "{} °C", t);
    }
    for tank in ["tank1", "tank2", "tank3"] {
        if let Some(l) = real(m, tank) {
            prop_assert!(l <= 90.0);
        }
    }
    if let Some(v) = real(m, "vessel") {
        prop_assert!(v <= 253.0 + 18.0);
    }
    let errors = m.errors();
    prop_assert!(errors.windows(2).all(|w| w[0].time <= w[1].time));
    prop_assert!(errors
        .iter()
        .all(|e| e.time <= now && e.cleared.is_none_or(|c| c > e.time)));
    prop_assert!(errors.iter().filter(|e| !e.recoverable).count() <= 2);
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn random_operations_never_panic(
        which in 0usize..4,
        pairs in options(),
        ops in prop::collection::vec(op(), 1..150),
    ) {
        let name = MODELS[which];
        let Ok(options) = LabOptions::parse(&pairs) else {
            return Err(TestCaseError::fail("options"));
        };
        let Ok(mut m) = open(name, &options) else {
            // An option that does not apply to this model.
            return Ok(());
        };
        let names: Vec<String> = m.signals().iter().map(|s| s.name.clone()).collect();
        let hottest = if options.get("heating") == Some("level") { 120.0 } else { 91.5 };
        for op in ops {
            match op {
                Op::Out(i, v) => {
                    let _ = m.set_output(&names[i % names.len()], Value::Bool(v));
                }
                Op::Console(line) => {
                    let _ = m.console(&line);
                }
                Op::Advance(ms) => {
                    let t = m.now() + Duration::from_millis(ms);
                    m.advance_to(t).unwrap();
                    prop_assert_eq!(m.now(), t);
                }
                Op::Reset => m.reset(),
                Op::Read(i) => {
                    prop_assert!(m.read(&names[i % names.len()]).is_ok());
                }
            }
            let _ = m.status();
            let _ = m.console_operations();
            check(m.as_ref(), hottest)?;
        }
    }
}
