//! Retention: the cutoff and the background purge on a virtual clock.

use chrono::{DateTime, Duration as Days, Utc};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use store::{open_store, spawn_retention, EventStore, PointValue, Retention};

use crate::suite::{ev, t0};

#[test]
fn default_retention_is_the_regulators_60_days_purged_hourly() {
    let r = Retention::default();
    assert_eq!(r.max_age, Retention::REGULATORY_MINIMUM);
    assert_eq!(r.max_age, Duration::from_secs(60 * 86_400));
    assert_eq!(r.interval, Duration::from_secs(3600));
    assert_eq!(r.cutoff(t0()), t0() - Days::days(60));
    let r = Retention::new(Duration::from_secs(90 * 86_400)).with_interval(Duration::ZERO);
    assert_eq!(r.interval, Duration::from_secs(1));
    assert_eq!(r.cutoff(t0()), t0() - Days::days(90));
    // Absurd ages do not panic.
    let r = Retention::new(Duration::MAX);
    assert_eq!(r.cutoff(t0()), DateTime::<Utc>::MIN_UTC);
}

#[tokio::test(start_paused = true)]
async fn background_purge_runs_at_once_and_every_interval() {
    let store: Arc<dyn EventStore> = Arc::from(open_store("sqlite::memory:").await.unwrap());
    let day = 86_400_000;
    // One event per day over 100 days.
    let events: Vec<_> = (0..100)
        .map(|d| ev("P", PointValue::Int(d), d * day))
        .collect();
    store.append_events(&events).await.unwrap();
    // The station's clock: day 100.
    let now = Arc::new(Mutex::new(t0() + Days::days(100)));
    let clock = {
        let now = Arc::clone(&now);
        move || *now.lock().unwrap()
    };
    let handle = spawn_retention(Arc::clone(&store), Retention::default(), clock);
    // The first purge runs at once: days 0..40 go.
    wait_for_events(&*store, 60).await;
    // The clock moves on ten days; within the next hour the purge catches up.
    *now.lock().unwrap() = t0() + Days::days(110);
    tokio::time::sleep(Duration::from_secs(3600)).await;
    wait_for_events(&*store, 50).await;
    // Stopped, it purges no more.
    handle.stop();
    *now.lock().unwrap() = t0() + Days::days(150);
    tokio::time::sleep(Duration::from_secs(5 * 3600)).await;
    assert_eq!(store.stats().await.unwrap().events, 50);
}

async fn wait_for_events(store: &dyn EventStore, want: u64) {
    for _ in 0..200 {
        if store.stats().await.unwrap().events == want {
            return;
        }
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
    panic!(
        "expected {want} events, have {}",
        store.stats().await.unwrap().events
    );
}
