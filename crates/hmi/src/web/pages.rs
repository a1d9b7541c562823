//! The pages and their static files (embedded from `web/`), and the mimic screens.

use axum::extract::{Path, State};
use axum::http::{header, HeaderValue};
use axum::response::{IntoResponse, Redirect, Response};
use axum::routing::get;
use axum::{Json, Router};
use serde_json::{json, Value};

use super::{AppError, AppState, LoggedIn};

mod files {
    include!(concat!(env!("OUT_DIR"), "/web_files.rs"));
}

pub(super) fn routes() -> Router<AppState> {
    Router::new()
        .route("/", get(index))
        .route("/login", get(login_page))
        .route("/static/{file}", get(static_file))
        .route("/api/screens", get(screens))
        .route("/api/screens/{id}", get(screen))
}

/// An embedded file of `web/`, revalidated on each use (`no-cache`).
fn file(name: &str) -> Result<Response, AppError> {
    files::FILES
        .iter()
        .find(|(n, _, _)| *n == name)
        .map(|(_, mime, bytes)| {
            (
                [
                    (header::CONTENT_TYPE, HeaderValue::from_static(mime)),
                    (header::CACHE_CONTROL, HeaderValue::from_static("no-cache")),
                ],
                *bytes,
            )
                .into_response()
        })
        .ok_or(AppError::NotFound)
}

/// The application, or the login page for a browser without a session.
async fn index(user: Result<LoggedIn, AppError>) -> Result<Response, AppError> {
    if user.is_err() {
        return Ok(Redirect::to("/login").into_response());
    }
    file("index.html")
}

async fn login_page() -> Result<Response, AppError> {
    file("login.html")
}

async fn static_file(Path(name): Path<String>) -> Result<Response, AppError> {
    file(&name)
}

async fn screens(State(state): State<AppState>, _: LoggedIn) -> Json<Value> {
    let list: Vec<Value> = state
        .station
        .config()
        .screens
        .iter()
        .map(|s| json!({"id": s.id, "title": s.title}))
        .collect();
    Json(json!(list))
}

async fn screen(
    State(state): State<AppState>,
    _: LoggedIn,
    Path(id): Path<String>,
) -> Result<impl IntoResponse, AppError> {
    let config = state.station.config();
    let screen = config
        .screens
        .iter()
        .find(|s| s.id == id)
        .ok_or_else(|| AppError::NoScreen(id.clone()))?;
    let svg = tokio::fs::read_to_string(config.folder.join(&screen.file))
        .await
        .map_err(|source| AppError::ScreenFile {
            id: id.clone(),
            source,
        })?;
    Ok((
        [(
            header::CONTENT_TYPE,
            HeaderValue::from_static("image/svg+xml"),
        )],
        svg,
    ))
}
