//! A new consumer of point changes is a new [`PointSink`], not a change to the node: a toy
//! sink attached to a running node gets every change the node publishes, in order, the
//! same the event store records; a sink that refuses a change does not stop the others
//! or the store.

use std::sync::{Arc, Mutex};
use std::time::Duration;

use points::PointChange;
use station::config::Project;
use station::runtime::sink::{PointSink, SinkError};
use station::runtime::{Pacing, Runtime, RuntimeOptions, StoreChoice};
use station::store::EventQuery;

const PROGRAM: &str = "
PROGRAM Count
VAR
    n : INT;
END_VAR
n := n + 1;
END_PROGRAM
";

const PROJECT: &str = r#"
[station]
name = "sink"
time_zone = "UTC"
store = "sqlite:events.sqlite"

[[node]]
name = "PLC1"
common_address = 1
sources = ["count.st"]

[[node.task]]
name = "main"
interval_ms = 10
programs = ["Count"]

[[node.point]]
name = "N"
type = "M_ME_NB_1"
ioa = 1
source = "Count.n"
"#;

/// Keeps what it is given.
#[derive(Debug, Default)]
struct Toy {
    seen: Mutex<Vec<(String, String)>>,
}

impl PointSink for Toy {
    fn publish(&self, change: &PointChange) -> Result<(), SinkError> {
        self.seen
            .lock()
            .unwrap()
            .push((change.name.clone(), change.value.to_string()));
        Ok(())
    }

    fn describe(&self) -> String {
        "toy sink".to_owned()
    }
}

/// Refuses everything.
#[derive(Debug)]
struct Refusing;

impl PointSink for Refusing {
    fn publish(&self, _: &PointChange) -> Result<(), SinkError> {
        Err("refused on purpose".into())
    }

    fn describe(&self) -> String {
        "refusing sink".to_owned()
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_toy_sink_gets_every_point_change_the_store_records() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("station.toml"), PROJECT).unwrap();
    std::fs::write(dir.path().join("count.st"), PROGRAM).unwrap();
    let project = Project::load(dir.path()).unwrap_or_else(|e| panic!("{e}"));
    let runtime = Runtime::start(
        project,
        RuntimeOptions {
            pacing: Pacing::Manual,
            store: StoreChoice::Project,
            ..RuntimeOptions::default()
        },
    )
    .await
    .unwrap();
    let node = runtime.node("PLC1").unwrap();
    node.points.attach_sink(Arc::new(Refusing));
    let toy = Arc::new(Toy::default());
    node.points.attach_sink(toy.clone());
    runtime.advance(Duration::from_millis(200)).await.unwrap();
    runtime.recorder().flush().await;

    let seen = toy.seen.lock().unwrap().clone();
    assert!(seen.len() >= 15, "the toy sink saw {} changes", seen.len());
    let stored: Vec<(String, String)> = runtime
        .store()
        .unwrap()
        .query_events(&EventQuery::default().with_point("N").with_limit(1000))
        .await
        .unwrap()
        .items
        .into_iter()
        .rev()
        .map(|event| (event.point, event.value.to_string()))
        .collect();
    // Every change after the sink was attached, in order, as the store has it.
    assert!(stored.ends_with(&seen), "sink {seen:?}\nstore {stored:?}");
    runtime.shutdown().await;
}
