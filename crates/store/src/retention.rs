//! Retention: how long the store keeps history, and the background task that purges it
//! and, on PostgreSQL, makes the coming days' partitions ahead and rewrites the closed
//! days' trend rollups in key order.

use chrono::{DateTime, Utc};
use std::sync::Arc;
use std::time::Duration;
use tokio::task::JoinHandle;

use crate::EventStore;

/// How long history is kept and how often the purge runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub struct Retention {
    /// Events (by event time) and command records older than this are deleted (on
    /// PostgreSQL by whole days). The railway regulator asks
    /// for at least 60 days, the default.
    pub max_age: Duration,
    /// Time between two purges (default one hour).
    pub interval: Duration,
}

impl Default for Retention {
    fn default() -> Retention {
        Retention {
            max_age: Duration::from_secs(60 * 24 * 3600),
            interval: Duration::from_secs(3600),
        }
    }
}

impl Retention {
    /// The regulator's minimum: 60 days.
    pub const REGULATORY_MINIMUM: Duration = Duration::from_secs(60 * 24 * 3600);

    /// Keep history for `max_age` (purge every hour).
    pub fn new(max_age: Duration) -> Retention {
        Retention {
            max_age,
            ..Retention::default()
        }
    }

    /// Purge every `interval` (at least one second).
    pub fn with_interval(mut self, interval: Duration) -> Retention {
        self.interval = interval.max(Duration::from_secs(1));
        self
    }

    /// The oldest time kept at `now`: everything before it is purged.
    pub fn cutoff(&self, now: DateTime<Utc>) -> DateTime<Utc> {
        let age = chrono::Duration::from_std(self.max_age).unwrap_or(chrono::Duration::MAX);
        now.checked_sub_signed(age)
            .unwrap_or(DateTime::<Utc>::MIN_UTC)
    }
}

/// The background purge task; dropping the handle stops it.
#[derive(Debug)]
pub struct RetentionHandle {
    task: JoinHandle<()>,
}

impl RetentionHandle {
    /// Stops the purge task.
    pub fn stop(self) {
        self.task.abort();
    }
}

impl Drop for RetentionHandle {
    fn drop(&mut self) {
        self.task.abort();
    }
}

/// Spawns a task that purges `store` at once and then every `retention.interval`, cutting
/// at `retention.cutoff(clock())`. The clock is the runtime's (virtual in tests and
/// demos). Failures are logged and retried at the next interval. Must be called within a
/// tokio runtime.
pub fn spawn_retention<C>(
    store: Arc<dyn EventStore>,
    retention: Retention,
    clock: C,
) -> RetentionHandle
where
    C: Fn() -> DateTime<Utc> + Send + 'static,
{
    if retention.max_age < Retention::REGULATORY_MINIMUM {
        tracing::warn!(
            days = retention.max_age.as_secs() / 86_400,
            "event retention below the regulator's 60 days"
        );
    }
    let task = tokio::spawn(async move {
        let mut ticks = tokio::time::interval(retention.interval.max(Duration::from_secs(1)));
        ticks.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
        loop {
            ticks.tick().await;
            let now = clock();
            if let Err(e) = store.prepare_partitions(now).await {
                tracing::warn!(error = %e, "retention: making the coming days' partitions failed");
            }
            let cutoff = retention.cutoff(now);
            match store.purge_older_than(cutoff).await {
                Ok(0) => tracing::debug!(%cutoff, "retention: nothing to purge"),
                Ok(n) => tracing::info!(%cutoff, rows = n, "retention: purged"),
                Err(e) => tracing::warn!(%cutoff, error = %e, "retention: purge failed"),
            }
            // After the purge: no day about to be dropped is rewritten first.
            if let Err(e) = store.compact_closed_days(now).await {
                tracing::warn!(error = %e, "retention: rewriting the closed days failed");
            }
        }
    });
    RetentionHandle { task }
}
