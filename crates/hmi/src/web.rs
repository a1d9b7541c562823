//! The HTTP and WebSocket API of docs/HMI.md.
//!
//! Every `/api` route but login checks the session cookie; every POST checks the CSRF
//! header; bodies are capped at [`MAX_BODY`]; refusals (wrong password, lockout, forged
//! or missing CSRF token, unknown point, level too low, control authority elsewhere) are
//! answered with a JSON error and logged with the client's address, any text the client
//! chose escaped ([`LogText`]). Every response, errors included, carries the security
//! headers of [`harden`]; an error without a JSON body gets one.

use std::net::SocketAddr;
use std::sync::{Arc, RwLock};

use axum::body::Body;
use axum::extract::ws::{CloseFrame, Message, WebSocket, WebSocketUpgrade};
use axum::extract::{ConnectInfo, DefaultBodyLimit, Path, Query, State};
use axum::http::{header, HeaderMap, HeaderValue, StatusCode};
use axum::response::{IntoResponse, Redirect, Response};
use axum::routing::{get, post};
use axum::{Json, Router};
use chrono::{DateTime, Utc};
use serde::Deserialize;
use serde_json::{json, Value};
use station::store::{
    Actor, CommandOutcome, CommandPhase, CommandQuery, CommandRecord, Cursor, EventQuery,
    EventStore, Order, PointFilter, PointValue, TimeBasis,
};

use crate::auth::{
    constant_time_eq, LoginLimiter, LoginRefusal, Session, Sessions, SocketRefusal, Verifier,
};
use crate::link::{ControlOutcome, Station};
use crate::tls::Peer;
use crate::users::Users;
use crate::LogText;

mod files {
    include!(concat!(env!("OUT_DIR"), "/web_files.rs"));
}

/// Largest request body accepted.
pub const MAX_BODY: usize = 16 * 1024;
/// Largest WebSocket message accepted from a browser (it sends none that matter).
pub const MAX_WS_MESSAGE: usize = 4 * 1024;
const COOKIE: &str = "stanice_session";
/// The detail of the write-ahead audit record of a command, written (and committed)
/// before the command goes to the station; the outcome follows as a second record.
pub const SENT_DETAIL: &str = "sent to the station; outcome pending";
/// The Content-Security-Policy of every response: nothing but the HMI's own files.
const CSP: &str = "default-src 'self'; img-src 'self' data:; style-src 'self' 'unsafe-inline'; \
                   connect-src 'self'; object-src 'none'; base-uri 'none'; \
                   frame-ancestors 'none'; form-action 'self'";

/// What the handlers share.
#[derive(Clone)]
pub struct AppState {
    /// The station link and points.
    pub station: Arc<Station>,
    /// The users.
    pub users: Arc<RwLock<Users>>,
    /// The sessions.
    pub sessions: Arc<Sessions>,
    /// Login rate limit.
    pub limiter: Arc<LoginLimiter>,
    /// The bound on password verifications running at once.
    pub verifier: Arc<Verifier>,
    /// The HMI's event store, if any.
    pub store: Option<Arc<dyn EventStore>>,
    /// The node the HMI's audit records name (the station's common address).
    pub audit_node: String,
    /// Cookies only over HTTPS (the HMI serves TLS itself).
    pub secure_cookies: bool,
}

/// The router.
pub fn router(state: AppState) -> Router {
    Router::new()
        .route("/", get(index))
        .route("/login", get(login_page))
        .route("/static/{file}", get(static_file))
        .route("/api/login", post(login))
        .route("/api/logout", post(logout))
        .route("/api/session", get(session_info))
        .route("/api/screens", get(screens))
        .route("/api/screens/{id}", get(screen))
        .route("/api/points", get(points))
        .route("/api/controls", get(controls))
        .route("/api/command", post(command))
        .route("/api/events", get(events))
        .route("/api/alarms", get(alarms))
        .route("/api/alarms/{id}/acknowledge", post(acknowledge))
        .route("/api/alarms/{id}/shelve", post(shelve))
        .route("/api/trend", get(trend))
        .route("/api/trends", get(trends))
        .route("/api/live", get(live))
        .fallback(not_found)
        // Inner to outer: the body limit applies to the handlers; `harden` sees every
        // response, the fallback's and the extractors' rejections included.
        .layer(DefaultBodyLimit::max(MAX_BODY))
        .layer(axum::middleware::map_response(harden))
        .with_state(state)
}

