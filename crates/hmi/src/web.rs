//! The HTTP and WebSocket API of docs/HMI.md: an axum router composed from one router per
//! area, the security headers as a layer over all of them.
//!
//! ```text
//!  request --> harden (security headers; JSON body for bare errors)    outermost
//!          --> DefaultBodyLimit (MAX_BODY)
//!          --> session | pages | points | events | alarms | trends | lifts | live
//!              (per-area routes)
//!              handler(extractors: LoggedIn / Writer / Operator / SameOrigin, then body)
//!          <-- Result<_, AppError>: an explicit status per refusal, {"error": "..."}
//! ```
//!
//! - [`extract`]: who is asking. Every `/api` handler but login takes a session extractor,
//!   so none can forget the session check; every POST takes [`Writer`] or [`Operator`],
//!   so none can forget the CSRF check.
//! - [`error`]: [`AppError`], every refusal (wrong password, lockout, forged or missing
//!   CSRF token, unknown point, level too low, control authority elsewhere) with its
//!   status; refusals are logged with the client's address, any text the client chose
//!   escaped ([`LogText`](crate::LogText)).
//! - Bodies are capped at [`MAX_BODY`], WebSocket messages at [`MAX_WS_MESSAGE`].
//! - Every response, errors, refused upgrades and static files included, carries the
//!   security headers of [`harden`]; an error without a JSON body gets one.

mod alarms;
mod choices;
pub mod error;
mod events;
pub mod extract;
mod lease;
mod lifts;
mod live;
mod pages;
mod points;
mod program;
mod session;
mod trends;
mod users;

use std::sync::{Arc, RwLock};

use axum::body::Body;
use axum::extract::DefaultBodyLimit;
use axum::http::{header, HeaderValue};
use axum::response::Response;
use axum::Router;
use serde_json::json;
use store::EventStore;

pub use error::AppError;
pub use extract::{LoggedIn, Operator, SameOrigin, Writer};

use crate::auth::{LoginLimiter, Sessions, Verifier};
use crate::link::Station;
use crate::users::Users;

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
    /// The station's event store (the lift fault archive, the lifts' history), if any.
    pub archive: Option<Arc<dyn EventStore>>,
    /// The node the HMI's audit records name (the station's common address).
    pub audit_node: String,
    /// Cookies only over HTTPS (the HMI serves TLS itself).
    pub secure_cookies: bool,
    /// The operator lease, when the screens folder has `[lease]`.
    pub lease: Option<Arc<std::sync::Mutex<crate::lease::LeaseDesk>>>,
    /// The program trial, when the folder has `[program]` and the application gave one.
    pub trial: Option<Arc<dyn crate::trial::ProgramTrial>>,
    /// One trial runs at a time.
    pub trial_running: Arc<tokio::sync::Semaphore>,
}

impl AppState {
    /// The event store, or [`AppError::NoStore`].
    fn store(&self) -> Result<Arc<dyn EventStore>, AppError> {
        self.store.clone().ok_or(AppError::NoStore)
    }
}

/// The router: every area's routes, the 404 fallback, and the layers.
pub fn router(state: AppState) -> Router {
    let camera = state.station.config().camera_origin();
    Router::new()
        .merge(session::routes())
        .merge(pages::routes())
        .merge(points::routes())
        .merge(events::routes())
        .merge(alarms::routes())
        .merge(trends::routes())
        .merge(users::routes())
        .merge(lease::routes())
        .merge(choices::routes())
        .merge(program::routes())
        .merge(pages::public_routes())
        .merge(lifts::routes())
        .merge(live::routes())
        .fallback(not_found)
        // Layers run outside in, the last added first. Inner: the body limit applies to
        // the handlers. Outer: `harden` sees every response, the fallback's, the
        // extractors' rejections and refused WebSocket upgrades included.
        .layer(DefaultBodyLimit::max(MAX_BODY))
        .layer(axum::middleware::map_response(move |response| {
            harden_with(response, camera.clone())
        }))
        .with_state(state)
}

async fn not_found() -> AppError {
    AppError::NotFound
}

/// The security headers of every response, and a JSON body for every error that has
/// none (axum's own rejections, such as 405, are plain text).
pub async fn harden(response: Response) -> Response {
    harden_with(response, None).await
}

/// [`harden`], letting pictures come from `camera` (an origin, `http://host:port`) too.
async fn harden_with(response: Response, camera: Option<String>) -> Response {
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
    let csp = match camera.as_deref() {
        // The origin was checked to hold only host characters (config::camera_origin).
        Some(origin) => HeaderValue::from_str(&CSP.replace(
            "img-src 'self' data:",
            &format!("img-src 'self' data: {origin}"),
        ))
        .unwrap_or(HeaderValue::from_static(CSP)),
        None => HeaderValue::from_static(CSP),
    };
    headers.insert(header::CONTENT_SECURITY_POLICY, csp);
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
