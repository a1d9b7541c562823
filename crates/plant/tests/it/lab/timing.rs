//! Step-size independence: the same output script gives identical state histories at
//! every whole second whether time advances by 1 ms, 7 ms, 250 ms or from event to event.

use std::time::Duration;

use plant::lab::LabModel;
use plant::Value;

use super::{model, ms, s};

/// One scripted action.
#[derive(Debug, Clone, Copy)]
enum Act {
    Out(&'static str, bool),
    Console(&'static str),
}

use Act::{Console, Out};

fn snapshot(m: &dyn LabModel) -> String {
    format!(
        "{:?} {:?} {:?} {:?} {:?}",
        m.now(),
        m.state(),
        m.inputs(),
        m.err_led(),
        m.errors()
    )
}

/// The history at each whole second up to `end`, stepping by `step` (or event to event).
fn history(
    name: &str,
    options: &[(&str, &str)],
    script: &[(u64, Act)],
    end: Duration,
    step: Option<Duration>,
) -> Vec<String> {
    let mut m = model(name, options);
    let mut out = Vec::new();
    let mut next = 0;
    let mut mark = s(0);
    loop {
        while let Some((at, act)) = script.get(next).filter(|(at, _)| ms(*at) == m.now()) {
            let _ = at;
            match act {
                Out(signal, v) => m.set_output(signal, Value::Bool(*v)).unwrap(),
                Console(line) => m.console(line).unwrap(),
            }
            next += 1;
        }
        if m.now() == mark {
            out.push(snapshot(m.as_ref()));
            mark += s(1);
            if mark > end {
                return out;
            }
        }
        let mut t = mark;
        if let Some((at, _)) = script.get(next) {
            t = t.min(ms(*at));
        }
        t = match step {
            Some(dt) => t.min(m.now() + dt),
            None => t.min(m.next_event().unwrap()),
        };
        m.advance_to(t).unwrap();
    }
}

fn check(name: &str, options: &[(&str, &str)], script: &[(u64, Act)], end: u64) {
    assert!(script.windows(2).all(|w| w[0].0 <= w[1].0));
    let reference = history(name, options, script, s(end), None);
    assert_eq!(reference.len() as u64, end + 1);
    for step in [ms(1), ms(7), ms(250)] {
        let h = history(name, options, script, s(end), Some(step));
        for (a, b) in reference.iter().zip(&h) {
            assert_eq!(a, b, "{name} stepping {step:?}");
        }
        assert_eq!(reference.len(), h.len());
    }
}

#[test]
fn slide_history_does_not_depend_on_the_step() {
    check(
        "slide",
        &[("program-err", "true")],
        &[
            (300, Out("EM1", true)),
            (2_100, Out("EM3", true)),
            (3_333, Out("EM2", true)),
            (4_900, Out("EM1", false)),
            (6_050, Out("EM3", false)),
            (9_700, Out("EM2", false)),
            (10_010, Out("EM1", true)),
            (10_777, Out("EM3", true)),
            (11_234, Out("EM3", false)),
            (20_500, Console("reset")),
            (20_500, Out("EM1", false)),
            (21_003, Out("EM2", true)),
            (24_100, Out("EM2", false)),
            (24_100, Out("RESET", true)),
            (24_601, Out("EM1", true)),
            (25_000, Console("broken EM1")),
            (26_500, Console("clear EM1")),
        ],
        30,
    );
}

#[test]
fn mixing_history_does_not_depend_on_the_step() {
    check(
        "mixing",
        &[],
        &[
            (400, Out("SV1", true)),
            (1_700, Out("SV2", true)),
            (2_200, Out("SV3", true)),
            (9_999, Out("SV1", false)),
            (12_001, Out("SV2", false)),
            (12_500, Out("SV4", true)),
            (13_250, Out("MIX", true)),
            (20_000, Out("SV3", false)),
            (26_100, Out("SV5", true)),
            (30_000, Out("SV1", true)),
            (40_000, Out("SV4", false)),
            (45_000, Out("SV2", true)),
        ],
        60,
    );
}

#[test]
fn washing_history_does_not_depend_on_the_step() {
    check(
        "washing",
        &[("heating", "level")],
        &[
            (200, Out("napousteni", true)),
            (900, Out("topeni", true)),
            (1_130, Out("buben_vpravo", true)),
            (2_710, Out("otacky", true)),
            (3_300, Out("buben_vlevo", true)),
            (5_010, Out("buben_vpravo", false)),
            (6_666, Out("otacky", false)),
            (12_345, Out("cerpadlo", true)),
            (15_000, Out("napousteni", false)),
            (22_222, Out("topeni", false)),
            (24_000, Out("topeni", true)),
            (30_000, Out("cerpadlo", false)),
            (30_000, Out("napousteni", true)),
        ],
        60,
    );
    check(
        "washing",
        &[],
        &[
            (100, Out("topeni", true)),
            (700, Out("buben_vlevo", true)),
            (1_234, Out("otacky", true)),
            (40_000, Out("topeni", false)),
            (47_500, Out("topeni", true)),
        ],
        80,
    );
}

#[test]
fn crossroad_history_does_not_depend_on_the_step() {
    check(
        "crossroad",
        &[],
        &[
            (0, Out("zel_spodek", true)),
            (1_500, Out("zel_vrch", true)),
            (2_750, Out("zel_vrch", false)),
            (3_001, Out("zel_chodci", true)),
            (3_001, Out("zel_spodek", false)),
            (4_444, Console("press tlacitko_chodci")),
            (5_555, Console("release tlacitko_chodci")),
        ],
        8,
    );
}
