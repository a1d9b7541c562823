//! The shared suite, continued: the lift fault archive and the notification record.

use chrono::{Duration, NaiveDateTime};
use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Arc;

use store::{
    EventStore, LiftFaultOrder, LiftFaultQuery, LiftFaultRecord, NotificationOutcome,
    NotificationQuery, NotificationRecord, StoreError, MAX_PAGE_SIZE,
};

use super::{at_ms, t0};

const NODE: &str = "LIFTS";

const ORDERS: [LiftFaultOrder; 6] = [
    LiftFaultOrder::Archived,
    LiftFaultOrder::BoardTime,
    LiftFaultOrder::Received,
    LiftFaultOrder::Code,
    LiftFaultOrder::Lift,
    LiftFaultOrder::Floor,
];

/// The board's wall clock `minutes` after 2026-03-01 00:00.
fn board(minutes: i64) -> NaiveDateTime {
    t0().naive_utc() + Duration::minutes(minutes)
}

/// A fault of `lift` on node [`NODE`], at `board_min` on the board's clock (`None`: an
/// impossible date) and received `received_min` minutes after t0.
fn fault(
    lift: &str,
    code: u8,
    floor: u8,
    board_min: Option<i64>,
    received_min: i64,
) -> LiftFaultRecord {
    LiftFaultRecord {
        id: None,
        node: NODE.into(),
        lift: lift.into(),
        stack_index: code.wrapping_mul(7),
        code,
        floor,
        target: floor.wrapping_add(1),
        board_time: board_min.map(board),
        received_time: at_ms(received_min * 60_000),
    }
}

fn ids(faults: &[LiftFaultRecord]) -> Vec<i64> {
    faults.iter().map(|f| f.id.unwrap()).collect()
}

/// Every record the query matches, one query with the largest page.
async fn all_faults(store: &dyn EventStore, q: LiftFaultQuery) -> Vec<LiftFaultRecord> {
    let page = store
        .query_lift_faults(&q.with_page(0, MAX_PAGE_SIZE as u32))
        .await
        .unwrap();
    assert_eq!(page.total, page.items.len() as u64);
    page.items
}

/// The sort key of `order`, as the store must order by it (ties by id).
fn key(f: &LiftFaultRecord, order: LiftFaultOrder) -> (i64, String, i64) {
    let id = f.id.unwrap();
    let k = match order {
        LiftFaultOrder::Archived => 0,
        LiftFaultOrder::BoardTime => f.filed_time().and_utc().timestamp_millis(),
        LiftFaultOrder::Received => f.received_time.timestamp_millis(),
        LiftFaultOrder::Code => i64::from(f.code),
        LiftFaultOrder::Floor => i64::from(f.floor),
        LiftFaultOrder::Lift => return (0, f.lift.clone(), id),
    };
    (k, String::new(), id)
}

/// `rows` sorted as the store must sort them.
fn model(mut rows: Vec<LiftFaultRecord>, order: LiftFaultOrder, descending: bool) -> Vec<i64> {
    rows.sort_by_key(|f| key(f, order));
    if descending {
        rows.reverse();
    }
    ids(&rows)
}

/// Appends `faults` and gives them their ids.
async fn append(store: &dyn EventStore, faults: &[LiftFaultRecord]) -> Vec<LiftFaultRecord> {
    let ids = store.append_lift_faults(faults).await.unwrap();
    assert_eq!(ids.len(), faults.len());
    assert!(ids.windows(2).all(|w| w[0] < w[1]), "{ids:?}");
    faults
        .iter()
        .zip(ids)
        .map(|(f, id)| LiftFaultRecord {
            id: Some(id),
            ..f.clone()
        })
        .collect()
}

