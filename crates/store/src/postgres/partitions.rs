//! The day partitions of the event history and `commands` on PostgreSQL (schema version
//! 3, the history's tables since 6): making the days an append or the calendar needs,
//! and dropping the days retention no longer keeps.
//!
//! A partition is one UTC day of the table's time (`event_blocks.first_ms`,
//! `event_segments.start_ms`, `commands.time_ms`), named `event_blocks_YYYYMMDD`; times
//! without a day partition go to the DEFAULT partition (`event_blocks_default`). The
//! database function `stanice_day_partition` (migrations 3, 5 and 6) makes a day, moving
//! that day's rows out of the DEFAULT partition first; a day of blocks comes with its
//! day of segments and of trend rollups. The store makes today
//! and [`DAYS_AHEAD`] days ahead at open and with each retention pass, and any other day an
//! append meets (within [`ON_DEMAND_PAST_DAYS`] back and [`ON_DEMAND_FUTURE_DAYS`] ahead of
//! today, so a source clock gone wild fills the DEFAULT partition, not the catalogue with
//! thousands of tables). Retention drops every partition whose whole day is older than its
//! cutoff and deletes the DEFAULT partition's rows older than it.
//!
//! `trend_rollups` is partitioned by the day of its minutes (schema version 5): retention
//! drops the rollup days with the event days, and [`Partitions::compact_closed_days`]
//! rewrites each closed rollup day in key order once.

use std::collections::HashSet;
use std::sync::atomic::{AtomicI64, Ordering};
use std::sync::Mutex;

use chrono::{DateTime, NaiveDate, Utc};
use tokio_postgres::Client;

use crate::StoreError;

/// One day in milliseconds.
pub(crate) const DAY_MS: i64 = 86_400_000;

/// Days after today whose partitions the store keeps made.
pub const DAYS_AHEAD: i64 = 7;

/// How long after its end a day counts as closed: its trend rollups are then rewritten in
/// key order ([`crate::EventStore::compact_closed_days`]). Events of the day arriving later (a
/// node's buffer replayed after an outage) are still stored and folded, as ordinary
/// updates.
pub const CLOSED_DAY_GRACE_MS: i64 = 3_600_000;

/// How many days before today an append's time may lie and still get a day partition.
pub const ON_DEMAND_PAST_DAYS: i64 = 3_660;

/// How many days after today an append's time may lie and still get a day partition.
pub const ON_DEMAND_FUTURE_DAYS: i64 = 366;

/// A partitioned table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) enum History {
    /// `event_blocks`, by `first_ms` (a block lies within one minute, so one day).
    Events,
    /// `commands` (the command audit), by `time_ms`.
    Commands,
    /// `trend_rollups`, by `start_ms`: made with the event days (by the day function),
    /// dropped with them.
    Rollups,
    /// `event_segments`, by `start_ms`: made and dropped with the event days.
    Segments,
}

impl History {
    pub(crate) const ALL: [History; 2] = [History::Events, History::Commands];

    pub(crate) fn table(self) -> &'static str {
        match self {
            History::Events => "event_blocks",
            History::Commands => "commands",
            History::Rollups => "trend_rollups",
            History::Segments => "event_segments",
        }
    }

    /// What counts the records of its rows: a block holds many events.
    fn count(self) -> &'static str {
        match self {
            History::Events => "CAST(COALESCE(SUM(events), 0) AS BIGINT)",
            _ => "count(*)",
        }
    }

    fn key(self) -> &'static str {
        match self {
            History::Events => "first_ms",
            History::Commands => "time_ms",
            History::Rollups | History::Segments => "start_ms",
        }
    }
}

/// The start of the UTC day holding `ms`.
pub(crate) fn day_of(ms: i64) -> i64 {
    ms.div_euclid(DAY_MS) * DAY_MS
}

/// The start of the day a partition's name says (`events_20260301`), `None` for the
/// DEFAULT partition or a name the store did not make.
fn day_of_name(history: History, name: &str) -> Option<i64> {
    let digits = name.strip_prefix(history.table())?.strip_prefix('_')?;
    let date = NaiveDate::parse_from_str(digits, "%Y%m%d").ok()?;
    Some(date.and_hms_opt(0, 0, 0)?.and_utc().timestamp_millis())
}

