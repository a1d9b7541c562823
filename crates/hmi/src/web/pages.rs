//! The pages and their static files (embedded from `web/`), and the mimic screens.

use axum::extract::{Path, State};
use axum::http::{header, HeaderMap, HeaderValue, StatusCode};
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

/// An embedded file of `web/`, revalidated on each use (`no-cache`) by its entity tag: a
/// reload answers 304 and the browser keeps its copy (and V8 its compiled scripts).
fn file(name: &str, headers: &HeaderMap) -> Result<Response, AppError> {
    let (_, mime, bytes, tag) = files::FILES
        .iter()
        .find(|(n, _, _, _)| *n == name)
        .ok_or(AppError::NotFound)?;
    let tag_header = HeaderValue::from_static(tag);
    let unchanged = headers
        .get(header::IF_NONE_MATCH)
        .and_then(|value| value.to_str().ok())
        .is_some_and(|value| {
            value
                .split(',')
                .any(|t| t.trim() == *tag || t.trim() == "*")
        });
    let cache = [
        (header::CACHE_CONTROL, HeaderValue::from_static("no-cache")),
        (header::ETAG, tag_header),
    ];
    if unchanged {
        return Ok((StatusCode::NOT_MODIFIED, cache).into_response());
    }
    Ok((
        [(header::CONTENT_TYPE, HeaderValue::from_static(mime))],
        cache,
        *bytes,
    )
        .into_response())
}

/// The application, or the login page for a browser without a session.
async fn index(user: Result<LoggedIn, AppError>, headers: HeaderMap) -> Result<Response, AppError> {
    if user.is_err() {
        return Ok(Redirect::to("/login").into_response());
    }
    file("index.html", &headers)
}

async fn login_page(headers: HeaderMap) -> Result<Response, AppError> {
    file("login.html", &headers)
}

async fn static_file(Path(name): Path<String>, headers: HeaderMap) -> Result<Response, AppError> {
    file(&name, &headers)
}

/// The public information pages: the screens folder's `public/`, served to anyone, apart
/// from the authenticated HMI (the sorting-lab thesis, section 11: anonymous pages lived
/// on another server so as not to weaken the HMI's).
pub(super) fn public_routes() -> Router<AppState> {
    Router::new()
        .route("/public", get(|| async { Redirect::permanent("/public/") }))
        .route("/public/", get(public_index))
        .route("/public/{file}", get(public_file))
}

async fn public_index(State(state): State<AppState>) -> Result<Response, AppError> {
    public_file(State(state), Path("index.html".to_owned())).await
}

async fn public_file(
    State(state): State<AppState>,
    Path(name): Path<String>,
) -> Result<Response, AppError> {
    // One plain file name of a known kind: no directories, no hidden files.
    let mime = match name
        .rsplit_once('.')
        .map(|(_, ext)| ext.to_ascii_lowercase())
    {
        Some(ext) if ext == "html" => "text/html; charset=utf-8",
        Some(ext) if ext == "css" => "text/css; charset=utf-8",
        Some(ext) if ext == "txt" => "text/plain; charset=utf-8",
        Some(ext) if ext == "png" => "image/png",
        Some(ext) if ext == "jpg" || ext == "jpeg" => "image/jpeg",
        Some(ext) if ext == "svg" => "image/svg+xml",
        _ => return Err(AppError::NotFound),
    };
    let plain = !name.starts_with('.')
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '.' | '-' | '_'));
    if !plain {
        return Err(AppError::NotFound);
    }
    let path = state.station.config().folder.join("public").join(&name);
    let bytes = tokio::fs::read(&path)
        .await
        .map_err(|_| AppError::NotFound)?;
    Ok((
        [
            (header::CONTENT_TYPE, HeaderValue::from_static(mime)),
            (header::CACHE_CONTROL, HeaderValue::from_static("no-cache")),
        ],
        bytes,
    )
        .into_response())
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
    let path = config.folder.join(&screen.file);
    let text = tokio::fs::read_to_string(&path)
        .await
        .map_err(|source| AppError::ScreenFile {
            id: id.clone(),
            source,
        })?;
    // Read from the file at every request (an edited screen shows on reload), checked
    // and made safe here, once, rather than in every browser (mimic-svg): the page puts
    // the markup in with its HTML parser, without a second pass over 10,000 elements.
    let svg = mimic_svg::clean(&text).map_err(|source| AppError::ScreenInvalid {
        id: id.clone(),
        file: path.display().to_string(),
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
