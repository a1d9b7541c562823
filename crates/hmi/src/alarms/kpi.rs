//! The alarm KPI report (`GET /api/alarms/kpi`), measured against EEMUA 191: alarms per
//! hour, the busiest 10 minutes, floods, the most frequent alarms, standing and stale
//! alarms and the priority distribution, counted by the HMI's receive time from the
//! activations the alarm system announced (the initial state after an interrogation,
//! consequences of a lost link, suppressed and out-of-service alarms are not
//! activations; chattering ones are, every one of them).
//!
//! The activations since the HMI started are its own log (in memory). Before that, when
//! the HMI has an event store, they are read back from the value changes it recorded
//! ([`stored_activations`]): a change of an alarm's point into its alarm value with good
//! quality, not an interrogation's answer, after a value that was not the alarm value.
//! The holds (settle window, suppression, out of service, link loss) were not recorded,
//! so that part counts what the points did.

use std::collections::{BTreeMap, HashMap};

use chrono::{DateTime, Duration, Utc};
use serde::Serialize;

use store::{EventCause, EventQuery, EventStore, Order, PointFilter, PointValue, TimeBasis};

use super::{Activation, Alarms, FLOOD_COUNT, FLOOD_WINDOW};
use crate::config::AlarmConfig;

/// Standing: active longer than this; stale: unacknowledged longer than this.
pub const STANDING_AFTER: Duration = Duration::hours(24);
/// At most this many alarms in `top`.
pub const TOP: usize = 10;

/// A flood: a period in which every activation lies in a 10-minute window holding at
/// least [`FLOOD_COUNT`] activations.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Flood {
    /// The first activation of it.
    pub start: DateTime<Utc>,
    /// The last.
    pub end: DateTime<Utc>,
    /// Activations in it.
    pub count: usize,
}

/// One of the most frequent alarms.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Frequent {
    /// The point.
    pub point: String,
    /// The alarm's text.
    pub text: String,
    /// Its priority.
    pub priority: u8,
    /// Activations in the period.
    pub count: usize,
}

/// An alarm standing or stale now.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Lingering {
    /// The alarm's id.
    pub id: usize,
    /// The point.
    pub point: String,
    /// Text.
    pub text: String,
    /// Priority.
    pub priority: u8,
    /// Raised then.
    pub since: Option<DateTime<Utc>>,
}

/// The report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct KpiReport {
    /// The period asked.
    pub from: DateTime<Utc>,
    /// Its end.
    pub to: DateTime<Utc>,
    /// The HMI's own log of activations starts then (its start; 35 days at most);
    /// before it they were read back from the HMI's event store when it has one.
    pub counted_since: DateTime<Utc>,
    /// Whether the part before `counted_since` was read from the event store.
    pub from_store: bool,
    /// Activations in the period.
    pub alarms: usize,
    /// Activations per hour of the period.
    pub alarms_per_hour: f64,
    /// The most activations in any 10 minutes of the period.
    pub peak_per_10min: usize,
    /// The floods.
    pub floods: Vec<Flood>,
    /// The most frequent alarms, most first.
    pub top: Vec<Frequent>,
    /// Active longer than 24 h (at `to`, or now if earlier).
    pub standing: Vec<Lingering>,
    /// Unacknowledged longer than 24 h.
    pub stale: Vec<Lingering>,
    /// Activations by priority, `"1"` ..= `"4"`.
    pub priority_distribution: BTreeMap<String, usize>,
}

/// The report of `from..to` (`now` bounds the standing and stale ones); `earlier` are
/// the activations before the HMI's own log (from its store), `None` without a store.
pub fn report(
    alarms: &Alarms,
    earlier: Option<&[Activation]>,
    from: DateTime<Utc>,
    to: DateTime<Utc>,
    now: DateTime<Utc>,
) -> KpiReport {
    let since = alarms.log_start();
    let times: Vec<(DateTime<Utc>, usize)> = earlier
        .unwrap_or_default()
        .iter()
        .filter(|a| a.time < since)
        .chain(alarms.activations())
        .filter(|a| a.time >= from && a.time < to)
        .map(|a| (a.time, a.id))
        .collect();
    let hours = (to - from).num_milliseconds() as f64 / 3_600_000.0;
    let alarms_per_hour = if hours > 0.0 {
        times.len() as f64 / hours
    } else {
        0.0
    };
    // Each window starts at an activation: the busiest 10 minutes start at one.
    let mut peak = 0;
    let mut floods: Vec<Flood> = Vec::new();
    let mut end_index = 0;
    for (start_index, (start, _)) in times.iter().enumerate() {
        end_index = end_index.max(start_index);
        while times
            .get(end_index)
            .is_some_and(|(t, _)| *t < *start + FLOOD_WINDOW)
        {
            end_index += 1;
        }
        let count = end_index - start_index;
        peak = peak.max(count);
        if count >= FLOOD_COUNT {
            let last = times
                .get(end_index.saturating_sub(1))
                .map_or(*start, |(t, _)| *t);
            match floods.last_mut() {
                Some(flood) if *start <= flood.end => flood.end = flood.end.max(last),
                _ => floods.push(Flood {
                    start: *start,
                    end: last,
                    count: 0,
                }),
            }
        }
    }
    for flood in &mut floods {
        flood.count = times
            .iter()
            .filter(|(t, _)| *t >= flood.start && *t <= flood.end)
            .count();
    }
    let mut counts: HashMap<usize, usize> = HashMap::new();
    let mut distribution: BTreeMap<String, usize> = (1..=4u8).map(|p| (p.to_string(), 0)).collect();
    for (_, id) in &times {
        *counts.entry(*id).or_default() += 1;
        if let Some(alarm) = alarms.get(*id) {
            *distribution.entry(alarm.priority.to_string()).or_default() += 1;
        }
    }
    let mut top: Vec<Frequent> = counts
        .into_iter()
        .filter_map(|(id, count)| {
            alarms.get(id).map(|a| Frequent {
                point: a.point.clone(),
                text: a.text.clone(),
                priority: a.priority,
                count,
            })
        })
        .collect();
    top.sort_by(|a, b| {
        b.count
            .cmp(&a.count)
            .then(a.priority.cmp(&b.priority))
            .then(a.point.cmp(&b.point))
    });
    top.truncate(TOP);
    let at = to.min(now);
    let old = |since: Option<DateTime<Utc>>| since.is_some_and(|s| at - s > STANDING_AFTER);
    let lingering = |a: &super::Alarm| Lingering {
        id: a.id,
        point: a.point.clone(),
        text: a.text.clone(),
        priority: a.priority,
        since: a.raised,
    };
    let standing = alarms
        .all()
        .iter()
        .filter(|a| a.active && old(a.raised))
        .map(lingering)
        .collect();
    let stale = alarms
        .all()
        .iter()
        .filter(|a| a.waiting() && old(a.raised))
        .map(lingering)
        .collect();
    KpiReport {
        from,
        to,
        counted_since: since,
        from_store: earlier.is_some() && from < since,
        alarms: times.len(),
        alarms_per_hour,
        peak_per_10min: peak,
        floods,
        top,
        standing,
        stale,
        priority_distribution: distribution,
    }
}

