//! The Stanice web HMI: a browser SCADA front end that is itself an IEC 104 controlling
//! station (docs/HMI.md has the files, the SVG bindings and the HTTP API).
//!
//! ```text
//!  outstation --IEC 104--> link::Station (points, alarms, audit) --broadcast--> web (WebSocket)
//!  browser --HTTP--> web: auth (users, sessions, CSRF, rate limit) --> Station::operate --> outstation
//! ```
//!
//! - [`config`]: the screens folder (`hmi.toml`, `points.csv`, SVG mimics).
//! - [`users`]: the users file, argon2id hashes, levels 0..=9.
//! - [`auth`]: sessions, CSRF tokens, login rate limit.
//! - [`link`]: the IEC 104 link to the station, point table, controls with select-before-operate,
//!   recording into the HMI's own event store.
//! - [`alarms`]: raised/cleared alarms, acknowledgement, shelving, suppression, out of
//!   service, the initial state after an interrogation, chattering and flood alarms, the
//!   KPI report (ISA-18.2, EEMUA 191).
//! - [`live`]: the messages of the live WebSocket (the browser's `HMI.receive`).
//! - [`web`]: the axum router: pages, JSON API, WebSocket; the lift screens' API reads
//!   the station's own store (the fault archive, the lifts' point history) when
//!   [`HmiOptions::archive`] names it.
//! - [`tls`]: HTTPS with the HMI's own certificate.
//!
//! # Screens
//!
//! A mimic is an SVG file of the screens folder; `web/mimic.js` binds its elements to
//! points by attributes, each kind of binding one entry of its `BINDINGS` table (the file's
//! header comment has the details):
//!
//! | attribute | the element | reads also |
//! |---|---|---|
//! | `data-point="P"` | `data-value` = on/off, off/on/between/faulty or the number (colour by CSS) | |
//! | `data-text="P"` | its text is the value | `data-unit`, `data-digits`, `data-on`, `data-off`, `data-map` |
//! | `data-energised="P"` | class `energised` while P is TRUE | |
//! | `data-visible="P"` | shown while P is on, or while its value word is `data-visible-when` | `data-visible-when` |
//! | `data-level="P"` | a `<rect>` filled to P's share of `data-min..data-max` (default 0..100) | `data-min`, `data-max`, `data-level-from` (bottom, top, left, right) |
//! | `data-position="P"` | moved by P's share along (`data-dx`, `data-dy`) | `data-min`, `data-max`, `data-dx`, `data-dy` |
//! | `data-rotate="P"` | turned to `data-angle-min..data-angle-max` degrees (default 0..360) | `data-min`, `data-max`, `data-angle-min`, `data-angle-max`, `data-cx`, `data-cy` |
//! | `data-command="C"` | a click opens the control dialog for C | `data-command-value`, `data-command-format`, `data-label` |
//! | `data-link-status` | shows the station link | |
//!
//! Level, position and rotation read TRUE as 1 and FALSE as 0, and clamp the share to
//! 0..1: a lab tank, a lift car or a conveyor needs no code of its own. Every bound
//! element blinks (`data-invalid`) while a point of it is invalid or the link is down.
//! The browser drops scripts, event handlers and foreign links from every SVG before it
//! enters the page; `data-*` attributes pass.
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]
#![cfg_attr(not(test), deny(clippy::indexing_slicing))]

pub mod alarms;
pub mod auth;
pub mod config;
pub mod lease;
pub mod link;
pub mod live;
pub mod tls;
pub mod trial;
pub mod users;
pub mod web;

use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::sync::{Arc, RwLock};
use std::time::Duration;

use ::store::Recorder;
use ::store::{open_store, EventStore};
use iec60870::asdu::CommonAddress;
use iec60870::time::TimeZonePolicy;

