//! A node's lifts (`[[node.lift]]`): the lift-monitoring role. Each lift is one EKM66
//! controller board on its own line (a serial port in the machine room, an
//! RS-232-to-Ethernet converter, or a simulated board in this process), polled by the
//! sans-IO [`Poller`] of `devices` and read only: the lift is never controlled.
//!
//! ```text
//!  board --line--> Poller --Event--> lift task --values--> NodePoints (IEC 104, events)
//!                    ^                    \--Fault--> archive writer --> EventStore.lift_faults
//!                    |                                        \--> LastFault, Faults points
//!   ArchiveCursor <--+-- rebuilt from the store's newest records     \--> ArchivedFault (broadcast:
//!                                                                         notifications, HMI)
//! ```
//!
//! - The archive remembers what it has: at start the lift's cursor is rebuilt from the
//!   newest records of the store, so that a restart of the station neither repeats nor
//!   loses a record of the board's fault log (the poller's synchronisation does the rest,
//!   wrap-around and a restarted board included).
//! - A record is archived with the board's time of occurrence and the time received; the
//!   points `LIFT.last_fault` and `LIFT.faults` change once it is committed.
//! - A board that stops answering turns the lift's points invalid and `LIFT.not_answering`
//!   TRUE (the communication alarm); a line that closes (a converter's TCP connection
//!   dropped, a serial adapter unplugged) is opened again with the cursor where it stood,
//!   after the field-source supervisor's pause (`field::supervise`).

use super::operation::OperationError;
use std::collections::HashMap;
use std::ops::ControlFlow;
use std::sync::Arc;
use std::time::Duration;

use chrono::{NaiveDate, NaiveDateTime};
use devices::ekm66::codec::{Direction, FaultRecord, FaultTime, Status, TimeOfDay};
use devices::ekm66::io::{run_poller, EndpointAction, LineStream, Transport};
use devices::ekm66::poller::{ArchiveCursor, CommStatus, Event, FaultKey, Poller};
use devices::ekm66::simulator::Simulator;
use devices::ekm66::tables::{self, ColourClass, StatusColours};
use tokio::sync::{broadcast, mpsc, watch};

use crate::config::{LiftConfig, LiftTransport};
use crate::store::{EventCause, EventStore, LiftFaultQuery, LiftFaultRecord, PointValue, Quality};
use points::{LiftSignal, PointId, PointSource};

use super::field::{supervise, CommunicationStatus, Ended, FieldSource};
use super::node::NodePoints;
use super::notification::Notifications;
use crate::device::DeviceError;

/// How many archived records rebuild the cursor: more than the largest fault stack, so
/// that every record still on the board is recognised.
const CURSOR_RECORDS: u32 = 512;

/// A fault record once it is in the archive (committed to the store, or only logged
/// when the station runs without one).
pub type ArchivedFault = LiftFaultRecord;

/// What a lift task needs.
#[derive(Debug, Clone)]
pub(crate) struct LiftSpec {
    pub config: LiftConfig,
    /// Its points by signal.
    pub points: HashMap<LiftSignal, PointId>,
}

impl LiftSpec {
    /// The spec of `config` with the ids of its points in `node`'s database.
    pub(crate) fn new(config: &LiftConfig, node: &NodePoints) -> LiftSpec {
        let db = node.lock();
        let points = db
            .points()
            .filter_map(|point| match &point.spec.source {
                PointSource::Lift { lift, signal } if *lift == config.name => {
                    db.id(point.spec.name.as_str()).map(|id| (*signal, id))
                }
                _ => None,
            })
            .collect();
        LiftSpec {
            config: config.clone(),
            points,
        }
    }
}

/// A running lift.
#[derive(Clone)]
pub struct LiftHandle {
    name: String,
    /// The simulated board's operations (`None` for a real board).
    simulated: Option<mpsc::UnboundedSender<EndpointAction<Simulator>>>,
    /// The polling task.
    task: tokio::task::AbortHandle,
    /// TRUE once the archive writer has written what it had (or was never started).
    archive_finished: watch::Receiver<bool>,
    /// What the poller has done so far.
    counts: Arc<PollCounts>,
}

/// Counts of a lift's polling, for monitoring and the fleet benchmark.
#[derive(Debug, Default)]
pub struct PollCounts {
    status_replies: std::sync::atomic::AtomicU64,
    line_errors: std::sync::atomic::AtomicU64,
}

impl PollCounts {
    /// Status replies received.
    pub fn status_replies(&self) -> u64 {
        self.status_replies
            .load(std::sync::atomic::Ordering::Relaxed)
    }

