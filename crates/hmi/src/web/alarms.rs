//! The alarm list and its management (docs/HMI.md, "Alarm management"): acknowledging
//! (any operator, level >= 1), shelving, out of service (level >= [`SHELVE_LEVEL`]), and
//! the KPI report (any logged-in user).

use axum::extract::rejection::{JsonRejection, QueryRejection};
use axum::extract::{Path, Query, State};
use axum::routing::{get, post};
use axum::{Json, Router};
use chrono::{DateTime, Utc};
use serde::Deserialize;
use serde_json::{json, Value};

use super::{AppError, AppState, LoggedIn, Operator};
use crate::alarms::{kpi, AlarmRefusal, Shelve};

pub(super) fn routes() -> Router<AppState> {
    Router::new()
        .route("/api/alarms", get(alarms))
        .route("/api/alarms/kpi", get(kpi))
        .route("/api/alarms/{id}/acknowledge", post(acknowledge))
        .route("/api/alarms/{id}/shelve", post(shelve))
        .route("/api/alarms/{id}/unshelve", post(unshelve))
        .route("/api/alarms/{id}/out-of-service", post(out_of_service))
        .route("/api/alarms/{id}/in-service", post(in_service))
}

/// Shelving and out of service need this level (an operator who may switch the boards'
/// breakers); acknowledging needs only a level above read-only.
pub(super) const SHELVE_LEVEL: u8 = 5;
/// Shelving lasts at most a week.
const MAX_SHELVE_SECONDS: u64 = 7 * 24 * 3600;
/// A reason is at most this long.
const MAX_REASON: usize = 200;
/// A KPI period is at most this long.
const MAX_KPI_DAYS: i64 = 366;

fn refused(refusal: AlarmRefusal) -> AppError {
    match refusal {
        AlarmRefusal::NoAlarm => AppError::NoAlarm,
        other => AppError::BadParameter {
            name: "alarm",
            message: other.to_string(),
        },
    }
}

fn level_at_least(operator: &Operator) -> Result<(), AppError> {
    let has = operator.0 .0.session.level;
    if has < SHELVE_LEVEL {
        return Err(AppError::ElementLevel {
            element: "shelving of alarms and taking them out of service",
            needed: SHELVE_LEVEL,
            has,
        });
    }
    Ok(())
}

fn reason(text: Option<String>, required: bool) -> Result<Option<String>, AppError> {
    let text = text.map(|t| t.trim().to_owned()).filter(|t| !t.is_empty());
    let bad = |message: &str| AppError::BadParameter {
        name: "reason",
        message: message.to_owned(),
    };
    match &text {
        None if required => Err(bad("say why (a reason of 1 to 200 characters)")),
        Some(t) if t.chars().count() > MAX_REASON => Err(bad("at most 200 characters")),
        Some(t) if t.chars().any(char::is_control) => Err(bad("no control characters")),
        _ => Ok(text),
    }
}

async fn alarms(State(state): State<AppState>, _: LoggedIn) -> Json<Value> {
    Json(json!(state.station.alarms()))
}