pub(crate) async fn lift_faults_round_trip_and_filters(store: Arc<dyn EventStore>) {
    assert!(store.append_lift_faults(&[]).await.unwrap().is_empty());
    let mut extreme = fault("Výtah 2 – sklad", 255, 255, Some(0), 0);
    extreme.stack_index = 255;
    extreme.target = 0;
    extreme.board_time = Some(board(0) + Duration::milliseconds(999));
    let mut other_node = fault("V1", 5, 1, Some(600), 600);
    other_node.node = "OTHER".into();
    let stored = append(
        &*store,
        &[
            fault("V1", 5, 1, Some(600), 601),  // 10:00
            fault("V1", 17, 2, Some(660), 661), // 11:00
            fault("V2", 5, 0, Some(690), 691),  // 11:30
            fault("V1", 3, 4, None, 720),       // impossible date, received 12:00 UTC
            fault("V2", 17, 3, Some(780), 790), // 13:00
            extreme,
            other_node,
        ],
    )
    .await;
    // Every field comes back as written.
    let mine = LiftFaultQuery::default().with_node(NODE);
    let mut back = all_faults(&*store, mine.clone()).await;
    back.sort_by_key(|f| f.id);
    assert_eq!(back, stored[..6]);
    let all = all_faults(&*store, LiftFaultQuery::default()).await;
    assert_eq!(all.len(), 7);

    // By lift, by codes, both.
    let lifts = |q: LiftFaultQuery| {
        let store = Arc::clone(&store);
        async move {
            let mut got = ids(&all_faults(&*store, q).await);
            got.sort();
            got
        }
    };
    let id = |i: usize| stored[i].id.unwrap();
    assert_eq!(
        lifts(mine.clone().with_lifts(["V1"])).await,
        [id(0), id(1), id(3)]
    );
    assert_eq!(
        lifts(mine.clone().with_lifts(["V2", "Výtah 2 – sklad"])).await,
        [id(2), id(4), id(5)]
    );
    assert_eq!(
        lifts(LiftFaultQuery::default().with_lifts(["V1"])).await,
        [id(0), id(1), id(3), id(6)]
    );
    assert_eq!(
        lifts(mine.clone().with_codes([5, 255])).await,
        [id(0), id(2), id(5)]
    );
    assert_eq!(
        lifts(mine.clone().with_lifts(["V2"]).with_codes([17])).await,
        [id(4)]
    );
    assert!(lifts(mine.clone().with_lifts(["nope"])).await.is_empty());
    assert!(lifts(mine.clone().with_codes([99])).await.is_empty());

    // By board time, [since, until); the record without a board time is filed under its
    // received time's UTC wall clock (12:00).
    assert_eq!(
        lifts(mine.clone().with_range(Some(board(660)), Some(board(780)))).await,
        [id(1), id(2), id(3)]
    );
    assert_eq!(
        lifts(mine.clone().with_range(Some(board(721)), None)).await,
        [id(4)]
    );
    assert_eq!(
        lifts(mine.clone().with_range(None, Some(board(600)))).await,
        [id(5)]
    );
    assert_eq!(
        lifts(mine.clone().with_range(None, Some(board(0)))).await,
        Vec::<i64>::new()
    );
    // By the time received, [since, until): 13:00 on the board came at 13:10.
    assert_eq!(
        lifts(
            mine.clone()
                .with_received_range(Some(at_ms(661 * 60_000)), Some(at_ms(790 * 60_000)))
        )
        .await,
        [id(1), id(2), id(3)]
    );
    assert_eq!(
        lifts(
            mine.clone()
                .with_received_range(Some(at_ms(781 * 60_000)), None)
        )
        .await,
        [id(4)]
    );
    assert_eq!(
        lifts(mine.clone().with_received_range(None, Some(at_ms(1)))).await,
        [id(5)]
    );
    // Sorted by board time, the record without one sits at 12:00.
    let by_time = all_faults(
        &*store,
        mine.clone()
            .with_order(LiftFaultOrder::BoardTime, false)
            .with_lifts(["V1", "V2"]),
    )
    .await;
    assert_eq!(ids(&by_time), [id(0), id(1), id(2), id(3), id(4)]);
    assert_eq!(by_time[3].board_time, None);
    assert_eq!(by_time[3].filed_time(), board(720));
}

pub(crate) async fn lift_faults_every_order_both_directions(store: Arc<dyn EventStore>) {
    // Ties in every column, the ids tell them apart; lift names compare byte-wise.
    let mut input = Vec::new();
    for i in 0..40u8 {
        let lift = ["V1", "V10", "V2", "a", "Výtah", "V1 "][usize::from(i % 6)];
        let board_min = (i % 5 != 4).then_some(i64::from(i % 7) * 30);
        input.push(fault(lift, i % 4, i % 3, board_min, i64::from(i % 9) * 20));
    }
    let stored = append(&*store, &input).await;
    for order in ORDERS {
        for descending in [false, true] {
            let q = LiftFaultQuery::default().with_order(order, descending);
            let got = ids(&all_faults(&*store, q).await);
            assert_eq!(
                got,
                model(stored.clone(), order, descending),
                "{order:?} descending {descending}"
            );
            // The same order within a filter.
            let q = LiftFaultQuery::default()
                .with_order(order, descending)
                .with_lifts(["V1", "a"])
                .with_codes([1, 2]);
            let expect: Vec<_> = stored
                .iter()
                .filter(|f| ["V1", "a"].contains(&f.lift.as_str()) && [1, 2].contains(&f.code))
                .cloned()
                .collect();
            let got = ids(&all_faults(&*store, q).await);
            assert_eq!(got, model(expect, order, descending), "{order:?}");
        }
    }
}

