//! The recorder's bounded channel: a store that does not keep up makes events drop,
//! counted and reported, while the process does not grow and commands are never lost.

use std::sync::Arc;

use chrono::{DateTime, Utc};
use store::Recorder;
use store::{
    open_store, Backend, CommandQuery, CommandRecord, CountedPage, EventQuery, EventRecord,
    EventStore, LiftFaultArchive, LiftFaultQuery, LiftFaultRecord, NotificationLog,
    NotificationQuery, NotificationRecord, Page, PointValue, RecordId, StoreFuture, StoreStats,
};
use tokio::sync::Semaphore;

use crate::suite::ev;

/// A SQLite store whose appends wait until the test lets them through.
struct Stalled {
    inner: Box<dyn EventStore>,
    gate: Semaphore,
}

impl EventStore for Stalled {
    fn backend(&self) -> Backend {
        self.inner.backend()
    }
    fn append_events<'a>(&'a self, events: &'a [EventRecord]) -> StoreFuture<'a, Vec<RecordId>> {
        Box::pin(async move {
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
    let store = Arc::new(Stalled {
        inner: open_store("sqlite::memory:").await.unwrap(),
        gate: Semaphore::new(0),
    });
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
    let command = CommandRecord {
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
    };
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
