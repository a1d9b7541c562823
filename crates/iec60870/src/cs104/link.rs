//! A controlling station's link to one outstation, kept up for as long as it is wanted.
//!
//! The station runtime's concentrator links (a node reading the node below it) and the web
//! HMI (reading the top node) both hold a [`client`](super::client) connection open,
//! follow its state, take the outstation's data, and let a person or a test cut the cable
//! and put it back. That loop is written here once; what each does with the data is a
//! [`LinkObserver`].
//!
//! ```text
//!  Link::spawn(config, observer)            one tokio task per link
//!     |  spawn_client(config) --> ClientEvent: Started  --> observer.started(&client)
//!     |                                        Asdu     --> observer.asdu(&asdu)
//!     |                                        Disconnected (after Started)
//!     |                                                 --> observer.down(Lost)
//!     |  every observer.period() while started           --> observer.every_period(&client)
//!     |  Link::cut()     --> client closed, observer.down(Cut), wait for restore
//!     |  Link::restore() --> a new client
//!     |  Link::stop() or the last Link dropped --> client closed, no report
//! ```
//!
//! The client itself reconnects with its back-off after a lost connection (see
//! [`ClientConfig`]); the link task only replaces it after a cut.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};
use std::time::Duration;

use tokio::sync::mpsc;

use crate::asdu::Asdu;
use crate::cs104::client::{spawn_client, ClientConfig, ClientEvent, ClientHandle};

/// Why a link's data stopped.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum LinkDown {
    /// The connection was lost or data transfer stopped; the reason as the client gave it.
    Lost(String),
    /// [`Link::cut`]: fault injection, a cable pulled.
    Cut,
}

impl std::fmt::Display for LinkDown {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LinkDown::Lost(reason) => f.write_str(reason),
            LinkDown::Cut => f.write_str("link cut"),
        }
    }
}

/// What a link's owner does with its state and data. Called from the link's task, one call
/// at a time, in the order the client reported.
pub trait LinkObserver: Send + Sync + 'static {
    /// Data transfer started (after every connection).
    fn started(&self, client: &ClientHandle);
    /// Data transfer stopped: the connection was lost after it had started, or the link
    /// was cut (reported on every cut, whether data was flowing or not).
    fn down(&self, why: &LinkDown);
    /// An ASDU from the outstation (monitor data, confirmations, terminations).
    fn asdu(&self, asdu: &Asdu);
    /// How often [`LinkObserver::every_period`] is called while data transfer is started;
    /// `None` (the default) for never.
    fn period(&self) -> Option<Duration> {
        None
    }
    /// A periodic duty while started (a clock synchronisation, for instance).
    fn every_period(&self, _client: &ClientHandle) {}
}

enum Control {
    Cut,
    Restore,
    /// Close without reporting the link down (the owner is shutting down).
    Stop,
}

/// A running link: cut, restore and stop it, reach its client.
#[derive(Debug, Clone)]
pub struct Link {
    control: mpsc::UnboundedSender<Control>,
    client: Arc<Mutex<Option<ClientHandle>>>,
    up: Arc<AtomicBool>,
}

impl Link {
    /// Starts the link's task on the current tokio runtime. `config` is used for every
    /// client the link makes (one at the start and one after each restore).
    pub fn spawn(config: ClientConfig, observer: Arc<dyn LinkObserver>) -> Link {
        let (control, receiver) = mpsc::unbounded_channel();
        let link = Link {
            control,
            client: Arc::new(Mutex::new(None)),
            up: Arc::new(AtomicBool::new(false)),
        };
        let state = LinkState {
            client: Arc::clone(&link.client),
            up: Arc::clone(&link.up),
        };
        tokio::spawn(run(config, observer, receiver, state));
        link
    }

    /// Whether data transfer is started.
    pub fn is_up(&self) -> bool {
        self.up.load(Ordering::Acquire)
    }

    /// The client, while the link is not cut or stopped (to send commands and requests).
    pub fn client(&self) -> Option<ClientHandle> {
        lock(&self.client).clone()
    }

