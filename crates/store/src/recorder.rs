//! The path from the nodes to the event store: a channel and one writer task that appends
//! events in batches (one transaction per batch) so that a burst of changes costs one
//! commit, not one per event. A command's record can be awaited until it is committed
//! ([`Recorder::command_committed`]): a positive confirmation leaves only once its audit
//! record would survive a crash of the process (write-ahead).
//!
//! Store, then forward: a node hands each change to the recorder together with what
//! forwards it to dispatch ([`Recorder::event_then`]), and the writer runs that only once
//! the batch holding the event is committed, so that a process killed at any instant has
//! stored every event a client above received (it may have stored some no client got:
//! those the clients read by interrogation after the restart). Changes not stored (left
//! out by a deadband) pass the same queue ([`Recorder::then`]), so that all leave in the
//! order the node took them. A store that is slow or gone holds them back for at most
//! [`FORWARD_DEADLINE`] (then they go up before their commit, in order, until the store
//! answers again: `Inbox::while_slow`): the historian must not stop a station's
//! telecontrol. A commit costs milliseconds (SQLite in WAL mode without a sync per
//! commit; one round trip to PostgreSQL), well inside IEC 104's timings.
//!
//! The channel is bounded ([`CHANNEL_CAPACITY`]): a store that cannot keep up (a
//! PostgreSQL server gone away) must not grow the process without limit. Events that do
//! not fit are dropped, counted and reported (a warning at most once a minute); commands
//! are never dropped: they wait for room.
//!
//! Every event leaves with an idempotent key ([`crate::EventKey`]): its own when the
//! source gave it one, else the recorder's (this run's identity and a sequence number), so
//! that a batch retried after an error whose commit did happen is not stored twice. The
//! recorder stores what it is given: which changes are worth a row (deadbands, storage
//! rate limits) the point's own storage rule decides before ([`points::StorageFilter`]).

use std::collections::VecDeque;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use tokio::sync::{mpsc, oneshot};

use crate::{CommandRecord, EventKey, EventRecord, EventStore};

/// Events taken from the channel per transaction at most. Only what is queued is taken,
/// so a quiet station writes small batches; under a flood a large batch costs far less
/// per event (the historian bench: SQLite 46,000/s in batches of 1,024, 59,000/s in 8,192).
const BATCH: usize = 8192;

/// Records waiting for the store at most: a minute of a busy station's changes.
pub const CHANNEL_CAPACITY: usize = 65_536;

/// How long a slow store may hold back the changes waiting for its commit before they
/// are forwarded anyway (the commit goes on).
pub const FORWARD_DEADLINE: std::time::Duration = std::time::Duration::from_secs(1);

/// What runs once an event is stored: forwards the change to the levels above.
pub type AfterStored = Box<dyn FnOnce() + Send>;

enum Record {
    /// An event, and what runs once it is stored.
    Event(EventRecord, Option<AfterStored>),
    /// What runs once every event queued before it is stored.
    Then(AfterStored),
    /// A command, and who waits for its commit (told whether it was stored).
    Command(CommandRecord, Option<oneshot::Sender<bool>>),
    Flush(oneshot::Sender<()>),
    /// Write what is queued, close the store and stop taking records.
    Close(oneshot::Sender<()>),
}

/// Hands records to the store writer; cheap to clone. Without a store it counts and drops.
#[derive(Clone)]
pub struct Recorder {
    sender: Option<mpsc::Sender<Record>>,
    counters: Arc<Counters>,
}

/// What the recorder has seen.
#[derive(Debug, Default)]
struct Counters {
    events: AtomicU64,
    commands: AtomicU64,
    failed: AtomicU64,
    /// Events dropped because the channel was full.
    overflowed: AtomicU64,
    /// When the overflow was last reported.
    overflow_warning: std::sync::Mutex<Option<std::time::Instant>>,
}

impl std::fmt::Debug for Recorder {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Recorder")
            .field("store", &self.sender.is_some())
            .field("counters", &self.counters)
            .finish()
    }
}

