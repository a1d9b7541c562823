//! A stop is safe and stays local (issue 15, "Runtime: a stop is safe"): a task that
//! faults stops alone — the points its programs feed turn invalid, the commands to them
//! are refused, the stop is recorded with task, cause and position — while the node's
//! other tasks run on; `plc-stop NODE` stops them all (recorded, points invalid) and
//! `plc-start NODE` resumes what was stopped, the faulted task staying stopped.

use std::time::Duration;

use station::config::Project;
use station::runtime::{Pacing, Runtime, RuntimeOptions, StoreChoice};
use station::store::{EventQuery, PointValue};

const PROGRAMS: &str = "
PROGRAM Fast
VAR
    n : INT;
    zero : INT;
    x : INT;
END_VAR
n := n + 1;
IF n >= 5 THEN
    x := 100 / zero;  (* the fault: a division by zero in the fifth cycle *)
END_IF;
END_PROGRAM

PROGRAM Slow
VAR
    n : INT;
END_VAR
n := n + 1;
END_PROGRAM
";

const PROJECT: &str = r#"
[station]
name = "isolation"
time_zone = "UTC"
store = "sqlite:events.sqlite"

[[node]]
name = "PLC1"
common_address = 1
sources = ["tasks.st"]

[[node.task]]
name = "fast"
interval_ms = 10
programs = ["Fast"]

[[node.task]]
name = "slow"
interval_ms = 50
programs = ["Slow"]

[[node.point]]
name = "FAST_N"
type = "M_ME_NB_1"
ioa = 1
source = "Fast.n"

[[node.point]]
name = "SLOW_N"
type = "M_ME_NB_1"
ioa = 2
source = "Slow.n"
"#;

fn value(runtime: &Runtime, point: &str) -> (Option<i64>, bool) {
    let point = runtime.node("PLC1").unwrap().points.point(point).unwrap();
    let value = match point.value {
        PointValue::Int(n) => Some(n),
        _ => None,
    };
    (value, point.quality.invalid)
}

async fn task_events(runtime: &Runtime, task: &str) -> Vec<String> {
    runtime.recorder().flush().await;
    runtime
        .store()
        .unwrap()
        .query_events(&EventQuery::default().with_point(format!("plc-task:{task}")))
        .await
        .unwrap()
        .items
        .into_iter()
        .map(|event| event.value.to_string())
        .collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_faulting_task_stops_alone_and_plc_stop_stops_the_rest() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("station.toml"), PROJECT).unwrap();
    std::fs::write(dir.path().join("tasks.st"), PROGRAMS).unwrap();
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
    runtime.advance(Duration::from_millis(500)).await.unwrap();

    // The fast task faulted in its fifth cycle; the slow one ran on.
    let (fast, fast_invalid) = value(&runtime, "FAST_N");
    assert_eq!(fast, Some(5));
    assert!(fast_invalid, "the faulted task's point is invalid");
    let (slow_before, slow_invalid) = value(&runtime, "SLOW_N");
    assert!(!slow_invalid, "the other task's point stays valid");
    runtime.advance(Duration::from_millis(500)).await.unwrap();
    let (slow_after, _) = value(&runtime, "SLOW_N");
    assert!(
        slow_after.unwrap() >= slow_before.unwrap() + 9,
        "the slow task runs on: {slow_before:?} -> {slow_after:?}"
    );
    let fast_events = task_events(&runtime, "fast").await;
    assert_eq!(fast_events.len(), 1, "{fast_events:?}");
    assert!(
        fast_events[0].starts_with("fault E") && fast_events[0].contains("tasks.st:10:"),
        "task, cause and position: {fast_events:?}"
    );
    assert!(task_events(&runtime, "slow").await.is_empty());

    // PLC STOP: the slow task stops too, recorded, its point invalid.
    runtime.operate("plc-stop PLC1").await.unwrap();
    runtime.advance(Duration::from_millis(200)).await.unwrap();
    let (stopped_at, slow_invalid) = value(&runtime, "SLOW_N");
    assert!(slow_invalid);
    let slow_events = task_events(&runtime, "slow").await;
    assert_eq!(slow_events.len(), 1, "{slow_events:?}");
    assert!(slow_events[0].starts_with("stop"), "{slow_events:?}");
    runtime.advance(Duration::from_millis(200)).await.unwrap();
    assert_eq!(
        value(&runtime, "SLOW_N").0,
        stopped_at,
        "stopped means stopped"
    );

    // PLC START: the slow task resumes; the faulted one stays stopped until a cold start.
    runtime.operate("plc-start PLC1").await.unwrap();
    runtime.advance(Duration::from_millis(200)).await.unwrap();
    let (resumed, slow_invalid) = value(&runtime, "SLOW_N");
    assert!(!slow_invalid);
    assert!(resumed.unwrap() > stopped_at.unwrap());
    assert!(
        value(&runtime, "FAST_N").1,
        "the faulted task stays stopped"
    );
    assert!(runtime.operate("plc-stop NOPE").await.is_err());
    runtime.shutdown().await;
}
