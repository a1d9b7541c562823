//! The IEC 104 controlling station (client).
//!
//! [`spawn_client`] starts a task that connects (trying each configured address in turn,
//! with exponential back-off between rounds; a connection that ends before
//! [`ClientConfig::healthy_after`] does not reset the back-off, so a server that accepts
//! and closes at once is not hammered), completes the TLS handshake if configured,
//! starts data transfer, optionally sends a general interrogation and a clock
//! synchronisation, and then hands every received ASDU to the application as a
//! [`ClientEvent`]. A [`ClientHandle`] sends requests; commands resolve when their
//! confirmation (and, where the standard has one, their termination) arrives, or time out.
//!
//! A started connection that receives nothing for [`ClientConfig::standby_probe`] sends a
//! test command (C_TS_TA_1): a station answers it only on the started connection of a
//! redundancy group, so no answer means another controlling station has taken the data
//! over (or the station is stuck), and the client says so, drops the connection and
//! connects again, rather than show stale values as live.
//!
//! ```text
//! ClientHandle ──mpsc──> client task ── Session ── TCP/TLS ── server
//!      ^  oneshot reply       │
//!      └──────────────────────┘──> mpsc<ClientEvent> ──> application
//! ```

use std::collections::VecDeque;
use std::net::SocketAddr;
use std::sync::Arc;
use std::time::Duration;

use tokio::io::{AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt};
use tokio::net::TcpStream;
use tokio::sync::{mpsc, oneshot};
use tracing::Instrument;

use crate::asdu::{
    Asdu, AsduParams, Cause, CommonAddress, Cot, Element, InformationObject, Ioa, TypeId,
};
use crate::controlling::{start_requests, Expired, OpenRequests};
use crate::cs104::config::ApciConfig;
use crate::cs104::repeated_warning::RepeatedWarning;
use crate::cs104::session::{Role, Session, SessionEvent, SessionState};
use crate::time::Cp56Time2a;

/// Configuration of a client.
#[derive(Debug, Clone)]
#[non_exhaustive]
pub struct ClientConfig {
    /// Server addresses (`host:port`), tried in order: the first is the main one, the
    /// others alternates.
    pub addresses: Vec<String>,
    /// The station's common address (for interrogation, clock sync and commands).
    pub common_address: CommonAddress,
    /// Our originator address (0 when unused).
    pub originator: u8,
    /// The local address to connect from (a multi-homed host; the server chooses a
    /// redundancy group and the command authority by it); `None` lets the system choose.
    pub local_address: Option<std::net::IpAddr>,
    /// APCI parameters (k, w, t0..t3).
    pub apci: ApciConfig,
    /// ASDU field sizes.
    pub asdu: AsduParams,
    /// Start data transfer (STARTDT) as soon as connected. Off: the connection is a
    /// standby of a redundancy group, connected and tested but sent no data, until
    /// [`ClientHandle::start_data_transfer`]; from then on every reconnection starts.
    pub start_on_connect: bool,
    /// Send a station interrogation after each start of data transfer.
    pub interrogate_on_start: bool,
    /// Send a clock synchronisation (the host's UTC time) after each start.
    pub clock_sync_on_start: bool,
    /// Connect again after a connection is lost or refused.
    pub reconnect: bool,
    /// Back-off after the first failed round of addresses; doubles each round.
    pub reconnect_delay: Duration,
    /// Back-off ceiling.
    pub reconnect_delay_max: Duration,
    /// How long a connection must have lasted for its loss to count as a loss rather than
    /// a refusal: only then is the back-off reset and the next attempt made at once.
    pub healthy_after: Duration,
    /// Probe a started connection that has received nothing for this long (see the
    /// module documentation); `None` never probes.
    pub standby_probe: Option<Duration>,
    /// How long a request waits for its confirmation, and an interrogation again for its
    /// termination.
    pub command_timeout: Duration,
    /// How long a positively confirmed command waits for its (optional) termination
    /// before it is reported done with `terminated = false`.
    pub termination_timeout: Duration,
    /// Received events the application may fall behind by: the event channel holds this
    /// many (at least 16), and as many more wait inside the client, which then stops
    /// reading the socket (TCP then slows the server down). Requests and their time-outs
    /// keep working meanwhile.
    pub event_capacity: usize,
    /// TLS (IEC 62351-3): client configuration and the server's name in its certificate.
    pub tls: Option<crate::cs104::tls::ClientTls>,
}