/// The days known to have a partition, and the retention's last cutoff.
#[derive(Debug)]
pub(crate) struct Partitions {
    known: Mutex<HashSet<(History, i64)>>,
    /// Days wholly before this (ms) are retention's: no partition is made for them again.
    kept_from: AtomicI64,
}

impl Default for Partitions {
    fn default() -> Partitions {
        Partitions {
            known: Mutex::default(),
            kept_from: AtomicI64::new(i64::MIN),
        }
    }
}

impl Partitions {
    /// The days of `times` that need their partition made (not known to exist, within the
    /// on-demand window around `now`, not already given up by retention).
    pub(crate) fn missing(
        &self,
        history: History,
        times: impl IntoIterator<Item = i64>,
        now: DateTime<Utc>,
    ) -> Vec<i64> {
        let today = day_of(now.timestamp_millis());
        let earliest = (today - ON_DEMAND_PAST_DAYS * DAY_MS).max(day_of(
            self.kept_from
                .load(Ordering::Relaxed)
                .max(i64::MIN + DAY_MS),
        ));
        let latest = today + ON_DEMAND_FUTURE_DAYS * DAY_MS;
        let known = self.known.lock().unwrap_or_else(|p| p.into_inner());
        let mut days: Vec<i64> = times
            .into_iter()
            .map(day_of)
            .filter(|day| (earliest..=latest).contains(day) && !known.contains(&(history, *day)))
            .collect();
        days.sort_unstable();
        days.dedup();
        days
    }

    /// Makes the partitions of `days` (those missing), on `client` outside any
    /// transaction of the caller, and remembers them.
    pub(crate) async fn make(
        &self,
        client: &Client,
        history: History,
        days: &[i64],
    ) -> Result<(), StoreError> {
        for &day in days {
            let made: bool = client
                .query_one(
                    "SELECT stanice_day_partition($1::text, $2::int8)",
                    &[&history.table(), &day],
                )
                .await?
                .try_get(0)?;
            if made {
                tracing::debug!(
                    table = history.table(),
                    day_ms = day,
                    "made a day partition"
                );
            }
            self.known
                .lock()
                .unwrap_or_else(|p| p.into_inner())
                .insert((history, day));
        }
        Ok(())
    }

    /// Makes today's partitions and [`DAYS_AHEAD`] days ahead, of both tables.
    pub(crate) async fn make_ahead(
        &self,
        client: &Client,
        now: DateTime<Utc>,
    ) -> Result<(), StoreError> {
        let today = day_of(now.timestamp_millis());
        let days: Vec<i64> = (0..=DAYS_AHEAD).map(|d| today + d * DAY_MS).collect();
        for history in History::ALL {
            let missing = self.missing(history, days.iter().copied(), now);
            self.make(client, history, &missing).await?;
        }
        Ok(())
    }

    /// CLUSTERs every rollup day that ended [`CLOSED_DAY_GRACE_MS`] before `now` and is not
    /// clustered yet on its key (point, start_ms), packing its pages full first (a closed
    /// day's minutes are not updated any more, so no room is kept for updates); returns
    /// how many days it rewrote. A day is rewritten once: CLUSTER marks its key's index
    /// as the table's clustering, which is what is checked.
    pub(crate) async fn compact_closed_days(
        &self,
        client: &Client,
        now: DateTime<Utc>,
    ) -> Result<u64, StoreError> {
        let last_closed = day_of(now.timestamp_millis() - CLOSED_DAY_GRACE_MS) - DAY_MS;
        let days = client
            .query(
                "SELECT c.relname::text, k.relname::text FROM pg_inherits i \
                   JOIN pg_class c ON c.oid = i.inhrelid \
                   JOIN pg_index x ON x.indrelid = c.oid AND x.indisprimary \
                   JOIN pg_class k ON k.oid = x.indexrelid \
                 WHERE i.inhparent = to_regclass('trend_rollups') AND NOT x.indisclustered \
                 ORDER BY 1",
                &[],
            )
            .await?;
        let mut rewritten = 0;
        for row in days {
            let (name, key): (String, String) = (row.try_get(0)?, row.try_get(1)?);
            match day_of_name(History::Rollups, &name) {
                Some(day) if day <= last_closed => {}
                _ => continue,
            }
            let started = std::time::Instant::now();
            // Both names are the database's for a partition the store made (checked
            // above) and its key: letters, digits, '_'.
            client
                .batch_execute(&format!(
                    "ALTER TABLE {name} SET (fillfactor = 100); CLUSTER {name} USING {key}"
                ))
                .await?;
            tracing::info!(partition = %name, ms = started.elapsed().as_millis() as u64,
                "rewrote a closed day's trend rollups in key order");
            rewritten += 1;
        }
        Ok(rewritten)
    }

