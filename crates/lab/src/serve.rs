//! The web mimic of a run (`stanice lab serve`): the model's front panel in the browser,
//! as the thesis's WebMaker pages draw it (LEDs as two-state images, the slide's track,
//! tank levels, the drum), with START, RESET and the model's buttons, speed control
//! (pause, 1x, 10x, max, one scan) and a logic-analyser time-line of every signal that
//! a student can scroll back through to a violation.
//!
//! ```text
//!  browser --GET /api/state (100 ms), /api/timeline?from=N (incremental)--> View (Mutex)
//!     |                                                                        ^ after each slice
//!     +--POST /api/control {speed|pause|step|console}--> mpsc --> simulation thread
//!                                                        (owns the Session: compiled there,
//!                                                         runs slices of 20 ms wall time)
//! ```
//!
//! The session lives on its own thread because a compiled program is not `Send`; the
//! server only sees what that thread publishes. Pausing stops simulated time; one scan
//! steps it by one PLC cycle; `max` runs as fast as the machine goes while the page
//! keeps updating.
//!
//! A lab project (several models, each with its program: [`LabProject`]) is served by
//! [`serve_many`]: an index at `/`, each mimic at `/m/N/` with its own session thread.
//! The page addresses its API relative to itself, so one page serves both.

use std::net::SocketAddr;
use std::sync::mpsc;
use std::sync::{Arc, Mutex, PoisonError};
use std::time::{Duration, Instant};

use axum::extract::{Path, Query, State};
use axum::http::{header, StatusCode};
use axum::response::{Html, IntoResponse, Response};
use axum::routing::{get, post};
use axum::{Json, Router};
use serde::Deserialize;
use serde_json::{json, Value};

use crate::program::Program;
use crate::report::Violation;
use crate::run::{RunSettings, Session, Speed};
use crate::scenario::Scenario;
use crate::timeline::{Change, Channel};

const PAGE: &str = include_str!("../web/mimic.html");
const SCRIPT: &str = include_str!("../web/mimic.js");
const STYLE: &str = include_str!("../web/mimic.css");

/// How long the simulation thread runs between publications.
const SLICE: Duration = Duration::from_millis(20);

/// What a mimic needs.
#[derive(Debug, Clone)]
pub struct ServeSettings {
    /// The run's settings (its duration is ignored: a mimic runs until stopped).
    pub run: RunSettings,
    /// The program's sources (name, text), compiled on the simulation thread.
    pub sources: Vec<(String, String)>,
    /// The PROGRAM to run, when the sources hold several.
    pub main: Option<String>,
    /// A scenario's lines and properties, if any.
    pub scenario: Option<Scenario>,
    /// Start paused (a test, or a teacher who wants to explain first).
    pub paused: bool,
}

/// A control from the page.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Control {
    /// Run at this speed: `1`, `10`, `max`.
    Speed(String),
    /// Stop simulated time.
    Pause,
    /// One PLC scan (pauses first).
    Step,
    /// A console line of the model (`press START`, `release START`, `reset`).
    Console(String),
}

/// What the page reads.
#[derive(Debug, Default)]
struct View {
    state: Value,
    channels: Vec<Channel>,
    changes: Vec<Change>,
    violations: Vec<Violation>,
}

#[derive(Clone)]
struct AppState {
    view: Arc<Mutex<View>>,
    controls: mpsc::Sender<Control>,
}

/// Why a mimic cannot start.
#[derive(Debug, thiserror::Error)]
pub enum ServeError {
    /// The program or model could not be started.
    #[error("{0}")]
    Start(String),
    /// The server failed.
    #[error("the web server: {0}")]
    Io(#[from] std::io::Error),
}

/// Starts the simulation thread and serves the mimic on `listener` until the future is
/// dropped. Fails if the session cannot start.
pub async fn serve(
    listener: tokio::net::TcpListener,
    settings: ServeSettings,
) -> Result<(), ServeError> {
    let app = start(settings).await?;
    axum::serve(listener, routes().with_state(app)).await?;
    Ok(())
}

/// Serves several mimics on `listener` (a lab project: one model and program each), an
/// index at `/` and each mimic at `/m/N/`. Fails if any session cannot start.
pub async fn serve_many(
    listener: tokio::net::TcpListener,
    mimics: Vec<(String, ServeSettings)>,
) -> Result<(), ServeError> {
    let mut apps = Vec::new();
    let mut titles = Vec::new();
    for (title, settings) in mimics {
        let app = start(settings)
            .await
            .map_err(|error| ServeError::Start(format!("{title}: {error}")))?;
        apps.push(app);
        titles.push(title);
    }
    let index = index_page(&titles);
    let apps = Arc::new(apps);
    let app = Router::new()
        .route("/", get(move || async move { Html(index) }))
        .route("/m/{n}/", get(|| async { Html(PAGE) }))
        .route(
            "/m/{n}/mimic.js",
            get(|| async { asset("text/javascript", SCRIPT) }),
        )
        .route(
            "/m/{n}/mimic.css",
            get(|| async { asset("text/css", STYLE) }),
        )
        .route("/m/{n}/api/state", get(many_state))
        .route("/m/{n}/api/timeline", get(many_timeline))
        .route("/m/{n}/api/control", post(many_control))
        .with_state(apps);
    axum::serve(listener, app).await?;
    Ok(())
}

/// The index of a lab project's mimics.
fn index_page(titles: &[String]) -> String {
    let items: String = titles
        .iter()
        .enumerate()
        .map(|(n, title)| {
            let title = title
                .replace('&', "&amp;")
                .replace('<', "&lt;")
                .replace('>', "&gt;");
            format!("<li><a href=\"/m/{n}/\">{title}</a></li>")
        })
        .collect();
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\
<title>Stanice lab</title><link rel=\"stylesheet\" href=\"/m/0/mimic.css\"></head>\
<body><header><h1>Stanice lab</h1></header><main><section><h2>Models</h2>\
<ul id=\"models\">{items}</ul></section></main></body></html>\n"
    )
}

