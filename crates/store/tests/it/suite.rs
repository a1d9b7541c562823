//! The shared suite: every function runs against SQLite and PostgreSQL alike (the lift
//! fault archive and the notification record in `suite/lift.rs`).

use chrono::{DateTime, Duration, TimeZone, Utc};
use std::collections::HashSet;
use std::sync::Arc;

mod lift;
pub(crate) use lift::*;

use store::{
    quality_from_bits, Actor, CommandOutcome, CommandPhase, CommandQuery, CommandRecord, Cursor,
    EventCause, EventKey, EventQuery, EventRecord, EventStore, Order, Page, PointValue, Quality,
    SourceTime, StoreError, TimeBasis, MAX_PAGE_SIZE,
};

/// 2026-03-01 00:00:00 UTC, the base of every test time.
pub(crate) fn t0() -> DateTime<Utc> {
    Utc.with_ymd_and_hms(2026, 3, 1, 0, 0, 0).unwrap()
}

pub(crate) fn at_ms(ms: i64) -> DateTime<Utc> {
    t0() + Duration::milliseconds(ms)
}

pub(crate) fn ev(point: &str, value: PointValue, received_ms: i64) -> EventRecord {
    EventRecord::new("RH2", point, value, at_ms(received_ms))
}

fn cmd(actor: Actor, point: &str, time_ms: i64, outcome: CommandOutcome) -> CommandRecord {
    CommandRecord {
        id: None,
        time: at_ms(time_ms),
        actor,
        node: "RDRT".into(),
        point: point.into(),
        ioa: Some(2021),
        value: PointValue::Bool(true),
        phase: CommandPhase::Execute,
        outcome,
        detail: String::new(),
    }
}

/// Compares records by their Debug form, so NaN equals NaN.
fn same<T: std::fmt::Debug>(a: &T, b: &T) -> bool {
    format!("{a:?}") == format!("{b:?}")
}

pub(crate) async fn all_events(store: &dyn EventStore, q: EventQuery) -> Vec<EventRecord> {
    let mut out = Vec::new();
    let mut after = None;
    loop {
        let page = store
            .query_events(&q.clone().with_after(after))
            .await
            .unwrap();
        assert!(page.items.len() <= q.limit);
        out.extend(page.items);
        match page.next {
            Some(c) => after = Some(c),
            None => return out,
        }
    }
}

fn points(events: &[EventRecord]) -> Vec<&str> {
    events.iter().map(|e| e.point.as_str()).collect()
}

pub(crate) async fn round_trip_every_value_cause_and_quality(store: Arc<dyn EventStore>) {
    let values = [
        PointValue::Bool(false),
        PointValue::Bool(true),
        PointValue::DoublePoint(0),
        PointValue::DoublePoint(1),
        PointValue::DoublePoint(2),
        PointValue::DoublePoint(3),
        PointValue::Int(0),
        PointValue::Int(i64::MIN),
        PointValue::Int(i64::MAX),
        PointValue::Int(-32768),
        PointValue::Float(0.1),
        PointValue::Float(-1.5e300),
        PointValue::Float(f64::INFINITY),
        PointValue::Float(f64::NEG_INFINITY),
        PointValue::Float(f64::NAN),
        PointValue::Float(f64::MIN_POSITIVE),
        PointValue::Bits(0),
        PointValue::Bits(u32::MAX),
        PointValue::Bits(0x8000_0001),
        PointValue::Text(String::new()),
        PointValue::Text("Porucha osvětlení ŽST Vsetín – věž 12 ✓".into()),
        PointValue::Text("quote ' and \" and \\ and %_".into()),
    ];
    let qualities = [
        Quality::GOOD,
        Quality::INVALID,
        quality_from_bits(0b11111),
        quality_from_bits(0b00110),
        quality_from_bits(0b11000),
    ];
    let mut input = Vec::new();
    for (i, value) in values.iter().enumerate() {
        for (j, cause) in EventCause::ALL.iter().enumerate() {
            let k = (i * EventCause::ALL.len() + j) as i64;
            let mut e = ev(&format!("P{i:02}"), value.clone(), 1000 + k);
            e.cause = *cause;
            e.quality = qualities[(i + j) % qualities.len()];
            e.ioa = match k % 3 {
                0 => None,
                1 => Some(0xFF_FFFF),
                _ => Some(k as u32),
            };
            e.source_time = match k % 3 {
                0 => None,
                1 => Some(SourceTime {
                    time: at_ms(k),
                    invalid: false,
                }),
                _ => Some(SourceTime {
                    time: at_ms(-k * 1000),
                    invalid: true,
                }),
            };
            e.origin = format!("link-{j}");
            e.node = format!("N{j}");
            input.push(e);
        }
    }
    let ids = store.append_events(&input).await.unwrap();
    assert_eq!(ids.len(), input.len());
    let got = all_events(
        &*store,
        EventQuery::default()
            .with_time_basis(TimeBasis::Received)
            .with_order(Order::OldestFirst)
            .with_limit(MAX_PAGE_SIZE),
    )
    .await;
    assert_eq!(got.len(), input.len());
    for ((want, got), id) in input.iter().zip(&got).zip(&ids) {
        let want = EventRecord {
            id: Some(*id),
            ..want.clone()
        };
        assert!(same(&want, got), "\nwant {want:?}\n got {got:?}");
    }
}

pub(crate) async fn ids_increase_in_batch_order(store: Arc<dyn EventStore>) {
    let mut all = Vec::new();
    for batch in 0..5 {
        let events: Vec<_> = (0..(batch * 7 + 1))
            .map(|i| ev(&format!("B{batch}_{i}"), PointValue::Int(i), 0))
            .collect();
        let ids = store.append_events(&events).await.unwrap();
        assert_eq!(ids.len(), events.len());
        all.extend(ids);
    }
    assert!(all.windows(2).all(|w| w[0] < w[1]), "{all:?}");
    // The ids belong to the right records.
    let got = all_events(
        &*store,
        EventQuery::default()
            .with_order(Order::OldestFirst)
            .with_limit(1000),
    )
    .await;
    let got_ids: Vec<_> = got.iter().map(|e| e.id.unwrap()).collect();
    assert_eq!(got_ids, all);
    assert_eq!(got[3].point, "B1_2");
}

pub(crate) async fn empty_batch_is_a_no_op(store: Arc<dyn EventStore>) {
    assert!(store.append_events(&[]).await.unwrap().is_empty());
    assert_eq!(store.stats().await.unwrap().events, 0);
    let page = store.query_events(&EventQuery::default()).await.unwrap();
    assert_eq!(
        page,
        Page {
            items: vec![],
            next: None
        }
    );
}