    /// Drops every partition of `history` whose day ends at or before `cutoff_ms` and
    /// deletes the DEFAULT partition's rows older than it; returns the rows gone.
    pub(crate) async fn drop_before(
        &self,
        client: &Client,
        history: History,
        cutoff_ms: i64,
    ) -> Result<u64, StoreError> {
        self.kept_from.fetch_max(cutoff_ms, Ordering::Relaxed);
        let partitions = client
            .query(
                "SELECT c.relname::text FROM pg_inherits i JOIN pg_class c ON c.oid = i.inhrelid \
                 WHERE i.inhparent = to_regclass($1::text)",
                &[&history.table()],
            )
            .await?;
        let mut gone = 0u64;
        for row in partitions {
            let name: String = row.try_get(0)?;
            let Some(day) = day_of_name(history, &name) else {
                continue;
            };
            if day + DAY_MS > cutoff_ms {
                continue;
            }
            // The name is one the store made (checked above): letters, digits, '_'.
            let rows: i64 = client
                .query_one(&format!("SELECT {} FROM {name}", history.count()), &[])
                .await?
                .try_get(0)?;
            client
                .batch_execute(&format!("DROP TABLE IF EXISTS {name}"))
                .await?;
            self.known
                .lock()
                .unwrap_or_else(|p| p.into_inner())
                .remove(&(history, day));
            tracing::info!(table = history.table(), partition = %name, rows, "retention dropped a day");
            gone += u64::try_from(rows).unwrap_or(0);
        }
        let rows: i64 = client
            .query_one(
                &format!(
                    "WITH gone AS (DELETE FROM {}_default WHERE {} < $1::int8 RETURNING *) \
                     SELECT {} FROM gone",
                    history.table(),
                    history.key(),
                    history.count()
                ),
                &[&cutoff_ms],
            )
            .await?
            .try_get(0)?;
        gone += u64::try_from(rows).unwrap_or(0);
        Ok(gone)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use chrono::TimeZone;

    #[test]
    fn days_are_utc_days_also_before_1970() {
        assert_eq!(day_of(0), 0);
        assert_eq!(day_of(DAY_MS - 1), 0);
        assert_eq!(day_of(-1), -DAY_MS);
        let t = Utc
            .with_ymd_and_hms(2026, 3, 1, 0, 0, 0)
            .unwrap()
            .timestamp_millis();
        assert_eq!(
            day_of_name(History::Events, "event_blocks_20260301"),
            Some(t)
        );
        assert_eq!(day_of_name(History::Commands, "commands_20260301"), Some(t));
        assert_eq!(day_of_name(History::Events, "event_blocks_default"), None);
        assert_eq!(day_of_name(History::Events, "commands_20260301"), None);
    }

    #[test]
    fn only_unknown_days_within_the_window_are_made() {
        let now = Utc.with_ymd_and_hms(2026, 3, 1, 12, 0, 0).unwrap();
        let p = Partitions::default();
        let today = day_of(now.timestamp_millis());
        let times = [
            today + 5,
            today + 7,
            today + DAY_MS,
            today + 400 * DAY_MS,  // a clock a year ahead: DEFAULT
            today - 4000 * DAY_MS, // eleven years back: DEFAULT
        ];
        assert_eq!(
            p.missing(History::Events, times, now),
            [today, today + DAY_MS]
        );
        p.known.lock().unwrap().insert((History::Events, today));
        assert_eq!(p.missing(History::Events, times, now), [today + DAY_MS]);
        assert_eq!(p.missing(History::Commands, times, now).len(), 2);
        // Retention gave up the days before its cutoff.
        p.kept_from.store(today + DAY_MS, Ordering::Relaxed);
        assert_eq!(p.missing(History::Commands, times, now), [today + DAY_MS]);
    }
}
