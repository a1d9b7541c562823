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
//! - [`alarms`]: raised/cleared alarms, acknowledgement, shelving.
//! - [`web`]: the axum router: pages, JSON API, WebSocket.
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]
#![cfg_attr(not(test), deny(clippy::indexing_slicing))]

pub mod alarms;
pub mod auth;
pub mod config;
pub mod link;
pub mod users;
pub mod web;

use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::{Arc, RwLock};

use ::station::pointdb::TimeZonePolicy;
use ::station::runtime::Recorder;
use ::station::store::{open_store, EventStore};
use iec60870::asdu::CommonAddress;

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
    Store(#[from] ::station::store::StoreError),
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
    /// The zone of the station's time tags.
    pub zone: TimeZonePolicy,
    /// The local address to connect to the station from (a station may grant its HMI
    /// link other rights than the dispatch links by the client's address).
    pub local_address: Option<std::net::IpAddr>,
}

/// A running HMI.
#[derive(Debug)]
pub struct Hmi {
    /// Where it listens.
    pub address: SocketAddr,
    /// The station link.
    pub station: Arc<link::Station>,
    shutdown: tokio::sync::watch::Sender<bool>,
    recorder: Recorder,
}

impl Hmi {
    /// Loads the folder and users, opens the store, connects to the station and starts
    /// serving on the current tokio runtime.
    pub async fn start(options: HmiOptions) -> Result<Hmi, HmiError> {
        let config = config::HmiConfig::load(&options.screens)?;
        let users = users::Users::load(&options.users)?;
        let store: Option<Arc<dyn EventStore>> = match &options.store {
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
            options.local_address,
        );
        let state = web::AppState {
            station: Arc::clone(&link),
            users: Arc::new(RwLock::new(users)),
            sessions: Arc::default(),
            limiter: Arc::default(),
            store,
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
        let (shutdown, mut stop) = tokio::sync::watch::channel(false);
        let app = web::router(state).into_make_service_with_connect_info::<SocketAddr>();
        tokio::spawn(async move {
            let served = axum::serve(listener, app)
                .with_graceful_shutdown(async move {
                    let _ = stop.changed().await;
                })
                .await;
            if let Err(error) = served {
                tracing::error!(%error, "HMI server ended");
            }
        });
        tracing::info!(%address, "HMI listening");
        Ok(Hmi {
            address,
            station: link,
            shutdown,
            recorder,
        })
    }

    /// Stops serving and waits until the store has every record.
    pub async fn shutdown(self) {
        let _ = self.shutdown.send(true);
        self.station.set_link(false);
        self.recorder.flush().await;
    }
}
