//! The recorder's bounded channel: a store that does not keep up makes events drop,
//! counted and reported, while the process does not grow and commands are never lost.
//! Store, then forward: what a node hands over with an event runs once it is committed.

use std::sync::Arc;

use chrono::{DateTime, Utc};
use store::Recorder;
use store::{
    open_store, Backend, CommandQuery, CommandRecord, CountedPage, EventQuery, EventRecord,
    EventStore, LiftFaultArchive, LiftFaultQuery, LiftFaultRecord, NotificationLog,
    NotificationQuery, NotificationRecord, Page, PointValue, RecordId, StoreFuture, StoreStats,
};
use tokio::sync::{Notify, Semaphore};

use crate::suite::ev;

/// A SQLite store whose appends wait until the test lets them through.
struct Stalled {
    inner: Box<dyn EventStore>,
    gate: Semaphore,
    /// Told when an append of events begins waiting at the gate.
    entered: Notify,
}

impl Stalled {
    async fn closed() -> Arc<Stalled> {
        Arc::new(Stalled {
            inner: open_store("sqlite::memory:").await.unwrap(),
            gate: Semaphore::new(0),
            entered: Notify::new(),
        })
    }
}

impl EventStore for Stalled {
    fn backend(&self) -> Backend {
        self.inner.backend()
    }
    fn append_events<'a>(&'a self, events: &'a [EventRecord]) -> StoreFuture<'a, Vec<RecordId>> {
        Box::pin(async move {
            self.entered.notify_one();
            let _pass = self.gate.acquire().await;
            self.inner.append_events(events).await
        })
    }
    fn append_command<'a>(&'a self, command: &'a CommandRecord) -> StoreFuture<'a, RecordId> {
        Box::pin(async move {
            let _pass = self.gate.acquire().await;
            self.inner.append_command(command).await
        })
    }
    fn query_events<'a>(&'a self, query: &'a EventQuery) -> StoreFuture<'a, Page<EventRecord>> {
        self.inner.query_events(query)
    }
    fn query_commands<'a>(
        &'a self,
        query: &'a CommandQuery,
    ) -> StoreFuture<'a, Page<CommandRecord>> {
        self.inner.query_commands(query)
    }
    fn purge_older_than(&self, cutoff: DateTime<Utc>) -> StoreFuture<'_, u64> {
        self.inner.purge_older_than(cutoff)
    }
    fn stats(&self) -> StoreFuture<'_, StoreStats> {
        self.inner.stats()
    }

    fn close(&self) -> StoreFuture<'_, ()> {
        self.inner.close()
    }
}

impl LiftFaultArchive for Stalled {
    fn append_lift_faults<'a>(
        &'a self,
        faults: &'a [LiftFaultRecord],
    ) -> StoreFuture<'a, Vec<RecordId>> {
        self.inner.append_lift_faults(faults)
    }
    fn query_lift_faults<'a>(
        &'a self,
        query: &'a LiftFaultQuery,
    ) -> StoreFuture<'a, CountedPage<LiftFaultRecord>> {
        self.inner.query_lift_faults(query)
    }
}

impl NotificationLog for Stalled {
    fn append_notification<'a>(
        &'a self,
        record: &'a NotificationRecord,
    ) -> StoreFuture<'a, RecordId> {
        self.inner.append_notification(record)
    }
    fn query_notifications<'a>(
        &'a self,
        query: &'a NotificationQuery,
    ) -> StoreFuture<'a, CountedPage<NotificationRecord>> {
        self.inner.query_notifications(query)
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_stalled_store_drops_counted_events_but_keeps_every_command() {
    let store = Stalled::closed().await;
    let recorder = Recorder::spawn_with_capacity(store.clone(), 16);
    for index in 0..1000 {
        recorder.event(ev("P", PointValue::Int(index), index));
    }
    // The channel holds 16 and the stalled writer what it took before stalling (at most
    // what the channel held then): the rest was dropped and counted.
    assert!(
        recorder.overflowed() >= 1000 - 2 * 16,
        "{}",
        recorder.overflowed()
    );
    let command = command_record();
    recorder.command(command.clone());
    let committed = {
        let recorder = recorder.clone();
        let command = command.clone();
        tokio::spawn(async move { recorder.command_committed(command).await })
    };
    store.gate.add_permits(1_000_000);
    assert!(committed.await.unwrap());
    recorder.flush().await;
    let commands = store
        .query_commands(&CommandQuery::default())
        .await
        .unwrap()
        .items;
    assert_eq!(commands.len(), 2, "no command is dropped");
    let (events, _, failed) = recorder.counts();
    assert_eq!((events, failed), (1000, 0));
}