/// Why the HMI could not start or a request failed.
#[derive(Debug, thiserror::Error)]
pub enum HmiError {
    /// The screens folder is wrong.
    #[error("{0}")]
    Config(String),
    /// The users file is wrong, or a user operation failed.
    #[error("{0}")]
    Users(String),
    /// The event store could not be opened.
    #[error("event store: {0}")]
    Store(#[from] ::store::StoreError),
    /// The TLS certificate or key.
    #[error("TLS: {0}")]
    Tls(String),
    /// The listening socket.
    #[error("cannot listen on {address}: {source}")]
    Listen {
        /// The address.
        address: SocketAddr,
        /// Why.
        source: std::io::Error,
    },
}

/// How to run an HMI.
#[derive(Debug, Clone)]
pub struct HmiOptions {
    /// The screens folder.
    pub screens: PathBuf,
    /// The users file.
    pub users: PathBuf,
    /// The station's address(es): main first, then alternates.
    pub connect: Vec<String>,
    /// The station's common address.
    pub common_address: CommonAddress,
    /// Where browsers connect.
    pub listen: SocketAddr,
    /// The HMI's event store (`None`: no history, events and trends are unavailable).
    pub store: Option<String>,
    /// The station's event store, read only for the lift screens' fault archive and
    /// service figures (`sqlite:PATH`, `postgres://...`); `None`: the lift screens show
    /// live values only and the archive API answers 404.
    pub archive: Option<String>,
    /// The zone of the station's time tags.
    pub zone: TimeZonePolicy,
    /// The local address to connect to the station from (a station may grant its HMI
    /// link other rights than the dispatch links by the client's address).
    pub local_address: Option<std::net::IpAddr>,
}

/// How the HMI serves its browsers, beyond [`HmiOptions`].
#[derive(Debug, Clone)]
#[non_exhaustive]
pub struct ServeConfig {
    /// Serve HTTPS with this certificate and key (cookies are then `Secure`).
    pub tls: Option<tls::TlsFiles>,
    /// A session ends after this long without a request; its WebSockets close then.
    pub session_idle: Duration,
    /// How often the users file is checked for changes (`stanice user remove`,
    /// `passwd`): a removed or changed user's sessions end.
    pub users_poll: Duration,
    /// The program trial of a remote lab, for a folder with `[program]` (the application
    /// picks it by the folder's `trial` name).
    pub trial: Option<std::sync::Arc<dyn trial::ProgramTrial>>,
}

impl Default for ServeConfig {
    fn default() -> Self {
        ServeConfig {
            tls: None,
            session_idle: auth::SESSION_IDLE,
            users_poll: Duration::from_secs(1),
            trial: None,
        }
    }
}

/// Text from outside (user names, paths, header values) made safe for one log line:
/// control characters are escaped, so a CR/LF in a user name cannot forge a line.
#[derive(Debug, Clone, Copy)]
pub struct LogText<'a>(pub &'a str);

impl std::fmt::Display for LogText<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        use std::fmt::Write as _;
        for c in self.0.chars() {
            if c.is_control() || c == '\\' {
                for escaped in c.escape_default() {
                    f.write_char(escaped)?;
                }
            } else {
                f.write_char(c)?;
            }
        }
        Ok(())
    }
}

/// A running HMI.
pub struct Hmi {
    /// Where it listens.
    pub address: SocketAddr,
    /// The station link.
    pub station: Arc<link::Station>,
    /// The password verifications (their figures).
    pub verifier: Arc<auth::Verifier>,
    shutdown: tokio::sync::watch::Sender<bool>,
    recorder: Recorder,
    /// The station's archive (read only), closed at shutdown after the recorder has
    /// closed the HMI's own store.
    stores: Vec<Arc<dyn EventStore>>,
}

impl std::fmt::Debug for Hmi {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Hmi")
            .field("address", &self.address)
            .field("station", &self.station)
            .field("verifier", &self.verifier)
            .field("stores", &self.stores.len())
            .finish_non_exhaustive()
    }
}