    /// Line errors (time-outs, invalid replies).
    pub fn line_errors(&self) -> u64 {
        self.line_errors.load(std::sync::atomic::Ordering::Relaxed)
    }
}

impl std::fmt::Debug for LiftHandle {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LiftHandle")
            .field("name", &self.name)
            .finish_non_exhaustive()
    }
}

impl LiftHandle {
    /// The lift's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// What the poller has done so far.
    pub fn counts(&self) -> &PollCounts {
        &self.counts
    }

    /// Stops polling; the records already read are still archived ([`Self::stopped`]
    /// waits for that).
    pub fn stop(&self) {
        self.task.abort();
    }

    /// Resolves once the lift is stopped and its archive writer has written every record
    /// it had.
    pub async fn stopped(&self) {
        let mut finished = self.archive_finished.clone();
        // An error: the writer was never started (stopped while reading the archive).
        let _ = finished.wait_for(|finished| *finished).await;
    }

    /// Whether its board is simulated in this process.
    pub fn is_simulated(&self) -> bool {
        self.simulated.is_some()
    }

    /// An operation on the simulated board (`fault 3C`, `silent`, `trip 4` ...:
    /// [`devices::ekm66::console::HELP`]); what happened, or why not.
    pub async fn operate(&self, words: &[&str]) -> Result<String, OperationError> {
        let Some(simulated) = &self.simulated else {
            return Err(OperationError::RealBoard(self.name.clone()));
        };
        let stopped = || OperationError::Stopped(format!("lift {}", self.name));
        let words: Vec<String> = words.iter().map(|word| (*word).to_owned()).collect();
        let (done, answer) = tokio::sync::oneshot::channel();
        simulated
            .send(Box::new(move |board: &mut Simulator| {
                let words: Vec<&str> = words.iter().map(String::as_str).collect();
                let _ = done.send(devices::ekm66::console::operate(board, &words));
            }))
            .map_err(|_| stopped())?;
        answer
            .await
            .map_err(|_| stopped())?
            .map_err(OperationError::Refused)
    }
}

/// Starts the lift's task (and its simulated board). Archived faults are also sent to
/// `archived`.
pub(crate) fn spawn_lift(
    spec: LiftSpec,
    node: Arc<NodePoints>,
    store: Option<Arc<dyn EventStore>>,
    archived: broadcast::Sender<ArchivedFault>,
    notifications: Option<Notifications>,
) -> LiftHandle {
    let name = spec.config.name.clone();
    let (simulated, board) = match &spec.config.transport {
        LiftTransport::Simulated(_) => {
            let (sender, receiver) = mpsc::unbounded_channel();
            (Some(sender), Some(receiver))
        }
        _ => None.unzip(),
    };
    let (finished, archive_finished) = watch::channel(false);
    let counts = Arc::new(PollCounts::default());
    let task = tokio::spawn(run(
        spec,
        node,
        Arc::clone(&counts),
        store,
        Outlets {
            archived,
            notifications,
        },
        board,
        finished,
    ))
    .abort_handle();
    LiftHandle {
        name,
        simulated,
        task,
        archive_finished,
        counts,
    }
}

/// Where a lift's archived faults and alarms go besides its points.
#[derive(Clone)]
struct Outlets {
    archived: broadcast::Sender<ArchivedFault>,
    notifications: Option<Notifications>,
}

/// The lift's task: rebuild the cursor, then open, poll, reopen.
async fn run(
    spec: LiftSpec,
    node: Arc<NodePoints>,
    counts: Arc<PollCounts>,
    store: Option<Arc<dyn EventStore>>,
    outlets: Outlets,
    board: Option<mpsc::UnboundedReceiver<EndpointAction<Simulator>>>,
    finished: watch::Sender<bool>,
) {
    let lift = Lift::new(spec, Arc::clone(&node));
    let (cursor, faults, newest) = match &store {
        Some(store) => rebuild_cursor(store.as_ref(), node.name(), &lift.spec.config.name).await,
        None => (ArchiveCursor::default(), 0, None),
    };
    lift.set(LiftSignal::Faults, total(faults));
    lift.set(LiftSignal::Errors, total(0));
    if let Some(code) = newest {
        lift.set(LiftSignal::LastFault, PointValue::Int(code.into()));
    }
    let (to_archive, queue) = mpsc::unbounded_channel();
    tokio::spawn(archive(
        queue,
        store,
        Arc::clone(&node),
        lift.clone(),
        faults,
        outlets.clone(),
        finished,
    ));
    let simulated_board = match &lift.spec.config.transport {
        LiftTransport::Simulated(config) => Some(Simulator::new(
            config.clone(),
            tokio::time::Instant::now().into_std(),
        )),
        _ => None,
    };
    let source = LiftSource {
        lift,
        node: Arc::clone(&node),
        counts,
        outlets,
        to_archive,
        cursor,
        simulated_board,
        board,
        errors: 0,
        answering: false,
    };
    supervise(node.name(), source).await;
}