/// Every event the recorder writes carries a key of its own (one source, consecutive
/// numbers), and every event given is stored.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_event_gets_a_key() {
    let store: Arc<dyn EventStore> = Arc::from(open_store("sqlite::memory:").await.unwrap());
    let recorder = Recorder::spawn(Arc::clone(&store));
    // A counter changing every 0.5 s for an hour, and a breaker switching as often.
    for i in 0..7200 {
        recorder.event(ev("C", PointValue::Int(i), i * 500));
        recorder.event(ev("Q", PointValue::Bool(i % 2 == 0), i * 500));
    }
    recorder.flush().await;
    assert_eq!(store.stats().await.unwrap().events, 2 * 7200);
    let mut keys = Vec::new();
    let mut after = None;
    loop {
        let page = store
            .query_events(&EventQuery::default().with_limit(1000).with_after(after))
            .await
            .unwrap();
        keys.extend(page.items.iter().map(|e| e.key.clone().unwrap()));
        after = page.next;
        if after.is_none() {
            break;
        }
    }
    let source = keys[0].source.clone();
    assert!(source.starts_with("recorder/"), "{source}");
    assert!(keys.iter().all(|k| k.source == source));
    let mut numbers: Vec<u64> = keys.iter().map(|k| k.sequence).collect();
    numbers.sort_unstable();
    assert_eq!(numbers, (0..2 * 7200).collect::<Vec<_>>());
    recorder.close().await;
}

/// What was forwarded, in order, and a way to wait for the next one.
#[derive(Default)]
struct Forwarded {
    names: std::sync::Mutex<Vec<&'static str>>,
    told: Notify,
}

impl Forwarded {
    fn forward(self: &Arc<Self>, name: &'static str) -> store::AfterStored {
        let forwarded = Arc::clone(self);
        Box::new(move || {
            forwarded.names.lock().unwrap().push(name);
            forwarded.told.notify_one();
        })
    }

    fn names(&self) -> Vec<&'static str> {
        self.names.lock().unwrap().clone()
    }

    async fn wait_for(&self, count: usize) {
        tokio::time::timeout(std::time::Duration::from_secs(30), async {
            while self.names.lock().unwrap().len() < count {
                self.told.notified().await;
            }
        })
        .await
        .expect("forwarded in time");
    }
}

/// A change handed over with its event leaves only once the event is committed, and a
/// change the store leaves out keeps its place behind it.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_change_is_forwarded_once_its_event_is_committed() {
    let store = Stalled::closed().await;
    let recorder = Recorder::spawn(store.clone());
    let forwarded = Arc::new(Forwarded::default());
    // Registered before the events, so that the writer's first append is seen.
    let entered = store.entered.notified();
    recorder.event_then(ev("A", PointValue::Int(1), 1), forwarded.forward("A"));
    recorder.then(forwarded.forward("not stored"));
    recorder.event_then(ev("B", PointValue::Int(2), 2), forwarded.forward("B"));
    entered.await;
    // The writer holds the batch at the gate: nothing has gone up yet.
    assert_eq!(forwarded.names(), Vec::<&str>::new());
    store.gate.add_permits(1_000);
    forwarded.wait_for(3).await;
    assert_eq!(forwarded.names(), ["A", "not stored", "B"]);
    // Each was forwarded after its event was in the store.
    assert_eq!(store.stats().await.unwrap().events, 2);
}

