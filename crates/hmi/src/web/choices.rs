//! Set-points chosen together (hmi.toml `[[choice]]`): `GET /api/choices` lists them
//! with each field's value now; `POST /api/choices/{id}` `{values: [...]}` checks the
//! combination (refused with the choice's own words, 409, before anything is sent) and
//! then sends each set-point as the control it is (level, authority, lease, audit),
//! stopping at the first that is not carried out.

use axum::extract::rejection::JsonRejection;
use axum::extract::{Path, State};
use axum::routing::{get, post};
use axum::{Json, Router};
use serde::Deserialize;
use serde_json::{json, Value};

use super::points::control;
use super::{AppError, AppState, LoggedIn, Writer};
use crate::link::ControlOutcome;
use crate::LogText;

pub(super) fn routes() -> Router<AppState> {
    Router::new()
        .route("/api/choices", get(list))
        .route("/api/choices/{id}", post(choose))
}

async fn list(State(state): State<AppState>, _: LoggedIn) -> Json<Value> {
    let config = state.station.config();
    let list: Vec<Value> = config
        .choices
        .iter()
        .map(|choice| {
            let now: Vec<Value> = choice
                .points
                .iter()
                .map(|point| {
                    state
                        .station
                        .point(point)
                        .filter(|p| !p.invalid)
                        .map_or(Value::Null, |p| p.value)
                })
                .collect();
            json!({"choice": choice, "now": now})
        })
        .collect();
    Json(json!(list))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ChoiceRequest {
    values: Vec<i64>,
}

async fn choose(
    State(state): State<AppState>,
    writer: Writer,
    Path(id): Path<String>,
    body: Result<Json<ChoiceRequest>, JsonRejection>,
) -> Result<Json<Value>, AppError> {
    let Json(request) = body.map_err(AppError::body("bad choice request: "))?;
    let config = state.station.config();
    let choice = config
        .choices
        .iter()
        .find(|c| c.id == id)
        .ok_or_else(|| AppError::NoChoice(id.clone()))?;
    if !choice.allows(&request.values) {
        tracing::warn!(peer = %writer.peer(), user = %LogText(writer.user()), choice = %id, values = ?request.values, "choice refused");
        return Err(AppError::Combination(choice.forbidden.clone()));
    }
    let mut results = Vec::new();
    let mut outcome = ControlOutcome::Executed;
    let mut detail = String::new();
    for (command, value) in choice.commands.iter().zip(&request.values) {
        let (this, words) = control(&state, &writer, command, *value as f64).await?;
        results.push(json!({"command": command, "value": value, "outcome": this, "detail": words}));
        if this != ControlOutcome::Executed {
            outcome = this;
            detail = format!("{command}: {words}");
            break;
        }
    }
    Ok(Json(
        json!({"outcome": outcome, "detail": detail, "results": results}),
    ))
}
