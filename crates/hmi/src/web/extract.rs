//! Who is asking: the extractors every `/api` handler but login takes. A handler that
//! needs a user names one of them among its arguments, so it cannot forget the check:
//!
//! - [`LoggedIn`]: a live session (the reads; level 0 suffices);
//! - [`Writer`]: a live session whose state-changing request echoes its CSRF token in
//!   `X-CSRF-Token`; [`Writer::require_level`] checks a control's level;
//! - [`Operator`]: a [`Writer`] above the read-only level 0 (alarm changes);
//! - [`SameOrigin`]: a WebSocket upgrade from a page of this HMI.
//!
//! Refusals are [`AppError`]s, logged with the client's address; the session token and
//! the CSRF token never reach the logs (`skip_all`).

use std::net::SocketAddr;

use axum::extract::{ConnectInfo, FromRequestParts};
use axum::http::request::Parts;
use axum::http::{header, HeaderMap};

use super::{AppError, AppState, COOKIE};
use crate::auth::{constant_time_eq, Session};
use crate::tls::Peer;
use crate::LogText;

/// The token of the session cookie, if the request has one.
pub(super) fn cookie_token(headers: &HeaderMap) -> Option<String> {
    headers
        .get_all(header::COOKIE)
        .iter()
        .filter_map(|v| v.to_str().ok())
        .flat_map(|v| v.split(';'))
        .filter_map(|pair| pair.trim().split_once('='))
        .find(|(name, _)| *name == COOKIE)
        .map(|(_, value)| value.to_owned())
}

async fn peer(parts: &mut Parts, state: &AppState) -> Result<SocketAddr, AppError> {
    let ConnectInfo(Peer(peer)) = ConnectInfo::<Peer>::from_request_parts(parts, state)
        .await
        .map_err(|_| AppError::NoPeer)?;
    Ok(peer)
}

/// A request of a logged-in user (its session is refreshed by it).
#[derive(Debug, Clone)]
pub struct LoggedIn {
    /// The session.
    pub session: Session,
    /// The session's token (the cookie's value).
    pub(super) token: String,
    /// The client's address.
    pub peer: SocketAddr,
}

impl FromRequestParts<AppState> for LoggedIn {
    type Rejection = AppError;

    #[tracing::instrument(name = "logged_in", skip_all)]
    async fn from_request_parts(parts: &mut Parts, state: &AppState) -> Result<Self, AppError> {
        let peer = peer(parts, state).await?;
        let token = cookie_token(&parts.headers).ok_or(AppError::NotLoggedIn)?;
        let session = state.sessions.get(&token).ok_or(AppError::NotLoggedIn)?;
        Ok(LoggedIn {
            session,
            token,
            peer,
        })
    }
}

/// A state-changing request of a logged-in user, with its session's CSRF token.
#[derive(Debug, Clone)]
pub struct Writer(pub LoggedIn);

impl Writer {
    /// The user's name.
    pub fn user(&self) -> &str {
        &self.0.session.user
    }

    /// The client's address.
    pub fn peer(&self) -> SocketAddr {
        self.0.peer
    }

    /// Whether the user's level reaches `needed` (a control's level); the refusal is
    /// [`AppError::LevelTooLow`], which the caller audits before returning it.
    pub fn require_level(&self, needed: u8) -> Result<(), AppError> {
        let has = self.0.session.level;
        if has < needed {
            tracing::warn!(peer = %self.0.peer, user = %LogText(self.user()), needed, has, "refused: level too low");
            return Err(AppError::LevelTooLow { needed, has });
        }
        Ok(())
    }
}

impl FromRequestParts<AppState> for Writer {
    type Rejection = AppError;

    #[tracing::instrument(name = "writer", skip_all)]
    async fn from_request_parts(parts: &mut Parts, state: &AppState) -> Result<Self, AppError> {
        let user = LoggedIn::from_request_parts(parts, state).await?;
        let sent = parts
            .headers
            .get("x-csrf-token")
            .and_then(|v| v.to_str().ok())
            .unwrap_or("");
        if !constant_time_eq(sent, &user.session.csrf) {
            tracing::warn!(peer = %user.peer, user = %LogText(&user.session.user), "request refused: missing or forged CSRF token");
            return Err(AppError::Csrf);
        }
        Ok(Writer(user))
    }
}

/// A [`Writer`] who is not read-only: level 0 sees everything and changes nothing.
#[derive(Debug, Clone)]
pub struct Operator(pub Writer);

impl Operator {
    /// The user's name.
    pub fn user(&self) -> &str {
        self.0.user()
    }
}

impl FromRequestParts<AppState> for Operator {
    type Rejection = AppError;

    #[tracing::instrument(name = "operator", skip_all)]
    async fn from_request_parts(parts: &mut Parts, state: &AppState) -> Result<Self, AppError> {
        let writer = Writer::from_request_parts(parts, state).await?;
        if writer.0.session.level == 0 {
            tracing::warn!(peer = %writer.peer(), user = %LogText(writer.user()), "read-only user refused a change");
            return Err(AppError::ReadOnly);
        }
        Ok(Operator(writer))
    }
}

/// A WebSocket upgrade from a page of this HMI. Browsers always send `Origin` with a
/// WebSocket (a page elsewhere cannot hide it, and the session cookie would otherwise
/// ride along: cross-site WebSocket hijacking); clients that are no browser send none and
/// carry no ambient cookie, so they are let through.
#[derive(Debug, Clone, Copy)]
pub struct SameOrigin;

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

impl FromRequestParts<AppState> for SameOrigin {
    type Rejection = AppError;

    async fn from_request_parts(parts: &mut Parts, state: &AppState) -> Result<Self, AppError> {
        if same_origin(&parts.headers) {
            return Ok(SameOrigin);
        }
        let peer = peer(parts, state).await?;
        let origin = parts
            .headers
            .get(header::ORIGIN)
            .map(|v| String::from_utf8_lossy(v.as_bytes()).into_owned())
            .unwrap_or_default();
        tracing::warn!(%peer, origin = %LogText(&origin), "WebSocket refused: foreign origin");
        Err(AppError::ForeignOrigin)
    }
}
