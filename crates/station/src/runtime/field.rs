//! The field-source supervisor: what every source of field data (a profiled device, a
//! lift board, a serial line of relays or outstations) needs around its protocol.
//!
//! - **Open, and open again.** A source that cannot be opened, or whose line closes, is
//!   opened again after a pause (`Reopen`): 1 s, doubling to [`REOPEN_MAX`], back to
//!   1 s once the source answered. A dead converter is not hammered; a cable plugged back
//!   in is read again within seconds.
//! - **Communication status.** While a device does not answer, its points are invalid
//!   (IV, last value kept) and its status point is TRUE (`NOT CommEnabled`, the TC700's
//!   convention); its next reading clears both.
//! - **Readings to points.** A driver reports by signal name ([`Readings`]); the
//!   supervisor finds the point and hands it to the node (sinks, recorder).
//!
//! Every source runs on the one loop, [`supervise`], as a [`FieldSource`]: profiled
//! devices (`[[node.device]]`, [`crate::device`], through `spawn_device`), lift boards
//! (`runtime::lift`) and serial lines of IEC 101 outstations or IEC 103 relays
//! (`runtime::line`). Each shows its state through one `CommunicationStatus` (a serial
//! line keeps one per device and one for the line), as do the IEC 104 links, which keep
//! the 104 client's own reconnection (the link layer's T0 and back-off, the same rule).
//!
//! ```text
//!  lost() --> open() --ok--> run(line) --ended--> lost() --> Reopen::pause (1 s .. 5 s) --+
//!               ^  \--error--> log --------------------------> Reopen::pause ----------+
//!               +-------------------------------------------------------------------------+
//! ```

use std::collections::HashMap;
use std::future::Future;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use points::{EventCause, PointId, PointSource, PointValue, Quality};

use super::node::NodePoints;
use crate::config::FieldDeviceConfig;
use crate::device::{DeviceDriver, DeviceError, IoImage, Readings};

/// The first pause before a source is opened again.
pub const REOPEN_FIRST: Duration = Duration::from_secs(1);
/// The longest pause before a source is opened again.
pub const REOPEN_MAX: Duration = Duration::from_secs(5);

/// The pauses between attempts to open a source: doubling from [`REOPEN_FIRST`] to
/// [`REOPEN_MAX`]; [`Reopen::answered`] starts over.
#[derive(Debug, Clone)]
struct Reopen {
    next: Duration,
}

impl Reopen {
    fn new() -> Reopen {
        Reopen { next: REOPEN_FIRST }
    }

    /// Waits before the next attempt.
    async fn pause(&mut self) {
        tokio::time::sleep(self.next).await;
        self.next = (self.next * 2).min(REOPEN_MAX);
    }

    /// The source answered: the next failure waits [`REOPEN_FIRST`] again.
    fn answered(&mut self) {
        self.next = REOPEN_FIRST;
    }
}

/// How reading an opened source ended.
#[derive(Debug)]
pub(crate) struct Ended {
    /// Whether the source answered while its line was open: the next pause is the
    /// shortest again.
    pub answered: bool,
    /// Why its line closed, for the log.
    pub reason: String,
}

/// A source of field data as [`supervise`] drives it: opened, read until its line
/// closes, reported lost, opened again after a pause.
pub(crate) trait FieldSource: Send {
    /// What an opened source is read from (a line, a connection).
    type Line: Send;

    /// Its name in the log (`lift L1`, `line L2`, `device D`).
    fn describe(&self) -> String;

    /// Opens its line or connection.
    fn open(&mut self) -> impl Future<Output = Result<Self::Line, DeviceError>> + Send;

    /// Reads it until its line closes or fails.
    fn run(&mut self, line: Self::Line) -> impl Future<Output = Ended> + Send;

    /// It is lost (before it is first opened and whenever its line closed): its points
    /// invalid (last value kept), its status point TRUE, whoever is told so told.
    fn lost(&mut self);
}