pub(crate) async fn lift_faults_paging_with_total_and_newest_tail(store: Arc<dyn EventStore>) {
    let input: Vec<_> = (0..25i64)
        .map(|i| fault(["V1", "V2"][(i % 2) as usize], 1, 0, Some(i / 3), i))
        .collect();
    let stored = append(&*store, &input).await;
    for order in ORDERS {
        for descending in [false, true] {
            let q = LiftFaultQuery::default().with_order(order, descending);
            let mut seen = Vec::new();
            for page_no in 0..4u64 {
                let page = store
                    .query_lift_faults(&q.clone().with_page(page_no * 7, 7))
                    .await
                    .unwrap();
                assert_eq!(page.total, 25);
                assert_eq!(page.items.len(), if page_no < 3 { 7 } else { 4 });
                seen.extend(ids(&page.items));
            }
            assert_eq!(seen, model(stored.clone(), order, descending), "{order:?}");
        }
    }
    // Past the end: no rows, still the total.
    let page = store
        .query_lift_faults(&LiftFaultQuery::default().with_page(25, 10))
        .await
        .unwrap();
    assert!(page.items.is_empty());
    assert_eq!(page.total, 25);
    let page = store
        .query_lift_faults(&LiftFaultQuery::default().with_lifts(["V2"]).with_page(0, 5))
        .await
        .unwrap();
    assert_eq!((page.items.len(), page.total), (5, 12));
    // The newest N of a lift in archive order: what a restarted monitor reads.
    let tail = store
        .query_lift_faults(&LiftFaultQuery::newest(NODE, "V1", 3))
        .await
        .unwrap();
    assert_eq!(tail.total, 13);
    let v1: Vec<_> = stored.iter().filter(|f| f.lift == "V1").collect();
    assert_eq!(
        tail.items.iter().collect::<Vec<_>>(),
        v1.iter().rev().take(3).copied().collect::<Vec<_>>()
    );
    let none = store
        .query_lift_faults(&LiftFaultQuery::newest("OTHER", "V1", 3))
        .await
        .unwrap();
    assert!(none.items.is_empty());
    assert_eq!(none.total, 0);
}

pub(crate) async fn lift_fault_pages_cover_every_row_once(store: Arc<dyn EventStore>) {
    let row = (
        0..3usize,
        0..4u8,
        0..3u8,
        proptest::option::weighted(0.8, 0..6i64),
        0..6i64,
    );
    let strategy = (
        proptest::collection::vec(row, 0..30),
        proptest::sample::select(ORDERS.to_vec()),
        any::<bool>(),
        1..8u32,
        proptest::option::of(0..3usize),
        proptest::collection::vec(0..4u8, 0..3),
    );
    let handle = tokio::runtime::Handle::current();
    let outcome = tokio::task::spawn_blocking(move || {
        let mut runner = TestRunner::new(Config {
            cases: 40,
            failure_persistence: None,
            ..Config::default()
        });
        // Each case files its rows under a node of its own in the one store.
        let case = AtomicU32::new(0);
        let result = runner.run(
            &strategy,
            |(rows, order, descending, limit, lift, codes)| {
                let node = format!("case{}", case.fetch_add(1, Ordering::Relaxed));
                let lifts = ["V1", "V2", "V3"];
                let input: Vec<_> = rows
                    .iter()
                    .map(
                        |&(l, code, floor, board_min, received_min)| LiftFaultRecord {
                            node: node.clone(),
                            ..fault(lifts[l], code, floor, board_min, received_min)
                        },
                    )
                    .collect();
                handle.block_on(async {
                    let stored = append(&*store, &input).await;
                    let mut q = LiftFaultQuery::default()
                        .with_node(node.clone())
                        .with_order(order, descending)
                        .with_codes(codes.clone());
                    if let Some(l) = lift {
                        q = q.with_lifts([lifts[l]]);
                    }
                    let expect: Vec<_> = stored
                        .into_iter()
                        .filter(|f| lift.is_none_or(|l| f.lift == lifts[l]))
                        .filter(|f| codes.is_empty() || codes.contains(&f.code))
                        .collect();
                    let expect = model(expect, order, descending);
                    let mut seen = Vec::new();
                    let mut offset = 0u64;
                    loop {
                        let page = store
                            .query_lift_faults(&q.clone().with_page(offset, limit))
                            .await
                            .unwrap();
                        assert_eq!(page.total, expect.len() as u64);
                        assert!(page.items.len() <= limit as usize);
                        if page.items.is_empty() {
                            break;
                        }
                        seen.extend(ids(&page.items));
                        offset += u64::from(limit);
                    }
                    assert_eq!(seen, expect);
                });
                Ok(())
            },
        );
        result.map_err(|e| e.to_string())
    })
    .await
    .unwrap();
    if let Err(failure) = outcome {
        panic!("{failure}");
    }
}

