//! A new kind of device is a new room: a toy counter kind, declared here with its
//! profile and driver and registered in a `DeviceKinds`, runs in a station with no change
//! to the runtime, the HMI or the CLI. The project loader makes its points from the
//! profile (and refuses a kind nobody registered); the field-source supervisor opens it,
//! opens it again after a failed open and after its line closed, turns its points
//! invalid and its status point TRUE while it is silent, and its readings reach the
//! point database and the store as every other point's.

use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use points::{DeviceProfile, PointKind, PointType, PointValue, Quality, SignalProfile, TimeStamp};
use station::config::{FieldDeviceConfig, Project};
use station::device::{DeviceDriver, DeviceError, DeviceKind, DeviceKinds, DriverFuture, Readings};
use station::runtime::{Runtime, RuntimeOptions, StoreChoice};
use station::store::{EventQuery, Order};

/// What the toy drivers did, for the test to see.
#[derive(Debug, Default)]
struct Counts {
    opens: AtomicU32,
    failed_opens: AtomicU32,
}

/// A counter that counts up every 10 ms; its first open fails, and after `readings`
/// readings it goes silent and its line closes.
struct ToyKind {
    profile: DeviceProfile,
    counts: Arc<Counts>,
}

impl ToyKind {
    fn new(counts: Arc<Counts>) -> ToyKind {
        let signal = |name: &str, offset, kind| SignalProfile {
            name: name.to_owned(),
            offset,
            point_type: PointType::new(kind, TimeStamp::Full),
            description: format!("the toy's {name}"),
            storage: points::StorageRule::default(),
        };
        ToyKind {
            profile: DeviceProfile {
                kind: "toy-counter".to_owned(),
                description: "a counter that counts".to_owned(),
                status_offset: 0,
                signals: vec![
                    signal("count", 1, PointKind::Total),
                    signal("level", 2, PointKind::Scaled),
                ],
            },
            counts,
        }
    }
}

impl DeviceKind for ToyKind {
    fn profile(&self) -> &DeviceProfile {
        &self.profile
    }

    fn driver(&self, device: &FieldDeviceConfig) -> Result<Box<dyn DeviceDriver>, DeviceError> {
        let readings = device
            .settings
            .get("readings")
            .and_then(toml::Value::as_integer)
            .ok_or_else(|| DeviceError::Setting {
                key: "readings".to_owned(),
                reason: "a whole number is needed".to_owned(),
            })?;
        Ok(Box::new(ToyDriver {
            readings: u32::try_from(readings).unwrap_or(1),
            count: 0,
            counts: Arc::clone(&self.counts),
        }))
    }
}

struct ToyDriver {
    readings: u32,
    count: i64,
    counts: Arc<Counts>,
}

impl DeviceDriver for ToyDriver {
    fn open(&mut self) -> DriverFuture<'_, Result<(), DeviceError>> {
        Box::pin(async move {
            if self.counts.failed_opens.load(Ordering::SeqCst) == 0 {
                self.counts.failed_opens.fetch_add(1, Ordering::SeqCst);
                return Err(DeviceError::Io(std::io::Error::new(
                    std::io::ErrorKind::NotFound,
                    "the toy's port is not there yet",
                )));
            }
            self.counts.opens.fetch_add(1, Ordering::SeqCst);
            Ok(())
        })
    }

    fn run<'a>(&'a mut self, readings: &'a dyn Readings) -> DriverFuture<'a, DeviceError> {
        Box::pin(async move {
            for _ in 0..self.readings {
                self.count += 1;
                readings.answering(true);
                readings.value("count", PointValue::Int(self.count), Quality::GOOD);
                readings.value("level", PointValue::Int(self.count * 10), Quality::GOOD);
                readings.value("no-such-signal", PointValue::Int(0), Quality::GOOD);
                tokio::time::sleep(Duration::from_millis(10)).await;
            }
            readings.answering(false);
            DeviceError::Closed
        })
    }
}

fn project_text(kind: &str) -> String {
    format!(
        r#"
[station]
name = "toy"
time_zone = "UTC"
store = "sqlite:events.sqlite"

[[node]]
name = "N"
common_address = 1

[[node.device]]
name = "T1"
kind = "{kind}"
description = "on the bench"
ioa_base = 100
settings = {{ readings = 100 }}
"#
    )
}

fn kinds(counts: &Arc<Counts>) -> DeviceKinds {
    let mut kinds = DeviceKinds::builtin();
    kinds
        .register(Arc::new(ToyKind::new(Arc::clone(counts))))
        .unwrap();
    kinds
}