async fn acknowledge(
    State(state): State<AppState>,
    operator: Operator,
    Path(id): Path<usize>,
) -> Result<Json<Value>, AppError> {
    let alarm = state
        .station
        .acknowledge(id, operator.user())
        .ok_or(AppError::NoAlarm)?;
    Ok(Json(json!(alarm)))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ShelveRequest {
    minutes: Option<u64>,
    seconds: Option<u64>,
    oneshot: Option<bool>,
    reason: Option<String>,
}

async fn shelve(
    State(state): State<AppState>,
    operator: Operator,
    Path(id): Path<usize>,
    body: Result<Json<ShelveRequest>, JsonRejection>,
) -> Result<Json<Value>, AppError> {
    level_at_least(&operator)?;
    let Json(request) = body.map_err(AppError::body(""))?;
    let bad = |message: &str| AppError::BadParameter {
        name: "shelve",
        message: message.to_owned(),
    };
    let how = match (request.minutes, request.seconds, request.oneshot) {
        (Some(minutes), None, None) => minutes.saturating_mul(60),
        (None, Some(seconds), None) => seconds,
        (None, None, Some(true)) => 0,
        (None, None, Some(false)) => return Err(bad("`oneshot` is `true` when given")),
        _ => {
            return Err(bad(
                "give exactly one of `minutes`, `seconds` or `oneshot: true`",
            ))
        }
    };
    let how = if request.oneshot == Some(true) {
        Shelve::OneShot
    } else if how == 0 || how > MAX_SHELVE_SECONDS {
        return Err(bad(
            "a shelve lasts 1 s to 7 days (POST .../unshelve ends one)",
        ));
    } else {
        let seconds = i64::try_from(how).map_err(|_| bad("too long"))?;
        Shelve::Until(Utc::now() + chrono::Duration::seconds(seconds))
    };
    let reason = reason(request.reason, false)?;
    let alarm = state
        .station
        .shelve(id, how, reason, operator.user())
        .map_err(refused)?;
    Ok(Json(json!(alarm)))
}

/// An empty body, `{}`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Nothing {}

async fn unshelve(
    State(state): State<AppState>,
    operator: Operator,
    Path(id): Path<usize>,
    body: Result<Json<Nothing>, JsonRejection>,
) -> Result<Json<Value>, AppError> {
    level_at_least(&operator)?;
    let Json(Nothing {}) = body.map_err(AppError::body(""))?;
    let alarm = state
        .station
        .unshelve(id, operator.user())
        .map_err(refused)?;
    Ok(Json(json!(alarm)))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct OutOfServiceRequest {
    reason: Option<String>,
}

async fn out_of_service(
    State(state): State<AppState>,
    operator: Operator,
    Path(id): Path<usize>,
    body: Result<Json<OutOfServiceRequest>, JsonRejection>,
) -> Result<Json<Value>, AppError> {
    level_at_least(&operator)?;
    let Json(request) = body.map_err(AppError::body(""))?;
    let reason = reason(request.reason, true)?.unwrap_or_default();
    let alarm = state
        .station
        .out_of_service(id, reason, operator.user())
        .map_err(refused)?;
    Ok(Json(json!(alarm)))
}

async fn in_service(
    State(state): State<AppState>,
    operator: Operator,
    Path(id): Path<usize>,
    body: Result<Json<Nothing>, JsonRejection>,
) -> Result<Json<Value>, AppError> {
    level_at_least(&operator)?;
    let Json(Nothing {}) = body.map_err(AppError::body(""))?;
    let alarm = state
        .station
        .in_service(id, operator.user())
        .map_err(refused)?;
    Ok(Json(json!(alarm)))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct KpiQuery {
    from: Option<String>,
    to: Option<String>,
}

fn time(name: &'static str, text: Option<String>) -> Result<Option<DateTime<Utc>>, AppError> {
    text.map(|t| {
        DateTime::parse_from_rfc3339(&t)
            .map(|t| t.with_timezone(&Utc))
            .map_err(|e| AppError::BadParameter {
                name,
                message: format!("an RFC 3339 time such as 2026-11-27T08:00:00Z ({e})"),
            })
    })
    .transpose()
}

/// `GET /api/alarms/kpi?from=&to=`: the last 24 h when not given.
async fn kpi(
    State(state): State<AppState>,
    _: LoggedIn,
    query: Result<Query<KpiQuery>, QueryRejection>,
) -> Result<Json<Value>, AppError> {
    let Query(query) = query?;
    let to = time("to", query.to)?.unwrap_or_else(Utc::now);
    let from = time("from", query.from)?.unwrap_or(to - chrono::Duration::hours(24));
    if from >= to {
        return Err(AppError::BadParameter {
            name: "from",
            message: "`from` must be before `to`".into(),
        });
    }
    if to - from > chrono::Duration::days(MAX_KPI_DAYS) {
        return Err(AppError::BadParameter {
            name: "from",
            message: format!("a period of at most {MAX_KPI_DAYS} days"),
        });
    }
    // Before the HMI's own log: what its store recorded of the alarms' points.
    let log_start = state.station.alarm_log_start();
    let earlier = match &state.store {
        Some(store) if from < log_start => Some(
            kpi::stored_activations(
                store.as_ref(),
                &state.station.config().alarms,
                from,
                to.min(log_start),
            )
            .await?,
        ),
        _ => None,
    };
    Ok(Json(json!(state.station.alarm_kpi(
        earlier.as_deref(),
        from,
        to
    ))))
}
