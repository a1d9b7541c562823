//! What the history keeps of a running node: a measurement ramping by 0.1 every PLC
//! cycle with `store_deadband = 1.0` is stored about once per unit it moves, a counter
//! with `store_min_interval_ms = 1000` once a simulated second, a percent deadband from
//! the station's default on a point without its own; every change is still sent (the
//! point database holds the newest value), and a breaker's every change is stored.

use std::time::Duration;

use points::PointValue;
use station::config::Project;
use station::runtime::{Runtime, StoreChoice};
use station::store::{EventQuery, Order};

use crate::harness::*;

const RAMP: &str = "PROGRAM Signals
VAR
    U : REAL;
    I : REAL := 100.0;
    Count : DINT;
    Breaker : BOOL;
END_VAR
    U := U + 0.1;
    I := I + 0.1;
    Count := Count + 1;
    Breaker := NOT Breaker;
END_PROGRAM
";

fn project() -> Project {
    let text = r#"
[station]
name = "storage"
time_zone = "UTC"
store_deadband_percent = 1

[[node]]
name = "N"
common_address = 1
sources = ["plc/signals.st"]

[[node.task]]
name = "main"
interval_ms = 100
programs = ["Signals"]

[[node.point]]
name = "U"
type = "M_ME_NC_1"
ioa = 1
source = "Signals.U"
store_deadband = 1.0

[[node.point]]
name = "I"
type = "M_ME_NC_1"
ioa = 2
source = "Signals.I"

[[node.point]]
name = "Count"
type = "M_IT_NA_1"
ioa = 3
source = "Signals.Count"
store_min_interval_ms = 1000

[[node.point]]
name = "Breaker"
type = "M_SP_TB_1"
ioa = 4
source = "Signals.Breaker"
"#;
    let folder = project_folder(&[("station.toml", text), ("plc/signals.st", RAMP)]);
    // The folder lives as long as the test process: the runtime reads the sources.
    let path = folder.keep();
    Project::load(&path).unwrap_or_else(|errors| panic!("{errors}"))
}

async fn stored(runtime: &Runtime, point: &str) -> Vec<PointValue> {
    runtime
        .store()
        .unwrap()
        .query_events(
            &EventQuery::default()
                .with_point(point)
                .with_order(Order::OldestFirst)
                .with_limit(10_000),
        )
        .await
        .unwrap()
        .items
        .into_iter()
        .map(|event| event.value)
        .collect()
}

fn float(value: &PointValue) -> f64 {
    match value {
        PointValue::Float(x) => *x,
        PointValue::Int(i) => *i as f64,
        other => panic!("not a number: {other:?}"),
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn storage_rules_thin_out_what_is_stored_not_what_is_sent() {
    let runtime = start(project(), StoreChoice::Url("sqlite::memory:".into())).await;
    // 60 simulated seconds: 600 PLC cycles, 600 changes of each point.
    runtime.advance(Duration::from_secs(60)).await.unwrap();
    runtime.recorder().flush().await;
    let node = &runtime.node("N").unwrap().points;

    // U went from 0 to about 60 in steps of 0.1: one stored value per unit moved, each
    // more than 1.0 from the one stored before it.
    let u = stored(&runtime, "U").await;
    assert!(
        (55..=62).contains(&u.len()),
        "{} values of U stored",
        u.len()
    );
    for pair in u.windows(2) {
        assert!(float(&pair[1]) - float(&pair[0]) > 1.0, "{pair:?}");
    }
    // Sent all the same: the point holds the newest value, not the last stored one.
    let newest = float(&node.point("U").unwrap().value);
    assert!(newest > 59.0, "U is {newest}");

    // I (the station's 1 % default) from 100 to 160: a stored value every ~1 %.
    let i = stored(&runtime, "I").await;
    assert!(
        (35..=55).contains(&i.len()),
        "{} values of I stored",
        i.len()
    );
    for pair in i.windows(2) {
        let (before, after) = (float(&pair[0]), float(&pair[1]));
        assert!(after - before > before * 0.01, "{pair:?}");
    }

    // The counter: once a simulated second.
    let count = stored(&runtime, "Count").await;
    assert!(
        (59..=62).contains(&count.len()),
        "{} counts stored",
        count.len()
    );

    // The breaker: every change (600 of them, and the first value).
    let breaker = stored(&runtime, "Breaker").await;
    assert!(
        breaker.len() >= 600,
        "{} breaker changes stored",
        breaker.len()
    );
    assert!(node.left_out_of_store() > 1000);
    runtime.shutdown().await;
}