/// Runs `source` for as long as the task lives: the one open-read-reopen loop of every
/// field source of the node called `node`.
pub(crate) async fn supervise(node: &str, mut source: impl FieldSource) {
    source.lost();
    let mut reopen = Reopen::new();
    loop {
        match source.open().await {
            Ok(line) => {
                let ended = source.run(line).await;
                if ended.answered {
                    reopen.answered();
                }
                source.lost();
                tracing::warn!(node, source = %source.describe(), reason = %ended.reason, "the line closed; opening it again");
            }
            Err(error) => {
                tracing::warn!(node, source = %source.describe(), %error, "cannot open the line; trying again");
            }
        }
        reopen.pause().await;
    }
}

/// A field source's communication status in its node's points: its status point (TRUE
/// while it does not answer, `NOT CommEnabled`) and the points it feeds (invalid while it
/// does not answer, last value kept). Profiled devices, lift boards, the devices and
/// lines of a serial line and the IEC 104 links each keep one.
pub(crate) struct CommunicationStatus {
    /// The origin of the changes it makes (`line L1`, `link:RH`, ...).
    origin: String,
    status_point: Option<String>,
    feeds: Box<dyn Fn(&PointSource) -> bool + Send + Sync>,
}

impl std::fmt::Debug for CommunicationStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CommunicationStatus")
            .field("origin", &self.origin)
            .field("status_point", &self.status_point)
            .finish_non_exhaustive()
    }
}

impl CommunicationStatus {
    /// The status of a source whose changes come from `origin`, shown by `status_point`,
    /// feeding the points whose source `feeds` selects.
    pub(crate) fn new(
        origin: impl Into<String>,
        status_point: Option<String>,
        feeds: impl Fn(&PointSource) -> bool + Send + Sync + 'static,
    ) -> CommunicationStatus {
        CommunicationStatus {
            origin: origin.into(),
            status_point,
            feeds: Box::new(feeds),
        }
    }

    /// It answers: its status point FALSE (its points turn valid with their next value).
    pub(crate) fn up(&self, node: &NodePoints) {
        let Some(point) = self.status_point.as_deref() else {
            return;
        };
        node.change_with(&self.origin, |db, now| {
            db.set_link_status(point, true, now)
                .ok()
                .flatten()
                .into_iter()
                .collect()
        });
    }

    /// It does not answer: its points invalid and its status point TRUE, in one batch.
    pub(crate) fn down(&self, node: &NodePoints) {
        node.change_with(&self.origin, |db, now| {
            let mut changes = db.invalidate_where(|spec| (self.feeds)(&spec.source), now);
            if let Some(point) = self.status_point.as_deref() {
                changes.extend(db.set_link_status(point, false, now).ok().flatten());
            }
            changes
        });
    }
}

/// A running profiled device.
#[derive(Debug)]
pub struct FieldDeviceHandle {
    name: String,
    task: tokio::task::AbortHandle,
    answering: Arc<AtomicBool>,
}

impl FieldDeviceHandle {
    /// The device's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Whether the device answers now.
    pub fn is_answering(&self) -> bool {
        self.answering.load(Ordering::Acquire)
    }

    /// Stops reading the device.
    pub fn stop(&self) {
        self.task.abort();
    }
}

/// Starts supervising `driver`, the driver of `config`, feeding `node`'s points.
pub(crate) fn spawn_device(
    config: &FieldDeviceConfig,
    driver: Box<dyn DeviceDriver>,
    node: Arc<NodePoints>,
    image: Option<Arc<IoImage>>,
) -> FieldDeviceHandle {
    let mut readings = DeviceReadings::new(config, node);
    readings.image = image;
    let answering = Arc::clone(&readings.answering);
    let task = tokio::spawn(async move {
        let node = Arc::clone(&readings.node);
        supervise(node.name(), ProfiledDevice { driver, readings }).await;
    })
    .abort_handle();
    FieldDeviceHandle {
        name: config.name.clone(),
        task,
        answering,
    }
}