/// A lift's board under the field-source supervisor.
struct LiftSource {
    lift: Lift,
    node: Arc<NodePoints>,
    counts: Arc<PollCounts>,
    outlets: Outlets,
    to_archive: mpsc::UnboundedSender<FaultRecord>,
    /// Where the fault log was read to: kept across reopenings of the line.
    cursor: ArchiveCursor,
    /// The simulated board, until its line is first opened.
    simulated_board: Option<Simulator>,
    board: Option<mpsc::UnboundedReceiver<EndpointAction<Simulator>>>,
    /// Line errors since the start.
    errors: u64,
    /// Whether the board answered since it was last reported lost: a loss is notified
    /// once, not at every reopening of a dead line.
    answering: bool,
}

impl LiftSource {
    /// The board is lost: its points invalid and, if it had answered, the loss notified.
    fn lost(lift: &Lift, node: &NodePoints, outlets: &Outlets, answering: &mut bool) {
        lift.down();
        if std::mem::take(answering) {
            if let Some(notifications) = &outlets.notifications {
                notifications.comm_lost(
                    &lift.spec.config.name,
                    &lift.description(),
                    node.clock().now(),
                );
            }
        }
    }
}

impl FieldSource for LiftSource {
    type Line = std::pin::Pin<Box<dyn LineStream>>;

    fn describe(&self) -> String {
        format!("lift {}", self.lift.spec.config.name)
    }

    async fn open(&mut self) -> Result<Self::Line, DeviceError> {
        Ok(open(
            &self.lift.spec.config,
            &mut self.simulated_board,
            &mut self.board,
        )
        .await?)
    }

    async fn run(&mut self, stream: Self::Line) -> Ended {
        let LiftSource {
            lift,
            node,
            counts,
            outlets,
            to_archive,
            cursor,
            errors,
            answering,
            ..
        } = self;
        let mut poller = Poller::new(
            lift.spec.config.poller.clone(),
            cursor.clone(),
            tokio::time::Instant::now().into_std(),
        );
        let mut answered = false;
        let mut no_actions = mpsc::unbounded_channel().1;
        let end = run_poller(stream, &mut poller, &mut no_actions, |event, _| {
            match event {
                Event::Status(status) => {
                    *answering = true;
                    answered = true;
                    counts
                        .status_replies
                        .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    lift.status(&status);
                }
                Event::Counters(counters) => lift.counters(&counters),
                Event::Fault(record) => {
                    let _ = to_archive.send(record);
                }
                Event::Comm(CommStatus::Lost) => {
                    LiftSource::lost(lift, node, outlets, answering);
                }
                Event::Comm(_) => {}
                Event::Error(error) => {
                    *errors += 1;
                    counts
                        .line_errors
                        .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    tracing::debug!(lift = %lift.spec.config.name, %error, "line error");
                    lift.set(LiftSignal::Errors, total(*errors));
                }
                Event::Resync(reason) => {
                    tracing::info!(lift = %lift.spec.config.name, ?reason, "reading the fault log again");
                }
            }
            ControlFlow::Continue(())
        })
        .await;
        *cursor = poller.cursor().clone();
        Ended {
            answered,
            reason: format!("{end:?}"),
        }
    }

    fn lost(&mut self) {
        // A converter's connection dropped or an adapter unplugged: the board is lost as
        // surely as one that stopped answering.
        LiftSource::lost(&self.lift, &self.node, &self.outlets, &mut self.answering);
    }
}

/// Opens the lift's line; a simulated board runs on an in-memory line of its own.
async fn open(
    config: &LiftConfig,
    simulated: &mut Option<Simulator>,
    operations: &mut Option<mpsc::UnboundedReceiver<EndpointAction<Simulator>>>,
) -> std::io::Result<std::pin::Pin<Box<dyn LineStream>>> {
    match &config.transport {
        LiftTransport::Serial(path) => Ok(Transport::Serial {
            path: path.clone(),
            line: config.poller.line,
        }
        .open()
        .await?
        .stream),
        LiftTransport::Tcp(address) => Ok(Transport::Connect(address.clone()).open().await?.stream),
        LiftTransport::Simulated(_) => {
            let (ours, theirs) = tokio::io::duplex(4096);
            // The board (its memory, clock and operations) lives as long as the lift
            // task; it is opened once and stays on its line.
            let (Some(mut board), Some(mut operations)) = (simulated.take(), operations.take())
            else {
                return Err(std::io::Error::other("the simulated board stopped"));
            };
            tokio::spawn(async move {
                let _ = devices::ekm66::io::run_simulator(
                    Box::pin(theirs),
                    &mut board,
                    &mut operations,
                    |_| ControlFlow::Continue(()),
                )
                .await;
            });
            Ok(Box::pin(ours))
        }
    }
}