fn routes() -> Router<AppState> {
    Router::new()
        .route("/", get(|| async { Html(PAGE) }))
        .route(
            "/mimic.js",
            get(|| async { asset("text/javascript", SCRIPT) }),
        )
        .route("/mimic.css", get(|| async { asset("text/css", STYLE) }))
        .route("/api/state", get(state))
        .route("/api/timeline", get(timeline))
        .route("/api/control", post(control))
}

/// Starts a mimic's simulation thread; its state once the session runs.
async fn start(settings: ServeSettings) -> Result<AppState, ServeError> {
    let view = Arc::new(Mutex::new(View::default()));
    let (controls, inbox) = mpsc::channel();
    let (started, start_result) = tokio::sync::oneshot::channel();
    {
        let view = Arc::clone(&view);
        std::thread::Builder::new()
            .name("lab-mimic".into())
            .spawn(move || simulate(settings, view, inbox, started))?;
    }
    start_result
        .await
        .map_err(|_| ServeError::Start("the simulation thread ended".into()))?
        .map_err(ServeError::Start)?;
    Ok(AppState { view, controls })
}

/// The mimic numbered `n` of a project, or 404.
fn nth(apps: &[AppState], n: usize) -> Result<AppState, StatusCode> {
    apps.get(n).cloned().ok_or(StatusCode::NOT_FOUND)
}

async fn many_state(
    State(apps): State<Arc<Vec<AppState>>>,
    Path(n): Path<usize>,
) -> Result<Json<Value>, StatusCode> {
    Ok(state(State(nth(&apps, n)?)).await)
}

async fn many_timeline(
    State(apps): State<Arc<Vec<AppState>>>,
    Path(n): Path<usize>,
    query: Query<TimelineQuery>,
) -> Result<Json<Value>, StatusCode> {
    Ok(timeline(State(nth(&apps, n)?), query).await)
}

async fn many_control(
    State(apps): State<Arc<Vec<AppState>>>,
    Path(n): Path<usize>,
    control_body: Json<Control>,
) -> Result<Response, StatusCode> {
    Ok(control(State(nth(&apps, n)?), control_body).await)
}

/// The address a listener is on, for the banner.
pub fn address(listener: &tokio::net::TcpListener) -> Option<SocketAddr> {
    listener.local_addr().ok()
}

fn asset(mime: &'static str, body: &'static str) -> Response {
    (
        [
            (header::CONTENT_TYPE, mime),
            (header::CACHE_CONTROL, "no-cache"),
        ],
        body,
    )
        .into_response()
}

async fn state(State(app): State<AppState>) -> Json<Value> {
    let view = app.view.lock().unwrap_or_else(PoisonError::into_inner);
    Json(view.state.clone())
}

#[derive(Debug, Deserialize)]
struct TimelineQuery {
    #[serde(default)]
    from: usize,
}

async fn timeline(State(app): State<AppState>, Query(query): Query<TimelineQuery>) -> Json<Value> {
    let view = app.view.lock().unwrap_or_else(PoisonError::into_inner);
    let changes: Vec<&Change> = view.changes.iter().skip(query.from).collect();
    Json(json!({
        "channels": view.channels,
        "changes": changes,
        "next": view.changes.len(),
        "violations": view.violations,
    }))
}

async fn control(State(app): State<AppState>, Json(control): Json<Control>) -> Response {
    match app.controls.send(control) {
        Ok(()) => StatusCode::NO_CONTENT.into_response(),
        Err(_) => (
            StatusCode::SERVICE_UNAVAILABLE,
            "the simulation has stopped",
        )
            .into_response(),
    }
}