pub(crate) async fn filters_time_range_by_source_and_received(store: Arc<dyn EventStore>) {
    // Received at 10 s steps; source times run backwards (the outstation buffered them).
    let events: Vec<_> = (0..10)
        .map(|i| {
            let mut e = ev(&format!("T{i}"), PointValue::Int(i), i * 10_000);
            e.source_time = Some(SourceTime {
                time: at_ms(-(i * 1000)),
                invalid: false,
            });
            e
        })
        .collect();
    store.append_events(&events).await.unwrap();
    let by_received = all_events(
        &*store,
        EventQuery::default()
            .with_time_basis(TimeBasis::Received)
            .with_range(Some(at_ms(20_000)), Some(at_ms(50_000)))
            .with_order(Order::OldestFirst),
    )
    .await;
    assert_eq!(points(&by_received), ["T2", "T3", "T4"]);
    let by_source = all_events(
        &*store,
        EventQuery::default()
            .with_range(Some(at_ms(-4000)), Some(at_ms(-1000)))
            .with_order(Order::OldestFirst),
    )
    .await;
    assert_eq!(points(&by_source), ["T4", "T3", "T2"]);
    // Open ends.
    let from_only = all_events(
        &*store,
        EventQuery::default().with_range(Some(at_ms(-1000)), None),
    )
    .await;
    assert_eq!(points(&from_only), ["T0", "T1"]);
    let to_only = all_events(
        &*store,
        EventQuery::default()
            .with_time_basis(TimeBasis::Received)
            .with_range(None, Some(at_ms(10_000))),
    )
    .await;
    assert_eq!(points(&to_only), ["T0"]);
    // An empty range.
    let empty = all_events(
        &*store,
        EventQuery::default().with_range(Some(at_ms(5)), Some(at_ms(5))),
    )
    .await;
    assert!(empty.is_empty());
}

pub(crate) async fn filters_point_exact_and_prefix(store: Arc<dyn EventStore>) {
    let names = [
        "RH2_V1_FA1",
        "RH2_V1_FA1.1",
        "RH2_P1",
        "RH2",
        "RH20_X",
        "RH1_Q1",
        "rh2_lower",
        "RH2%odd",
        "RH2_Ž",
        "RH3",
    ];
    let events: Vec<_> = names
        .iter()
        .enumerate()
        .map(|(i, n)| ev(n, PointValue::Bool(true), i as i64))
        .collect();
    store.append_events(&events).await.unwrap();
    let q = EventQuery::default().with_order(Order::OldestFirst);
    let exact = all_events(&*store, q.clone().with_point("RH2_V1_FA1")).await;
    assert_eq!(points(&exact), ["RH2_V1_FA1"]);
    let prefix = all_events(&*store, q.clone().with_point_prefix("RH2_")).await;
    assert_eq!(
        points(&prefix),
        ["RH2_V1_FA1", "RH2_V1_FA1.1", "RH2_P1", "RH2_Ž"]
    );
    let prefix = all_events(&*store, q.clone().with_point_prefix("RH2")).await;
    assert_eq!(
        points(&prefix),
        [
            "RH2_V1_FA1",
            "RH2_V1_FA1.1",
            "RH2_P1",
            "RH2",
            "RH20_X",
            "RH2%odd",
            "RH2_Ž"
        ]
    );
    // '%' and '_' are plain characters, not patterns.
    let pct = all_events(&*store, q.clone().with_point_prefix("RH2%")).await;
    assert_eq!(points(&pct), ["RH2%odd"]);
    let none = all_events(&*store, q.clone().with_point("RH2_")).await;
    assert!(none.is_empty());
    let all = all_events(&*store, q.clone().with_point_prefix("")).await;
    assert_eq!(all.len(), names.len());
    let uni = all_events(&*store, q.with_point_prefix("RH2_Ž")).await;
    assert_eq!(points(&uni), ["RH2_Ž"]);
}

pub(crate) async fn filters_node_cause_and_invalid(store: Arc<dyn EventStore>) {
    let mut events = Vec::new();
    for i in 0..60i64 {
        let mut e = ev(&format!("P{i}"), PointValue::Int(i), i);
        e.node = ["RH2", "RZS1", "RDRT"][(i % 3) as usize].into();
        e.cause = EventCause::ALL[(i % 7) as usize];
        e.quality = if i % 5 == 0 {
            Quality::INVALID
        } else if i % 5 == 1 {
            quality_from_bits(0b10) // NT only: not invalid
        } else {
            Quality::GOOD
        };
        events.push(e);
    }
    store.append_events(&events).await.unwrap();
    let q = EventQuery::default()
        .with_order(Order::OldestFirst)
        .with_limit(7);
    let rzs = all_events(&*store, q.clone().with_node("RZS1")).await;
    assert_eq!(rzs.len(), 20);
    assert!(rzs.iter().all(|e| e.node == "RZS1"));
    let cyc = all_events(&*store, q.clone().with_causes([EventCause::Cyclic])).await;
    assert_eq!(cyc.len(), (0..60).filter(|i| i % 7 == 2).count());
    assert!(cyc.iter().all(|e| e.cause == EventCause::Cyclic));
    let two = all_events(
        &*store,
        q.clone()
            .with_causes([EventCause::ReturnLocal, EventCause::ReturnRemote]),
    )
    .await;
    assert_eq!(
        two.len(),
        (0..60).filter(|i| i % 7 == 5 || i % 7 == 6).count()
    );
    let inv = all_events(&*store, q.clone().with_invalid_only(true)).await;
    assert_eq!(inv.len(), 12);
    assert!(inv.iter().all(|e| e.quality.invalid));
    // Everything at once.
    let mix = all_events(
        &*store,
        q.with_node("RH2")
            .with_invalid_only(true)
            .with_causes([EventCause::Spontaneous, EventCause::Interrogated])
            .with_range(Some(at_ms(10)), None),
    )
    .await;
    let want: Vec<String> = (10..60)
        .filter(|i| i % 3 == 0 && i % 5 == 0 && (i % 7 == 0 || i % 7 == 1))
        .map(|i| format!("P{i}"))
        .collect();
    assert_eq!(
        points(&mix),
        want.iter().map(String::as_str).collect::<Vec<_>>()
    );
}

