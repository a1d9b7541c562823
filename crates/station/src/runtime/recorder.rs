//! The path from the nodes to the event store: a channel and one writer task that appends
//! events in batches (one transaction per batch) so that a burst of changes costs one
//! commit, not one per event. A command's record can be awaited until it is committed
//! ([`Recorder::command_committed`]): a positive confirmation leaves only once its audit
//! record would survive a crash of the process (write-ahead).

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use tokio::sync::{mpsc, oneshot};

use crate::store::{CommandRecord, EventRecord, EventStore};

/// Events taken from the channel per transaction at most.
const BATCH: usize = 1024;

enum Record {
    Event(EventRecord),
    /// A command, and who waits for its commit (told whether it was stored).
    Command(CommandRecord, Option<oneshot::Sender<bool>>),
    Flush(oneshot::Sender<()>),
}

/// Hands records to the store writer; cheap to clone. Without a store it counts and drops.
#[derive(Clone)]
pub struct Recorder {
    sender: Option<mpsc::UnboundedSender<Record>>,
    counters: Arc<Counters>,
}

/// What the recorder has seen.
#[derive(Debug, Default)]
struct Counters {
    events: AtomicU64,
    commands: AtomicU64,
    failed: AtomicU64,
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
        let (sender, receiver) = mpsc::unbounded_channel();
        let counters = Arc::new(Counters::default());
        tokio::spawn(write_loop(store, receiver, Arc::clone(&counters)));
        Recorder {
            sender: Some(sender),
            counters,
        }
    }

    /// Records a value change.
    pub fn event(&self, record: EventRecord) {
        self.counters.events.fetch_add(1, Ordering::Relaxed);
        if let Some(sender) = &self.sender {
            let _ = sender.send(Record::Event(record));
        }
    }

    /// Records a command.
    pub fn command(&self, record: CommandRecord) {
        self.counters.commands.fetch_add(1, Ordering::Relaxed);
        if let Some(sender) = &self.sender {
            let _ = sender.send(Record::Command(record, None));
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
        if sender.send(Record::Flush(done)).is_ok() {
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
}

async fn write_loop(
    store: Arc<dyn EventStore>,
    mut receiver: mpsc::UnboundedReceiver<Record>,
    counters: Arc<Counters>,
) {
    let mut buffer = Vec::with_capacity(BATCH);
    let mut events = Vec::with_capacity(BATCH);
    while receiver.recv_many(&mut buffer, BATCH).await > 0 {
        for record in buffer.drain(..) {
            match record {
                Record::Event(event) => events.push(event),
                Record::Command(command, committed) => {
                    write_events(&*store, &mut events, &counters).await;
                    let stored = match store.append_command(&command).await {
                        Ok(_) => true,
                        Err(error) => {
                            counters.failed.fetch_add(1, Ordering::Relaxed);
                            tracing::error!(%error, point = %command.point, "command record lost");
                            false
                        }
                    };
                    if let Some(committed) = committed {
                        let _ = committed.send(stored);
                    }
                }
                Record::Flush(done) => {
                    write_events(&*store, &mut events, &counters).await;
                    let _ = done.send(());
                }
            }
        }
        write_events(&*store, &mut events, &counters).await;
    }
}

async fn write_events(store: &dyn EventStore, events: &mut Vec<EventRecord>, counters: &Counters) {
    if events.is_empty() {
        return;
    }
    if let Err(error) = store.append_events(events).await {
        // A batch is all or nothing; retry one by one so that one bad record does not take
        // its neighbours with it.
        tracing::warn!(%error, count = events.len(), "event batch refused; writing one by one");
        for event in events.iter() {
            if let Err(error) = store.append_events(std::slice::from_ref(event)).await {
                counters.failed.fetch_add(1, Ordering::Relaxed);
                tracing::error!(%error, point = %event.point, "event record lost");
            }
        }
    }
    events.clear();
}