impl Recorder {
    /// A recorder that keeps nothing (no store configured).
    pub fn disabled() -> Recorder {
        Recorder {
            sender: None,
            counters: Arc::default(),
        }
    }

    /// A recorder writing to `store` from a task on the current tokio runtime.
    pub fn spawn(store: Arc<dyn EventStore>) -> Recorder {
        Recorder::spawn_with_capacity(store, CHANNEL_CAPACITY)
    }

    /// As [`Recorder::spawn`], with a channel of `capacity` records.
    pub fn spawn_with_capacity(store: Arc<dyn EventStore>, capacity: usize) -> Recorder {
        let (sender, receiver) = mpsc::channel(capacity.max(1));
        let counters = Arc::new(Counters::default());
        let writer = Writer {
            store,
            counters: Arc::clone(&counters),
            keys: EventKey::new(
                format!(
                    "recorder/{}/{}",
                    std::process::id(),
                    chrono::Utc::now().timestamp_millis()
                ),
                0,
            ),
        };
        tokio::spawn(writer.run(receiver));
        Recorder {
            sender: Some(sender),
            counters,
        }
    }

    /// Records a value change; when the channel is full the event is dropped and
    /// counted (see the module documentation).
    pub fn event(&self, record: EventRecord) {
        self.counters.events.fetch_add(1, Ordering::Relaxed);
        if let Some(sender) = &self.sender {
            if let Err(mpsc::error::TrySendError::Full(_)) =
                sender.try_send(Record::Event(record, None))
            {
                self.overflow();
            }
        }
    }

    /// Records a value change and runs `forward` once it is committed (store, then
    /// forward: see the module documentation). Without a store, or when the event is
    /// dropped for a full channel, `forward` runs at once: what the store cannot take
    /// still goes to dispatch.
    pub fn event_then(&self, record: EventRecord, forward: AfterStored) {
        self.counters.events.fetch_add(1, Ordering::Relaxed);
        let Some(sender) = &self.sender else {
            return forward();
        };
        match sender.try_send(Record::Event(record, Some(forward))) {
            Ok(()) => {}
            Err(mpsc::error::TrySendError::Full(record)) => {
                self.overflow();
                if let Record::Event(_, Some(forward)) = record {
                    forward();
                }
            }
            Err(mpsc::error::TrySendError::Closed(record)) => {
                if let Record::Event(_, Some(forward)) = record {
                    forward();
                }
            }
        }
    }

    /// Runs `forward` once every event recorded before is committed: a change the store
    /// leaves out keeps its place among those it keeps. At once without a store or when
    /// the channel is full.
    pub fn then(&self, forward: AfterStored) {
        let Some(sender) = &self.sender else {
            return forward();
        };
        if let Err(
            mpsc::error::TrySendError::Full(Record::Then(forward))
            | mpsc::error::TrySendError::Closed(Record::Then(forward)),
        ) = sender.try_send(Record::Then(forward))
        {
            forward();
        }
    }

    fn overflow(&self) {
        let dropped = self.counters.overflowed.fetch_add(1, Ordering::Relaxed) + 1;
        let mut last = self
            .counters
            .overflow_warning
            .lock()
            .unwrap_or_else(|poison| poison.into_inner());
        let now = std::time::Instant::now();
        if last.is_none_or(|at| now.duration_since(at) >= std::time::Duration::from_secs(60)) {
            *last = Some(now);
            tracing::warn!(
                dropped,
                capacity = CHANNEL_CAPACITY,
                "the event store does not keep up: events are being dropped"
            );
        }
    }

    /// Records a command without waiting for its commit. A command is never dropped:
    /// when the channel is full it waits for room on a task of its own (the caller may be
    /// the simulation thread, which must not block).
    pub fn command(&self, record: CommandRecord) {
        self.counters.commands.fetch_add(1, Ordering::Relaxed);
        if let Some(sender) = &self.sender {
            if let Err(mpsc::error::TrySendError::Full(record)) =
                sender.try_send(Record::Command(record, None))
            {
                let sender = sender.clone();
                match tokio::runtime::Handle::try_current() {
                    Ok(runtime) => {
                        runtime.spawn(async move {
                            let _ = sender.send(record).await;
                        });
                    }
                    Err(_) => {
                        let _ = sender.blocking_send(record);
                    }
                }
            }
        }
    }