/// The security headers of every response, and a JSON body for every error that has
/// none (axum's own rejections, such as 405, are plain text).
pub async fn harden(response: Response) -> Response {
    let status = response.status();
    let json = response
        .headers()
        .get(header::CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .is_some_and(|v| v.starts_with("application/json"));
    let mut response = if (status.is_client_error() || status.is_server_error()) && !json {
        let message = status
            .canonical_reason()
            .unwrap_or("error")
            .to_ascii_lowercase();
        let (mut parts, _) = response.into_parts();
        parts.headers.remove(header::CONTENT_LENGTH);
        parts.headers.insert(
            header::CONTENT_TYPE,
            HeaderValue::from_static("application/json"),
        );
        Response::from_parts(parts, Body::from(json!({"error": message}).to_string()))
    } else {
        response
    };
    let headers = response.headers_mut();
    headers.insert(
        header::X_CONTENT_TYPE_OPTIONS,
        HeaderValue::from_static("nosniff"),
    );
    headers.insert(
        header::CONTENT_SECURITY_POLICY,
        HeaderValue::from_static(CSP),
    );
    headers.insert(header::X_FRAME_OPTIONS, HeaderValue::from_static("DENY"));
    headers.insert(
        header::REFERRER_POLICY,
        HeaderValue::from_static("no-referrer"),
    );
    if !headers.contains_key(header::CACHE_CONTROL) {
        headers.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
    }
    response
}

/// An API error: status and message.
#[derive(Debug)]
pub struct ApiError(StatusCode, String);

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        (self.0, Json(json!({"error": self.1}))).into_response()
    }
}

fn error(status: StatusCode, message: impl Into<String>) -> ApiError {
    ApiError(status, message.into())
}

fn cookie_token(headers: &HeaderMap) -> Option<String> {
    headers
        .get_all(header::COOKIE)
        .iter()
        .filter_map(|v| v.to_str().ok())
        .flat_map(|v| v.split(';'))
        .filter_map(|pair| pair.trim().split_once('='))
        .find(|(name, _)| *name == COOKIE)
        .map(|(_, value)| value.to_owned())
}

fn session_cookie(secure: bool, token: &str, end: bool) -> String {
    let secure = if secure { "; Secure" } else { "" };
    let age = if end { "; Max-Age=0" } else { "" };
    format!("{COOKIE}={token}; HttpOnly; SameSite=Strict; Path=/{secure}{age}")
}

fn session(state: &AppState, headers: &HeaderMap) -> Result<Session, ApiError> {
    cookie_token(headers)
        .and_then(|token| state.sessions.get(&token))
        .ok_or_else(|| error(StatusCode::UNAUTHORIZED, "not logged in"))
}

/// The session of a state-changing request: its CSRF header must match.
fn session_for_change(
    state: &AppState,
    headers: &HeaderMap,
    peer: SocketAddr,
) -> Result<Session, ApiError> {
    let session = session(state, headers)?;
    let sent = headers
        .get("x-csrf-token")
        .and_then(|v| v.to_str().ok())
        .unwrap_or("");
    if !constant_time_eq(sent, &session.csrf) {
        tracing::warn!(%peer, user = %LogText(&session.user), "request refused: missing or forged CSRF token");
        return Err(error(StatusCode::FORBIDDEN, "missing or wrong CSRF token"));
    }
    Ok(session)
}

fn file(name: &str) -> Option<Response> {
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
}

