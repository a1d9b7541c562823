//! Logging in and out, and the session's own facts.

use std::sync::Arc;

use axum::extract::rejection::JsonRejection;
use axum::extract::{ConnectInfo, State};
use axum::http::{header, HeaderValue};
use axum::response::IntoResponse;
use axum::routing::{get, post};
use axum::{Json, Router};
use serde::Deserialize;
use serde_json::{json, Value};

use super::{AppError, AppState, LoggedIn, Writer, COOKIE};
use crate::auth::LoginRefusal;
use crate::tls::Peer;
use crate::LogText;

pub(super) fn routes() -> Router<AppState> {
    Router::new()
        .route("/api/login", post(login))
        .route("/api/logout", post(logout))
        .route("/api/session", get(session_info))
}

fn session_cookie(secure: bool, token: &str, end: bool) -> Result<HeaderValue, AppError> {
    let secure = if secure { "; Secure" } else { "" };
    let age = if end { "; Max-Age=0" } else { "" };
    HeaderValue::from_str(&format!(
        "{COOKIE}={token}; HttpOnly; SameSite=Strict; Path=/{secure}{age}"
    ))
    .map_err(|_| AppError::Cookie)
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
    body: Result<Json<LoginRequest>, JsonRejection>,
) -> Result<impl IntoResponse, AppError> {
    let Json(request) = body.map_err(AppError::body("bad login request: "))?;
    let name = LogText(&request.username);
    // Checked and counted in one step, before any verification.
    let attempt = match state.limiter.begin(peer.ip(), &request.username) {
        Ok(attempt) => attempt,
        Err(LoginRefusal::TooManyFailures(wait)) => {
            tracing::warn!(%peer, user = %name, "login refused: too many failures from this address");
            return Err(AppError::TooManyLogins(wait.as_secs().max(1)));
        }
    };
    if !attempt.delay.is_zero() {
        // The name has failed often: slowed down, but its user is not locked out.
        tokio::time::sleep(attempt.delay).await;
    }
    if !crate::users::valid_name(&request.username) {
        // No such user can exist: nothing to verify and nothing to learn from the timing.
        attempt.failed();
        tracing::warn!(%peer, user = %name, "login failed: impossible user name");
        return Err(AppError::WrongLogin);
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
            return Err(busy.into());
        }
    };
    let Some(level) = level else {
        attempt.failed();
        tracing::warn!(%peer, user = %name, "login failed: wrong user name or password");
        return Err(AppError::WrongLogin);
    };
    attempt.succeeded();
    let (token, session) = state.sessions.create(&request.username, level);
    tracing::info!(%peer, user = %name, level, "logged in");
    Ok((
        [(
            header::SET_COOKIE,
            session_cookie(state.secure_cookies, &token, false)?,
        )],
        Json(json!({"user": session.user, "level": session.level, "csrf": session.csrf})),
    ))
}

async fn logout(
    State(state): State<AppState>,
    writer: Writer,
) -> Result<impl IntoResponse, AppError> {
    state.sessions.remove(&writer.0.token);
    tracing::info!(peer = %writer.peer(), user = %LogText(writer.user()), "logged out");
    Ok((
        [(
            header::SET_COOKIE,
            session_cookie(state.secure_cookies, "", true)?,
        )],
        Json(json!({})),
    ))
}

async fn session_info(State(state): State<AppState>, user: LoggedIn) -> Json<Value> {
    let start = state
        .users
        .read()
        .unwrap_or_else(|p| p.into_inner())
        .start(&user.session.user)
        .map(str::to_owned);
    Json(json!({
        "user": user.session.user,
        "start": start,
        "level": user.session.level,
        "csrf": user.session.csrf,
        "title": state.station.config().title,
        "camera": state.station.config().camera,
        "lease": state.lease.is_some(),
        "program": state.trial.is_some() && state.station.config().program.is_some(),
        "program_live": state.trial.as_ref().is_some_and(|trial| trial.live())
            && state.station.config().program.is_some(),
        "public": state.station.config().folder.join("public").join("index.html").exists(),
    }))
}