impl Hmi {
    /// Loads the folder and users, opens the store, connects to the station and starts
    /// serving on the current tokio runtime.
    pub async fn start(options: HmiOptions) -> Result<Hmi, HmiError> {
        Hmi::start_with(options, ServeConfig::default()).await
    }

    /// [`Hmi::start`] with the serving options of `serve`.
    pub async fn start_with(options: HmiOptions, serve: ServeConfig) -> Result<Hmi, HmiError> {
        let config = config::HmiConfig::load(&options.screens)?;
        let local_address = config.local_address;
        let lease = match &config.lease {
            Some(lease) => Some(Arc::new(std::sync::Mutex::new(
                lease::LeaseDesk::open(lease.clone(), Some(&config.folder.join("bookings.json")))
                    .map_err(HmiError::Config)?,
            ))),
            None => None,
        };
        let tls_config = match &serve.tls {
            Some(files) => Some(files.server_config()?),
            None => None,
        };
        let users = users::Users::load(&options.users)?;
        let store: Option<Arc<dyn EventStore>> = match &options.store {
            Some(url) => Some(Arc::from(open_store(url).await?)),
            None => None,
        };
        let archive: Option<Arc<dyn EventStore>> = match &options.archive {
            Some(url) => Some(Arc::from(open_store(url).await?)),
            None => None,
        };
        let recorder = match &store {
            Some(store) => Recorder::spawn(Arc::clone(store)),
            None => Recorder::disabled(),
        };
        let link = link::Station::spawn(
            config,
            options.connect.clone(),
            options.common_address,
            recorder.clone(),
            options.zone,
            // The command line's address, else the screens folder's.
            options.local_address.or(local_address),
        );
        let verifier = Arc::new(auth::Verifier::default());
        let state = web::AppState {
            station: Arc::clone(&link),
            users: Arc::new(RwLock::new(users)),
            sessions: Arc::new(auth::Sessions::new(serve.session_idle)),
            limiter: Arc::default(),
            verifier: Arc::clone(&verifier),
            store,
            archive,
            audit_node: format!("CA{}", options.common_address.get()),
            secure_cookies: tls_config.is_some(),
            lease,
            trial: serve.trial.clone(),
            trial_running: Arc::new(tokio::sync::Semaphore::new(1)),
        };
        let listener = tokio::net::TcpListener::bind(options.listen)
            .await
            .map_err(|source| HmiError::Listen {
                address: options.listen,
                source,
            })?;
        let address = listener.local_addr().map_err(|source| HmiError::Listen {
            address: options.listen,
            source,
        })?;
        let (shutdown, stop) = tokio::sync::watch::channel(false);
        tokio::spawn(end_idle_sessions(Arc::clone(&state.sessions), stop.clone()));
        tokio::spawn(follow_users_file(
            options.users.clone(),
            Arc::clone(&state.users),
            Arc::clone(&state.sessions),
            serve.users_poll,
            stop.clone(),
        ));
        // Closed at shutdown: the archive is a second set of connections to the station's
        // own database, whose write-ahead log is removed only when the last one closes.
        let stores: Vec<Arc<dyn EventStore>> = state.archive.iter().cloned().collect();
        let app = web::router(state).into_make_service_with_connect_info::<tls::Peer>();
        let mut stopped = stop;
        let until_stopped = async move {
            let _ = stopped.wait_for(|stop| *stop).await;
        };
        match tls_config {
            Some(tls_config) => {
                let listener = tls::TlsListener::spawn(listener, tls_config).map_err(|source| {
                    HmiError::Listen {
                        address: options.listen,
                        source,
                    }
                })?;
                tokio::spawn(async move {
                    let served = axum::serve(listener, app)
                        .with_graceful_shutdown(until_stopped)
                        .await;
                    if let Err(error) = served {
                        tracing::error!(%error, "HMI server ended");
                    }
                });
            }
            None => {
                let listener = tls::PlainListener(listener);
                tokio::spawn(async move {
                    let served = axum::serve(listener, app)
                        .with_graceful_shutdown(until_stopped)
                        .await;
                    if let Err(error) = served {
                        tracing::error!(%error, "HMI server ended");
                    }
                });
            }
        }
        tracing::info!(%address, tls = serve.tls.is_some(), "HMI listening");
        Ok(Hmi {
            address,
            station: link,
            verifier,
            shutdown,
            recorder,
            stores,
        })
    }

