//! The event list: values and commands from the HMI's store, merged newest first, paged
//! by a cursor that says where each of the two lists continues.

use axum::extract::rejection::QueryRejection;
use axum::extract::{Query, State};
use axum::routing::get;
use axum::{Json, Router};
use chrono::{DateTime, Utc};
use serde::Deserialize;
use serde_json::{json, Value};
use store::{CommandOutcome, CommandQuery, Cursor, EventQuery, Order, PointFilter, TimeBasis};

use super::{AppError, AppState, LoggedIn, SENT_DETAIL};

pub(super) fn routes() -> Router<AppState> {
    Router::new().route("/api/events", get(events))
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct EventsQuery {
    from: Option<DateTime<Utc>>,
    to: Option<DateTime<Utc>>,
    point: Option<String>,
    kind: Option<String>,
    user: Option<String>,
    cursor: Option<String>,
    limit: Option<usize>,
}

/// The cursor of the merged event list: where each of the two lists continues.
fn parse_cursor(text: &str) -> Result<(Option<Cursor>, Option<Cursor>, bool, bool), AppError> {
    let bad = || AppError::BadCursor;
    let mut values = (None, None, false, false);
    for part in text.split(',') {
        let (kind, rest) = part.split_once('=').ok_or_else(bad)?;
        match (kind, rest) {
            ("v", "end") => values.2 = true,
            ("c", "end") => values.3 = true,
            ("v", c) => values.0 = Some(c.parse().map_err(|_| bad())?),
            ("c", c) => values.1 = Some(c.parse().map_err(|_| bad())?),
            _ => return Err(bad()),
        }
    }
    Ok(values)
}

async fn events(
    State(state): State<AppState>,
    _: LoggedIn,
    query: Result<Query<EventsQuery>, QueryRejection>,
) -> Result<Json<Value>, AppError> {
    let Query(query) = query?;
    let store = state.store()?;
    let limit = query.limit.unwrap_or(100).clamp(1, 1000);
    let (value_after, command_after, values_done, commands_done) = match &query.cursor {
        Some(text) => parse_cursor(text)?,
        None => (None, None, false, false),
    };
    let want_values =
        query.kind.as_deref() != Some("command") && query.user.is_none() && !values_done;
    let want_commands = query.kind.as_deref() != Some("value") && !commands_done;
    let mut items: Vec<(i64, Value, bool, Cursor)> = Vec::new();
    let mut values_exhausted = !want_values;
    let mut commands_exhausted = !want_commands;
    if want_values {
        // Ordered by when the HMI received them, the clock commands are stamped with, so
        // that values and commands interleave truly even if the station's clock differs.
        let mut q = EventQuery::default()
            .with_time_basis(TimeBasis::Received)
            .with_range(query.from, query.to)
            .with_order(Order::NewestFirst)
            .with_limit(limit)
            .with_after(value_after);
        q.point = query.point.as_deref().map(PointFilter::parse);
        let page = store.query_events(&q).await?;
        values_exhausted = page.next.is_none();
        for e in page.items {
            let time = e.received_time;
            let id = e.id.unwrap_or_default();
            items.push((
                time.timestamp_millis(),
                json!({"id": format!("v{id}"), "time": time,
                       "source_time": e.source_time.map(|s| s.time), "kind": "value",
                       "point": e.point, "ioa": e.ioa, "value": crate_value(&e.value),
                       "invalid": e.quality.invalid}),
                true,
                Cursor::new(time.timestamp_millis(), id),
            ));
        }
    }
    if want_commands {
        let mut q = CommandQuery::default()
            .with_range(query.from, query.to)
            .with_order(Order::NewestFirst)
            .with_limit(limit)
            .with_after(command_after);
        q.point = query.point.as_deref().map(PointFilter::parse);
        if let Some(user) = &query.user {
            q = q.with_actor_name(user);
        }
        let page = store.query_commands(&q).await?;
        commands_exhausted = page.next.is_none();
        for c in page.items {
            let id = c.id.unwrap_or_default();
            items.push((
                c.time.timestamp_millis(),
                json!({"id": format!("c{id}"), "time": c.time, "kind": "command", "point": c.point,
                       "ioa": c.ioa, "value": crate_value(&c.value), "user": c.actor.name(),
                       "outcome": if c.outcome == CommandOutcome::Failed && c.detail == SENT_DETAIL {
                           "sent"
                       } else {
                           outcome_word(c.outcome)
                       },
                       "detail": c.detail}),
                false,
                Cursor::new(c.time.timestamp_millis(), id),
            ));
        }
    }
    // Newest first across both lists; a stable order for equal times.
    items.sort_by(|a, b| b.0.cmp(&a.0).then(b.2.cmp(&a.2)));
    items.truncate(limit);
    let last_value = items.iter().rev().find(|i| i.2).map(|i| i.3);
    let last_command = items.iter().rev().find(|i| !i.2).map(|i| i.3);
    let value_part = match (last_value, value_after) {
        (Some(c), _) => Some(format!("v={c}")),
        (None, Some(c)) => Some(format!("v={c}")),
        (None, None) if values_exhausted => Some("v=end".into()),
        (None, None) => None,
    };
    let took_all_values = items.iter().filter(|i| i.2).count() == limit || !values_exhausted;
    let command_part = match (last_command, command_after) {
        (Some(c), _) => Some(format!("c={c}")),
        (None, Some(c)) => Some(format!("c={c}")),
        (None, None) if commands_exhausted => Some("c=end".into()),
        (None, None) => None,
    };
    let more =
        items.len() == limit || (!values_exhausted && took_all_values) || !commands_exhausted;
    let next = if more {
        let parts: Vec<String> = [value_part, command_part].into_iter().flatten().collect();
        (!parts.is_empty()).then(|| parts.join(","))
    } else {
        None
    };
    let list: Vec<Value> = items.into_iter().map(|i| i.1).collect();
    Ok(Json(json!({"items": list, "next": next})))
}

/// The outcome as `/api/command` words it.
fn outcome_word(outcome: CommandOutcome) -> &'static str {
    match outcome {
        CommandOutcome::Executed => "executed",
        CommandOutcome::RefusedLocalMode => "refused-local",
        CommandOutcome::RefusedPermission => "refused-permission",
        CommandOutcome::Refused => "refused",
        CommandOutcome::Failed => "no-link",
        CommandOutcome::TimedOut => "timed-out",
        CommandOutcome::RefusedAuthority => "refused-authority",
    }
}

fn crate_value(value: &store::PointValue) -> Value {
    use store::PointValue;
    match value {
        PointValue::Bool(b) => json!(b),
        PointValue::DoublePoint(d) => json!(d),
        PointValue::Int(i) => json!(i),
        PointValue::Float(f) => json!(f),
        PointValue::Bits(b) => json!(b),
        PointValue::Text(t) => json!(t),
    }
}