    /// Records a command and waits until its record (and every event recorded before it)
    /// is committed to the store; returns whether it was stored (`true` without a store:
    /// there is nothing to wait for).
    pub async fn command_committed(&self, record: CommandRecord) -> bool {
        self.counters.commands.fetch_add(1, Ordering::Relaxed);
        let Some(sender) = &self.sender else {
            return true;
        };
        let (committed, wait) = oneshot::channel();
        if sender
            .send(Record::Command(record, Some(committed)))
            .await
            .is_err()
        {
            return false;
        }
        wait.await.unwrap_or(false)
    }

    /// Waits until everything recorded before this call is in the store.
    pub async fn flush(&self) {
        let Some(sender) = &self.sender else { return };
        let (done, wait) = oneshot::channel();
        if sender.send(Record::Flush(done)).await.is_ok() {
            let _ = wait.await;
        }
    }

    /// At shutdown: writes what is queued, closes the store ([`EventStore::close`]) and
    /// stops; records handed over afterwards (a last value from a connection still
    /// closing) are dropped without a word, as they come after the stop was asked for.
    pub async fn close(&self) {
        let Some(sender) = &self.sender else { return };
        let (done, wait) = oneshot::channel();
        if sender.send(Record::Close(done)).await.is_ok() {
            let _ = wait.await;
        }
    }

    /// (events recorded, commands recorded, records the store refused).
    pub fn counts(&self) -> (u64, u64, u64) {
        (
            self.counters.events.load(Ordering::Relaxed),
            self.counters.commands.load(Ordering::Relaxed),
            self.counters.failed.load(Ordering::Relaxed),
        )
    }

    /// Events dropped because the store did not keep up.
    pub fn overflowed(&self) -> u64 {
        self.counters.overflowed.load(Ordering::Relaxed)
    }
}

/// Where the writer takes its records from: the records taken from the channel and not
/// yet handled, in order, then the channel.
struct Inbox {
    receiver: mpsc::Receiver<Record>,
    queue: VecDeque<Record>,
}

impl Inbox {
    /// Waits for records and takes what is queued (at most [`BATCH`]); `false` once the
    /// channel is closed and empty.
    async fn fill(&mut self) -> bool {
        let mut taken = Vec::with_capacity(BATCH);
        let received = self.receiver.recv_many(&mut taken, BATCH).await;
        self.queue.extend(taken);
        received > 0
    }

    /// Drives `work` (a write to the store) to its end, then runs `forwards` (in order).
    /// When the store takes longer than [`FORWARD_DEADLINE`], `forwards` run at the
    /// deadline, then those of the records taken and not yet handled, and until the store
    /// answers what arrives is forwarded at once and queued for the writes after (at most
    /// [`CHANNEL_CAPACITY`] records: beyond, the channel fills and the callers forward
    /// themselves). A store that hangs (a PostgreSQL server gone: a connect timeout of
    /// seconds, a retry per event) holds the station's changes back by the deadline, not
    /// by its outage, and they still go up in the order they came.
    async fn while_slow<T>(
        &mut self,
        work: impl std::future::Future<Output = T>,
        forwards: &mut Vec<AfterStored>,
    ) -> T {
        tokio::pin!(work);
        if let Ok(done) = tokio::time::timeout(FORWARD_DEADLINE, &mut work).await {
            forwards.drain(..).for_each(|forward| forward());
            return done;
        }
        tracing::warn!(
            waiting = forwards.len() + self.queue.len(),
            "the event store has not answered in {FORWARD_DEADLINE:?}: changes go up before \
             their commit until it does"
        );
        forwards.drain(..).for_each(|forward| forward());
        self.queue.retain_mut(|record| match record {
            Record::Event(_, forward) => {
                if let Some(forward) = forward.take() {
                    forward();
                }
                true
            }
            Record::Then(forward) => {
                // Run and dropped (a no-op closure in its place allocates nothing).
                std::mem::replace(forward, Box::new(|| {}))();
                false
            }
            _ => true,
        });
        loop {
            tokio::select! {
                biased;
                done = &mut work => return done,
                record = self.receiver.recv(), if self.queue.len() < CHANNEL_CAPACITY => {
                    match record {
                        Some(Record::Event(event, forward)) => {
                            if let Some(forward) = forward {
                                forward();
                            }
                            self.queue.push_back(Record::Event(event, None));
                        }
                        Some(Record::Then(forward)) => forward(),
                        Some(other) => self.queue.push_back(other),
                        None => return work.await,
                    }
                }
            }
        }
    }
}

