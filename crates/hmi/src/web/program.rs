//! A student's program from the browser (crate::trial): `POST /api/program/check` and
//! `POST /api/program/run`, each `{files: [{name, text}], seed?}`, for users of the
//! `[program]` level. Bodies up to [`MAX_PROGRAM`]; one trial at a time (another waits).
//! `POST /api/program/load` (`{files}`) loads the program into the lab itself and `POST
//! /api/program/restore` (`{}`) puts the lab's own back: the level, and the operator
//! lease where the lab has one (409 with the reason otherwise).

use axum::extract::rejection::JsonRejection;
use axum::extract::{DefaultBodyLimit, State};
use axum::routing::post;
use axum::{Json, Router};
use serde::Deserialize;
use serde_json::{json, Value};

use super::{AppError, AppState, Writer};
use std::sync::Arc;

use tokio::sync::OwnedSemaphorePermit;

use crate::trial::{ProgramTrial, SourceFile};
use crate::LogText;

/// Largest upload: a few ST files.
pub(super) const MAX_PROGRAM: usize = 256 * 1024;

pub(super) fn routes() -> Router<AppState> {
    Router::new()
        .route("/api/program/check", post(check))
        .route("/api/program/run", post(run))
        .route("/api/program/load", post(load))
        .route("/api/program/restore", post(restore))
        .layer(DefaultBodyLimit::max(MAX_PROGRAM))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ProgramRequest {
    files: Vec<SourceFile>,
    #[serde(default)]
    seed: Option<u64>,
}

/// The trial, once the user is of the `[program]` level.
fn trial_for(state: &AppState, writer: &Writer) -> Result<Arc<dyn ProgramTrial>, AppError> {
    let program = state
        .station
        .config()
        .program
        .clone()
        .ok_or(AppError::NoTrial)?;
    let trial = state.trial.clone().ok_or(AppError::NoTrial)?;
    writer.require_level(program.level)?;
    Ok(trial)
}

/// This request's turn: one trial at a time (another waits).
async fn turn(state: &AppState) -> Result<OwnedSemaphorePermit, AppError> {
    Arc::clone(&state.trial_running)
        .acquire_owned()
        .await
        .map_err(|_| AppError::NoTrial)
}

/// The trial, the request and this request's turn, once the user may try programs and
/// the files are one to sixteen.
async fn prepare(
    state: &AppState,
    writer: &Writer,
    body: Result<Json<ProgramRequest>, JsonRejection>,
) -> Result<(Arc<dyn ProgramTrial>, ProgramRequest, OwnedSemaphorePermit), AppError> {
    let Json(request) = body.map_err(AppError::body("bad program request: "))?;
    let trial = trial_for(state, writer)?;
    if request.files.is_empty() || request.files.len() > 16 {
        return Err(AppError::BadParameter {
            name: "files",
            message: "one to sixteen ST files".into(),
        });
    }
    Ok((trial, request, turn(state).await?))
}

async fn check(
    State(state): State<AppState>,
    writer: Writer,
    body: Result<Json<ProgramRequest>, JsonRejection>,
) -> Result<Json<Value>, AppError> {
    let (trial, request, _turn) = prepare(&state, &writer, body).await?;
    let report = tokio::task::spawn_blocking(move || trial.check(&request.files))
        .await
        .map_err(|e| AppError::Trial(e.to_string()))?;
    tracing::info!(peer = %writer.peer(), user = %LogText(writer.user()), ok = report.ok, "program checked");
    Ok(Json(json!(report)))
}

async fn run(
    State(state): State<AppState>,
    writer: Writer,
    body: Result<Json<ProgramRequest>, JsonRejection>,
) -> Result<Json<Value>, AppError> {
    let (trial, request, _turn) = prepare(&state, &writer, body).await?;
    let seed = request.seed.unwrap_or(1);
    let outcome = tokio::task::spawn_blocking(move || {
        let check = trial.check(&request.files);
        if !check.ok {
            return Ok(json!({"check": check, "report": null}));
        }
        trial
            .run(&request.files, seed)
            .map(|report| json!({"check": check, "report": report}))
    })
    .await
    .map_err(|e| AppError::Trial(e.to_string()))?
    .map_err(AppError::Trial)?;
    tracing::info!(peer = %writer.peer(), user = %LogText(writer.user()), seed, "program tried");
    Ok(Json(outcome))
}

/// The lease holder only: the live lab is controlled by one user at a time.
fn require_lease(state: &AppState, writer: &Writer) -> Result<(), AppError> {
    match super::points::lease_refusal(state, writer.user()) {
        Some(refused) => Err(AppError::NoAuthority(refused)),
        None => Ok(()),
    }
}

async fn load(
    State(state): State<AppState>,
    writer: Writer,
    body: Result<Json<ProgramRequest>, JsonRejection>,
) -> Result<Json<Value>, AppError> {
    let (trial, request, _turn) = prepare(&state, &writer, body).await?;
    if !trial.live() {
        return Err(AppError::NotLive);
    }
    require_lease(&state, &writer)?;
    let files = request.files;
    let check = {
        let (trial, files) = (Arc::clone(&trial), files.clone());
        tokio::task::spawn_blocking(move || trial.check(&files))
            .await
            .map_err(|e| AppError::Trial(e.to_string()))?
    };
    if !check.ok {
        return Ok(Json(json!({"check": check, "loaded": null})));
    }
    // A program that compiles but does not fit the lab (a variable the station binds
    // missing) is the student's to fix: said in words, not a server error.
    let outcome = trial.load(files, writer.user().to_owned()).await;
    tracing::info!(peer = %writer.peer(), user = %LogText(writer.user()), ok = outcome.is_ok(), "program loaded into the lab");
    Ok(Json(match outcome {
        Ok(loaded) => json!({"check": check, "loaded": loaded}),
        Err(error) => json!({"check": check, "loaded": null, "error": error}),
    }))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RestoreRequest {}

async fn restore(
    State(state): State<AppState>,
    writer: Writer,
    body: Result<Json<RestoreRequest>, JsonRejection>,
) -> Result<Json<Value>, AppError> {
    let Json(RestoreRequest {}) = body.map_err(AppError::body("bad restore request: "))?;
    let trial = trial_for(&state, &writer)?;
    if !trial.live() {
        return Err(AppError::NotLive);
    }
    require_lease(&state, &writer)?;
    let _turn = turn(&state).await?;
    let outcome = trial.restore(writer.user().to_owned()).await;
    tracing::info!(peer = %writer.peer(), user = %LogText(writer.user()), ok = outcome.is_ok(), "the lab's program restored");
    outcome.map(Json).map_err(AppError::Trial)
}