pub(crate) async fn ordering_by_event_time(store: Arc<dyn EventStore>) {
    // Event time = valid source time, else received time.
    let mut a = ev("A", PointValue::Bool(true), 5000);
    a.source_time = Some(SourceTime {
        time: at_ms(1000),
        invalid: false,
    });
    let b = ev("B", PointValue::Bool(true), 2000); // no source time: 2000
    let mut c = ev("C", PointValue::Bool(true), 3000);
    c.source_time = Some(SourceTime {
        time: at_ms(-99_000),
        invalid: true, // an invalid time tag does not order: 3000
    });
    let mut d = ev("D", PointValue::Bool(true), 500);
    d.source_time = Some(SourceTime {
        time: at_ms(4000),
        invalid: false,
    });
    store.append_events(&[a, b, c, d]).await.unwrap();
    let newest = all_events(&*store, EventQuery::default()).await;
    assert_eq!(points(&newest), ["D", "C", "B", "A"]);
    let oldest = all_events(
        &*store,
        EventQuery::default().with_order(Order::OldestFirst),
    )
    .await;
    assert_eq!(points(&oldest), ["A", "B", "C", "D"]);
    let received = all_events(
        &*store,
        EventQuery::default().with_time_basis(TimeBasis::Received),
    )
    .await;
    assert_eq!(points(&received), ["A", "C", "B", "D"]);
}

/// Pages across days and across appends that reach back: 3 points over 5 days, a batch
/// of the newest day first, then batches reaching back into the older days (a source's
/// buffer sent late), each listed whole and in order, newest and oldest first, through
/// the blocks (all points, a prefix) and through one point's segments.
pub(crate) async fn pagination_across_days_and_late_batches(store: Arc<dyn EventStore>) {
    let day = 86_400_000i64;
    let at = |i: i64| (i * 7_777_777) % (5 * day);
    let all: Vec<_> = (0..3_000i64)
        .map(|i| {
            let mut e = ev(
                &format!("D{}", i % 3),
                PointValue::Int(i),
                4 * day + at(i) % day,
            );
            e.source_time = Some(SourceTime::at(at_ms(at(i))));
            e
        })
        .collect();
    let (newest, older): (Vec<_>, Vec<_>) = all
        .iter()
        .cloned()
        .partition(|e| e.event_time() >= at_ms(4 * day));
    store.append_events(&newest).await.unwrap();
    for chunk in older.chunks(400) {
        store.append_events(chunk).await.unwrap();
    }
    let expect = |events: &[&EventRecord], order: Order| {
        let mut keys: Vec<_> = events.iter().map(|e| e.event_time()).collect();
        keys.sort();
        if order == Order::NewestFirst {
            keys.reverse();
        }
        keys
    };
    for order in [Order::NewestFirst, Order::OldestFirst] {
        for (filter, points) in [(None, "D"), (Some("D*"), "D"), (Some("D1"), "D1")] {
            for limit in [7, 250] {
                let mut query = EventQuery::default().with_order(order).with_limit(limit);
                if let Some(f) = filter {
                    query.point = Some(store::PointFilter::parse(f));
                }
                let got = all_events(&*store, query).await;
                let wanted: Vec<&EventRecord> =
                    all.iter().filter(|e| e.point.starts_with(points)).collect();
                assert_eq!(got.len(), wanted.len(), "{order:?} {filter:?} {limit}");
                let times: Vec<_> = got.iter().map(|e| e.event_time()).collect();
                assert_eq!(
                    times,
                    expect(&wanted, order),
                    "{order:?} {filter:?} {limit}"
                );
                let ids: HashSet<_> = got.iter().map(|e| e.id.unwrap()).collect();
                assert_eq!(
                    ids.len(),
                    got.len(),
                    "duplicates: {order:?} {filter:?} {limit}"
                );
            }
        }
    }
}

pub(crate) async fn pagination_with_equal_timestamps(store: Arc<dyn EventStore>) {
    // 1000 events on only 7 distinct times, appended in shuffled batches.
    let mut events: Vec<_> = (0..1000i64)
        .map(|i| {
            ev(
                &format!("P{i:04}"),
                PointValue::Int(i),
                (i * 7919 % 7) * 1000,
            )
        })
        .collect();
    events.sort_by_key(|e| (e.point.len() * 31 + e.point.as_bytes()[3] as usize) % 13);
    for chunk in events.chunks(97) {
        store.append_events(chunk).await.unwrap();
    }
    for order in [Order::NewestFirst, Order::OldestFirst] {
        for basis in [TimeBasis::Source, TimeBasis::Received] {
            for limit in [1, 13, 999, 1000, 1001] {
                if limit == 1 && basis == TimeBasis::Received {
                    continue; // 1000 round trips once is enough
                }
                let got = all_events(
                    &*store,
                    EventQuery::default()
                        .with_order(order)
                        .with_time_basis(basis)
                        .with_limit(limit),
                )
                .await;
                assert_eq!(got.len(), 1000, "{order:?} {basis:?} {limit}");
                let ids: HashSet<_> = got.iter().map(|e| e.id.unwrap()).collect();
                assert_eq!(ids.len(), 1000, "duplicates with {order:?} {limit}");
                let keys: Vec<_> = got
                    .iter()
                    .map(|e| (e.received_time, e.id.unwrap()))
                    .collect();
                let mut sorted = keys.clone();
                sorted.sort();
                if order == Order::NewestFirst {
                    sorted.reverse();
                }
                assert_eq!(keys, sorted, "{order:?} {basis:?} {limit}");
            }
        }
    }
    // The last page's cursor is None; a page exactly at the end says so.
    let page = store
        .query_events(&EventQuery::default().with_limit(1000))
        .await
        .unwrap();
    assert_eq!(page.items.len(), 1000);
    assert_eq!(page.next, None);
    // Filtered pagination (one time only, across several pages).
    let some = all_events(
        &*store,
        EventQuery::default()
            .with_range(Some(at_ms(3000)), Some(at_ms(4000)))
            .with_limit(10),
    )
    .await;
    assert_eq!(some.len(), (0..1000).filter(|i| i * 7919 % 7 == 3).count());
    // A cursor travels as text.
    let first = store
        .query_events(&EventQuery::default().with_limit(10))
        .await
        .unwrap();
    let cursor: Cursor = first.next.unwrap().to_string().parse().unwrap();
    assert_eq!(Some(cursor), first.next);
}