/// The write task: the store and the next key of this run.
struct Writer {
    store: Arc<dyn EventStore>,
    counters: Arc<Counters>,
    /// The key the next event without one gets.
    keys: EventKey,
}

impl Writer {
    async fn run(mut self, receiver: mpsc::Receiver<Record>) {
        let mut inbox = Inbox {
            receiver,
            queue: VecDeque::with_capacity(BATCH),
        };
        let mut events = Vec::with_capacity(BATCH);
        let mut forwards: Vec<AfterStored> = Vec::new();
        loop {
            let Some(record) = inbox.queue.pop_front() else {
                // Everything taken: one transaction for the events gathered, then wait.
                inbox
                    .while_slow(self.write(&mut events), &mut forwards)
                    .await;
                if inbox.queue.is_empty() && !inbox.fill().await {
                    return;
                }
                continue;
            };
            match record {
                Record::Event(event, forward) => {
                    events.push(self.keyed(event));
                    forwards.extend(forward);
                }
                Record::Then(forward) => forwards.push(forward),
                Record::Command(command, committed) => {
                    inbox
                        .while_slow(self.write(&mut events), &mut forwards)
                        .await;
                    let appended = inbox
                        .while_slow(self.store.append_command(&command), &mut forwards)
                        .await;
                    let stored = match appended {
                        Ok(_) => true,
                        Err(error) => {
                            self.counters.failed.fetch_add(1, Ordering::Relaxed);
                            tracing::error!(%error, point = %command.point, "command record lost");
                            false
                        }
                    };
                    if let Some(committed) = committed {
                        let _ = committed.send(stored);
                    }
                }
                Record::Flush(done) => {
                    inbox
                        .while_slow(self.write(&mut events), &mut forwards)
                        .await;
                    let _ = done.send(());
                }
                Record::Close(done) => {
                    inbox
                        .while_slow(self.write(&mut events), &mut forwards)
                        .await;
                    if let Err(error) = self.store.close().await {
                        tracing::warn!(%error, "the store did not close cleanly");
                    }
                    let _ = done.send(());
                    // The receiver goes: later records find the channel closed.
                    return;
                }
            }
        }
    }

    /// The event with a key: its own, or the next of this run.
    fn keyed(&mut self, mut event: EventRecord) -> EventRecord {
        if event.key.is_none() {
            event.key = Some(self.keys.clone());
            self.keys.sequence += 1;
        }
        event
    }

    async fn write(&self, events: &mut Vec<EventRecord>) {
        if events.is_empty() {
            return;
        }
        if let Err(error) = self.store.append_events(events).await {
            // A batch is all or nothing; retry one by one so that one bad record does not
            // take its neighbours with it. Had the batch been committed after all (the
            // connection lost before the answer), the keys make the retry store nothing
            // twice.
            tracing::warn!(%error, count = events.len(), "event batch refused; writing one by one");
            for event in events.iter() {
                if let Err(error) = self.store.append_events(std::slice::from_ref(event)).await {
                    self.counters.failed.fetch_add(1, Ordering::Relaxed);
                    tracing::error!(%error, point = %event.point, "event record lost");
                }
            }
        }
        events.clear();
    }
}