impl ClientConfig {
    /// A configuration with the standard's defaults for one server.
    pub fn new(address: impl Into<String>, common_address: CommonAddress) -> Self {
        Self {
            addresses: vec![address.into()],
            common_address,
            originator: 0,
            local_address: None,
            start_on_connect: true,
            apci: ApciConfig::default(),
            asdu: AsduParams::IEC104,
            interrogate_on_start: false,
            clock_sync_on_start: false,
            reconnect: true,
            reconnect_delay: Duration::from_millis(500),
            reconnect_delay_max: Duration::from_secs(30),
            healthy_after: Duration::from_secs(10),
            standby_probe: Some(Duration::from_secs(30)),
            command_timeout: Duration::from_secs(10),
            termination_timeout: Duration::from_secs(2),
            event_capacity: 10_000,
            tls: None,
        }
    }
}

/// What the client tells the application.
#[derive(Debug, Clone, PartialEq)]
pub enum ClientEvent {
    /// A TCP (and TLS) connection to a server is up.
    Connected {
        /// The server's address.
        peer: SocketAddr,
    },
    /// The server confirmed STARTDT: data flows.
    Started,
    /// An ASDU from the server (data, confirmations, terminations).
    Asdu(Asdu),
    /// An ASDU that could not be decoded, with the reason; shown rather than hidden, as
    /// a test tool must.
    Undecodable {
        /// Why it could not be decoded.
        error: String,
        /// Its bytes.
        raw: Vec<u8>,
    },
    /// The connection ended.
    Disconnected {
        /// Why.
        reason: String,
    },
}

/// Why a request failed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ClientError {
    /// No started connection.
    #[error("not connected (no started connection to the server)")]
    NotConnected,
    /// The connection ended before the request finished.
    #[error("connection lost before the request finished")]
    Disconnected,
    /// The confirmation or termination did not arrive in time.
    #[error("timed out waiting for {0}")]
    Timeout(&'static str),
    /// A request of the same type to the same address is still open.
    #[error("a request of this type to this address is still open")]
    Busy,
    /// The request could not be encoded.
    #[error("cannot encode the request: {0}")]
    Encode(String),
    /// The client task has ended.
    #[error("the client has stopped")]
    Stopped,
}

pub use crate::controlling::RequestOutcome;

enum Request {
    Exchange {
        asdu: Asdu,
        reply: oneshot::Sender<Result<RequestOutcome, ClientError>>,
    },
    /// Start data transfer on a standby connection.
    Start,
    /// Stop; the sender is dropped once the connection is closed.
    Close(oneshot::Sender<()>),
}

/// Sends requests to a running client. Cloning is cheap.
#[derive(Debug, Clone)]
pub struct ClientHandle {
    requests: mpsc::Sender<Request>,
    common_address: CommonAddress,
    originator: u8,
}

/// Starts a client on the current tokio runtime. Returns the handle and the stream of
/// events; the client stops when [`ClientHandle::close`] is called or every handle is
/// dropped.
pub fn spawn_client(config: ClientConfig) -> (ClientHandle, mpsc::Receiver<ClientEvent>) {
    let (requests_tx, requests_rx) = mpsc::channel(64);
    let (events_tx, events_rx) = mpsc::channel(config.event_capacity.max(16));
    let handle = ClientHandle {
        requests: requests_tx,
        common_address: config.common_address,
        originator: config.originator,
    };
    tokio::spawn(run(config, requests_rx, events_tx));
    (handle, events_rx)
}

impl ClientHandle {
    async fn exchange(&self, asdu: Asdu) -> Result<RequestOutcome, ClientError> {
        let (reply, answer) = oneshot::channel();
        self.requests
            .send(Request::Exchange { asdu, reply })
            .await
            .map_err(|_| ClientError::Stopped)?;
        answer.await.map_err(|_| ClientError::Stopped)?
    }

    fn request(&self, type_id: TypeId, cause: Cause, object: InformationObject) -> Asdu {
        let mut cot = Cot::new(cause);
        cot.originator = self.originator;
        let mut asdu = Asdu::new(type_id, cot, self.common_address);
        asdu.objects.push(object);
        asdu
    }