pub(crate) async fn pagination_while_appending(store: Arc<dyn EventStore>) {
    let events: Vec<_> = (0..100)
        .map(|i| ev("P", PointValue::Int(i), i / 10))
        .collect();
    store.append_events(&events).await.unwrap();
    let q = EventQuery::default().with_limit(15);
    let mut seen = Vec::new();
    let mut after = None;
    let mut round = 0;
    loop {
        let page = store
            .query_events(&q.clone().with_after(after))
            .await
            .unwrap();
        seen.extend(page.items.iter().map(|e| e.id.unwrap()));
        // New events arrive between pages, some with old times (late buffered events).
        let late: Vec<_> = (0..5)
            .map(|i| ev("NEW", PointValue::Int(i), 1000 + round))
            .collect();
        store.append_events(&late).await.unwrap();
        round += 1;
        match page.next {
            Some(c) => after = Some(c),
            None => break,
        }
    }
    let unique: HashSet<_> = seen.iter().collect();
    assert_eq!(unique.len(), seen.len(), "a row was handed out twice");
    assert_eq!(seen.len(), 100, "newer rows do not slip into an older page");
}

pub(crate) async fn command_audit_round_trip_and_queries(store: Arc<dyn EventStore>) {
    let outcomes = CommandOutcome::ALL;
    let mut input = Vec::new();
    for (i, outcome) in outcomes.iter().enumerate() {
        for (j, actor) in [
            Actor::User("dispecer.novak".into()),
            Actor::User("Šárka".into()),
            Actor::Remote("10.20.30.40:2404".into()),
        ]
        .into_iter()
        .enumerate()
        {
            let k = (i * 3 + j) as i64;
            let mut c = cmd(actor, &format!("RH2_VypnoutQF{k}"), k * 100, *outcome);
            c.phase = if k % 2 == 0 {
                CommandPhase::Select
            } else {
                CommandPhase::Execute
            };
            c.value = match k % 4 {
                0 => PointValue::Bool(false),
                1 => PointValue::DoublePoint(2),
                2 => PointValue::Float(12.5),
                _ => PointValue::Int(-7),
            };
            c.ioa = (k % 2 == 0).then_some(2021 + k as u32);
            c.detail = format!("detail {k}: negative confirmation ✗");
            input.push(c);
        }
    }
    let mut ids = Vec::new();
    for c in &input {
        ids.push(store.append_command(c).await.unwrap());
    }
    assert!(ids.windows(2).all(|w| w[0] < w[1]));
    let all = store
        .query_commands(&CommandQuery::default().with_order(Order::OldestFirst))
        .await
        .unwrap();
    assert_eq!(all.items.len(), input.len());
    for ((want, got), id) in input.iter().zip(&all.items).zip(&ids) {
        let want = CommandRecord {
            id: Some(*id),
            ..want.clone()
        };
        assert_eq!(&want, got);
    }
    // By user.
    let sarka = store
        .query_commands(&CommandQuery::default().with_actor(&Actor::User("Šárka".into())))
        .await
        .unwrap();
    assert_eq!(sarka.items.len(), outcomes.len());
    assert!(sarka.items.iter().all(|c| c.actor.name() == "Šárka"));
    assert!(sarka.items.windows(2).all(|w| w[0].time >= w[1].time));
    // By remote address.
    let remote = store
        .query_commands(&CommandQuery::default().with_actor_name("10.20.30.40:2404"))
        .await
        .unwrap();
    assert!(remote
        .items
        .iter()
        .all(|c| matches!(c.actor, Actor::Remote(_))));
    assert_eq!(remote.items.len(), outcomes.len());
    // By outcome.
    let refused = store
        .query_commands(&CommandQuery::default().with_outcomes([
            CommandOutcome::RefusedLocalMode,
            CommandOutcome::RefusedPermission,
        ]))
        .await
        .unwrap();
    assert_eq!(refused.items.len(), 6);
    let timed_out = store
        .query_commands(
            &CommandQuery::default()
                .with_outcomes([CommandOutcome::TimedOut])
                .with_actor_name("dispecer.novak"),
        )
        .await
        .unwrap();
    assert_eq!(timed_out.items.len(), 1);
    assert_eq!(timed_out.items[0].outcome, CommandOutcome::TimedOut);
    // By point and time.
    let point = store
        .query_commands(&CommandQuery::default().with_point("RH2_VypnoutQF4"))
        .await
        .unwrap();
    assert_eq!(point.items.len(), 1);
    let prefix = store
        .query_commands(&CommandQuery::default().with_point_prefix("RH2_VypnoutQF1"))
        .await
        .unwrap();
    // QF1, QF10, QF11, ...: as many as the input has.
    let want = input
        .iter()
        .filter(|c| c.point.starts_with("RH2_VypnoutQF1"))
        .count();
    assert!(want > 1);
    assert_eq!(prefix.items.len(), want);
    let range = store
        .query_commands(
            &CommandQuery::default()
                .with_range(Some(at_ms(300)), Some(at_ms(600)))
                .with_node("RDRT"),
        )
        .await
        .unwrap();
    assert_eq!(range.items.len(), 3);
    let other_node = store
        .query_commands(&CommandQuery::default().with_node("RH2"))
        .await
        .unwrap();
    assert!(other_node.items.is_empty());
}

pub(crate) async fn command_pagination(store: Arc<dyn EventStore>) {
    for i in 0..95 {
        store
            .append_command(&cmd(
                Actor::User(format!("u{}", i % 2)),
                "P",
                i / 10,
                CommandOutcome::Executed,
            ))
            .await
            .unwrap();
    }
    for order in [Order::NewestFirst, Order::OldestFirst] {
        let q = CommandQuery::default()
            .with_order(order)
            .with_limit(9)
            .with_actor_name("u1");
        let mut after = None;
        let mut seen = Vec::new();
        loop {
            let page = store
                .query_commands(&q.clone().with_after(after))
                .await
                .unwrap();
            seen.extend(page.items.iter().map(|c| (c.time, c.id.unwrap())));
            match page.next {
                Some(c) => after = Some(c),
                None => break,
            }
        }
        assert_eq!(seen.len(), 47);
        let mut sorted = seen.clone();
        sorted.sort();
        sorted.dedup();
        if order == Order::NewestFirst {
            sorted.reverse();
        }
        assert_eq!(seen, sorted);
    }
}