/// The simulation thread: compiles the program, then runs slices and publishes.
fn simulate(
    settings: ServeSettings,
    view: Arc<Mutex<View>>,
    inbox: mpsc::Receiver<Control>,
    started: tokio::sync::oneshot::Sender<Result<(), String>>,
) {
    let session = Program::compile(&settings.sources, settings.main.as_deref())
        .map_err(|error| error.to_string())
        .and_then(|program| {
            Session::new(program, settings.run.clone(), settings.scenario.as_ref())
                .map_err(|error| error.to_string())
        });
    let mut session = match session {
        Ok(session) => session,
        Err(error) => {
            let _ = started.send(Err(error));
            return;
        }
    };
    session.record_timeline();
    let mut speed = settings.run.speed;
    let mut paused = settings.paused;
    let mut published = 0;
    publish(&session, speed, paused, &view, &mut published);
    let _ = started.send(Ok(()));
    loop {
        let slice_start = Instant::now();
        // Controls first; a paused mimic waits for one instead of spinning.
        let first = if paused {
            match inbox.recv_timeout(Duration::from_millis(200)) {
                Ok(control) => Some(control),
                Err(mpsc::RecvTimeoutError::Timeout) => None,
                Err(mpsc::RecvTimeoutError::Disconnected) => return,
            }
        } else {
            None
        };
        let mut step = false;
        for control in first.into_iter().chain(inbox.try_iter()) {
            match control {
                Control::Speed(text) => match text.parse::<Speed>() {
                    Ok(new) => {
                        speed = new;
                        paused = false;
                    }
                    Err(error) => tracing::debug!(%error, "speed refused"),
                },
                Control::Pause => paused = true,
                Control::Step => {
                    paused = true;
                    step = true;
                }
                Control::Console(line) => {
                    if let Err(error) = session.console(&line) {
                        tracing::debug!(%line, %error, "console line refused");
                    }
                }
            }
        }
        if step {
            if let Err(error) = session.step() {
                tracing::warn!(%error, "the run stopped");
                return;
            }
        } else if !paused {
            let simulated = match speed {
                Speed::Max => None,
                Speed::Times(factor) => Some(SLICE.mul_f64(factor)),
            };
            let end = simulated.map(|d| session.now() + d);
            while end.is_none_or(|end| session.now() < end) && slice_start.elapsed() < SLICE {
                if let Err(error) = session.step() {
                    tracing::warn!(%error, "the run stopped");
                    return;
                }
            }
        }
        publish(&session, speed, paused, &view, &mut published);
        if !paused {
            if let Some(rest) = SLICE.checked_sub(slice_start.elapsed()) {
                std::thread::sleep(rest);
            }
        }
    }
}

fn value(value: plant::Value) -> Value {
    match value {
        plant::Value::Bool(b) => json!(b),
        plant::Value::Real(x) => json!(x),
    }
}

/// Publishes the session's state and its new time-line changes.
fn publish(session: &Session, speed: Speed, paused: bool, view: &Mutex<View>, published: &mut u64) {
    let model = session.model();
    let signals: serde_json::Map<String, Value> = model
        .signals()
        .iter()
        .map(|info| {
            let reading = model
                .read(&info.name)
                .map_or(Value::Null, |r| value(r.value));
            (info.name.clone(), reading)
        })
        .collect();
    let state: serde_json::Map<String, Value> = model
        .state()
        .into_iter()
        .map(|(name, v)| (name.to_owned(), value(v)))
        .collect();
    let err_led = match model.err_led() {
        plant::lab::ErrLed::Off => "off",
        plant::lab::ErrLed::Blinking => "blinking",
        plant::lab::ErrLed::Steady => "steady",
    };
    let errors: Vec<Value> = model
        .errors()
        .iter()
        .map(|e| {
            json!({"t": e.time.as_secs_f64(), "kind": e.kind.name(), "detail": e.detail,
                   "recoverable": e.recoverable, "cleared": e.cleared.map(|c| c.as_secs_f64())})
        })
        .collect();
    let operations: Vec<&str> = model.console_operations().iter().map(|o| o.usage).collect();
    let speed_text = match speed {
        Speed::Max => "max".to_owned(),
        Speed::Times(x) => format!("{x}"),
    };
    let state = json!({
        "model": model.model(),
        "t": session.now().as_secs_f64(),
        "scans": session.scans(),
        "speed": speed_text,
        "paused": paused,
        "stopped": session.stopped(),
        "err_led": err_led,
        "err_lit": model.err_lit(),
        "signals": signals,
        "state": state,
        "errors": errors,
        "operations": operations,
        "violations": session.violations().len(),
    });
    let (changes, next) = session
        .timeline()
        .map(|timeline| timeline.since(*published))
        .unwrap_or_default();
    let mut view = view.lock().unwrap_or_else(PoisonError::into_inner);
    if view.channels.is_empty() {
        if let Some(timeline) = session.timeline() {
            view.channels = timeline.channels().to_vec();
        }
    }
    view.state = state;
    view.changes.extend(changes);
    // The page's copy is bounded like the session's.
    let excess = view
        .changes
        .len()
        .saturating_sub(crate::timeline::Timeline::CAPACITY);
    if excess > 0 {
        view.changes.drain(..excess);
    }
    view.violations = session.violations().to_vec();
    *published = next;
}