    /// Sends a command (types 45..=64) and waits for its confirmation and, for an
    /// executed (not select) command confirmed positively, its termination. The standard
    /// leaves the termination of a command to the station: when none comes within
    /// [`ClientConfig::termination_timeout`] the outcome is positive with
    /// `terminated = false`.
    pub async fn command(
        &self,
        type_id: TypeId,
        ioa: Ioa,
        element: Element,
        time: Option<Cp56Time2a>,
    ) -> Result<RequestOutcome, ClientError> {
        let object = InformationObject {
            ioa,
            element,
            time: time.map(crate::asdu::TimeTag::Cp56),
        };
        self.exchange(self.request(type_id, Cause::ACTIVATION, object))
            .await
    }

    /// Sends a general interrogation (qualifier 20 = station, 21..=36 = group 1..=16)
    /// and waits for its termination. The data arrive as [`ClientEvent::Asdu`].
    pub async fn interrogate(&self, qualifier: u8) -> Result<RequestOutcome, ClientError> {
        let object = InformationObject {
            ioa: Ioa::default(),
            element: Element::Interrogation { qualifier },
            time: None,
        };
        self.exchange(self.request(TypeId::C_IC_NA_1, Cause::ACTIVATION, object))
            .await
    }

    /// Sends a counter interrogation (request 1..=4 group, 5 general; freeze 0..=3).
    pub async fn interrogate_counters(
        &self,
        request: u8,
        freeze: u8,
    ) -> Result<RequestOutcome, ClientError> {
        let object = InformationObject {
            ioa: Ioa::default(),
            element: Element::CounterInterrogation { request, freeze },
            time: None,
        };
        self.exchange(self.request(TypeId::C_CI_NA_1, Cause::ACTIVATION, object))
            .await
    }

    /// Synchronises the server's clock.
    pub async fn clock_sync(&self, time: Cp56Time2a) -> Result<RequestOutcome, ClientError> {
        let object = InformationObject {
            ioa: Ioa::default(),
            element: Element::ClockSync { time },
            time: None,
        };
        self.exchange(self.request(TypeId::C_CS_NA_1, Cause::ACTIVATION, object))
            .await
    }

    /// Sends a test command with time tag (C_TS_TA_1).
    pub async fn test(
        &self,
        counter: u16,
        time: Cp56Time2a,
    ) -> Result<RequestOutcome, ClientError> {
        let object = InformationObject {
            ioa: Ioa::default(),
            element: Element::TestWithTime { counter },
            time: Some(crate::asdu::TimeTag::Cp56(time)),
        };
        self.exchange(self.request(TypeId::C_TS_TA_1, Cause::ACTIVATION, object))
            .await
    }

    /// Sends a read request (C_RD_NA_1); the value arrives as an ASDU with cause 5, a
    /// refusal as the mirrored request with cause 47.
    pub async fn read(&self, ioa: Ioa) -> Result<RequestOutcome, ClientError> {
        let object = InformationObject {
            ioa,
            element: Element::Read,
            time: None,
        };
        self.exchange(self.request(TypeId::C_RD_NA_1, Cause::REQUEST, object))
            .await
    }

    /// Sends any ASDU and waits for the server's answer to it: confirmation and (for
    /// commands and interrogations) termination, or the data answering a read.
    pub async fn send(&self, asdu: Asdu) -> Result<RequestOutcome, ClientError> {
        self.exchange(asdu).await
    }

    /// Starts data transfer on a standby connection (`start_on_connect = false`): the
    /// server makes this connection the active one of its redundancy group and sends what
    /// the previous active connection left unacknowledged, then everything new. Returns
    /// at once; [`ClientEvent::Started`] follows.
    pub async fn start_data_transfer(&self) -> Result<(), ClientError> {
        self.requests
            .send(Request::Start)
            .await
            .map_err(|_| ClientError::Stopped)
    }