/// A profiled device under the supervisor: its driver and where its readings go.
struct ProfiledDevice {
    driver: Box<dyn DeviceDriver>,
    readings: DeviceReadings,
}

impl FieldSource for ProfiledDevice {
    type Line = ();

    fn describe(&self) -> String {
        self.readings.origin.clone()
    }

    async fn open(&mut self) -> Result<(), DeviceError> {
        self.driver.open().await
    }

    async fn run(&mut self, (): ()) -> Ended {
        let end = self.driver.run(&self.readings).await;
        Ended {
            answered: self.readings.answered.swap(false, Ordering::AcqRel),
            reason: end.to_string(),
        }
    }

    fn lost(&mut self) {
        self.readings.answering.store(false, Ordering::Release);
        if let Some(image) = &self.readings.image {
            image.set_answering(false);
        }
        self.readings.down();
    }
}

/// A profiled device's points, as its driver's readings reach them.
struct DeviceReadings {
    node: Arc<NodePoints>,
    device: String,
    /// `device NAME`, the origin of its changes.
    origin: String,
    /// Signal name -> point.
    points: HashMap<String, PointId>,
    comm: CommunicationStatus,
    answering: Arc<AtomicBool>,
    /// Whether it answered since the line was last opened.
    answered: AtomicBool,
    /// Its part of the node's PLC I/O image, if the PLC is bound to items of it.
    image: Option<Arc<IoImage>>,
}

impl DeviceReadings {
    fn new(config: &FieldDeviceConfig, node: Arc<NodePoints>) -> DeviceReadings {
        let (points, status) = {
            let db = node.lock();
            let mut points = HashMap::new();
            let mut status = None;
            for point in db.points() {
                let id = db.id(point.spec.name.as_str());
                match (&point.spec.source, id) {
                    (PointSource::Device { device, signal }, Some(id))
                        if *device == config.name =>
                    {
                        points.insert(signal.clone(), id);
                    }
                    (PointSource::DeviceComm { device }, _) if *device == config.name => {
                        status = Some(point.spec.name.clone());
                    }
                    _ => {}
                }
            }
            (points, status)
        };
        let origin = format!("device {}", config.name);
        let device = config.name.clone();
        let comm = CommunicationStatus::new(
            origin.clone(),
            status,
            move |source| matches!(source, PointSource::Device { device: d, .. } if *d == device),
        );
        DeviceReadings {
            node,
            device: config.name.clone(),
            origin,
            points,
            comm,
            answering: Arc::new(AtomicBool::new(false)),
            answered: AtomicBool::new(false),
            image: None,
        }
    }

    /// Every point invalid and the status point TRUE.
    fn down(&self) {
        self.comm.down(&self.node);
    }
}

impl Readings for DeviceReadings {
    fn value(&self, signal: &str, value: PointValue, quality: Quality) {
        let Some(&id) = self.points.get(signal) else {
            tracing::warn!(device = %self.device, signal, "the driver reports a signal its profile does not have");
            return;
        };
        if let Err(error) = self.node.update(
            id,
            value,
            quality,
            None,
            EventCause::Spontaneous,
            &self.origin,
            false,
        ) {
            tracing::warn!(device = %self.device, signal, %error, "value refused");
        }
    }

    fn image(&self) -> Option<&IoImage> {
        self.image.as_deref()
    }

    fn answering(&self, answering: bool) {
        if answering {
            self.answered.store(true, Ordering::Release);
        }
        if let Some(image) = &self.image {
            image.set_answering(answering);
        }
        if self.answering.swap(answering, Ordering::AcqRel) == answering {
            return;
        }
        if answering {
            tracing::info!(node = %self.node.name(), device = %self.device, "device answering");
            self.comm.up(&self.node);
        } else {
            tracing::warn!(node = %self.node.name(), device = %self.device, "device not answering");
            self.down();
        }
    }
}