/// A store that does not commit holds the changes back for at most the deadline, and
/// while it still does not answer, what comes after goes up at once, in order (a change
/// handed over behind a command too); all of it is stored once the store answers.
/// (Paused time: the runtime moves the clock on when every task waits.)
#[tokio::test(start_paused = true)]
async fn a_store_that_does_not_commit_holds_changes_back_for_at_most_the_deadline() {
    let store = Stalled::closed().await;
    let recorder = Recorder::spawn(store.clone());
    let forwarded = Arc::new(Forwarded::default());
    let started = tokio::time::Instant::now();
    recorder.event_then(ev("A", PointValue::Int(1), 1), forwarded.forward("A"));
    forwarded.wait_for(1).await;
    assert_eq!(started.elapsed(), store::FORWARD_DEADLINE);
    assert_eq!(store.stats().await.unwrap().events, 0, "not committed yet");

    // The store still hangs: the next changes do not wait another deadline.
    recorder.event_then(ev("B", PointValue::Int(2), 2), forwarded.forward("B"));
    recorder.then(forwarded.forward("not stored"));
    recorder.command(command_record());
    recorder.event_then(ev("C", PointValue::Int(3), 3), forwarded.forward("C"));
    forwarded.wait_for(4).await;
    assert_eq!(
        started.elapsed(),
        store::FORWARD_DEADLINE,
        "forwarded at once"
    );
    assert_eq!(forwarded.names(), ["A", "B", "not stored", "C"]);

    store.gate.add_permits(1_000);
    recorder.flush().await;
    assert_eq!(
        store.stats().await.unwrap().events,
        3,
        "committed after all"
    );
    let commands = store
        .query_commands(&CommandQuery::default())
        .await
        .unwrap();
    assert_eq!(commands.items.len(), 1);
    // The store answers again: a change waits for its commit once more.
    let entered = store.entered.notified();
    store.gate.forget_permits(1_000);
    recorder.event_then(ev("D", PointValue::Int(4), 4), forwarded.forward("D"));
    entered.await;
    tokio::task::yield_now().await;
    assert_eq!(forwarded.names().len(), 4, "D waits for its commit");
    store.gate.add_permits(1);
    forwarded.wait_for(5).await;
}

fn command_record() -> CommandRecord {
    CommandRecord {
        id: None,
        time: crate::suite::at_ms(5),
        actor: store::Actor::Remote("127.0.0.1:1".into()),
        node: "RDRT".into(),
        point: "QF1".into(),
        ioa: Some(2021),
        value: PointValue::Bool(true),
        phase: store::CommandPhase::Execute,
        outcome: store::CommandOutcome::Executed,
        detail: String::new(),
    }
}

/// Without a store, or when the channel is full, a change is forwarded at once.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn without_room_or_store_a_change_is_forwarded_at_once() {
    let forwarded = Arc::new(Forwarded::default());
    Recorder::disabled().event_then(ev("A", PointValue::Int(1), 1), forwarded.forward("none"));
    assert_eq!(forwarded.names(), ["none"]);

    let store = Stalled::closed().await;
    let recorder = Recorder::spawn_with_capacity(store.clone(), 1);
    for _ in 0..4 {
        recorder.event_then(ev("A", PointValue::Int(1), 1), forwarded.forward("full"));
    }
    // The writer took at most one and the channel holds one: the others were dropped
    // from the store but went up.
    assert!(forwarded.names().len() >= 3, "{:?}", forwarded.names());
    assert!(recorder.overflowed() >= 2);
    store.gate.add_permits(1_000);
    forwarded.wait_for(5).await;
}
