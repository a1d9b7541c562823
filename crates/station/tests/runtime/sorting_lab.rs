//! The sorting lab as a station project (`examples/sorting-lab`): the sorting PLC and the
//! supervisor as two nodes on the plant `sorter`, the DP exchange through the plant's
//! wiring; an automatic sorting commanded over IEC 104 as the HMI does, the manual
//! switches refused in automatic mode, and the supervisor's lock-out recorded as an
//! event of the station. The balance is read as on the model: the plant's balance port on
//! a pseudo-terminal, the balance driver on it, its points into the program's inputs.

use std::time::Duration;

use station::config::Project;
use station::runtime::{Runtime, StoreChoice};
use station::store::{EventQuery, PointValue};

use crate::harness::*;

/// The command IOAs of SORTER (station.toml).
const SORT_AUTOMATIC: u32 = 2001;
const SORT_START: u32 = 2002;
const MAN_S1: u32 = 2013;

fn project() -> Project {
    let project = Project::load(&testkit::projects::example("sorting-lab"))
        .unwrap_or_else(|errors| panic!("{errors}"));
    project.with_port_base(free_port_range(2))
}

fn number(runtime: &Runtime, node: &str, point: &str) -> Option<f64> {
    let point = runtime.node(node)?.points.point(point)?;
    match point.value {
        PointValue::Int(n) => Some(n as f64),
        PointValue::Float(x) => Some(x),
        PointValue::Bool(b) => Some(f64::from(u8::from(b))),
        _ => None,
    }
}

/// The balance's newest record as the plant sent it on its port (grams).
async fn plant_balance(runtime: &Runtime) -> f64 {
    runtime
        .with_simulation(|sim| sim.plant().unwrap().real("Balance_g").unwrap())
        .await
        .unwrap()
}

/// Whether the balance's points show the newest record the plant sent: the driver has
/// read everything the pseudo-terminal carried so far.
fn balance_read(runtime: &Runtime, weight: f64) -> bool {
    let Some(point) = runtime.node("SORTER").unwrap().points.point("BAL.weight") else {
        return false;
    };
    !point.quality.invalid
        && matches!(point.value, PointValue::Float(x) if (x - weight).abs() < 1e-4)
}