    /// Closes the connection politely and stops the client: acknowledges every ASDU
    /// received (so that the server does not send them again to the next connection of
    /// its redundancy group), closes the socket, and returns once that is done. Requests
    /// still open fail with [`ClientError::Disconnected`]; later ones with
    /// [`ClientError::Stopped`].
    pub async fn close(&self) {
        let (done, closed) = oneshot::channel();
        if self.requests.send(Request::Close(done)).await.is_ok() {
            // Err once the client task dropped the sender: it has finished.
            let _ = closed.await;
        }
    }
}

/// Where the answer to an open request goes.
type Reply = oneshot::Sender<Result<RequestOutcome, ClientError>>;

async fn run(
    config: ClientConfig,
    mut requests: mpsc::Receiver<Request>,
    events: mpsc::Sender<ClientEvent>,
) {
    let mut delay = config.reconnect_delay;
    let mut start = config.start_on_connect;
    let mut failures = RepeatedWarning::default();
    loop {
        // Whether a connection of this round lasted long enough to reset the back-off.
        let mut healthy = false;
        let mut last_failure = None;
        for address in &config.addresses {
            let attempt = connect(&config, address);
            tokio::pin!(attempt);
            // Requests made while connecting fail at once rather than wait for t0.
            let attempt = loop {
                tokio::select! {
                    result = &mut attempt => break result,
                    request = requests.recv() => match request {
                        None | Some(Request::Close(_)) => return,
                        Some(Request::Start) => start = true,
                        Some(Request::Exchange { reply, .. }) => {
                            let _ = reply.send(Err(ClientError::NotConnected));
                        }
                    },
                }
            };
            match attempt {
                Ok((stream, peer)) => {
                    let connected_at = tokio::time::Instant::now();
                    if events.send(ClientEvent::Connected { peer }).await.is_err() {
                        return;
                    }
                    // One span per connection, as the server has: field engineers filter
                    // logs by peer.
                    let span = tracing::info_span!("iec104_client", %peer);
                    let outcome = match stream {
                        Transport::Plain(stream) => {
                            drive(&config, stream, &mut requests, &events, &mut start)
                                .instrument(span)
                                .await
                        }
                        Transport::Tls(stream) => {
                            drive(&config, *stream, &mut requests, &events, &mut start)
                                .instrument(span)
                                .await
                        }
                    };
                    let reason = match outcome {
                        DriveEnd::Closed => return,
                        DriveEnd::Lost(reason) => reason,
                    };
                    if connected_at.elapsed() >= config.healthy_after {
                        healthy = true;
                        delay = config.reconnect_delay;
                        failures = RepeatedWarning::default();
                        tracing::info!(%peer, %reason, "disconnected");
                    } else if let Some(repeats) = failures.due(tokio::time::Instant::now()) {
                        tracing::warn!(%peer, %reason, repeats, retry_in_ms = delay.as_millis(), "connection ended at once");
                    }
                    if events
                        .send(ClientEvent::Disconnected { reason })
                        .await
                        .is_err()
                    {
                        return;
                    }
                    if !config.reconnect {
                        return;
                    }
                }
                Err(reason) => {
                    if let Some(repeats) = failures.due(tokio::time::Instant::now()) {
                        tracing::warn!(%address, %reason, repeats, retry_in_ms = delay.as_millis(), "connection failed");
                    }
                    last_failure = Some(reason);
                }
            }
        }
        if !config.reconnect {
            // Without reconnection the client gives up after one round of addresses; it
            // says so whatever the number of addresses.
            if let Some(reason) = last_failure {
                let _ = events.send(ClientEvent::Disconnected { reason }).await;
            }
            return;
        }
        if !healthy {
            // Requests made while nobody is connected fail at once rather than hang.
            let wait = tokio::time::sleep(delay);
            tokio::pin!(wait);
            loop {
                tokio::select! {
                    () = &mut wait => break,
                    request = requests.recv() => match request {
                        None | Some(Request::Close(_)) => return,
                        Some(Request::Start) => start = true,
                        Some(Request::Exchange { reply, .. }) => {
                            let _ = reply.send(Err(ClientError::NotConnected));
                        }
                    },
                }
            }
            delay = (delay * 2).min(config.reconnect_delay_max);
        }
    }
}

enum Transport {
    Plain(TcpStream),
    Tls(Box<tokio_rustls::client::TlsStream<TcpStream>>),
}