pub(crate) async fn lift_fault_bad_input_is_refused(store: Arc<dyn EventStore>) {
    let good = fault("V1", 1, 1, Some(0), 0);
    let mut empty_lift = good.clone();
    empty_lift.lift = String::new();
    let mut empty_node = good.clone();
    empty_node.node = String::new();
    let mut nul = good.clone();
    nul.lift = "V\0 1".into();
    for bad in [empty_lift, empty_node, nul] {
        // A batch with one bad record stores nothing.
        let err = store
            .append_lift_faults(&[good.clone(), bad])
            .await
            .unwrap_err();
        assert!(matches!(err, StoreError::InvalidRecord(_)), "{err}");
    }
    assert_eq!(
        store
            .query_lift_faults(&LiftFaultQuery::default())
            .await
            .unwrap()
            .total,
        0
    );
    for limit in [0, MAX_PAGE_SIZE as u32 + 1, u32::MAX] {
        let err = store
            .query_lift_faults(&LiftFaultQuery::default().with_page(0, limit))
            .await
            .unwrap_err();
        assert!(matches!(err, StoreError::InvalidQuery(_)), "{err}");
        let err = store
            .query_notifications(&NotificationQuery::default().with_page(0, limit))
            .await
            .unwrap_err();
        assert!(matches!(err, StoreError::InvalidQuery(_)), "{err}");
    }
    let err = store
        .query_lift_faults(&LiftFaultQuery::default().with_page(u64::MAX, 1))
        .await
        .unwrap_err();
    assert!(matches!(err, StoreError::InvalidQuery(_)), "{err}");
    // The largest valid offset is no error, just an empty page.
    let page = store
        .query_lift_faults(&LiftFaultQuery::default().with_page(i64::MAX as u64, 1))
        .await
        .unwrap();
    assert!(page.items.is_empty());
    // Extreme but valid times round-trip.
    let mut far = good.clone();
    far.board_time = Some(NaiveDateTime::MIN);
    far.received_time = chrono::DateTime::<chrono::Utc>::MAX_UTC;
    let mut far2 = good.clone();
    far2.board_time = Some(NaiveDateTime::MAX);
    let stored = append(&*store, &[far, far2]).await;
    let mut back = all_faults(&*store, LiftFaultQuery::default()).await;
    back.sort_by_key(|f| f.id);
    let ms = |t: NaiveDateTime| {
        chrono::DateTime::from_timestamp_millis(t.and_utc().timestamp_millis())
            .unwrap()
            .naive_utc()
    };
    assert_eq!(back[0].board_time, stored[0].board_time.map(ms));
    assert_eq!(back[1].board_time, stored[1].board_time.map(ms));
    assert_eq!(
        back[0].received_time.timestamp_millis(),
        stored[0].received_time.timestamp_millis()
    );
}

fn note(source: &str, time_ms: i64, outcome: NotificationOutcome) -> NotificationRecord {
    NotificationRecord {
        id: None,
        time: at_ms(time_ms),
        rule: "lift-fault".into(),
        channel: "email".into(),
        recipient: "servis@example.cz".into(),
        source: source.into(),
        subject: format!("{source}: porucha 0x11 – dveře"),
        outcome,
        detail: match outcome {
            NotificationOutcome::Sent => "250 2.0.0 Ok: queued".into(),
            NotificationOutcome::Failed => "550 mailbox unavailable".into(),
            NotificationOutcome::Suppressed => "quiet period until 12:30".into(),
        },
    }
}

