//! The event list: values and commands from the HMI's store and the station's own command
//! audit (the commands of every client, dispatch's included, when the HMI reads the
//! station's store), merged newest first, paged by a cursor that says where each list
//! continues.

use axum::extract::rejection::QueryRejection;
use axum::extract::{Query, State};
use axum::routing::get;
use axum::{Json, Router};
use chrono::{DateTime, Utc};
use serde::Deserialize;
use serde_json::{json, Value};
use store::{
    Actor, CommandOutcome, CommandPhase, CommandQuery, CommandRecord, Cursor, EventQuery, Order,
    PointFilter, TimeBasis,
};

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

/// The lists the event list merges, each paged by its own cursor: the HMI's values (`v`),
/// the HMI's command audit (`c`) and the station's own command audit (`s`, from its store
/// when the HMI reads it, [`AppState::archive`]).
const LISTS: [&str; 3] = ["v", "c", "s"];

/// Where each list continues: `None` from its start, `Some(None)` at its end.
type Positions = [Option<Option<Cursor>>; 3];

/// The cursor of the merged event list: `v=TIME:ID,c=end,...`.
fn parse_cursor(text: &str) -> Result<Positions, AppError> {
    let bad = || AppError::BadCursor;
    let mut positions: Positions = [None, None, None];
    for part in text.split(',') {
        let (kind, rest) = part.split_once('=').ok_or_else(bad)?;
        let index = LISTS.iter().position(|l| *l == kind).ok_or_else(bad)?;
        let position = if rest == "end" {
            None
        } else {
            Some(rest.parse().map_err(|_| bad())?)
        };
        *positions.get_mut(index).ok_or_else(bad)? = Some(position);
    }
    Ok(positions)
}

/// One row of the merged list: its time, its JSON, its list, its cursor.
struct Row {
    time: i64,
    json: Value,
    list: usize,
    cursor: Cursor,
}

/// A command record as the event list shows it: who (`origin`), what, the outcome and,
/// for a refusal, the reason in the station's or the HMI's words.
fn command_row(c: CommandRecord, list: usize, prefix: &str) -> Row {
    let id = c.id.unwrap_or_default();
    let outcome = if c.outcome == CommandOutcome::Failed && c.detail == SENT_DETAIL {
        "sent"
    } else {
        outcome_word(c.outcome)
    };
    let origin = match &c.actor {
        Actor::User(name) => format!("HMI user {name}"),
        Actor::Remote(peer) => format!("IEC 104 client {peer}"),
    };
    // The station names a client as `ADDR:PORT (group NAME)` (store::Actor::Remote).
    let remote = match &c.actor {
        Actor::Remote(name) => Some(match name.split_once(" (group ") {
            Some((peer, group)) => (peer, group.strip_suffix(')')),
            None => (name.as_str(), None),
        }),
        Actor::User(_) => None,
    };
    let refused = !matches!(c.outcome, CommandOutcome::Executed);
    let reason =
        (refused && !c.detail.is_empty() && c.detail != SENT_DETAIL).then(|| c.detail.clone());
    Row {
        time: c.time.timestamp_millis(),
        json: json!({"id": format!("{prefix}{id}"), "time": c.time, "kind": "command",
               "point": c.point, "ioa": c.ioa, "value": crate_value(&c.value),
               "user": c.actor.name(), "origin": origin,
               "peer": remote.map(|(peer, _)| peer),
               "group": remote.and_then(|(_, group)| group),
               "source": if list == 2 { "station" } else { "hmi" },
               "phase": match c.phase { CommandPhase::Select => "select", CommandPhase::Execute => "execute" },
               "outcome": outcome, "reason": reason, "detail": c.detail}),
        list,
        cursor: Cursor::new(c.time.timestamp_millis(), id),
    }
}