async fn index(State(state): State<AppState>, headers: HeaderMap) -> Response {
    if session(&state, &headers).is_err() {
        return Redirect::to("/login").into_response();
    }
    file("index.html").unwrap_or_else(not_found_response)
}

async fn login_page() -> Response {
    file("login.html").unwrap_or_else(not_found_response)
}

async fn static_file(Path(name): Path<String>) -> Response {
    file(&name).unwrap_or_else(not_found_response)
}

fn not_found_response() -> Response {
    error(StatusCode::NOT_FOUND, "not found").into_response()
}

async fn not_found() -> Response {
    not_found_response()
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LoginRequest {
    username: String,
    password: String,
}

async fn login(
    State(state): State<AppState>,
    ConnectInfo(Peer(peer)): ConnectInfo<Peer>,
    body: Result<Json<LoginRequest>, axum::extract::rejection::JsonRejection>,
) -> Result<Response, ApiError> {
    let Json(request) = body.map_err(|e| error(e.status(), format!("bad login request: {e}")))?;
    let name = LogText(&request.username);
    // Checked and counted in one step, before any verification.
    let attempt = match state.limiter.begin(peer.ip(), &request.username) {
        Ok(attempt) => attempt,
        Err(LoginRefusal::TooManyFailures(wait)) => {
            tracing::warn!(%peer, user = %name, "login refused: too many failures from this address");
            let seconds = wait.as_secs().max(1);
            return Ok((
                StatusCode::TOO_MANY_REQUESTS,
                [(header::RETRY_AFTER, HeaderValue::from(seconds))],
                Json(json!({"error": "too many failed logins; try again later",
                            "retry_after_s": seconds})),
            )
                .into_response());
        }
    };
    if !attempt.delay.is_zero() {
        // The name has failed often: slowed down, but its user is not locked out.
        tokio::time::sleep(attempt.delay).await;
    }
    let wrong = || error(StatusCode::UNAUTHORIZED, "wrong user name or password");
    if !crate::users::valid_name(&request.username) {
        // No such user can exist: nothing to verify and nothing to learn from the timing.
        attempt.failed();
        tracing::warn!(%peer, user = %name, "login failed: impossible user name");
        return Err(wrong());
    }
    let users = Arc::clone(&state.users);
    let (username, password) = (request.username.clone(), request.password);
    let verified = state
        .verifier
        .run(move || {
            users
                .read()
                .unwrap_or_else(|p| p.into_inner())
                .verify(&username, &password)
        })
        .await;
    let level = match verified {
        Ok(level) => level,
        Err(busy) => {
            attempt.abandoned();
            tracing::warn!(%peer, user = %name, "login refused: verifier busy");
            return Ok((
                StatusCode::SERVICE_UNAVAILABLE,
                [(header::RETRY_AFTER, HeaderValue::from_static("1"))],
                Json(json!({"error": busy.to_string(), "retry_after_s": 1})),
            )
                .into_response());
        }
    };
    let Some(level) = level else {
        attempt.failed();
        tracing::warn!(%peer, user = %name, "login failed: wrong user name or password");
        return Err(wrong());
    };
    attempt.succeeded();
    let (token, session) = state.sessions.create(&request.username, level);
    tracing::info!(%peer, user = %name, level, "logged in");
    let cookie = session_cookie(state.secure_cookies, &token, false);
    Ok((
        [(
            header::SET_COOKIE,
            HeaderValue::from_str(&cookie)
                .map_err(|_| error(StatusCode::INTERNAL_SERVER_ERROR, "cookie"))?,
        )],
        Json(json!({"user": session.user, "level": session.level, "csrf": session.csrf})),
    )
        .into_response())
}

async fn logout(
    State(state): State<AppState>,
    ConnectInfo(Peer(peer)): ConnectInfo<Peer>,
    headers: HeaderMap,
) -> Result<Response, ApiError> {
    let session = session_for_change(&state, &headers, peer)?;
    if let Some(token) = cookie_token(&headers) {
        state.sessions.remove(&token);
    }
    tracing::info!(%peer, user = %LogText(&session.user), "logged out");
    let cookie = session_cookie(state.secure_cookies, "", true);
    Ok((
        [(
            header::SET_COOKIE,
            HeaderValue::from_str(&cookie)
                .map_err(|_| error(StatusCode::INTERNAL_SERVER_ERROR, "cookie"))?,
        )],
        Json(json!({})),
    )
        .into_response())
}

async fn session_info(
    State(state): State<AppState>,
    headers: HeaderMap,
) -> Result<Json<Value>, ApiError> {
    let session = session(&state, &headers)?;
    Ok(Json(json!({
        "user": session.user,
        "level": session.level,
        "csrf": session.csrf,
        "title": state.station.config().title,
    })))
}

async fn screens(
    State(state): State<AppState>,
    headers: HeaderMap,
) -> Result<Json<Value>, ApiError> {
    session(&state, &headers)?;
    let list: Vec<Value> = state
        .station
        .config()
        .screens
        .iter()
        .map(|s| json!({"id": s.id, "title": s.title}))
        .collect();
    Ok(Json(json!(list)))
}

async fn screen(
    State(state): State<AppState>,
    headers: HeaderMap,
    Path(id): Path<String>,
) -> Result<Response, ApiError> {
    session(&state, &headers)?;
    let config = state.station.config();
    let screen = config
        .screens
        .iter()
        .find(|s| s.id == id)
        .ok_or_else(|| error(StatusCode::NOT_FOUND, format!("no screen `{id}`")))?;
    let svg = tokio::fs::read_to_string(config.folder.join(&screen.file))
        .await
        .map_err(|e| {
            error(
                StatusCode::INTERNAL_SERVER_ERROR,
                format!("screen `{id}`: {e}"),
            )
        })?;
    Ok((
        [(
            header::CONTENT_TYPE,
            HeaderValue::from_static("image/svg+xml"),
        )],
        svg,
    )
        .into_response())
}

async fn points(
    State(state): State<AppState>,
    headers: HeaderMap,
) -> Result<Json<Value>, ApiError> {
    session(&state, &headers)?;
    Ok(Json(
        json!({"link": state.station.link_json(), "points": state.station.points()}),
    ))
}

async fn controls(
    State(state): State<AppState>,
    headers: HeaderMap,
) -> Result<Json<Value>, ApiError> {
    let session = session(&state, &headers)?;
    let config = state.station.config();
    let list: Vec<Value> = config
        .points
        .iter()
        .filter(|p| p.type_id.is_command())
        .map(|p| {
            let control = config.control(&p.name);
            json!({
                "command": p.name,
                "ioa": p.ioa,
                "type": p.type_id.to_string(),
                "description": p.description,
                "level": control.level,
                "select": control.select,
                "confirm": control.confirm,
                "allowed": session.level >= control.level,
            })
        })
        .collect();
    Ok(Json(json!(list)))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CommandRequest {
    command: String,
    value: Value,
}

async fn command(
    State(state): State<AppState>,
    ConnectInfo(Peer(peer)): ConnectInfo<Peer>,
    headers: HeaderMap,
    body: Result<Json<CommandRequest>, axum::extract::rejection::JsonRejection>,
) -> Result<Response, ApiError> {
    let session = session_for_change(&state, &headers, peer)?;
    let Json(request) = body.map_err(|e| error(e.status(), format!("bad command request: {e}")))?;
    let config = state.station.config();
    let Some(row) = config
        .points
        .iter()
        .find(|p| p.name == request.command && p.type_id.is_command())
    else {
        tracing::warn!(%peer, user = %LogText(&session.user), command = %LogText(&request.command), "unknown command refused");
        return Err(error(
            StatusCode::NOT_FOUND,
            format!("no command `{}`", request.command),
        ));
    };
    let value = match &request.value {
        Value::Bool(b) => f64::from(u8::from(*b)),
        Value::Number(n) => n
            .as_f64()
            .filter(|v| v.is_finite())
            .ok_or_else(|| error(StatusCode::BAD_REQUEST, "value is not a finite number"))?,
        _ => {
            return Err(error(
                StatusCode::BAD_REQUEST,
                "value must be a boolean or a number",
            ))
        }
    };
    let control = config.control(&row.name);
    if session.level < control.level {
        let detail = format!("level {} needed, user has {}", control.level, session.level);
        state.station.audit(
            &session.user,
            &row.name,
            row.ioa,
            value,
            ControlOutcome::RefusedPermission,
            &detail,
        );
        return Ok((
            StatusCode::FORBIDDEN,
            Json(json!({"outcome": ControlOutcome::RefusedPermission, "detail": detail})),
        )
            .into_response());
    }
    if let Some(authority) = &control.authority {
        let point = state.station.point(&authority.point);
        let held = point
            .as_ref()
            .is_some_and(|p| !p.invalid && p.value == json!(authority.state));
        if !held {
            let now = match &point {
                Some(p) if !p.invalid => p.value.to_string(),
                _ => "unknown (invalid)".to_owned(),
            };
            let detail = format!(
                "the control authority is not with this HMI ({} is {now}, {} needed)",
                authority.point, authority.state
            );
            tracing::warn!(%peer, user = %LogText(&session.user), command = %row.name, "control refused: no control authority");
            state.station.audit(
                &session.user,
                &row.name,
                row.ioa,
                value,
                ControlOutcome::RefusedAuthority,
                &detail,
            );
            state.station.recorder().flush().await;
            return Ok((
                StatusCode::CONFLICT,
                Json(json!({"outcome": ControlOutcome::RefusedAuthority, "detail": detail})),
            )
                .into_response());
        }
    }
    // Write-ahead: the attempt is committed to the store before the command leaves, so
    // a command the station carried out is in the audit even if the HMI dies meanwhile.
    if let Some(store) = &state.store {
        let sent = CommandRecord {
            id: None,
            time: Utc::now(),
            actor: Actor::User(session.user.clone()),
            node: state.audit_node.clone(),
            point: row.name.clone(),
            ioa: Some(row.ioa),
            value: PointValue::Float(value),
            phase: CommandPhase::Execute,
            outcome: CommandOutcome::Failed,
            detail: SENT_DETAIL.to_owned(),
        };
        if let Err(e) = store.append_command(&sent).await {
            tracing::error!(error = %e, command = %row.name, "command not sent: its audit record cannot be written");
            return Err(error(
                StatusCode::SERVICE_UNAVAILABLE,
                "the audit record cannot be written; the command was not sent",
            ));
        }
    }
    let (outcome, detail) = state.station.operate(&session.user, &row.name, value).await;
    // The outcome's record is committed before the user hears of it.
    state.station.recorder().flush().await;
    Ok(Json(json!({"outcome": outcome, "detail": detail})).into_response())
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
fn parse_cursor(text: &str) -> Result<(Option<Cursor>, Option<Cursor>, bool, bool), ApiError> {
    let bad = || error(StatusCode::BAD_REQUEST, "bad cursor");
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
    headers: HeaderMap,
    query: Result<Query<EventsQuery>, axum::extract::rejection::QueryRejection>,
) -> Result<Json<Value>, ApiError> {
    session(&state, &headers)?;
    let Query(query) = query.map_err(|e| error(StatusCode::BAD_REQUEST, e.to_string()))?;
    let store = state
        .store
        .clone()
        .ok_or_else(|| error(StatusCode::SERVICE_UNAVAILABLE, "no event store"))?;
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
        let page = store
            .query_events(&q)
            .await
            .map_err(|e| error(StatusCode::BAD_REQUEST, e.to_string()))?;
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
        let page = store
            .query_commands(&q)
            .await
            .map_err(|e| error(StatusCode::BAD_REQUEST, e.to_string()))?;
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

fn crate_value(value: &station::store::PointValue) -> Value {
    use station::store::PointValue;
    match value {
        PointValue::Bool(b) => json!(b),
        PointValue::DoublePoint(d) => json!(d),
        PointValue::Int(i) => json!(i),
        PointValue::Float(f) => json!(f),
        PointValue::Bits(b) => json!(b),
        PointValue::Text(t) => json!(t),
    }
}

/// Level 0 is read-only: it sees everything and changes nothing, alarms included.
fn read_only_refused(session: &Session, peer: SocketAddr) -> Result<(), ApiError> {
    if session.level == 0 {
        tracing::warn!(%peer, user = %LogText(&session.user), "read-only user refused an alarm change");
        return Err(error(
            StatusCode::FORBIDDEN,
            "read-only users cannot change alarms",
        ));
    }
    Ok(())
}

async fn alarms(
    State(state): State<AppState>,
    headers: HeaderMap,
) -> Result<Json<Value>, ApiError> {
    session(&state, &headers)?;
    Ok(Json(json!(state.station.alarms())))
}

async fn acknowledge(
    State(state): State<AppState>,
    ConnectInfo(Peer(peer)): ConnectInfo<Peer>,
    headers: HeaderMap,
    Path(id): Path<usize>,
) -> Result<Json<Value>, ApiError> {
    let session = session_for_change(&state, &headers, peer)?;
    read_only_refused(&session, peer)?;
    let alarm = state
        .station
        .acknowledge(id, &session.user)
        .ok_or_else(|| error(StatusCode::NOT_FOUND, "no such alarm"))?;
    Ok(Json(json!(alarm)))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ShelveRequest {
    minutes: u32,
}

async fn shelve(
    State(state): State<AppState>,
    ConnectInfo(Peer(peer)): ConnectInfo<Peer>,
    headers: HeaderMap,
    Path(id): Path<usize>,
    body: Result<Json<ShelveRequest>, axum::extract::rejection::JsonRejection>,
) -> Result<Json<Value>, ApiError> {
    let session = session_for_change(&state, &headers, peer)?;
    read_only_refused(&session, peer)?;
    let Json(request) = body.map_err(|e| error(e.status(), e.to_string()))?;
    let alarm = state
        .station
        .shelve(id, request.minutes.min(7 * 24 * 60), &session.user)
        .ok_or_else(|| error(StatusCode::NOT_FOUND, "no such alarm"))?;
    Ok(Json(json!(alarm)))
}

async fn trends(
    State(state): State<AppState>,
    headers: HeaderMap,
) -> Result<Json<Value>, ApiError> {
    session(&state, &headers)?;
    let config = state.station.config();
    let list: Vec<Value> = config
        .trends
        .iter()
        .filter_map(|name| config.points.iter().find(|p| &p.name == name))
        .map(|p| json!({"point": p.name, "description": p.description}))
        .collect();
    Ok(Json(json!(list)))
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
    headers: HeaderMap,
    query: Result<Query<TrendQuery>, axum::extract::rejection::QueryRejection>,
) -> Result<Json<Value>, ApiError> {
    session(&state, &headers)?;
    let Query(query) = query.map_err(|e| error(StatusCode::BAD_REQUEST, e.to_string()))?;
    if state.station.point(&query.point).is_none() {
        return Err(error(
            StatusCode::NOT_FOUND,
            format!("no point `{}`", query.point),
        ));
    }
    let store = state
        .store
        .clone()
        .ok_or_else(|| error(StatusCode::SERVICE_UNAVAILABLE, "no event store"))?;
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
            .await
            .map_err(|e| error(StatusCode::BAD_REQUEST, e.to_string()))?;
        for e in &page.items {
            let value = match &e.value {
                station::store::PointValue::Float(f) => *f,
                station::store::PointValue::Int(i) => *i as f64,
                station::store::PointValue::Bool(b) => f64::from(u8::from(*b)),
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

/// Whether a WebSocket upgrade comes from a page of this HMI. Browsers always send
/// `Origin` with a WebSocket (a page elsewhere cannot hide it, and the session cookie
/// would otherwise ride along: cross-site WebSocket hijacking); clients that are no
/// browser send none and carry no ambient cookie, so they are let through.
fn same_origin(headers: &HeaderMap) -> bool {
    let Some(origin) = headers.get(header::ORIGIN) else {
        return true;
    };
    let host = headers.get(header::HOST).and_then(|v| v.to_str().ok());
    let authority = origin.to_str().ok().and_then(|origin| {
        origin
            .strip_prefix("https://")
            .or_else(|| origin.strip_prefix("http://"))
    });
    matches!((authority, host), (Some(a), Some(h)) if a.eq_ignore_ascii_case(h))
}

async fn live(
    State(state): State<AppState>,
    ConnectInfo(Peer(peer)): ConnectInfo<Peer>,
    headers: HeaderMap,
    upgrade: WebSocketUpgrade,
) -> Result<Response, ApiError> {
    if !same_origin(&headers) {
        let origin = headers
            .get(header::ORIGIN)
            .map(|v| String::from_utf8_lossy(v.as_bytes()).into_owned())
            .unwrap_or_default();
        tracing::warn!(%peer, origin = %LogText(&origin), "WebSocket refused: foreign origin");
        return Err(error(StatusCode::FORBIDDEN, "foreign origin"));
    }
    let session = session(&state, &headers)?;
    let token = cookie_token(&headers).unwrap_or_default();
    let ended = state.sessions.open_socket(&token).map_err(|refusal| {
        tracing::warn!(%peer, user = %LogText(&session.user), %refusal, "WebSocket refused");
        match refusal {
            SocketRefusal::NoSession => error(StatusCode::UNAUTHORIZED, refusal.to_string()),
            SocketRefusal::TooMany => error(StatusCode::TOO_MANY_REQUESTS, refusal.to_string()),
        }
    })?;
    Ok(upgrade
        .max_message_size(MAX_WS_MESSAGE)
        .on_upgrade(move |socket| stream(socket, state, ended)))
}

/// Feeds one browser until it goes away or its session ends (`ended` then reports an
/// error: the session's sender is gone).
async fn stream(
    mut socket: WebSocket,
    state: AppState,
    mut ended: tokio::sync::watch::Receiver<()>,
) {
    // Subscribe before the snapshot, so nothing falls between them.
    let mut updates = state.station.subscribe();
    let snapshot = json!({
        "type": "snapshot",
        "link": state.station.link_json(),
        "points": state.station.points(),
        "alarms": state.station.alarms(),
    });
    if socket
        .send(Message::Text(snapshot.to_string().into()))
        .await
        .is_err()
    {
        return;
    }
    loop {
        tokio::select! {
            update = updates.recv() => match update {
                Ok(text) => {
                    if socket.send(Message::Text(text.into())).await.is_err() {
                        return;
                    }
                }
                Err(tokio::sync::broadcast::error::RecvError::Lagged(_)) => {
                    // Too slow a browser: start it over from a fresh snapshot.
                    let snapshot = json!({"type": "snapshot", "link": state.station.link_json(),
                                          "points": state.station.points(), "alarms": state.station.alarms()});
                    if socket.send(Message::Text(snapshot.to_string().into())).await.is_err() {
                        return;
                    }
                }
                Err(_) => return,
            },
            _ = ended.changed() => {
                let close = CloseFrame { code: 4001, reason: "session ended".into() };
                let _ = socket.send(Message::Close(Some(close))).await;
                return;
            }
            incoming = socket.recv() => match incoming {
                Some(Ok(Message::Close(_))) | None | Some(Err(_)) => return,
                Some(Ok(_)) => {}
            },
        }
    }
}