pub(crate) async fn purge_by_age(store: Arc<dyn EventStore>) {
    let day = 86_400_000i64;
    // 30 000 events over 100 days (SQLite purges in chunks of 10 000; PostgreSQL drops
    // whole day partitions: the cutoff is a UTC midnight, so both purge the same rows).
    let events: Vec<_> = (0..30_000i64)
        .map(|i| ev("P", PointValue::Int(i), i * (100 * day / 30_000)))
        .collect();
    store.append_events(&events).await.unwrap();
    for d in 0..100 {
        store
            .append_command(&cmd(
                Actor::User("op".into()),
                "P",
                d * day,
                CommandOutcome::Executed,
            ))
            .await
            .unwrap();
    }
    let cutoff = at_ms(40 * day);
    let expect_events = events.iter().filter(|e| e.received_time < cutoff).count() as u64;
    let purged = store.purge_older_than(cutoff).await.unwrap();
    assert_eq!(purged, expect_events + 40);
    let stats = store.stats().await.unwrap();
    assert_eq!(stats.events, 30_000 - expect_events);
    assert_eq!(stats.commands, 60);
    assert!(stats.oldest_event.unwrap() >= cutoff);
    let oldest = store
        .query_commands(&CommandQuery::default().with_order(Order::OldestFirst))
        .await
        .unwrap();
    assert_eq!(oldest.items[0].time, cutoff);
    // The trend rollups went with their events (12,000 minutes: more than one chunk).
    let trend = |from: i64, to: i64| store::TrendQuery::new("P", at_ms(from), at_ms(to), 100);
    assert!(store
        .query_trend(&trend(0, 40 * day))
        .await
        .unwrap()
        .is_empty());
    let kept = store
        .query_trend(&trend(40 * day, 100 * day))
        .await
        .unwrap();
    assert_eq!(
        kept.iter().map(|b| b.count).sum::<u64>(),
        30_000 - expect_events
    );
    // Purging again deletes nothing; appends still work, also of a day already purged.
    assert_eq!(store.purge_older_than(cutoff).await.unwrap(), 0);
    store
        .append_events(&[ev("P", PointValue::Int(1), 0)])
        .await
        .unwrap();
    assert_eq!(store.purge_older_than(cutoff).await.unwrap(), 1);
}

/// Retention goes by the event time (the partition key on PostgreSQL): an event received
/// late but stamped at its source before the cutoff goes, one stamped after it stays.
pub(crate) async fn purge_goes_by_event_time(store: Arc<dyn EventStore>) {
    let day = 86_400_000i64;
    let stamped = |received: i64, source: i64| {
        let mut e = ev("P", PointValue::Int(source), received);
        e.source_time = Some(SourceTime::at(at_ms(source)));
        e
    };
    store
        .append_events(&[
            stamped(50 * day, 10 * day), // buffered at the source, sent late
            stamped(5 * day, 45 * day),  // a source clock ahead
            stamped(50 * day, 50 * day),
        ])
        .await
        .unwrap();
    assert_eq!(store.purge_older_than(at_ms(40 * day)).await.unwrap(), 1);
    let left = all_events(
        &*store,
        EventQuery::default()
            .with_order(Order::OldestFirst)
            .with_limit(10),
    )
    .await;
    let values: Vec<_> = left.iter().map(|e| e.value.clone()).collect();
    assert_eq!(
        values,
        [PointValue::Int(45 * day), PointValue::Int(50 * day)]
    );
}

/// The idempotent key: a batch written again (a crash between commit and acknowledgement,
/// then the retry) stores nothing twice, and answers the stored ids; events without a key
/// are all kept.
pub(crate) async fn keyed_events_are_stored_once(store: Arc<dyn EventStore>) {
    let keyed = |seq: u64| {
        ev("K", PointValue::Int(seq as i64), seq as i64 * 10)
            .with_key(EventKey::new("RH2/run-1", seq))
    };
    let first: Vec<_> = (0..100).map(keyed).collect();
    let ids = store.append_events(&first).await.unwrap();
    // The retry overlaps: 50..100 again, and 100..150 new; and one duplicate within it.
    let mut retry: Vec<_> = (50..150).map(keyed).collect();
    retry.push(keyed(120));
    let again = store.append_events(&retry).await.unwrap();
    assert_eq!(again.len(), retry.len());
    assert_eq!(&again[..50], &ids[50..]);
    assert_eq!(again[100], again[70]);
    // The same key from another source is another event; unkeyed events are all kept.
    store
        .append_events(&[
            ev("K", PointValue::Int(0), 0).with_key(EventKey::new("RH2/run-2", 0)),
            ev("K", PointValue::Int(0), 0),
            ev("K", PointValue::Int(0), 0),
        ])
        .await
        .unwrap();
    let got = all_events(
        &*store,
        EventQuery::default()
            .with_order(Order::OldestFirst)
            .with_limit(MAX_PAGE_SIZE),
    )
    .await;
    assert_eq!(got.len(), 153);
    let mut keys: Vec<_> = got.iter().filter_map(|e| e.key.clone()).collect();
    assert_eq!(keys.len(), 151);
    keys.sort();
    keys.dedup();
    assert_eq!(keys.len(), 151, "a key stored twice");
    assert_eq!(got[0].key, Some(EventKey::new("RH2/run-1", 0)));
    // A key's sequence must fit the database's 64-bit integer.
    let too_big = ev("K", PointValue::Int(0), 0).with_key(EventKey::new("S", u64::MAX));
    assert!(matches!(
        store.append_events(&[too_big]).await,
        Err(StoreError::InvalidRecord(_))
    ));
}

pub(crate) async fn stats_count_rows(store: Arc<dyn EventStore>) {
    let empty = store.stats().await.unwrap();
    assert_eq!((empty.events, empty.commands), (0, 0));
    assert_eq!(empty.oldest_event, None);
    let events: Vec<_> = (0..25)
        .map(|i| ev("P", PointValue::Int(i), 1000 - i))
        .collect();
    store.append_events(&events).await.unwrap();
    store
        .append_command(&cmd(
            Actor::Remote("1.2.3.4:5".into()),
            "P",
            0,
            CommandOutcome::Failed,
        ))
        .await
        .unwrap();
    let s = store.stats().await.unwrap();
    assert_eq!((s.events, s.commands), (25, 1));
    assert_eq!(s.oldest_event, Some(at_ms(976)));
    assert_eq!(s.newest_event, Some(at_ms(1000)));
}

pub(crate) async fn batch_of_100k_events(store: Arc<dyn EventStore>) {
    let n = 100_000i64;
    let events: Vec<_> = (0..n)
        .map(|i| {
            let mut e = ev(
                &format!("ROV{:02}_P{}", i % 12, i % 50),
                match i % 3 {
                    0 => PointValue::Bool(i % 2 == 0),
                    1 => PointValue::Float(i as f64 / 10.0),
                    _ => PointValue::Int(i),
                },
                i,
            );
            e.ioa = Some((i % 5000) as u32);
            e
        })
        .collect();
    let started = std::time::Instant::now();
    let ids = store.append_events(&events).await.unwrap();
    let took = started.elapsed();
    eprintln!(
        "{:?}: 100000 events in one batch: {:.2} s",
        store.backend(),
        took.as_secs_f64()
    );
    assert_eq!(ids.len(), n as usize);
    assert!(ids.windows(2).all(|w| w[0] < w[1]));
    assert_eq!(store.stats().await.unwrap().events, n as u64);
    let newest = store
        .query_events(&EventQuery::default().with_limit(3))
        .await
        .unwrap();
    assert_eq!(newest.items[0].received_time, at_ms(n - 1));
    assert_eq!(newest.items[0].id, ids.last().copied());
    let one_point = all_events(
        &*store,
        EventQuery::default()
            .with_point("ROV07_P7")
            .with_limit(MAX_PAGE_SIZE),
    )
    .await;
    assert_eq!(
        one_point.len(),
        (0..n).filter(|i| i % 12 == 7 && i % 50 == 7).count()
    );
    let board = store
        .query_events(
            &EventQuery::default()
                .with_point_prefix("ROV11_")
                .with_range(Some(at_ms(50_000)), Some(at_ms(50_120)))
                .with_limit(MAX_PAGE_SIZE),
        )
        .await
        .unwrap();
    assert_eq!(board.items.len(), 10);
}