/// The cursor from the lift's newest archived records, how many it has in all, and the
/// code of the newest.
async fn rebuild_cursor(
    store: &dyn EventStore,
    node: &str,
    lift: &str,
) -> (ArchiveCursor, u64, Option<u8>) {
    let query = LiftFaultQuery::newest(node, lift, CURSOR_RECORDS);
    match store.query_lift_faults(&query).await {
        Ok(page) => {
            // Newest first from the store; the cursor keeps them oldest first. A record
            // whose date the board got wrong has no key to rebuild (see `fault_key`).
            let known: std::collections::VecDeque<FaultKey> =
                page.items.iter().rev().filter_map(fault_key).collect();
            let cursor = ArchiveCursor {
                base: None,
                last: page.items.first().and_then(fault_key),
                known,
            };
            (
                cursor,
                page.total,
                page.items.first().map(|record| record.code),
            )
        }
        Err(error) => {
            tracing::error!(%node, %lift, %error, "cannot read the fault archive: starting without it (records may be archived twice)");
            (ArchiveCursor::default(), 0, None)
        }
    }
}

/// The key of an archived record, as the poller made it from the board's reply.
fn fault_key(record: &LiftFaultRecord) -> Option<FaultKey> {
    use chrono::{Datelike, Timelike};
    let time = record.board_time?;
    let octet = |value: u32| u8::try_from(value).ok();
    Some(FaultKey {
        index: record.stack_index,
        code: record.code,
        time: FaultTime {
            year: u16::try_from(time.year()).ok()?,
            month: octet(time.month())?,
            day: octet(time.day())?,
            time: TimeOfDay {
                hour: octet(time.hour())?,
                minute: octet(time.minute())?,
                second: octet(time.second())?,
            },
        },
    })
}

/// The board's time of a record; `None` for a date that does not exist.
fn board_time(time: &FaultTime) -> Option<NaiveDateTime> {
    NaiveDate::from_ymd_opt(time.year.into(), time.month.into(), time.day.into())?.and_hms_opt(
        time.time.hour.into(),
        time.time.minute.into(),
        time.time.second.into(),
    )
}

/// The archive writer of one lift: each record into the store (retried while the store
/// fails), then the lift's fault points and the broadcast.
async fn archive(
    mut queue: mpsc::UnboundedReceiver<FaultRecord>,
    store: Option<Arc<dyn EventStore>>,
    node: Arc<NodePoints>,
    lift: Lift,
    mut count: u64,
    outlets: Outlets,
    finished: watch::Sender<bool>,
) {
    while let Some(fault) = queue.recv().await {
        let record = LiftFaultRecord {
            id: None,
            node: node.name().to_owned(),
            lift: lift.spec.config.name.clone(),
            stack_index: fault.index,
            code: fault.code,
            floor: fault.floor,
            target: fault.target,
            board_time: board_time(&fault.time),
            // Milliseconds, as the store keeps it: the record broadcast is the one stored.
            received_time: chrono::DateTime::from_timestamp_millis(
                node.clock().now().timestamp_millis(),
            )
            .unwrap_or_default(),
        };
        let mut record = record;
        if let Some(store) = &store {
            let mut attempt = 0u32;
            loop {
                match store
                    .append_lift_faults(std::slice::from_ref(&record))
                    .await
                {
                    Ok(ids) => {
                        record.id = ids.first().copied();
                        break;
                    }
                    Err(error) if attempt < 10 => {
                        attempt += 1;
                        tracing::warn!(lift = %record.lift, %error, attempt, "cannot archive a fault; trying again");
                        tokio::time::sleep(Duration::from_secs(1)).await;
                    }
                    Err(error) => {
                        // The poller has moved on; the record is read again after the
                        // next restart (the cursor is rebuilt from the store).
                        tracing::error!(lift = %record.lift, %error, "fault not archived");
                        break;
                    }
                }
            }
        }
        count += 1;
        tracing::info!(
            node = %record.node,
            lift = %record.lift,
            code = record.code,
            index = record.stack_index,
            board_time = ?record.board_time,
            "fault archived: {}",
            tables::fault_text(record.code)
        );
        lift.set(LiftSignal::LastFault, PointValue::Int(record.code.into()));
        lift.set(LiftSignal::Faults, total(count));
        if let Some(notifications) = &outlets.notifications {
            notifications.fault(&record, &lift.description());
        }
        let _ = outlets.archived.send(record);
    }
    let _ = finished.send(true);
}

