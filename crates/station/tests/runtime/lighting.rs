//! A year of lighting decisions of one lighting board, run by the station runtime on the
//! simulated clock: the board's PLC (the lighting FB with the weekly calendar loaded from
//! `calendar/vsetin-weekly.csv`) switches the lamps in local time, through both DST
//! changes, exactly once each evening and once each morning.

use std::time::Duration;

use chrono::{Datelike, NaiveDate, NaiveTime, TimeZone, Timelike, Utc};
use chrono_tz::Europe::Prague;
use station::runtime::{Pacing, Runtime, RuntimeOptions, StoreChoice};
use station::store::{EventQuery, Order, PointValue};

use crate::harness::*;

/// (off, on) in UTC minutes after midnight, per week index 0..=52.
fn calendar() -> Vec<(i64, i64)> {
    let text = std::fs::read_to_string(vsetin_folder().join("calendar/vsetin-weekly.csv")).unwrap();
    let minutes = |hhmm: &str| {
        let (h, m) = hhmm.split_once(':').unwrap();
        h.parse::<i64>().unwrap() * 60 + m.parse::<i64>().unwrap()
    };
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("week"))
        .map(|l| {
            let cells: Vec<&str> = l.split(',').collect();
            (minutes(cells[1]), minutes(cells[2]))
        })
        .collect()
}

/// The week index the FB computes for a date (spec 4.5: ROUND(N / 7)).
fn week(date: NaiveDate) -> usize {
    (f64::from(date.ordinal()) / 7.0).round() as usize
}

/// The UTC offset in hours at 10:00 local of `date` (when the FB adopts it, L16).
fn offset_at_ten(date: NaiveDate) -> i64 {
    let ten = Prague
        .from_local_datetime(&date.and_hms_opt(10, 0, 0).unwrap())
        .unwrap();
    i64::from(ten.offset().fix_offset_seconds()) / 3600
}

trait FixOffsetSeconds {
    fn fix_offset_seconds(&self) -> i32;
}

impl FixOffsetSeconds for chrono_tz::TzOffset {
    fn fix_offset_seconds(&self) -> i32 {
        use chrono::Offset;
        self.fix().local_minus_utc()
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_year_of_lighting_follows_the_calendar_in_local_time_across_dst() {
    let mut project = vsetin_project();
    // One decision a minute is enough to check minute-accurate switching over a year.
    let board = project
        .nodes
        .iter_mut()
        .find(|n| n.name == "ROV01")
        .unwrap();
    board.tasks[0].interval = Duration::from_secs(60);
    let start = Utc.with_ymd_and_hms(2025, 1, 1, 0, 0, 0).unwrap();
    let runtime = Runtime::start(
        project,
        RuntimeOptions {
            nodes: vec!["ROV01".into()],
            pacing: Pacing::Manual,
            start,
            store: StoreChoice::Url("sqlite::memory:".into()),
            device_kinds: station::device::DeviceKinds::builtin(),
        },
    )
    .await
    .unwrap();
    for _ in 0..73 {
        runtime
            .advance(Duration::from_secs(5 * 86_400))
            .await
            .unwrap();
    }
    runtime.recorder().flush().await;
    let events = runtime
        .store()
        .unwrap()
        .query_events(
            &EventQuery::default()
                .with_node("ROV01")
                .with_point("ROV01_Osv_Zap")
                .with_order(Order::OldestFirst)
                .with_limit(10_000),
        )
        .await
        .unwrap()
        .items;
    let table = calendar();
    let mut evenings = std::collections::BTreeMap::new();
    let mut mornings = std::collections::BTreeMap::new();
    for event in &events {
        let local = event.event_time().with_timezone(&Prague);
        let PointValue::Bool(on) = event.value else {
            panic!("{event:?}")
        };
        let date = local.date_naive();
        if date < NaiveDate::from_ymd_opt(2025, 1, 2).unwrap() {
            continue;
        }
        let slot = if on { &mut evenings } else { &mut mornings };
        let previous = slot.insert(date, local.time());
        assert!(
            previous.is_none(),
            "two switchings {on} on {date}: {previous:?} and {}",
            local.time()
        );
        assert_eq!(on, local.hour() >= 12, "switched {on} at {local}");
    }
    let minute = |t: NaiveTime| i64::from(t.num_seconds_from_midnight()) / 60;
    let mut checked = 0;
    let mut date = NaiveDate::from_ymd_opt(2025, 1, 2).unwrap();
    while date <= NaiveDate::from_ymd_opt(2025, 12, 30).unwrap() {
        // Evening: the table's on time of today's week, in today's offset (adopted at 10:00),
        // plus the board's 2 s delay, within the minute cycle.
        let on = evenings
            .get(&date)
            .unwrap_or_else(|| panic!("no switch-on on {date}"));
        let expected_on = table[week(date)].1 + 60 * offset_at_ten(date);
        let late = minute(*on) - expected_on;
        assert!(
            (0..=2).contains(&late),
            "{date}: on at {on}, expected {expected_on} min"
        );
        // Morning: yesterday's table and offset (the update runs at 10:00), on today's clock.
        let yesterday = date.pred_opt().unwrap();
        let off = mornings
            .get(&date)
            .unwrap_or_else(|| panic!("no switch-off on {date}"));
        let expected_off = table[week(yesterday)].0 + 60 * offset_at_ten(yesterday);
        let late = minute(*off) - expected_off;
        assert!(
            (0..=1).contains(&late),
            "{date}: off at {off}, expected {expected_off} min"
        );
        checked += 1;
        date = date.succ_opt().unwrap();
    }
    assert_eq!(checked, 363);
    // Summer evenings are in CEST: late June the lamps go on after 21:00 local.
    let midsummer = evenings[&NaiveDate::from_ymd_opt(2025, 6, 21).unwrap()];
    assert!(midsummer.hour() == 21, "{midsummer}");
    runtime.shutdown().await;
}