pub(crate) async fn notifications_round_trip_and_paging(store: Arc<dyn EventStore>) {
    let empty = store
        .query_notifications(&NotificationQuery::default())
        .await
        .unwrap();
    assert!(empty.items.is_empty());
    assert_eq!(empty.total, 0);
    let mut stored = Vec::new();
    // Times out of insertion order and with ties, every outcome.
    for i in 0..14i64 {
        let outcome = NotificationOutcome::ALL[(i % 3) as usize];
        let mut n = note(["V1", "V2"][(i % 2) as usize], (i * 7) % 5 * 1000, outcome);
        if i == 13 {
            n.channel = "webhook".into();
            n.recipient = "https://hooks.example.cz/lift?id=1&x=\"2\"".into();
            n.detail = "HTTP 204".into();
            n.time = at_ms(1234);
        }
        let id = store.append_notification(&n).await.unwrap();
        n.id = Some(id);
        stored.push(n);
    }
    assert!(stored.windows(2).all(|w| w[0].id < w[1].id));
    let mut newest_first = stored.clone();
    newest_first.sort_by_key(|n| (n.time, n.id));
    newest_first.reverse();
    let all = store
        .query_notifications(&NotificationQuery::default().with_page(0, 100))
        .await
        .unwrap();
    assert_eq!(all.total, 14);
    assert_eq!(all.items, newest_first);
    // Pages of 4.
    let mut seen = Vec::new();
    for p in 0..4u64 {
        let page = store
            .query_notifications(&NotificationQuery::default().with_page(p * 4, 4))
            .await
            .unwrap();
        assert_eq!(page.total, 14);
        seen.extend(page.items);
    }
    assert_eq!(seen, newest_first);
    // By source.
    let v2 = store
        .query_notifications(
            &NotificationQuery::default()
                .with_source("V2")
                .with_page(1, 3),
        )
        .await
        .unwrap();
    assert_eq!(v2.total, 7);
    let expect: Vec<_> = newest_first
        .iter()
        .filter(|n| n.source == "V2")
        .skip(1)
        .take(3)
        .cloned()
        .collect();
    assert_eq!(v2.items, expect);
    let none = store
        .query_notifications(&NotificationQuery::default().with_source("V9"))
        .await
        .unwrap();
    assert_eq!((none.items.len(), none.total), (0, 0));
    // Refused: an empty rule or channel, NUL anywhere.
    let good = note("V1", 0, NotificationOutcome::Sent);
    let bad = [
        NotificationRecord {
            rule: String::new(),
            ..good.clone()
        },
        NotificationRecord {
            channel: String::new(),
            ..good.clone()
        },
        NotificationRecord {
            detail: "a\0b".into(),
            ..good.clone()
        },
        NotificationRecord {
            subject: "\0".into(),
            ..good
        },
    ];
    for n in bad {
        let err = store.append_notification(&n).await.unwrap_err();
        assert!(matches!(err, StoreError::InvalidRecord(_)), "{err}");
    }
    let after = store
        .query_notifications(&NotificationQuery::default())
        .await
        .unwrap();
    assert_eq!(after.total, 14);
}

pub(crate) async fn purge_keeps_lift_faults_and_drops_old_notifications(
    store: Arc<dyn EventStore>,
) {
    let day_min = 24 * 60;
    // Faults received years ago and today.
    let faults: Vec<_> = (0..10i64)
        .map(|i| fault("V1", 1, 0, Some(i * 100 * day_min), i * 100 * day_min))
        .collect();
    append(&*store, &faults).await;
    for d in 0..10i64 {
        store
            .append_notification(&note("V1", d * 86_400_000, NotificationOutcome::Sent))
            .await
            .unwrap();
    }
    let purged = store
        .purge_older_than(at_ms(5 * 86_400_000 + 1))
        .await
        .unwrap();
    assert_eq!(purged, 6);
    let left = store
        .query_notifications(&NotificationQuery::default())
        .await
        .unwrap();
    assert_eq!(left.total, 4);
    assert!(left.items.iter().all(|n| n.time > at_ms(5 * 86_400_000)));
    // Even a cutoff after every fault keeps the archive.
    store
        .purge_older_than(at_ms(10_000 * 86_400_000))
        .await
        .unwrap();
    let archive = store
        .query_lift_faults(&LiftFaultQuery::default())
        .await
        .unwrap();
    assert_eq!(archive.total, 10);
    let left = store
        .query_notifications(&NotificationQuery::default())
        .await
        .unwrap();
    assert_eq!(left.total, 0);
}