pub(crate) async fn concurrent_writers(store: Arc<dyn EventStore>) {
    let writers = 8;
    let batches = 25;
    let per_batch = 20;
    let mut tasks = Vec::new();
    for w in 0..writers {
        let store = Arc::clone(&store);
        tasks.push(tokio::spawn(async move {
            let mut ids = Vec::new();
            let mut command_ids = Vec::new();
            for b in 0..batches {
                let events: Vec<_> = (0..per_batch)
                    .map(|i| {
                        let mut e = ev(&format!("W{w}"), PointValue::Int(b * 100 + i), b);
                        e.origin = format!("writer-{w}");
                        e
                    })
                    .collect();
                ids.extend(store.append_events(&events).await.unwrap());
                command_ids.push(
                    store
                        .append_command(&cmd(
                            Actor::User(format!("w{w}")),
                            "P",
                            b,
                            CommandOutcome::Executed,
                        ))
                        .await
                        .unwrap(),
                );
                // Readers run alongside.
                store
                    .query_events(&EventQuery::default().with_point(format!("W{w}")))
                    .await
                    .unwrap();
            }
            (ids, command_ids)
        }));
    }
    let mut event_ids = HashSet::new();
    let mut command_ids = HashSet::new();
    for t in tasks {
        let (events, commands) = t.await.unwrap();
        for id in events {
            assert!(event_ids.insert(id), "event id {id} handed out twice");
        }
        for id in commands {
            assert!(command_ids.insert(id), "command id {id} handed out twice");
        }
    }
    let s = store.stats().await.unwrap();
    assert_eq!(s.events, (writers * batches * per_batch) as u64);
    assert_eq!(s.commands, (writers * batches) as u64);
    // Each writer's events are all there, in its order.
    for w in 0..writers {
        let got = all_events(
            &*store,
            EventQuery::default()
                .with_point(format!("W{w}"))
                .with_time_basis(TimeBasis::Received)
                .with_order(Order::OldestFirst)
                .with_limit(1000),
        )
        .await;
        let values: Vec<_> = got
            .iter()
            .map(|e| match e.value {
                PointValue::Int(v) => v,
                _ => -1,
            })
            .collect();
        let want: Vec<_> = (0..batches)
            .flat_map(|b| (0..per_batch).map(move |i| b * 100 + i))
            .collect();
        assert_eq!(values, want);
    }
}

pub(crate) async fn bad_input_is_refused_cleanly(store: Arc<dyn EventStore>) {
    for limit in [0, MAX_PAGE_SIZE + 1, usize::MAX] {
        let err = store
            .query_events(&EventQuery::default().with_limit(limit))
            .await
            .unwrap_err();
        assert!(matches!(err, StoreError::InvalidQuery(_)), "{err}");
        let err = store
            .query_commands(&CommandQuery::default().with_limit(limit))
            .await
            .unwrap_err();
        assert!(matches!(err, StoreError::InvalidQuery(_)), "{err}");
    }
    for bad in [
        "",
        "12",
        "a:b",
        "1:",
        ":2",
        "1:2:3",
        "99999999999999999999:1",
    ] {
        let err = bad.parse::<Cursor>().unwrap_err();
        assert!(err.to_string().contains("cursor"), "{err}");
    }
    let good = ev("OK", PointValue::Bool(true), 0);
    let bad_events = [
        ev("", PointValue::Bool(true), 0),
        ev("NUL\0point", PointValue::Bool(true), 0),
        ev("P", PointValue::DoublePoint(4), 0),
        ev("P", PointValue::Text("nul \0 inside".into()), 0),
        EventRecord::new("", "P", PointValue::Int(1), at_ms(0)),
    ];
    for bad in bad_events {
        // A batch with one bad record stores nothing.
        let err = store
            .append_events(&[good.clone(), bad.clone()])
            .await
            .unwrap_err();
        assert!(matches!(err, StoreError::InvalidRecord(_)), "{err}");
    }
    let mut bad_cmd = cmd(Actor::User(String::new()), "P", 0, CommandOutcome::Refused);
    assert!(matches!(
        store.append_command(&bad_cmd).await.unwrap_err(),
        StoreError::InvalidRecord(_)
    ));
    bad_cmd.actor = Actor::User("ok".into());
    bad_cmd.detail = "nul\0".into();
    assert!(matches!(
        store.append_command(&bad_cmd).await.unwrap_err(),
        StoreError::InvalidRecord(_)
    ));
    // Extreme but valid times and a cursor from nowhere work.
    let mut far = ev("FAR", PointValue::Bool(true), 0);
    far.received_time = Utc.with_ymd_and_hms(9999, 12, 31, 23, 59, 59).unwrap();
    far.source_time = Some(SourceTime {
        time: Utc.with_ymd_and_hms(1900, 1, 1, 0, 0, 0).unwrap(),
        invalid: false,
    });
    store.append_events(&[far]).await.unwrap();
    let page = store
        .query_events(&EventQuery::default().with_after(Some(Cursor::new(i64::MAX, i64::MAX))))
        .await
        .unwrap();
    assert_eq!(points(&page.items), ["FAR"]);
    let page = store
        .query_events(
            &EventQuery::default()
                .with_after(Some(Cursor::new(i64::MIN, i64::MIN)))
                .with_range(
                    Some(DateTime::<Utc>::MIN_UTC),
                    Some(DateTime::<Utc>::MAX_UTC),
                ),
        )
        .await
        .unwrap();
    assert!(page.items.is_empty());
    // Nothing of the refused batches was stored.
    assert_eq!(store.stats().await.unwrap().events, 1);
}