/// [`advance_until`] for the balance on its line: after each step, waits until the
/// driver has read what the step sent, so the program weighs what the plant weighed
/// however late the machine delivers the octets.
async fn advance_until_weighed(
    runtime: &Runtime,
    step: Duration,
    what: &str,
    mut condition: impl FnMut() -> bool,
) {
    for _ in 0..400 {
        if condition() {
            return;
        }
        runtime.advance(step).await.unwrap();
        let weight = plant_balance(runtime).await;
        eventually("the balance's record read from the pseudo-terminal", || {
            balance_read(runtime, weight)
        })
        .await;
    }
    panic!("timed out waiting until {what}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_automatic_sorting_through_the_station_and_the_supervisor_stepping_in() {
    let runtime = start(project(), StoreChoice::Url("sqlite::memory:".into())).await;
    links_up(&runtime).await;
    let ports = runtime.plant_ports();
    assert_eq!(ports.len(), 1);
    assert_eq!(
        (ports[0].port(), ports[0].device()),
        ("balance", "SORTER/BAL")
    );
    assert!(
        ports[0].pty_path().starts_with("/dev/"),
        "{}",
        ports[0].pty_path()
    );
    let sorter = runtime.node("SORTER").unwrap();
    let address = sorter.server.as_ref().unwrap().local_addr();
    let hmi = Dispatch::connect(address, 1, true).await;

    // Manual mode at power-on: a manual switch is carried out...
    assert!(
        hmi.single_command(MAN_S1, true, false).await,
        "MAN_S1 in manual mode"
    );
    assert!(hmi.single_command(MAN_S1, false, false).await);
    // ... and refused once the mode is automatic (the station refuses it: remote_enable).
    assert!(
        hmi.single_command(SORT_AUTOMATIC, true, false).await,
        "SORT_Automatic"
    );
    advance_until(
        &runtime,
        Duration::from_millis(100),
        "automatic mode",
        || number(&runtime, "SORTER", "SORT_Automatic") == Some(1.0),
    )
    .await;
    assert!(
        !hmi.single_command(MAN_S1, true, false).await,
        "manual switching is refused in automatic mode"
    );

    // Start: initialisation (about 37 s), then eight balls, each in its colour's shaft.
    assert!(
        hmi.single_command(SORT_START, true, false).await,
        "SORT_Start"
    );
    advance_until_weighed(&runtime, Duration::from_secs(1), "one sorting done", || {
        number(&runtime, "SORTER", "SORT_Sortings") == Some(1.0)
    })
    .await;
    for k in 1..=4 {
        assert_eq!(
            number(&runtime, "SORTER", &format!("SORT_Shaft{k}")),
            Some(2.0),
            "shaft {k}"
        );
    }
    let plant_shafts = runtime
        .with_simulation(|sim| {
            let plant = sim
                .plant()
                .unwrap()
                .as_any()
                .downcast_ref::<plant::sorter::SorterPlant>()
                .unwrap();
            (1..=4).map(|k| plant.shaft(k).len()).collect::<Vec<_>>()
        })
        .await
        .unwrap();
    assert_eq!(plant_shafts, vec![2, 2, 2, 2]);
    // The supervisor republished through SORTER (IOA + 1000) and never stepped in.
    assert_eq!(number(&runtime, "SORTER", "SUP_S1_State"), Some(0.0));

    // Manual mode again: S1 held on for 3 s is cut off at its MaxOnTime, an event of
    // the station naming the actuator and the rule.
    assert!(hmi.single_command(SORT_AUTOMATIC, false, false).await);
    advance_until(&runtime, Duration::from_millis(100), "manual mode", || {
        number(&runtime, "SORTER", "SORT_Automatic") == Some(0.0)
    })
    .await;
    assert!(hmi.single_command(MAN_S1, true, false).await, "MAN_S1 on");
    advance_until(
        &runtime,
        Duration::from_millis(500),
        "S1 in PENALTY",
        || number(&runtime, "SUPERVISOR", "SUP_S1_State") == Some(3.0),
    )
    .await;
    runtime.recorder().flush().await;
    let events = runtime
        .store()
        .unwrap()
        .query_events(&EventQuery::default().with_point("SUP_S1_LockedOut".to_owned()))
        .await
        .unwrap()
        .items;
    assert!(
        events.iter().any(|e| e.value == PointValue::Bool(true)),
        "{events:?}"
    );
    let description = runtime
        .node("SUPERVISOR")
        .unwrap()
        .points
        .point("SUP_S1_LockedOut")
        .unwrap()
        .spec
        .description
        .clone();
    assert!(description.contains("MaxOnTime"), "{description}");

    // The balance's link lost: its line falls silent, the driver calls it not answering
    // (2 s without a legal record) and its weight invalid; back, it answers again.
    runtime.operate("balance-link-loss").await.unwrap();
    runtime.advance(Duration::from_secs(1)).await.unwrap();
    eventually("the balance not answering", || {
        number(&runtime, "SORTER", "BAL.not_answering") == Some(1.0)
    })
    .await;
    let weight = runtime
        .node("SORTER")
        .unwrap()
        .points
        .point("BAL.weight")
        .unwrap();
    assert!(weight.quality.invalid, "{weight:?}");
    runtime.operate("clear balance-link-loss").await.unwrap();
    advance_until_weighed(
        &runtime,
        Duration::from_secs(1),
        "the balance answering",
        || number(&runtime, "SORTER", "BAL.not_answering") == Some(0.0),
    )
    .await;
    runtime.shutdown().await;
}

/// A student's program loaded into the running SORTER node (the lab itself, not a
/// simulation of its own): one that does not compile is refused with its place and the
/// lab runs on; one that holds gate S1 open runs, and the supervisor locks S1 out; the
/// lab's own program is put back. Each load is an event of the station.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_students_program_runs_on_the_lab_and_the_labs_own_comes_back() {
    use station::runtime::program::ProgramDownload;

    let runtime = start(project(), StoreChoice::Url("sqlite::memory:".into())).await;
    links_up(&runtime).await;
    let loader = runtime.program_loader();
    let student = |text: &str| ProgramDownload {
        files: vec![("student.st".to_owned(), text.to_owned())],
        keep: vec!["interface.st".to_owned()],
        tasks: vec![("main".to_owned(), vec!["Holder".to_owned()])],
        by: "student".to_owned(),
    };

    let error = loader
        .download(
            "SORTER",
            student("PROGRAM Holder\nVAR s1 AT %QX0.0 : BOOL; END_VAR\ns1 := TRUE\nEND_PROGRAM\n"),
        )
        .await
        .unwrap_err()
        .to_string();
    assert!(error.contains("student.st:3:11"), "{error}");
    // Refused: the lab's program runs on (it answers a mode change).
    runtime.advance(Duration::from_millis(100)).await.unwrap();
    assert_eq!(number(&runtime, "SORTER", "SORT_Automatic"), Some(0.0));

    let loaded = loader
        .download(
            "SORTER",
            student("PROGRAM Holder\nVAR s1 AT %QX0.0 : BOOL; END_VAR\ns1 := TRUE;\nEND_PROGRAM\n"),
        )
        .await
        .unwrap();
    assert_eq!(
        loaded.tasks,
        vec![("main".to_owned(), vec!["Holder".to_owned()])]
    );
    assert!(loaded.files[0].ends_with("interface.st") && loaded.files[1] == "student.st");
    advance_until(
        &runtime,
        Duration::from_millis(500),
        "S1 locked out by the supervisor",
        || number(&runtime, "SUPERVISOR", "SUP_S1_State") == Some(3.0),
    )
    .await;

    loader.restore("SORTER", "admin").await.unwrap();
    advance_until(
        &runtime,
        Duration::from_millis(100),
        "S1 released by the lab's own program",
        || {
            runtime
                .node("SUPERVISOR")
                .and_then(|node| node.points.point("SUP_S1_State"))
                .is_some_and(|point| point.value != PointValue::Int(1))
        },
    )
    .await;
    let held = runtime
        .with_simulation(|sim| sim.plant().unwrap().bool("Cmd_S1").unwrap())
        .await
        .unwrap();
    assert!(
        !held,
        "the lab's own program does not hold S1 in manual mode"
    );
    runtime.recorder().flush().await;
    let loads: Vec<String> = runtime
        .store()
        .unwrap()
        .query_events(&EventQuery::default().with_point("plc-program".to_owned()))
        .await
        .unwrap()
        .items
        .into_iter()
        .map(|event| event.value.to_string())
        .collect();
    assert_eq!(loads.len(), 2, "{loads:?}");
    assert!(
        loads.iter().any(|text| text.contains("loaded by student")
            && text.contains("student.st")
            && text.contains("task main: Holder")),
        "{loads:?}"
    );
    assert!(
        loads.iter().any(|text| text.contains("restored by admin")),
        "{loads:?}"
    );
    runtime.shutdown().await;
}