async fn connect(config: &ClientConfig, address: &str) -> Result<(Transport, SocketAddr), String> {
    let attempt = async {
        match config.local_address {
            None => TcpStream::connect(address).await,
            Some(local) => {
                let remote = tokio::net::lookup_host(address)
                    .await?
                    .find(|remote| remote.is_ipv4() == local.is_ipv4())
                    .ok_or_else(|| {
                        std::io::Error::new(
                            std::io::ErrorKind::AddrNotAvailable,
                            format!("no address of the family of {local}"),
                        )
                    })?;
                let socket = if local.is_ipv4() {
                    tokio::net::TcpSocket::new_v4()?
                } else {
                    tokio::net::TcpSocket::new_v6()?
                };
                socket.bind(SocketAddr::new(local, 0))?;
                socket.connect(remote).await
            }
        }
    };
    let stream = tokio::time::timeout(config.apci.t0, attempt)
        .await
        .map_err(|_| format!("t0 expired connecting to {address}"))?
        .map_err(|error| format!("cannot connect to {address}: {error}"))?;
    let _ = stream.set_nodelay(true);
    let peer = stream
        .peer_addr()
        .map_err(|error| format!("cannot connect to {address}: {error}"))?;
    match &config.tls {
        None => Ok((Transport::Plain(stream), peer)),
        Some((tls, name)) => {
            let connector = tokio_rustls::TlsConnector::from(Arc::clone(tls));
            let stream =
                tokio::time::timeout(config.apci.t0, connector.connect(name.clone(), stream))
                    .await
                    .map_err(|_| format!("t0 expired in the TLS handshake with {address}"))?
                    .map_err(|error| format!("TLS handshake with {address} failed: {error}"))?;
            Ok((Transport::Tls(Box::new(stream)), peer))
        }
    }
}

enum DriveEnd {
    /// The application closed the client.
    Closed,
    /// The connection was lost; reconnect if configured.
    Lost(String),
}