/// A count as an integrated total (32 bits, wrapping as a counter does).
fn total(count: u64) -> PointValue {
    // The low 32 bits, as the counter's wire form: wrapping is what a counter does.
    #[allow(clippy::cast_possible_truncation)]
    let low = count as u32;
    PointValue::Int(i32::from_ne_bytes(low.to_ne_bytes()).into())
}

/// A lift's points.
#[derive(Clone)]
struct Lift {
    spec: Arc<LiftSpec>,
    node: Arc<NodePoints>,
    origin: Arc<str>,
    colours: Arc<StatusColours>,
}

impl Lift {
    fn new(spec: LiftSpec, node: Arc<NodePoints>) -> Lift {
        let origin: Arc<str> = format!("lift {}", spec.config.name).into();
        Lift {
            spec: Arc::new(spec),
            node,
            origin,
            colours: Arc::new(StatusColours::default()),
        }
    }

    /// ` (description)` for messages, or nothing.
    fn description(&self) -> String {
        if self.spec.config.description.is_empty() {
            String::new()
        } else {
            format!(" ({})", self.spec.config.description)
        }
    }

    fn set(&self, signal: LiftSignal, value: PointValue) {
        let Some(id) = self.spec.points.get(&signal) else {
            return;
        };
        if let Err(error) = self.node.update(
            *id,
            value,
            Quality::GOOD,
            None,
            EventCause::Spontaneous,
            &self.origin,
            false,
        ) {
            tracing::warn!(lift = %self.spec.config.name, ?signal, %error, "value refused");
        }
    }

    /// A status reply: the board answers.
    fn status(&self, status: &Status) {
        let colour = self.colours.class(status.code);
        let mode = tables::lift_mode(status.code);
        self.set(LiftSignal::NotAnswering, PointValue::Bool(false));
        self.set(LiftSignal::Status, PointValue::Int(status.code.into()));
        self.set(
            LiftSignal::Colour,
            PointValue::Int(match colour {
                ColourClass::Green => 0,
                ColourClass::Orange => 1,
                ColourClass::Red => 2,
            }),
        );
        self.set(
            LiftSignal::Position,
            PointValue::Int(status.position.into()),
        );
        self.set(LiftSignal::Target, PointValue::Int(status.target.into()));
        self.set(
            LiftSignal::Direction,
            PointValue::Int(match status.direction {
                Direction::Stopped => 0,
                Direction::Up => 1,
                Direction::Down => 2,
                _ => 0,
            }),
        );
        self.set(LiftSignal::Door, PointValue::Int(door_code(status.code)));
        self.set(
            LiftSignal::OutOfService,
            PointValue::Bool(mode == tables::LiftMode::OutOfService),
        );
        self.set(
            LiftSignal::Inspection,
            PointValue::Bool(mode == tables::LiftMode::Inspection),
        );
    }

    /// A counter reply.
    fn counters(&self, counters: &[u32]) {
        let mut sum: u64 = 0;
        for (floor, count) in (1..=self.spec.config.floors).zip(counters) {
            sum += u64::from(*count);
            self.set(LiftSignal::FloorTrips(floor), total(u64::from(*count)));
        }
        self.set(LiftSignal::Trips, total(sum));
    }

    /// The board does not answer: its values invalid, the communication alarm on.
    /// The board does not answer: its readings invalid (the monitor's own counts, the
    /// archive's points and the alarm itself stay valid), the communication alarm on.
    fn down(&self) {
        let lift = self.spec.config.name.clone();
        let comm = CommunicationStatus::new(
            self.origin.to_string(),
            Some(LiftSignal::NotAnswering.point_name(&lift)),
            move |source| {
                matches!(source, PointSource::Lift { lift: l, signal }
                    if *l == lift && !matches!(signal, LiftSignal::NotAnswering | LiftSignal::Errors | LiftSignal::Faults | LiftSignal::LastFault))
            },
        );
        comm.down(&self.node);
    }
}

/// The door point's value for a status: 0 unknown, 1 closed, 2 partly open, 3 open, 4
/// door fault.
fn door_code(status: u8) -> i64 {
    match tables::door_state(status) {
        None => 0,
        Some(tables::DoorState::Closed) => 1,
        Some(tables::DoorState::PartlyOpen) => 2,
        Some(tables::DoorState::Open) => 3,
        Some(tables::DoorState::Fault) => 4,
    }
}
