//! The alarm list, acknowledging and shelving (not for read-only users: [`Operator`]).

use axum::extract::rejection::JsonRejection;
use axum::extract::{Path, State};
use axum::routing::{get, post};
use axum::{Json, Router};
use serde::Deserialize;
use serde_json::{json, Value};

use super::{AppError, AppState, LoggedIn, Operator};

pub(super) fn routes() -> Router<AppState> {
    Router::new()
        .route("/api/alarms", get(alarms))
        .route("/api/alarms/{id}/acknowledge", post(acknowledge))
        .route("/api/alarms/{id}/shelve", post(shelve))
}

/// Shelving lasts at most a week.
const MAX_SHELVE_MINUTES: u32 = 7 * 24 * 60;

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
    minutes: u32,
}

async fn shelve(
    State(state): State<AppState>,
    operator: Operator,
    Path(id): Path<usize>,
    body: Result<Json<ShelveRequest>, JsonRejection>,
) -> Result<Json<Value>, AppError> {
    let Json(request) = body.map_err(AppError::body(""))?;
    let alarm = state
        .station
        .shelve(id, request.minutes.min(MAX_SHELVE_MINUTES), operator.user())
        .ok_or(AppError::NoAlarm)?;
    Ok(Json(json!(alarm)))
}