    /// Stops serving, waits until the store has every record and closes the stores.
    pub async fn shutdown(self) {
        let _ = self.shutdown.send(true);
        self.station.set_link(false);
        // The HMI's own store closes with its recorder; the station's archive after it.
        self.recorder.close().await;
        for store in &self.stores {
            store.close().await.ok();
        }
    }
}

/// Ends idle sessions (closing their WebSockets) about once a second.
async fn end_idle_sessions(
    sessions: Arc<auth::Sessions>,
    mut stop: tokio::sync::watch::Receiver<bool>,
) {
    let mut tick = tokio::time::interval(Duration::from_secs(1));
    tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    loop {
        tokio::select! {
            _ = tick.tick() => {
                let ended = sessions.sweep();
                if ended > 0 {
                    tracing::info!(ended, "idle sessions ended");
                }
            }
            _ = stop.wait_for(|stop| *stop) => return,
        }
    }
}

/// The users file is read at most this large (a users file is a few kilobytes).
const MAX_USERS_FILE: u64 = 4 * 1024 * 1024;

fn read_users_file(path: &Path) -> Option<Vec<u8>> {
    use std::io::Read as _;
    let file = std::fs::File::open(path).ok()?;
    let mut bytes = Vec::new();
    file.take(MAX_USERS_FILE).read_to_end(&mut bytes).ok()?;
    Some(bytes)
}

/// Reloads the users file when its content changes (the `stanice user` commands rewrite
/// it while the HMI runs) and ends the sessions of every user removed or changed, so
/// that a removed user or a changed password takes effect at once.
async fn follow_users_file(
    path: PathBuf,
    users: Arc<RwLock<users::Users>>,
    sessions: Arc<auth::Sessions>,
    every: Duration,
    mut stop: tokio::sync::watch::Receiver<bool>,
) {
    let mut known = read_users_file(&path);
    let mut tick = tokio::time::interval(every.max(Duration::from_millis(10)));
    tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    loop {
        tokio::select! {
            _ = tick.tick() => {}
            _ = stop.wait_for(|stop| *stop) => return,
        }
        let current = read_users_file(&path);
        if current == known {
            continue;
        }
        known = current;
        let load_path = path.clone();
        // Loading hashes a decoy password (argon2): keep it off the async workers.
        let loaded = tokio::task::spawn_blocking(move || users::Users::load(&load_path)).await;
        let fresh = match loaded {
            Ok(Ok(fresh)) => fresh,
            Ok(Err(error)) => {
                tracing::warn!(error = %LogText(&error.to_string()), "users file not reloaded; the previous users stay");
                continue;
            }
            Err(_) => continue,
        };
        let changed: Vec<String> = {
            // The page's administration changes the users and writes their file under
            // this lock: a file read before such a change is stale by now, and applying
            // it would undo the change (the next tick loads the file as it is).
            let mut old = users.write().unwrap_or_else(|p| p.into_inner());
            if read_users_file(&path) != known {
                continue;
            }
            let changed = old
                .names()
                .filter(|name| old.record(name) != fresh.record(name))
                .map(str::to_owned)
                .collect();
            *old = fresh;
            changed
        };
        for name in &changed {
            sessions.remove_user(name);
            tracing::info!(user = %LogText(name), "user removed or changed: sessions ended");
        }
        tracing::info!(file = %LogText(&path.display().to_string()), "users file reloaded");
    }
}