async fn events(
    State(state): State<AppState>,
    _: LoggedIn,
    query: Result<Query<EventsQuery>, QueryRejection>,
) -> Result<Json<Value>, AppError> {
    let Query(query) = query?;
    let store = state.store()?;
    let limit = query.limit.unwrap_or(100).clamp(1, 1000);
    let positions = match &query.cursor {
        Some(text) => parse_cursor(text)?,
        None => [None, None, None],
    };
    let after = |list: usize| positions.get(list).copied().flatten().flatten();
    let done = |list: usize| matches!(positions.get(list), Some(Some(None)));
    let wanted = [
        query.kind.as_deref() != Some("command") && query.user.is_none() && !done(0),
        query.kind.as_deref() != Some("value") && !done(1),
        query.kind.as_deref() != Some("value") && state.archive.is_some() && !done(2),
    ];
    let mut rows: Vec<Row> = Vec::new();
    // Per list: how many rows it gave, and whether it has no more after them.
    let mut fetched = [0usize; 3];
    let mut exhausted = [true; 3];
    if wanted[0] {
        // Ordered by when the HMI received them, the clock commands are stamped with, so
        // that values and commands interleave truly even if the station's clock differs.
        let mut q = EventQuery::default()
            .with_time_basis(TimeBasis::Received)
            .with_range(query.from, query.to)
            .with_order(Order::NewestFirst)
            .with_limit(limit)
            .with_after(after(0));
        q.point = query.point.as_deref().map(PointFilter::parse);
        let page = store.query_events(&q).await?;
        exhausted[0] = page.next.is_none();
        fetched[0] = page.items.len();
        for e in page.items {
            let time = e.received_time;
            let id = e.id.unwrap_or_default();
            rows.push(Row {
                time: time.timestamp_millis(),
                json: json!({"id": format!("v{id}"), "time": time,
                       "source_time": e.source_time.map(|s| s.time), "kind": "value",
                       "point": e.point, "ioa": e.ioa, "value": crate_value(&e.value),
                       "invalid": e.quality.invalid}),
                list: 0,
                cursor: Cursor::new(time.timestamp_millis(), id),
            });
        }
    }
    let command_stores = [(1, Some(store)), (2, state.archive.clone())];
    for (list, command_store) in command_stores {
        let (true, Some(command_store)) =
            (wanted.get(list).copied().unwrap_or(false), command_store)
        else {
            continue;
        };
        let mut q = CommandQuery::default()
            .with_range(query.from, query.to)
            .with_order(Order::NewestFirst)
            .with_limit(limit)
            .with_after(after(list));
        q.point = query.point.as_deref().map(PointFilter::parse);
        if let Some(user) = &query.user {
            q = q.with_actor_name(user);
        }
        let page = command_store.query_commands(&q).await?;
        if let Some(slot) = exhausted.get_mut(list) {
            *slot = page.next.is_none();
        }
        if let Some(slot) = fetched.get_mut(list) {
            *slot = page.items.len();
        }
        let prefix = LISTS.get(list).copied().unwrap_or("c");
        rows.extend(page.items.into_iter().map(|c| command_row(c, list, prefix)));
    }
    // Newest first across the lists; values before commands at equal times (stable).
    rows.sort_by(|a, b| b.time.cmp(&a.time).then(a.list.cmp(&b.list)));
    rows.truncate(limit);
    let mut parts = Vec::new();
    let mut more = false;
    for (list, name) in LISTS.iter().enumerate() {
        let taken: Vec<&Row> = rows.iter().filter(|r| r.list == list).collect();
        let all_taken = taken.len() == fetched.get(list).copied().unwrap_or(0);
        if exhausted.get(list).copied().unwrap_or(true) && all_taken {
            parts.push(format!("{name}=end"));
        } else {
            more = true;
            // Without a cursor, the list continues from its start.
            if let Some(cursor) = taken.last().map(|r| r.cursor).or(after(list)) {
                parts.push(format!("{name}={cursor}"));
            }
        }
    }
    let next = more.then(|| parts.join(","));
    let station_audit = state.archive.is_some();
    let list: Vec<Value> = rows.into_iter().map(|r| r.json).collect();
    Ok(Json(json!({
        "items": list,
        "next": next,
        "station_audit": station_audit,
        "note": (!station_audit).then_some(NO_STATION_AUDIT),
    })))
}

/// What the event list says when the HMI does not read the station's store.
const NO_STATION_AUDIT: &str = "the station keeps no command audit this HMI can read; \
                                showing this HMI's own commands";

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
