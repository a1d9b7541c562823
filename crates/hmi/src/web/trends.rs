//! Trends: the points that have one, and a point's samples over a time range.

use axum::extract::rejection::QueryRejection;
use axum::extract::{Query, State};
use axum::routing::get;
use axum::{Json, Router};
use chrono::{DateTime, Utc};
use serde::Deserialize;
use serde_json::{json, Value};
use store::{EventQuery, Order};

use super::{AppError, AppState, LoggedIn};

pub(super) fn routes() -> Router<AppState> {
    Router::new()
        .route("/api/trend", get(trend))
        .route("/api/trends", get(trends))
}

async fn trends(State(state): State<AppState>, _: LoggedIn) -> Json<Value> {
    let config = state.station.config();
    let list: Vec<Value> = config
        .trends
        .iter()
        .filter_map(|name| config.points.iter().find(|p| &p.name == name))
        .map(|p| json!({"point": p.name, "description": p.description}))
        .collect();
    Json(json!(list))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TrendQuery {
    point: String,
    from: Option<DateTime<Utc>>,
    to: Option<DateTime<Utc>>,
}

async fn trend(
    State(state): State<AppState>,
    _: LoggedIn,
    query: Result<Query<TrendQuery>, QueryRejection>,
) -> Result<Json<Value>, AppError> {
    let Query(query) = query?;
    if state.station.point(&query.point).is_none() {
        return Err(AppError::NoPoint(query.point));
    }
    let store = state.store()?;
    let to = query.to.unwrap_or_else(Utc::now);
    let from = query.from.unwrap_or(to - chrono::Duration::hours(24));
    let mut samples = Vec::new();
    let mut after = None;
    // At most 20,000 samples per request; the browser zooms by asking again.
    for _ in 0..20 {
        let page = store
            .query_events(
                &EventQuery::default()
                    .with_point(&query.point)
                    .with_range(Some(from), Some(to))
                    .with_order(Order::OldestFirst)
                    .with_limit(1000)
                    .with_after(after),
            )
            .await?;
        for e in &page.items {
            let value = match &e.value {
                store::PointValue::Float(f) => *f,
                store::PointValue::Int(i) => *i as f64,
                store::PointValue::Bool(b) => f64::from(u8::from(*b)),
                _ => continue,
            };
            samples.push(json!([
                e.event_time().timestamp_millis(),
                value,
                e.quality.invalid
            ]));
        }
        after = page.next;
        if after.is_none() {
            break;
        }
    }
    Ok(Json(
        json!({"point": query.point, "from": from, "to": to, "samples": samples}),
    ))
}