    /// Cuts the link: closes the connection and stays disconnected until
    /// [`Link::restore`].
    pub fn cut(&self) {
        let _ = self.control.send(Control::Cut);
    }

    /// Connects a cut link again.
    pub fn restore(&self) {
        let _ = self.control.send(Control::Restore);
    }

    /// Closes the link for good, without reporting it down.
    pub fn stop(&self) {
        let _ = self.control.send(Control::Stop);
    }
}

/// The parts of [`Link`] the task writes.
struct LinkState {
    client: Arc<Mutex<Option<ClientHandle>>>,
    up: Arc<AtomicBool>,
}

fn lock(client: &Mutex<Option<ClientHandle>>) -> MutexGuard<'_, Option<ClientHandle>> {
    client.lock().unwrap_or_else(PoisonError::into_inner)
}

/// What ended one client's life.
enum ClientEnd {
    /// The client's task ended on its own.
    Ended,
    Cut,
    Stop,
}

async fn run(
    config: ClientConfig,
    observer: Arc<dyn LinkObserver>,
    mut control: mpsc::UnboundedReceiver<Control>,
    state: LinkState,
) {
    loop {
        match drive_client(&config, observer.as_ref(), &mut control, &state).await {
            ClientEnd::Stop => return,
            // The client gave up by itself: a new one, after its first back-off so a
            // client that ends at once cannot spin.
            ClientEnd::Ended => tokio::time::sleep(config.reconnect_delay).await,
            ClientEnd::Cut => loop {
                match control.recv().await {
                    Some(Control::Restore) => break,
                    Some(Control::Cut) => {}
                    Some(Control::Stop) | None => return,
                }
            },
        }
    }
}

/// Runs one client until the link is cut or stopped.
async fn drive_client(
    config: &ClientConfig,
    observer: &dyn LinkObserver,
    control: &mut mpsc::UnboundedReceiver<Control>,
    state: &LinkState,
) -> ClientEnd {
    let (client, mut events) = spawn_client(config.clone());
    *lock(&state.client) = Some(client.clone());
    // A period of "never" still needs a timer to select on; it is only polled when set.
    let period = observer.period();
    let mut timer = tokio::time::interval(period.unwrap_or(Duration::from_secs(3600)));
    timer.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    loop {
        tokio::select! {
            // Control first: a stop is sent before the runtime closes the client and the
            // servers, so a connection that ends at shutdown is never reported as lost.
            biased;
            request = control.recv() => match request {
                Some(Control::Cut) => {
                    *lock(&state.client) = None;
                    // Nobody reads the client's events from here on: closed, so that a
                    // client waiting to hand one over (a full channel after a burst)
                    // gets to the close request instead of waiting for ever.
                    events.close();
                    client.close().await;
                    state.up.store(false, Ordering::Release);
                    observer.down(&LinkDown::Cut);
                    return ClientEnd::Cut;
                }
                Some(Control::Restore) => {}
                Some(Control::Stop) | None => {
                    *lock(&state.client) = None;
                    events.close();
                    client.close().await;
                    state.up.store(false, Ordering::Release);
                    return ClientEnd::Stop;
                }
            },
            event = events.recv() => match event {
                None => {
                    *lock(&state.client) = None;
                    if state.up.swap(false, Ordering::AcqRel) {
                        observer.down(&LinkDown::Lost("the client ended".to_owned()));
                    }
                    return ClientEnd::Ended;
                }
                Some(ClientEvent::Started) => {
                    state.up.store(true, Ordering::Release);
                    observer.started(&client);
                }
                Some(ClientEvent::Asdu(asdu)) => observer.asdu(&asdu),
                Some(ClientEvent::Disconnected { reason }) => {
                    if state.up.swap(false, Ordering::AcqRel) {
                        observer.down(&LinkDown::Lost(reason));
                    }
                }
                Some(ClientEvent::Connected { .. } | ClientEvent::Undecodable { .. }) => {}
            },
            _ = timer.tick(), if period.is_some() => {
                if state.up.load(Ordering::Acquire) {
                    observer.every_period(&client);
                }
            }
        }
    }
}