/// A trend downsampled in the database: per bucket the first and last time, min, max,
/// mean, count and whether any value was invalid; booleans and integers count, texts
/// and other points do not; empty buckets are left out; bad bucket counts are refused.
pub(crate) async fn trend_downsamples_per_bucket(store: Arc<dyn EventStore>) {
    use store::{TrendQuery, MAX_TREND_BUCKETS};
    let mut events: Vec<EventRecord> = (0..10)
        .map(|i| {
            ev(
                "RH2_U",
                PointValue::Float(f64::from(i)),
                i64::from(i) * 1000,
            )
        })
        .collect();
    // Second bucket (10..20 s): integers and a boolean, one invalid.
    events.push(ev("RH2_U", PointValue::Int(40), 12_000));
    let mut invalid = ev("RH2_U", PointValue::Bool(true), 15_000);
    invalid.quality = quality_from_bits(1);
    events.push(invalid);
    events.push(ev("RH2_U", PointValue::Text("n/a".into()), 16_000));
    // Nothing from 20 to 30 s; another point in the range.
    events.push(ev("RH2_I", PointValue::Float(99.0), 5_000));
    events.push(ev("RH2_U", PointValue::Float(-3.0), 35_000));
    store.append_events(&events).await.unwrap();

    let query = TrendQuery::new("RH2_U", at_ms(0), at_ms(40_000), 4);
    assert_eq!(query.bucket_ms(), 10_000);
    let buckets = store.query_trend(&query).await.unwrap();
    assert_eq!(buckets.len(), 3, "{buckets:?}");
    let first = buckets[0];
    assert_eq!(
        (first.first_time, first.last_time),
        (at_ms(0), at_ms(9_000))
    );
    assert_eq!(
        (first.min, first.max, first.avg, first.count),
        (0.0, 9.0, 4.5, 10)
    );
    assert!(!first.invalid);
    let second = buckets[1];
    assert_eq!(
        (second.min, second.max, second.avg, second.count),
        (1.0, 40.0, 20.5, 2)
    );
    assert!(second.invalid);
    assert_eq!(buckets[2].first_time, at_ms(35_000));
    assert_eq!((buckets[2].min, buckets[2].count), (-3.0, 1));

    // The end is exclusive; an empty or reversed range has no buckets.
    let tail = TrendQuery::new("RH2_U", at_ms(0), at_ms(9_000), 9);
    assert_eq!(store.query_trend(&tail).await.unwrap().len(), 9);
    let reversed = TrendQuery::new("RH2_U", at_ms(10_000), at_ms(0), 10);
    assert!(store.query_trend(&reversed).await.unwrap().is_empty());
    for buckets in [0, MAX_TREND_BUCKETS + 1] {
        let bad = TrendQuery::new("RH2_U", at_ms(0), at_ms(10_000), buckets);
        assert!(matches!(
            store.query_trend(&bad).await,
            Err(StoreError::InvalidQuery(_))
        ));
    }
}

/// The first and last value of each bucket, by index seeks: the same buckets as the
/// aggregation, with the ends' values and times.
pub(crate) async fn trend_first_and_last_per_bucket(store: Arc<dyn EventStore>) {
    use store::{TrendMode, TrendQuery};
    let mut events: Vec<EventRecord> = (0..10)
        .map(|i| {
            ev(
                "RH2_U",
                PointValue::Float(f64::from(i)),
                i64::from(i) * 1000,
            )
        })
        .collect();
    events.push(ev("RH2_U", PointValue::Int(40), 12_000));
    let mut invalid = ev("RH2_U", PointValue::Bool(true), 15_000);
    invalid.quality = quality_from_bits(1);
    events.push(invalid);
    events.push(ev("RH2_U", PointValue::Text("n/a".into()), 16_000));
    events.push(ev("RH2_I", PointValue::Float(99.0), 5_000));
    events.push(ev("RH2_U", PointValue::Float(-3.0), 35_000));
    store.append_events(&events).await.unwrap();

    let query =
        TrendQuery::new("RH2_U", at_ms(0), at_ms(40_000), 4).with_mode(TrendMode::FirstLast);
    let buckets = store.query_trend(&query).await.unwrap();
    assert_eq!(buckets.len(), 3, "{buckets:?}");
    let first = buckets[0];
    assert_eq!(
        (first.first_time, first.last_time),
        (at_ms(0), at_ms(9_000))
    );
    assert_eq!((first.first, first.last), (Some(0.0), Some(9.0)));
    // Every value of the bucket counts (the ten floats 0 to 9), not only its two ends.
    assert_eq!((first.min, first.max, first.count), (0.0, 9.0, 10));
    assert_eq!(first.avg, 4.5);
    assert!(!first.invalid);
    let second = buckets[1];
    assert_eq!((second.first, second.last), (Some(40.0), Some(1.0)));
    assert_eq!(
        (second.first_time, second.last_time),
        (at_ms(12_000), at_ms(15_000))
    );
    assert!(second.invalid);
    let third = buckets[2];
    assert_eq!(
        (third.first, third.last, third.count),
        (Some(-3.0), Some(-3.0), 1)
    );
    assert_eq!(third.avg, -3.0);
    // The end is exclusive, the range not a multiple of the width.
    let short =
        TrendQuery::new("RH2_U", at_ms(0), at_ms(35_000), 3).with_mode(TrendMode::FirstLast);
    let buckets = store.query_trend(&short).await.unwrap();
    assert_eq!(buckets.len(), 2, "{buckets:?}");
}

/// What an aggregated trend must answer, folded by hand from `events`: with a rollup span,
/// a value of a whole span inside the range counts in the bucket the span's start falls
/// in, a value of the partial spans at the range's ends by its own time; without, every
/// value by its own time.
fn trend_by_hand(events: &[EventRecord], query: &store::TrendQuery) -> Vec<(i64, TrendFold)> {
    let (from, to) = (query.from.timestamp_millis(), query.to.timestamp_millis());
    let width = query.bucket_ms();
    let mut folds = std::collections::BTreeMap::<i64, TrendFold>::new();
    for e in events {
        let t = e.event_time().timestamp_millis();
        let v = match e.value {
            PointValue::Bool(b) => f64::from(u8::from(b)),
            PointValue::Int(i) => i as f64,
            PointValue::Float(f) => f,
            _ => continue,
        };
        if e.point != query.point || t < from || t >= to {
            continue;
        }
        let at = match query.rollup_span_ms() {
            Some(span) => {
                let start = t.div_euclid(span) * span;
                if start >= from && start + span <= to {
                    start
                } else {
                    t
                }
            }
            None => t,
        };
        let fold = folds.entry((at - from) / width).or_insert(TrendFold {
            first: t,
            last: t,
            first_value: v,
            last_value: v,
            min: v,
            max: v,
            sum: 0.0,
            count: 0,
            invalid: false,
        });
        // `events` are in the order they are stored (their ids'): on the same millisecond
        // the first is the earlier stored, the last the later.
        if t < fold.first {
            (fold.first, fold.first_value) = (t, v);
        }
        if t >= fold.last {
            (fold.last, fold.last_value) = (t, v);
        }
        fold.min = fold.min.min(v);
        fold.max = fold.max.max(v);
        fold.sum += v;
        fold.count += 1;
        fold.invalid |= e.quality.invalid;
    }
    folds.into_iter().collect()
}