async fn drive<S>(
    config: &ClientConfig,
    stream: S,
    requests: &mut mpsc::Receiver<Request>,
    events: &mpsc::Sender<ClientEvent>,
    start: &mut bool,
) -> DriveEnd
where
    S: AsyncRead + AsyncWrite + Unpin,
{
    let (mut reader, mut writer) = tokio::io::split(stream);
    let now = tokio::time::Instant::now().into_std();
    let mut session = Session::new(config.apci.clone(), Role::ControllingStation, now);
    if *start {
        if let Err(error) = session.start_data_transfer(now) {
            return DriveEnd::Lost(format!("cannot start data transfer: {error}"));
        }
    }
    let mut pending: OpenRequests<Reply> =
        OpenRequests::new(config.command_timeout, config.termination_timeout);
    let mut outgoing: VecDeque<Vec<u8>> = VecDeque::new();
    let mut input = vec![0u8; 16 * 1024];
    let mut output = Vec::with_capacity(16 * 1024);
    let mut started = false;
    let mut closing: Option<oneshot::Sender<()>> = None;
    // When the last I frame arrived, and the deadline of an unanswered standby probe.
    let mut last_received = tokio::time::Instant::now();
    let mut probe_deadline: Option<tokio::time::Instant> = None;
    let mut probe_counter: u16 = 0;
    // Events the application has not taken yet. The task never waits for the
    // application inside the loop (a command awaited while events pile up would never
    // complete, nor time out); it stops reading the socket instead once this backlog is
    // as large as the channel, and TCP then slows the server down.
    let mut backlog: VecDeque<ClientEvent> = VecDeque::new();
    let backlog_limit = config.event_capacity.max(16);
    let result = 'connection: loop {
        let now = tokio::time::Instant::now().into_std();
        while let Some(event) = session.poll_event() {
            match event {
                SessionEvent::Asdu(raw) => {
                    last_received = tokio::time::Instant::now();
                    let event = match Asdu::decode(&raw, &config.asdu) {
                        Ok(asdu) => {
                            tracing::debug!(%asdu, "received");
                            if probe_deadline.is_some()
                                && asdu.type_id == TypeId::C_TS_TA_1
                                && !pending.any_of_type(TypeId::C_TS_TA_1)
                            {
                                // The answer to our own probe: the connection carries data.
                                probe_deadline = None;
                                continue;
                            }
                            probe_deadline = None;
                            if let Some((reply, outcome)) = pending.offer(now, &asdu) {
                                let _ = reply.send(Ok(outcome));
                            }
                            ClientEvent::Asdu(asdu)
                        }
                        Err(error) => {
                            tracing::warn!(%error, "undecodable ASDU");
                            ClientEvent::Undecodable {
                                error: error.to_string(),
                                raw,
                            }
                        }
                    };
                    backlog.push_back(event);
                }
                SessionEvent::Started => {
                    started = true;
                    backlog.push_back(ClientEvent::Started);
                    let clock = config.clock_sync_on_start.then(|| {
                        crate::cs104::server::time_tag_now(crate::time::TimeZonePolicy::Utc)
                    });
                    for asdu in start_requests(
                        config.common_address,
                        config.originator,
                        clock,
                        config.interrogate_on_start,
                    ) {
                        queue(&mut outgoing, &asdu, &config.asdu);
                    }
                }
                SessionEvent::Stopped => started = false,
                SessionEvent::Acknowledged { .. } => {}
                SessionEvent::Closed(reason) => {
                    break 'connection DriveEnd::Lost(reason.to_string());
                }
            }
        }
        while session.can_send() {
            let Some(asdu) = outgoing.pop_front() else {
                break;
            };
            if let Err(error) = session.send_asdu(now, &asdu) {
                tracing::debug!(%error, "send deferred");
                outgoing.push_front(asdu);
                break;
            }
        }
        while session.poll_transmit(&mut output) {}
        if !output.is_empty() {
            tracing::trace!(tx = ?format_args!("{output:02X?}"), "raw");
            if let Err(error) = writer.write_all(&output).await {
                break DriveEnd::Lost(format!("write failed: {error}"));
            }
            output.clear();
        }
        if matches!(session.state(), SessionState::Closed(_)) {
            continue;
        }
        let instant = tokio::time::Instant::now();
        if let Some(deadline) = probe_deadline {
            if deadline <= instant {
                break DriveEnd::Lost(format!(
                    "no answer to the standby probe within {:.1} s: another controlling station has taken the data over, or the station stopped answering",
                    config.command_timeout.as_secs_f64()
                ));
            }
        }
        // Probe a quiet started connection (see the module documentation).
        let probe_due = match (config.standby_probe, started, probe_deadline) {
            (Some(interval), true, None) => Some(last_received + interval),
            _ => None,
        };
        if probe_due.is_some_and(|due| due <= instant) {
            probe_counter = probe_counter.wrapping_add(1);
            let mut asdu = Asdu::new(
                TypeId::C_TS_TA_1,
                Cot::new(Cause::ACTIVATION),
                config.common_address,
            );
            asdu.cot.originator = config.originator;
            asdu.objects.push(InformationObject {
                ioa: Ioa::default(),
                element: Element::TestWithTime {
                    counter: probe_counter,
                },
                time: Some(crate::asdu::TimeTag::Cp56(
                    crate::cs104::server::time_tag_now(crate::time::TimeZonePolicy::Utc),
                )),
            });
            tracing::debug!("nothing received for a while: standby probe");
            queue(&mut outgoing, &asdu, &config.asdu);
            probe_deadline = Some(instant + config.command_timeout);
            continue;
        }
        let protocol_deadline = session.poll_timeout().map(tokio::time::Instant::from_std);
        let request_deadline = pending.next_deadline().map(tokio::time::Instant::from_std);
        let deadline = [
            protocol_deadline,
            request_deadline,
            probe_due,
            probe_deadline,
        ]
        .into_iter()
        .flatten()
        .min();
        while let Some(event) = backlog.pop_front() {
            match events.try_send(event) {
                Ok(()) => {}
                Err(mpsc::error::TrySendError::Full(event)) => {
                    backlog.push_front(event);
                    break;
                }
                Err(mpsc::error::TrySendError::Closed(_)) => break 'connection DriveEnd::Closed,
            }
        }
        let reading_allowed = backlog.len() < backlog_limit;
        tokio::select! {
            read = reader.read(&mut input), if reading_allowed => match read {
                Ok(0) => break DriveEnd::Lost("closed by the server".to_owned()),
                Ok(count) => {
                    let now = tokio::time::Instant::now().into_std();
                    let bytes = input.get(..count).unwrap_or_default();
                    // The raw-bytes layer of the protocol log (APCI and ASDU log at debug).
                    tracing::trace!(rx = ?format_args!("{bytes:02X?}"), "raw");
                    session.handle_input(now, bytes);
                }
                Err(error) => break DriveEnd::Lost(format!("read failed: {error}")),
            },
            permit = events.reserve(), if !backlog.is_empty() => match permit {
                Ok(permit) => {
                    if let Some(event) = backlog.pop_front() {
                        permit.send(event);
                    }
                }
                Err(_) => break DriveEnd::Closed,
            },
            () = sleep_until(deadline) => {
                let now = tokio::time::Instant::now();
                session.handle_timeout(now.into_std());
                for (reply, end) in pending.expire(now.into_std()) {
                    let _ = reply.send(match end {
                        Expired::Done(outcome) => Ok(outcome),
                        Expired::TimedOut(waited_for) => Err(ClientError::Timeout(waited_for)),
                    });
                }
            }
            request = requests.recv() => match request {
                None => break DriveEnd::Closed,
                Some(Request::Close(done)) => {
                    closing = Some(done);
                    break DriveEnd::Closed;
                }
                Some(Request::Start) => {
                    if !*start {
                        *start = true;
                        let now = tokio::time::Instant::now().into_std();
                        if let Err(error) = session.start_data_transfer(now) {
                            break DriveEnd::Lost(format!("cannot start data transfer: {error}"));
                        }
                    }
                }
                Some(Request::Exchange { asdu, reply }) => {
                    if !started {
                        let _ = reply.send(Err(ClientError::NotConnected));
                        continue;
                    }
                    let ioa = asdu.objects.first().map(|object| object.ioa).unwrap_or_default();
                    if pending.is_open(asdu.type_id, ioa) {
                        let _ = reply.send(Err(ClientError::Busy));
                        continue;
                    }
                    let mut bytes = Vec::new();
                    if let Err(error) = asdu.encode(&config.asdu, &mut bytes) {
                        let _ = reply.send(Err(ClientError::Encode(error.to_string())));
                        continue;
                    }
                    outgoing.push_back(bytes);
                    pending.open(tokio::time::Instant::now().into_std(), &asdu, reply);
                }
            },
        }
    };
    if let DriveEnd::Closed = result {
        // Leave politely: acknowledge what we received (the S frame must be written
        // before `close`, which drops whatever is still queued), then close the socket.
        // A server that stopped reading must not hold the close up beyond t1.
        session.acknowledge_received();
        output.clear();
        while session.poll_transmit(&mut output) {}
        let farewell = async {
            if !output.is_empty() {
                let _ = writer.write_all(&output).await;
            }
            let _ = writer.shutdown().await;
        };
        if tokio::time::timeout(config.apci.t1, farewell)
            .await
            .is_err()
        {
            tracing::warn!("the server did not take the closing acknowledgement within t1");
        }
        session.close(crate::cs104::session::CloseReason::LocalRequest);
    }
    if let DriveEnd::Lost(_) = result {
        // What arrived before the loss comes before the news of it.
        for event in backlog {
            if events.send(event).await.is_err() {
                break;
            }
        }
    }
    // Dropping the sender tells `ClientHandle::close` that the connection is closed.
    drop(closing);
    end(pending, result)
}

fn end(mut pending: OpenRequests<Reply>, result: DriveEnd) -> DriveEnd {
    for reply in pending.drain() {
        let _ = reply.send(Err(ClientError::Disconnected));
    }
    result
}

fn queue(outgoing: &mut VecDeque<Vec<u8>>, asdu: &Asdu, params: &AsduParams) {
    let mut bytes = Vec::new();
    match asdu.encode(params, &mut bytes) {
        Ok(()) => outgoing.push_back(bytes),
        Err(error) => tracing::error!(%error, "cannot encode request"),
    }
}

async fn sleep_until(deadline: Option<tokio::time::Instant>) {
    match deadline {
        Some(deadline) => tokio::time::sleep_until(deadline).await,
        None => std::future::pending().await,
    }
}