/// The activations of `config`'s alarms in `from..to` read back from the value changes
/// the HMI recorded in `store` (by receive time, oldest first).
pub async fn stored_activations(
    store: &dyn EventStore,
    config: &[AlarmConfig],
    from: DateTime<Utc>,
    to: DateTime<Utc>,
) -> Result<Vec<Activation>, store::StoreError> {
    let mut points: Vec<&str> = config.iter().map(|c| c.point.as_str()).collect();
    points.sort_unstable();
    points.dedup();
    let mut activations = Vec::new();
    for point in points {
        // Each alarm of the point: its id, its alarm value, whether it was active.
        let mut alarms: Vec<(usize, bool, Option<bool>)> = config
            .iter()
            .enumerate()
            .filter(|(_, c)| c.point == point)
            .map(|(id, c)| (id, c.when, None))
            .collect();
        let mut query = EventQuery::default();
        query.time_basis = TimeBasis::Received;
        query.from = Some(from);
        query.to = Some(to);
        query.point = Some(PointFilter::Exact(point.to_owned()));
        query.order = Order::OldestFirst;
        query.limit = store::MAX_PAGE_SIZE;
        loop {
            let page = store.query_events(&query).await?;
            for event in &page.items {
                let PointValue::Bool(on) = event.value else {
                    continue;
                };
                if event.quality.invalid {
                    continue;
                }
                for (id, when, was) in &mut alarms {
                    let active = on == *when;
                    let change = *was != Some(true) && active;
                    if change && event.cause != EventCause::Interrogated {
                        activations.push(Activation {
                            time: event.received_time,
                            id: *id,
                        });
                    }
                    *was = Some(active);
                }
            }
            match page.next {
                Some(next) => query.after = Some(next),
                None => break,
            }
        }
    }
    activations.sort_by_key(|a| a.time);
    Ok(activations)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::AlarmConfig;

    #[test]
    fn rates_peak_floods_top_and_distribution() {
        let configs: Vec<AlarmConfig> = (0..12)
            .map(|i| AlarmConfig {
                point: format!("P{i}"),
                when: true,
                priority: if i == 0 { 1 } else { 3 },
                text: format!("alarm {i}"),
                acknowledge: true,
                suppress_when: None,
                link: None,
            })
            .collect();
        let mut alarms = Alarms::new(&configs);
        let start = Utc::now() - Duration::hours(2);
        // P0 chatters 4 times in the first hour; 11 alarms in 2 minutes later.
        for i in 0..4 {
            let t = start + Duration::seconds(i * 20);
            alarms.point("P0", true, false, t);
            alarms.point("P0", false, false, t + Duration::seconds(5));
        }
        for i in 1..12 {
            alarms.point(
                &format!("P{i}"),
                true,
                false,
                start + Duration::minutes(60) + Duration::seconds(i * 10),
            );
        }
        let kpi = report(&alarms, None, start, start + Duration::hours(2), Utc::now());
        assert_eq!(kpi.alarms, 15);
        assert!((kpi.alarms_per_hour - 7.5).abs() < 1e-9);
        assert_eq!(kpi.peak_per_10min, 11);
        assert_eq!(kpi.floods.len(), 1);
        assert_eq!(kpi.floods[0].count, 11);
        assert_eq!(kpi.top[0].point, "P0");
        assert_eq!(kpi.top[0].count, 4);
        assert_eq!(kpi.top.len(), TOP);
        assert_eq!(kpi.priority_distribution["1"], 4);
        assert_eq!(kpi.priority_distribution["3"], 11);
        assert_eq!(kpi.priority_distribution["4"], 0);
        assert!(kpi.standing.is_empty() && kpi.stale.is_empty());
    }
}