#[derive(Debug, Clone, Copy)]
struct TrendFold {
    first: i64,
    last: i64,
    first_value: f64,
    last_value: f64,
    min: f64,
    max: f64,
    sum: f64,
    count: u64,
    invalid: bool,
}

/// Trends of wide buckets are read from the rollups the database keeps as it stores the
/// events, and answer what every event folded by hand answers (buckets of many minutes,
/// and ranges that start and end inside a minute); a batch written again under its keys,
/// single appends and a text value leave them exact; retention takes them with the
/// events.
pub(crate) async fn trend_reads_the_rollups(store: Arc<dyn EventStore>) {
    use store::{TrendMode, TrendQuery};
    let hour = 3_600_000;
    // Six hours of a value about every 7 s: floats, integers and booleans, some invalid.
    let mut x: u64 = 0x5eed;
    let events: Vec<EventRecord> = (0..3_000u64)
        .map(|i| {
            x = x
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            let t = i64::try_from(i * 7_000 + (x >> 59) * 100).unwrap();
            let value = match i % 5 {
                0 => PointValue::Int(i64::try_from(x >> 54).unwrap() - 512),
                1 => PointValue::Bool(x & 1 == 1),
                _ => PointValue::Float((x >> 11) as f64 / (1u64 << 53) as f64 * 100.0 - 50.0),
            };
            let mut e = ev("RH2_P", value, t).with_key(EventKey::new("rollups", i));
            if i % 97 == 0 {
                e.quality = quality_from_bits(1);
            }
            e
        })
        .collect();
    store.append_events(&events[..1_000]).await.unwrap();
    // The first thousand again (a batch retried after a crash): stored once.
    store.append_events(&events[..2_000]).await.unwrap();
    for e in &events[2_000..2_010] {
        store.append_events(std::slice::from_ref(e)).await.unwrap();
    }
    store.append_events(&events[2_010..]).await.unwrap();
    store
        .append_events(&[
            ev("RH2_P", PointValue::Text("n/a".into()), 600_000),
            ev("RH2_Q", PointValue::Float(1e9), 600_000),
        ])
        .await
        .unwrap();

    let queries = [
        // Edges inside minutes: 40 buckets of 8.9 minutes, minute spans.
        (
            TrendQuery::new("RH2_P", at_ms(90_500), at_ms(6 * hour - 12_345), 40),
            Some(60_000),
        ),
        // One bucket of 6.5 hours, partial minutes at both ends.
        (
            TrendQuery::new("RH2_P", at_ms(-1_800_100), at_ms(6 * hour + 1), 1),
            Some(60_000),
        ),
        // Aligned to minutes: no partial spans.
        (
            TrendQuery::new("RH2_P", at_ms(0), at_ms(2 * hour), 30),
            Some(60_000),
        ),
        // Buckets of 2 minutes: every event read.
        (TrendQuery::new("RH2_P", at_ms(0), at_ms(hour), 30), None),
    ];
    // Each aggregated and as first/last: of buckets read from the rollups, the first and
    // last value are the events' (by time, then as stored) and the rest is as aggregated.
    let modes = queries.into_iter().flat_map(|(query, span)| {
        let ends = query.clone().with_mode(TrendMode::FirstLast);
        [(query, span), (ends, span)]
    });
    for (query, span) in modes.filter(|(q, span)| q.mode == TrendMode::Aggregate || span.is_some())
    {
        assert_eq!(query.rollup_span_ms(), span, "{query:?}");
        let got = store.query_trend(&query).await.unwrap();
        let want = trend_by_hand(&events, &query);
        assert_eq!(got.len(), want.len(), "{query:?}: {got:?}");
        for (bucket, (index, fold)) in got.iter().zip(&want) {
            let context = format!("{query:?}, bucket {index}: {bucket:?} against {fold:?}");
            let ends = match query.mode {
                TrendMode::Aggregate => (None, None),
                TrendMode::FirstLast => (Some(fold.first_value), Some(fold.last_value)),
            };
            assert_eq!((bucket.first, bucket.last), ends, "{context}");
            assert_eq!(
                (
                    bucket.first_time.timestamp_millis(),
                    bucket.last_time.timestamp_millis()
                ),
                (fold.first, fold.last),
                "{context}"
            );
            assert_eq!(
                (bucket.min, bucket.max, bucket.count, bucket.invalid),
                (fold.min, fold.max, fold.count, fold.invalid),
                "{context}"
            );
            let mean = fold.sum / fold.count as f64;
            assert!(
                (bucket.avg - mean).abs() <= 1e-9 * mean.abs().max(1.0),
                "{context}"
            );
        }
    }
    // Narrow first/last buckets are read by seeks.
    assert_eq!(
        TrendQuery::new("RH2_P", at_ms(0), at_ms(hour), 30)
            .with_mode(TrendMode::FirstLast)
            .rollup_span_ms(),
        None
    );

    // Retention keeps what is younger than its cutoff (SQLite the events by their time,
    // PostgreSQL whole days)...
    store.purge_older_than(at_ms(3 * hour)).await.unwrap();
    let kept = TrendQuery::new("RH2_P", at_ms(3 * hour), at_ms(6 * hour), 20);
    let got = store.query_trend(&kept).await.unwrap();
    let want = trend_by_hand(&events, &kept);
    assert_eq!(
        got.iter()
            .map(|b| (b.min, b.max, b.count))
            .collect::<Vec<_>>(),
        want.iter()
            .map(|(_, f)| (f.min, f.max, f.count))
            .collect::<Vec<_>>()
    );
    // ... and takes the rollups with their events (a whole day here, as PostgreSQL drops
    // day partitions).
    store.purge_older_than(at_ms(24 * hour)).await.unwrap();
    for buckets in [1, 40] {
        let gone = TrendQuery::new("RH2_P", at_ms(0), at_ms(6 * hour), buckets);
        assert!(gone.rollup_span_ms().is_some());
        assert!(store.query_trend(&gone).await.unwrap().is_empty());
    }
}