#[test]
fn the_loader_makes_the_profiles_points_and_refuses_unknown_kinds() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("station.toml");
    let counts = Arc::new(Counts::default());
    let project = Project::parse_with(
        dir.path(),
        &file,
        &project_text("toy-counter"),
        &kinds(&counts),
    )
    .unwrap_or_else(|errors| panic!("{errors}"));
    let node = project.node("N").unwrap();
    let points: Vec<(String, u32, String)> = node
        .points
        .iter()
        .map(|p| {
            (
                p.name.clone(),
                p.ioa.get(),
                points_iec::type_id(p.point_type).to_string(),
            )
        })
        .collect();
    assert_eq!(
        points,
        [
            ("T1.not_answering".to_owned(), 100, "M_SP_TB_1".to_owned()),
            ("T1.count".to_owned(), 101, "M_IT_TB_1".to_owned()),
            ("T1.level".to_owned(), 102, "M_ME_TE_1".to_owned()),
        ]
    );
    assert_eq!(node.devices.len(), 1);
    assert_eq!(node.devices[0].kind, "toy-counter");

    let errors = Project::parse_with(
        dir.path(),
        &file,
        &project_text("toy-clock"),
        &kinds(&counts),
    )
    .unwrap_err()
    .to_string();
    assert!(
        errors.contains("station.toml:13:8")
            && errors
                .contains("no device kind `toy-clock` (known: balance, modbus, s7, toy-counter)"),
        "{errors}"
    );
    // The built-in kinds alone do not know the toy.
    let errors = Project::parse(dir.path(), &file, &project_text("toy-counter"))
        .unwrap_err()
        .to_string();
    assert!(errors.contains("no device kind `toy-counter`"), "{errors}");
}

/// Waits (bounded) until `condition` holds, checking every 10 ms.
async fn wait_until(what: &str, mut condition: impl FnMut() -> bool) {
    let deadline = Instant::now() + Duration::from_secs(30);
    while !condition() {
        assert!(Instant::now() < deadline, "timed out waiting for {what}");
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_supervisor_opens_reads_invalidates_and_reopens_a_toy_device() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("station.toml"), project_text("toy-counter")).unwrap();
    let counts = Arc::new(Counts::default());
    let kinds = kinds(&counts);
    let project =
        Project::load_with(dir.path(), &kinds).unwrap_or_else(|errors| panic!("{errors}"));
    let runtime = Runtime::start(
        project,
        RuntimeOptions {
            store: StoreChoice::Project,
            device_kinds: kinds,
            ..RuntimeOptions::default()
        },
    )
    .await
    .unwrap();
    let node = Arc::clone(&runtime.node("N").unwrap().points);
    let point = |name: &str| node.point(name).unwrap();
    let value_of = |name: &str| {
        let point = point(name);
        (!point.quality.invalid).then_some(point.value)
    };

    // Before it answers: invalid, the communication alarm on.
    assert!(point("T1.count").quality.invalid);
    // The first open fails, the second (after the supervisor's pause) reads.
    // Seen together while it reads (the toy counts every 10 ms for a second; a busy
    // machine may look less often, so no exact count is waited for).
    wait_until("the first readings with the alarm off", || {
        value_of("T1.count")
            .is_some_and(|v| matches!(v, PointValue::Int(n) if (5..100).contains(&n)))
            && value_of("T1.not_answering") == Some(PointValue::Bool(false))
            && runtime.node("N").unwrap().devices[0].is_answering()
    })
    .await;
    assert_eq!(counts.failed_opens.load(Ordering::SeqCst), 1);

    // Silent and closed after 100 readings: its points invalid (last value kept), the
    // alarm on; then opened again, and counting on.
    wait_until("the device reported lost", || {
        point("T1.count").quality.invalid
            && value_of("T1.not_answering") == Some(PointValue::Bool(true))
    })
    .await;
    assert_eq!(point("T1.count").value, PointValue::Int(100));
    assert_eq!(point("T1.level").value, PointValue::Int(1000));
    wait_until("the device opened again", || {
        value_of("T1.count").is_some_and(|v| matches!(v, PointValue::Int(n) if n >= 105))
    })
    .await;
    assert_eq!(counts.opens.load(Ordering::SeqCst), 2);
    assert_eq!(value_of("T1.not_answering"), Some(PointValue::Bool(false)));

    // Every change is in the store, as any point's.
    runtime.recorder().flush().await;
    let counted = runtime
        .store()
        .unwrap()
        .query_events(
            &EventQuery::default()
                .with_point("T1.count")
                .with_order(Order::OldestFirst)
                .with_limit(1000),
        )
        .await
        .unwrap()
        .items;
    let good: Vec<i64> = counted
        .iter()
        .filter(|event| !event.quality.invalid)
        .filter_map(|event| match event.value {
            PointValue::Int(n) => Some(n),
            _ => None,
        })
        .collect();
    assert!(
        good.len() >= 105 && good.windows(2).all(|w| w[1] == w[0] + 1),
        "{good:?}"
    );
    assert!(counted.iter().any(|event| event.quality.invalid));
    runtime.shutdown().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_setting_the_driver_refuses_stops_the_start_naming_the_device() {
    let dir = tempfile::tempdir().unwrap();
    let text = project_text("toy-counter").replace("settings = { readings = 100 }", "");
    std::fs::write(dir.path().join("station.toml"), text).unwrap();
    let counts = Arc::new(Counts::default());
    let kinds = kinds(&counts);
    let project =
        Project::load_with(dir.path(), &kinds).unwrap_or_else(|errors| panic!("{errors}"));
    let started = Runtime::start(
        project,
        RuntimeOptions {
            store: StoreChoice::Disabled,
            device_kinds: kinds,
            ..RuntimeOptions::default()
        },
    )
    .await;
    let Err(error) = started else {
        panic!("the start should fail");
    };
    let error = error.to_string();
    assert!(
        error.contains("node `N`: device `T1`: setting `readings`: a whole number is needed"),
        "{error}"
    );
}
