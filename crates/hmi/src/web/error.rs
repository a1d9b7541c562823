//! [`AppError`]: every refusal and failure of the HTTP API, each variant with its status.

use axum::extract::rejection::{JsonRejection, QueryRejection};
use axum::http::{header, HeaderValue, StatusCode};
use axum::response::{IntoResponse, Response};
use axum::Json;
use serde_json::json;

use crate::auth::{SocketRefusal, VerifierBusy};
use crate::link::ControlOutcome;

/// Why a request was refused or failed. The body is `{"error": "<the Display text>"}`
/// unless a variant says otherwise; [`AppError::status`] is the status of each.
#[derive(Debug, thiserror::Error)]
pub enum AppError {
    /// 401: no session cookie, or its session has ended.
    #[error("not logged in")]
    NotLoggedIn,
    /// 401: the login's user name or password is wrong (which, is not told).
    #[error("wrong user name or password")]
    WrongLogin,
    /// 403: a state-changing request without its session's CSRF token.
    #[error("missing or wrong CSRF token")]
    Csrf,
    /// 403: a read-only user (level 0) tried to change an alarm.
    #[error("read-only users cannot change alarms")]
    ReadOnly,
    /// 403: a WebSocket from a page of another origin.
    #[error("foreign origin")]
    ForeignOrigin,
    /// 403, body `{"outcome": "refused-permission", "detail"}`: the user's level is below
    /// the control's.
    #[error("level {needed} needed, user has {has}")]
    LevelTooLow {
        /// The control's level.
        needed: u8,
        /// The user's.
        has: u8,
    },
    /// 409, body `{"outcome": "refused-authority", "detail"}`: the control authority is
    /// not with this HMI (the detail says where it is).
    #[error("{0}")]
    NoAuthority(String),
    /// The operator lease's refusal: 403 for a level too low, 404 for an unknown
    /// booking, 500 when the bookings cannot be saved, else 409 (held, booked, not
    /// holding it, a bad booking).
    #[error("{0}")]
    Lease(#[from] crate::lease::LeaseRefusal),
    /// 404: no program trial here (no `[program]` in hmi.toml, or the application
    /// offers none).
    #[error("this HMI tries no programs (no [program] in hmi.toml)")]
    NoTrial,
    /// 404: programs are tried on a simulation only here ([`crate::trial::NOT_LIVE`]).
    #[error("{}", crate::trial::NOT_LIVE)]
    NotLive,
    /// 500: the trial failed (not the program: the program's own faults are its report).
    #[error("the trial failed: {0}")]
    Trial(String),
    /// 404: no `[[choice]]` with this id.
    #[error("no choice `{0}`")]
    NoChoice(String),
    /// 409: a combination the choice forbids, in its own words; nothing was sent.
    #[error("{0}")]
    Combination(String),
    /// 404: the screens folder has no `[lease]`.
    #[error("this HMI has no operator lease (no [lease] in hmi.toml)")]
    NoLease,
    /// 403: the user's level is below the level of a lift screen element
    /// (`[lift_levels]` of hmi.toml).
    #[error("the {element} needs level {needed}, user has {has}")]
    ElementLevel {
        /// The element (`export`, `figures`, ...).
        element: &'static str,
        /// Its level.
        needed: u8,
        /// The user's.
        has: u8,
    },
    /// 404: the HMI runs without the station's store: no lift fault archive or figures.
    #[error("no archive: the HMI was started without the station's store")]
    NoArchive,
    /// 404: no lift of this name in hmi.toml.
    #[error("no lift `{0}`")]
    NoLift(String),
    /// 400: a query parameter that is not what it should be.
    #[error("bad parameter `{name}`: {message}")]
    BadParameter {
        /// The parameter.
        name: &'static str,
        /// What is wrong with it.
        message: String,
    },
    /// 404: no such route or file.
    #[error("not found")]
    NotFound,
    /// 404: no screen with this id.
    #[error("no screen `{0}`")]
    NoScreen(String),
    /// 404: no command point of this name.
    #[error("no command `{0}`")]
    NoCommand(String),
    /// 404: no point of this name.
    #[error("no point `{0}`")]
    NoPoint(String),
    /// 404: no alarm with this id.
    #[error("no such alarm")]
    NoAlarm,
    /// The JSON body was refused, with the rejection's own status (400 malformed, 413
    /// too large, 415 not JSON, 422 wrong fields); `context` starts the message.
    #[error("{context}{rejection}")]
    Body {
        /// What the body was for (`"bad login request: "`), or empty.
        context: &'static str,
        /// Why it was refused.
        rejection: JsonRejection,
    },
    /// 400: the query string was refused.
    #[error("{0}")]
    Query(#[from] QueryRejection),
    /// 400: an event list cursor this server did not hand out.
    #[error("bad cursor")]
    BadCursor,
    /// 400: a command value that is neither a boolean nor a finite number.
    #[error("{0}")]
    BadValue(&'static str),
    /// 400: the event store refused the query.
    #[error("{0}")]
    Store(#[from] store::StoreError),
    /// 429, with `Retry-After` and `retry_after_s`: too many failed logins from this
    /// address; it must wait this many seconds.
    #[error("too many failed logins; try again later")]
    TooManyLogins(u64),
    /// 401 (the session ended) or 429 (too many sockets): no WebSocket for this session.
    #[error("{0}")]
    Socket(SocketRefusal),
    /// 503, with `Retry-After: 1` and `retry_after_s`: every password verification slot
    /// is taken.
    #[error("{0}")]
    Busy(#[from] VerifierBusy),
    /// 503: the HMI runs without an event store.
    #[error("no event store")]
    NoStore,
    /// 503: the write-ahead audit record of a command could not be written, so the
    /// command was not sent.
    #[error("the audit record cannot be written; the command was not sent")]
    AuditUnavailable,
    /// 500: a screen's SVG file could not be read.
    #[error("screen `{id}`: {source}")]
    ScreenFile {
        /// The screen.
        id: String,
        /// Why.
        source: std::io::Error,
    },
    /// 500: a screen's SVG file is not well-formed (edited since the HMI started).
    #[error("screen `{id}`, file {file}: {source}")]
    ScreenInvalid {
        /// The screen.
        id: String,
        /// Its file.
        file: String,
        /// Where and why.
        source: mimic_svg::SvgError,
    },
    /// 500: the session cookie could not be made into a header.
    #[error("cookie")]
    Cookie,
    /// 500: the server was started without the client's address (no `ConnectInfo`).
    #[error("no client address")]
    NoPeer,
}

impl AppError {
    /// The HTTP status of the error.
    pub fn status(&self) -> StatusCode {
        match self {
            AppError::NotLoggedIn | AppError::WrongLogin => StatusCode::UNAUTHORIZED,
            AppError::Csrf
            | AppError::ReadOnly
            | AppError::ForeignOrigin
            | AppError::LevelTooLow { .. }
            | AppError::ElementLevel { .. } => StatusCode::FORBIDDEN,
            AppError::NoAuthority(_) => StatusCode::CONFLICT,
            AppError::Lease(refusal) => {
                use crate::lease::LeaseRefusal as R;
                match refusal {
                    R::Level { .. } | R::NotAdmin { .. } => StatusCode::FORBIDDEN,
                    R::NoBooking(_) => StatusCode::NOT_FOUND,
                    R::Save(_) => StatusCode::INTERNAL_SERVER_ERROR,
                    R::Held { .. } | R::Booked { .. } | R::NotHolder | R::BadBooking(_) => {
                        StatusCode::CONFLICT
                    }
                }
            }
            AppError::NoLease | AppError::NoTrial | AppError::NotLive | AppError::NoChoice(_) => {
                StatusCode::NOT_FOUND
            }
            AppError::Combination(_) => StatusCode::CONFLICT,
            AppError::Trial(_) => StatusCode::INTERNAL_SERVER_ERROR,
            AppError::NotFound
            | AppError::NoScreen(_)
            | AppError::NoCommand(_)
            | AppError::NoPoint(_)
            | AppError::NoAlarm
            | AppError::NoArchive
            | AppError::NoLift(_) => StatusCode::NOT_FOUND,
            AppError::Body { rejection, .. } => rejection.status(),
            AppError::Query(_)
            | AppError::BadCursor
            | AppError::BadValue(_)
            | AppError::BadParameter { .. }
            | AppError::Store(_) => StatusCode::BAD_REQUEST,
            AppError::TooManyLogins(_) => StatusCode::TOO_MANY_REQUESTS,
            AppError::Socket(SocketRefusal::NoSession) => StatusCode::UNAUTHORIZED,
            AppError::Socket(SocketRefusal::TooMany) => StatusCode::TOO_MANY_REQUESTS,
            AppError::Busy(_) | AppError::NoStore | AppError::AuditUnavailable => {
                StatusCode::SERVICE_UNAVAILABLE
            }
            AppError::ScreenFile { .. }
            | AppError::ScreenInvalid { .. }
            | AppError::Cookie
            | AppError::NoPeer => StatusCode::INTERNAL_SERVER_ERROR,
        }
    }

    /// A JSON body refused for `context` (`"bad command request: "`).
    pub fn body(context: &'static str) -> impl FnOnce(JsonRejection) -> AppError {
        move |rejection| AppError::Body { context, rejection }
    }
}

impl IntoResponse for AppError {
    fn into_response(self) -> Response {
        let status = self.status();
        let message = self.to_string();
        match self {
            AppError::LevelTooLow { .. } => (
                status,
                Json(json!({"outcome": ControlOutcome::RefusedPermission, "detail": message})),
            )
                .into_response(),
            AppError::NoAuthority(_) => (
                status,
                Json(json!({"outcome": ControlOutcome::RefusedAuthority, "detail": message})),
            )
                .into_response(),
            AppError::TooManyLogins(seconds) => (
                status,
                [(header::RETRY_AFTER, HeaderValue::from(seconds))],
                Json(json!({"error": message, "retry_after_s": seconds})),
            )
                .into_response(),
            AppError::Busy(_) => (
                status,
                [(header::RETRY_AFTER, HeaderValue::from_static("1"))],
                Json(json!({"error": message, "retry_after_s": 1})),
            )
                .into_response(),
            _ => (status, Json(json!({"error": message}))).into_response(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test]
    async fn bodies_and_statuses() {
        async fn reply(error: AppError) -> (StatusCode, serde_json::Value) {
            let response = error.into_response();
            let status = response.status();
            let bytes = axum::body::to_bytes(response.into_body(), 4096)
                .await
                .unwrap();
            (status, serde_json::from_slice(&bytes).unwrap())
        }
        assert_eq!(
            reply(AppError::NotLoggedIn).await,
            (StatusCode::UNAUTHORIZED, json!({"error": "not logged in"}))
        );
        assert_eq!(
            reply(AppError::LevelTooLow { needed: 7, has: 5 }).await,
            (
                StatusCode::FORBIDDEN,
                json!({"outcome": "refused-permission", "detail": "level 7 needed, user has 5"})
            )
        );
        assert_eq!(
            reply(AppError::TooManyLogins(5)).await,
            (
                StatusCode::TOO_MANY_REQUESTS,
                json!({"error": "too many failed logins; try again later", "retry_after_s": 5})
            )
        );
        assert_eq!(
            reply(AppError::Socket(SocketRefusal::TooMany)).await.0,
            StatusCode::TOO_MANY_REQUESTS
        );
    }
}
