//! The operator lease and the booking calendar over HTTP (crate::lease has the rules).
//!
//! | route | |
//! |---|---|
//! | `GET /api/lease` | the lease, the bookings and what the user may do |
//! | `POST /api/lease` `{}` | take the lease |
//! | `POST /api/lease/release` `{}` | give it back |
//! | `POST /api/lease/revoke` `{}` | an administrator ends it |
//! | `POST /api/bookings` `{start, end}` | book a slot (RFC 3339 times on the grid) |
//! | `POST /api/bookings/{id}/cancel` `{}` | the owner or an administrator cancels it |
//!
//! Each answers with the lease as `GET /api/lease` gives it.

use std::sync::{Arc, Mutex, MutexGuard};

use axum::extract::rejection::JsonRejection;
use axum::extract::{Path, State};
use axum::routing::{get, post};
use axum::{Json, Router};
use chrono::{DateTime, Utc};
use serde::Deserialize;

use super::{AppError, AppState, LoggedIn, Writer};
use crate::lease::{LeaseDesk, LeaseView};
use crate::LogText;

pub(super) fn routes() -> Router<AppState> {
    Router::new()
        .route("/api/lease", get(view).post(take))
        .route("/api/lease/release", post(release))
        .route("/api/lease/revoke", post(revoke))
        .route("/api/bookings", post(book))
        .route("/api/bookings/{id}/cancel", post(cancel))
}

fn desk(state: &AppState) -> Result<&Arc<Mutex<LeaseDesk>>, AppError> {
    state.lease.as_ref().ok_or(AppError::NoLease)
}

fn lock(desk: &Mutex<LeaseDesk>) -> MutexGuard<'_, LeaseDesk> {
    desk.lock().unwrap_or_else(|p| p.into_inner())
}

/// An empty JSON object (the POSTs that carry nothing still send `{}`).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Empty {}

async fn view(State(state): State<AppState>, user: LoggedIn) -> Result<Json<LeaseView>, AppError> {
    let desk = desk(&state)?;
    let view = lock(desk).view(&user.session.user, user.session.level, Utc::now());
    Ok(Json(view))
}

fn answer(desk: &Mutex<LeaseDesk>, writer: &Writer) -> Json<LeaseView> {
    Json(lock(desk).view(writer.user(), writer.0.session.level, Utc::now()))
}

async fn take(
    State(state): State<AppState>,
    writer: Writer,
    body: Result<Json<Empty>, JsonRejection>,
) -> Result<Json<LeaseView>, AppError> {
    let Json(Empty {}) = body.map_err(AppError::body("bad lease request: "))?;
    let desk = desk(&state)?;
    let taken = lock(desk).take(writer.user(), writer.0.session.level, Utc::now());
    match taken {
        Ok(_) => {
            tracing::info!(peer = %writer.peer(), user = %LogText(writer.user()), "operator lease taken")
        }
        Err(refused) => {
            tracing::warn!(peer = %writer.peer(), user = %LogText(writer.user()), %refused, "operator lease refused");
            return Err(refused.into());
        }
    }
    Ok(answer(desk, &writer))
}

async fn release(
    State(state): State<AppState>,
    writer: Writer,
    body: Result<Json<Empty>, JsonRejection>,
) -> Result<Json<LeaseView>, AppError> {
    let Json(Empty {}) = body.map_err(AppError::body("bad lease request: "))?;
    let desk = desk(&state)?;
    lock(desk).release(writer.user(), Utc::now())?;
    tracing::info!(peer = %writer.peer(), user = %LogText(writer.user()), "operator lease released");
    Ok(answer(desk, &writer))
}

async fn revoke(
    State(state): State<AppState>,
    writer: Writer,
    body: Result<Json<Empty>, JsonRejection>,
) -> Result<Json<LeaseView>, AppError> {
    let Json(Empty {}) = body.map_err(AppError::body("bad lease request: "))?;
    let desk = desk(&state)?;
    let holder = lock(desk).revoke(writer.0.session.level, Utc::now())?;
    tracing::warn!(peer = %writer.peer(), user = %LogText(writer.user()), holder = ?holder.as_deref().map(LogText), "operator lease revoked");
    Ok(answer(desk, &writer))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BookingRequest {
    start: DateTime<Utc>,
    end: DateTime<Utc>,
}

async fn book(
    State(state): State<AppState>,
    writer: Writer,
    body: Result<Json<BookingRequest>, JsonRejection>,
) -> Result<Json<LeaseView>, AppError> {
    let Json(request) = body.map_err(AppError::body("bad booking request: "))?;
    let desk = desk(&state)?;
    let booking = lock(desk).book(
        writer.user(),
        writer.0.session.level,
        request.start,
        request.end,
        Utc::now(),
    )?;
    tracing::info!(peer = %writer.peer(), user = %LogText(writer.user()), start = %booking.start, end = %booking.end, "lab booked");
    Ok(answer(desk, &writer))
}

async fn cancel(
    State(state): State<AppState>,
    writer: Writer,
    Path(id): Path<u64>,
    body: Result<Json<Empty>, JsonRejection>,
) -> Result<Json<LeaseView>, AppError> {
    let Json(Empty {}) = body.map_err(AppError::body("bad booking request: "))?;
    let desk = desk(&state)?;
    lock(desk).cancel(writer.user(), writer.0.session.level, id)?;
    tracing::info!(peer = %writer.peer(), user = %LogText(writer.user()), id, "booking cancelled");
    Ok(answer(desk, &writer))
}
