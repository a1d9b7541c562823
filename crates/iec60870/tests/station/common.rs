//! Helpers of the station tests: a server builder, a recording handler, client helpers,
//! a log capture, and `RawPeer`, a controlling station driven by hand over a real socket.

use std::collections::VecDeque;
use std::future::Future;
use std::io::Write;
use std::net::{IpAddr, SocketAddr};
use std::sync::{Arc, Mutex, OnceLock};
use std::time::{Duration, Instant};

use iec60870::asdu::{
    Asdu, AsduParams, Cause, CommonAddress, Cot, Cp56Time2a, DoublePointState, Element,
    InformationObject, Ioa, Quality, TypeId,
};
use iec60870::cs104::client::{spawn_client, ClientConfig, ClientEvent, ClientHandle};
use iec60870::cs104::server::{
    ready, spawn_server, Command, CommandFuture, CommandOutcome, CommandPoint, MonitorPoint,
    ProcessImage, ServerConfig, ServerHandle, StationHandler,
};
use iec60870::cs104::{ApciConfig, Role, Session, SessionEvent};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::{TcpSocket, TcpStream};
use tokio::sync::mpsc;

/// The station's common address in every test.
pub(crate) const CA: u16 = 1;
/// The longest any single wait of a test may take.
pub(crate) const WAIT: Duration = Duration::from_secs(5);

pub(crate) fn ca() -> CommonAddress {
    CommonAddress::new(CA)
}

pub(crate) fn ioa(value: u32) -> Ioa {
    Ioa::try_new(value).unwrap()
}

pub(crate) fn params() -> AsduParams {
    AsduParams::IEC104
}

/// Awaits `future` for at most `limit`, failing the test with `what` otherwise.
pub(crate) async fn within<F: Future>(limit: Duration, what: &str, future: F) -> F::Output {
    match tokio::time::timeout(limit, future).await {
        Ok(output) => output,
        Err(_) => panic!("timed out after {limit:?} waiting for {what}"),
    }
}

/// Polls `condition` every few milliseconds until it holds, for at most `limit`.
pub(crate) async fn eventually(limit: Duration, what: &str, mut condition: impl FnMut() -> bool) {
    within(limit, what, async {
        while !condition() {
            tokio::time::sleep(Duration::from_millis(5)).await;
        }
    })
    .await;
}

// ---------------------------------------------------------------------------------------
// Log capture: the server's reasons for closing connections are checked in its logs.

#[derive(Clone, Default)]
struct LogBuffer(Arc<Mutex<Vec<u8>>>);

impl Write for LogBuffer {
    fn write(&mut self, bytes: &[u8]) -> std::io::Result<usize> {
        self.0.lock().unwrap().extend_from_slice(bytes);
        Ok(bytes.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

static LOGS: OnceLock<LogBuffer> = OnceLock::new();

/// Installs the capturing subscriber (once per test binary).
pub(crate) fn init_logs() {
    LOGS.get_or_init(|| {
        let buffer = LogBuffer::default();
        let writer = buffer.clone();
        let _ = tracing_subscriber::fmt()
            .with_max_level(tracing::Level::INFO)
            .with_ansi(false)
            .with_writer(move || writer.clone())
            .try_init();
        buffer
    });
}

/// Captured log lines containing every one of `needles`.
pub(crate) fn log_lines_with(needles: &[&str]) -> Vec<String> {
    let Some(buffer) = LOGS.get() else {
        return Vec::new();
    };
    let bytes = buffer.0.lock().unwrap().clone();
    String::from_utf8_lossy(&bytes)
        .lines()
        .filter(|line| needles.iter().all(|needle| line.contains(needle)))
        .map(str::to_owned)
        .collect()
}

/// Waits until the server logged that the connection from `peer` closed with a reason
/// containing `reason`.
pub(crate) async fn expect_close_logged(peer: SocketAddr, reason: &str) {
    let peer = format!("peer={peer}");
    let what = format!("the server to log the close of {peer} with '{reason}'");
    eventually(WAIT, &what, || {
        !log_lines_with(&[&peer, "connection closed", reason]).is_empty()
    })
    .await;
}

// ---------------------------------------------------------------------------------------
// Server side.

/// A server configuration for tests: loopback, port 0, no end of initialisation.
pub(crate) fn server_config() -> ServerConfig {
    let mut config = ServerConfig::new("127.0.0.1:0".parse().unwrap(), ca());
    config.outstation.send_end_of_initialisation = false;
    config
}

/// APCI timers short enough to watch them expire in a test.
pub(crate) fn fast_apci() -> ApciConfig {
    let mut apci = ApciConfig::default();
    apci.t0 = Duration::from_secs(2);
    apci.t1 = Duration::from_secs(1);
    apci.t2 = Duration::from_millis(200);
    apci.t3 = Duration::from_secs(1);
    apci
}

pub(crate) fn single(on: bool) -> Element {
    Element::SinglePoint {
        on,
        quality: Quality::GOOD,
    }
}

pub(crate) fn double(state: DoublePointState) -> Element {
    Element::DoublePoint {
        state,
        quality: Quality::GOOD,
    }
}

pub(crate) fn scaled(value: i16) -> Element {
    Element::Scaled {
        value,
        quality: Quality::GOOD,
    }
}

pub(crate) fn monitor(
    address: u32,
    event_type: TypeId,
    groups: u16,
    element: Element,
) -> MonitorPoint {
    MonitorPoint {
        ioa: ioa(address),
        event_type,
        groups,
        element,
        time: None,
    }
}

pub(crate) fn command_point(
    address: u32,
    command_type: TypeId,
    select_required: bool,
) -> CommandPoint {
    CommandPoint {
        ioa: ioa(address),
        command_type,
        select_required,
        max_age: None,
    }
}

pub(crate) type Decide = dyn Fn(&Command) -> CommandFuture + Send + Sync;

/// A handler that records what it is asked and decides commands with a closure.
pub(crate) struct Recorder {
    pub(crate) commands: Mutex<Vec<Command>>,
    pub(crate) clock_syncs: Mutex<Vec<Cp56Time2a>>,
    pub(crate) resets: Mutex<Vec<u8>>,
    pub(crate) accept_clock_sync: bool,
    pub(crate) decide: Box<Decide>,
}

impl Recorder {
    /// Executes every command at once.
    pub(crate) fn accepting() -> Arc<Recorder> {
        Recorder::deciding(|_| ready(CommandOutcome::Executed))
    }

    pub(crate) fn deciding(
        decide: impl Fn(&Command) -> CommandFuture + Send + Sync + 'static,
    ) -> Arc<Recorder> {
        Arc::new(Recorder {
            commands: Mutex::new(Vec::new()),
            clock_syncs: Mutex::new(Vec::new()),
            resets: Mutex::new(Vec::new()),
            accept_clock_sync: true,
            decide: Box::new(decide),
        })
    }

    pub(crate) fn commands(&self) -> Vec<Command> {
        self.commands.lock().unwrap().clone()
    }
}

impl StationHandler for Recorder {
    fn handle_command(&self, command: Command) -> CommandFuture {
        let future = (self.decide)(&command);
        self.commands.lock().unwrap().push(command);
        future
    }

    fn handle_clock_sync(&self, time: Cp56Time2a, _peer: &iec60870::outstation::Peer) -> bool {
        self.clock_syncs.lock().unwrap().push(time);
        self.accept_clock_sync
    }

    fn handle_reset_process(&self, qualifier: u8, _peer: &iec60870::outstation::Peer) -> bool {
        self.resets.lock().unwrap().push(qualifier);
        qualifier == 1
    }
}

pub(crate) async fn start_server(
    config: ServerConfig,
    image: ProcessImage,
    handler: Arc<dyn StationHandler>,
) -> ServerHandle {
    within(
        WAIT,
        "the server to start",
        spawn_server(config, image, handler),
    )
    .await
    .expect("server starts")
}

/// Waits until the server has exactly `count` open connections.
pub(crate) async fn wait_connections(server: &ServerHandle, count: usize) {
    let what = format!("{count} open connections");
    eventually(WAIT, &what, || server.stats().connections == count).await;
}

// ---------------------------------------------------------------------------------------
// Client side (the library's client).

pub(crate) fn client_config(server: SocketAddr) -> ClientConfig {
    let mut config = ClientConfig::new(server.to_string(), ca());
    config.reconnect = false;
    config.command_timeout = Duration::from_secs(5);
    // Acknowledge quickly: some tests run the server with t1 = 1 s.
    config.apci.t2 = Duration::from_millis(100);
    config
}

pub(crate) struct Client {
    pub(crate) handle: ClientHandle,
    pub(crate) events: mpsc::Receiver<ClientEvent>,
}

impl Client {
    /// Spawns a client and waits for its data transfer to start.
    pub(crate) async fn start(config: ClientConfig) -> Client {
        let (handle, events) = spawn_client(config);
        let mut client = Client { handle, events };
        client.wait_started().await;
        client
    }

    pub(crate) async fn connect(server: SocketAddr) -> Client {
        Client::start(client_config(server)).await
    }

    pub(crate) async fn wait_started(&mut self) {
        within(WAIT, "STARTDT con", async {
            loop {
                match self.events.recv().await {
                    Some(ClientEvent::Started) => return,
                    Some(ClientEvent::Disconnected { reason }) => {
                        panic!("disconnected before start: {reason}")
                    }
                    Some(_) => {}
                    None => panic!("client stopped before start"),
                }
            }
        })
        .await
    }

    /// The next ASDU received (other events are skipped).
    pub(crate) async fn next_asdu(&mut self) -> Asdu {
        within(WAIT, "an ASDU", async {
            loop {
                match self.events.recv().await {
                    Some(ClientEvent::Asdu(asdu)) => return asdu,
                    Some(ClientEvent::Disconnected { reason }) => {
                        panic!("disconnected while waiting for an ASDU: {reason}")
                    }
                    Some(_) => {}
                    None => panic!("client stopped while waiting for an ASDU"),
                }
            }
        })
        .await
    }

    /// The next ASDU if one arrives within `limit`.
    pub(crate) async fn try_next_asdu(&mut self, limit: Duration) -> Option<Asdu> {
        tokio::time::timeout(limit, async {
            loop {
                match self.events.recv().await {
                    Some(ClientEvent::Asdu(asdu)) => return Some(asdu),
                    Some(ClientEvent::Disconnected { .. }) | None => return None,
                    Some(_) => {}
                }
            }
        })
        .await
        .ok()
        .flatten()
    }

    /// ASDUs up to and including the first one of `type_id` with `cause`.
    pub(crate) async fn asdus_until(
        &mut self,
        type_id: TypeId,
        cause: Cause,
        limit: Duration,
    ) -> Vec<Asdu> {
        let mut asdus = Vec::new();
        within(limit, "the end of an exchange", async {
            loop {
                let asdu = self.next_asdu().await;
                let done = asdu.type_id == type_id && asdu.cot.cause == cause;
                asdus.push(asdu);
                if done {
                    return;
                }
            }
        })
        .await;
        asdus
    }

    /// Spontaneous objects (cause 3) until `count` have arrived.
    pub(crate) async fn spontaneous_objects(
        &mut self,
        count: usize,
    ) -> Vec<(TypeId, InformationObject)> {
        let mut objects = Vec::new();
        while objects.len() < count {
            let asdu = self.next_asdu().await;
            assert_eq!(asdu.cot.cause, Cause::SPONTANEOUS, "unexpected {asdu}");
            for object in asdu.objects {
                objects.push((asdu.type_id, object));
            }
        }
        objects
    }
}

// ---------------------------------------------------------------------------------------
// RawPeer: a controlling station written by hand, for what `ClientHandle` cannot do.

/// A controlling station made of a socket and a sans-IO [`Session`], pumped by hand.
pub(crate) struct RawPeer {
    pub(crate) stream: TcpStream,
    pub(crate) session: Session,
    pub(crate) local: SocketAddr,
    received: VecDeque<Vec<u8>>,
    started: bool,
    closed: bool,
    eof: bool,
}

impl RawPeer {
    /// Connects from 127.0.0.1 with the standard APCI parameters.
    pub(crate) async fn connect(server: SocketAddr) -> RawPeer {
        RawPeer::connect_with(server, None, ApciConfig::default()).await
    }

    /// Connects from `source` (any loopback address) with the given APCI parameters.
    pub(crate) async fn connect_with(
        server: SocketAddr,
        source: Option<IpAddr>,
        apci: ApciConfig,
    ) -> RawPeer {
        let stream = within(WAIT, "TCP connect", async {
            match source {
                None => TcpStream::connect(server).await,
                Some(ip) => {
                    let socket = TcpSocket::new_v4()?;
                    socket.bind(SocketAddr::new(ip, 0))?;
                    socket.connect(server).await
                }
            }
        })
        .await
        .expect("TCP connect");
        stream.set_nodelay(true).unwrap();
        let local = stream.local_addr().unwrap();
        RawPeer {
            stream,
            session: Session::new(apci, Role::ControllingStation, Instant::now()),
            local,
            received: VecDeque::new(),
            started: false,
            closed: false,
            eof: false,
        }
    }

    /// APCI parameters of a peer that never acknowledges on its own (large w, t2 long).
    pub(crate) fn lazy_apci() -> ApciConfig {
        let mut apci = ApciConfig::default();
        apci.k = 100;
        apci.w = 100;
        apci.t1 = Duration::from_secs(120);
        apci.t2 = Duration::from_secs(100);
        apci.t3 = Duration::from_secs(100);
        apci
    }

    /// Writes what the session has to send.
    pub(crate) async fn flush(&mut self) {
        let mut out = Vec::new();
        while self.session.poll_transmit(&mut out) {}
        if !out.is_empty() && !self.eof && self.stream.write_all(&out).await.is_err() {
            self.eof = true;
        }
    }

    fn drain_events(&mut self) {
        while let Some(event) = self.session.poll_event() {
            match event {
                SessionEvent::Asdu(asdu) => self.received.push_back(asdu),
                SessionEvent::Started => self.started = true,
                SessionEvent::Stopped => self.started = false,
                SessionEvent::Acknowledged { .. } => {}
                SessionEvent::Closed(_) => self.closed = true,
            }
        }
    }

    /// Reads and handles input (and the session's timers) until `until` or the end of
    /// the connection. Returns as soon as `done` holds.
    async fn pump_until(
        &mut self,
        until: tokio::time::Instant,
        mut done: impl FnMut(&Self) -> bool,
    ) {
        let mut buffer = vec![0u8; 16 * 1024];
        loop {
            self.drain_events();
            self.flush().await;
            if done(self) || self.closed || self.eof {
                return;
            }
            let protocol = self
                .session
                .poll_timeout()
                .map(tokio::time::Instant::from_std);
            let wake = protocol.map_or(until, |at| at.min(until));
            tokio::select! {
                read = self.stream.read(&mut buffer) => match read {
                    Ok(0) | Err(_) => self.eof = true,
                    Ok(count) => self.session.handle_input(Instant::now(), &buffer[..count]),
                },
                () = tokio::time::sleep_until(wake) => {
                    if wake >= until {
                        return;
                    }
                    self.session.handle_timeout(Instant::now());
                }
            }
        }
    }

    /// Pumps the connection for `duration` (answering TESTFR, acknowledging per w/t2).
    pub(crate) async fn pump_for(&mut self, duration: Duration) {
        self.pump_until(tokio::time::Instant::now() + duration, |_| false)
            .await;
    }

    /// Sends STARTDT act and waits for STARTDT con.
    pub(crate) async fn start(&mut self) {
        self.session.start_data_transfer(Instant::now()).unwrap();
        self.pump_until(tokio::time::Instant::now() + WAIT, |peer| peer.started)
            .await;
        assert!(self.started, "STARTDT con not received");
    }

    /// Sends STOPDT act and waits for STOPDT con.
    pub(crate) async fn stop(&mut self) {
        self.session.stop_data_transfer(Instant::now()).unwrap();
        self.pump_until(tokio::time::Instant::now() + WAIT, |peer| !peer.started)
            .await;
        assert!(!self.started, "STOPDT con not received");
    }

    /// Sends an ASDU (bytes as they are) in an I frame.
    pub(crate) async fn send_asdu(&mut self, asdu: &[u8]) {
        self.session.send_asdu(Instant::now(), asdu).unwrap();
        self.flush().await;
    }

    /// Encodes and sends an ASDU.
    pub(crate) async fn send(&mut self, asdu: &Asdu) {
        let bytes = asdu.to_bytes(&params()).unwrap();
        self.send_asdu(&bytes).await;
    }

    /// The next received ASDU as bytes, if one arrives within `limit`.
    pub(crate) async fn next_raw(&mut self, limit: Duration) -> Option<Vec<u8>> {
        if self.received.is_empty() {
            self.pump_until(tokio::time::Instant::now() + limit, |peer| {
                !peer.received.is_empty()
            })
            .await;
        }
        self.received.pop_front()
    }

    /// The next received ASDU, decoded, if one arrives within `limit`.
    pub(crate) async fn next_asdu(&mut self, limit: Duration) -> Option<Asdu> {
        let raw = self.next_raw(limit).await?;
        Some(Asdu::decode(&raw, &params()).expect("the server sends decodable ASDUs"))
    }

    /// The next received ASDU; fails the test after [`WAIT`].
    pub(crate) async fn expect_asdu(&mut self) -> Asdu {
        match self.next_asdu(WAIT).await {
            Some(asdu) => asdu,
            None => panic!("no ASDU within {WAIT:?} (closed: {})", self.is_closed()),
        }
    }

    /// ASDUs up to and including the first one of `type_id` with `cause`.
    pub(crate) async fn asdus_until(&mut self, type_id: TypeId, cause: Cause) -> Vec<Asdu> {
        let mut asdus = Vec::new();
        loop {
            let asdu = self.expect_asdu().await;
            let done = asdu.type_id == type_id && asdu.cot.cause == cause;
            asdus.push(asdu);
            if done {
                return asdus;
            }
        }
    }

    /// Writes bytes to the socket, bypassing the session.
    pub(crate) async fn write_raw(&mut self, bytes: &[u8]) {
        if self.stream.write_all(bytes).await.is_err() {
            self.eof = true;
        }
    }

    /// Whether the connection ended (EOF or reset seen, or the session closed).
    pub(crate) fn is_closed(&self) -> bool {
        self.eof || self.closed
    }

    /// Waits, without answering anything, until the server closes the connection.
    /// Returns whether it did within `limit`.
    pub(crate) async fn wait_closed(&mut self, limit: Duration) -> bool {
        if self.eof {
            return true;
        }
        let mut buffer = vec![0u8; 4096];
        let closed = tokio::time::timeout(limit, async {
            loop {
                match self.stream.read(&mut buffer).await {
                    Ok(0) | Err(_) => return,
                    Ok(_) => {}
                }
            }
        })
        .await
        .is_ok();
        self.eof |= closed;
        closed
    }

    pub(crate) fn unexpected_frames(&self) -> u64 {
        self.session.stats().unexpected_frames_received
    }
}

// ---------------------------------------------------------------------------------------
// ASDU builders.

pub(crate) fn request(
    type_id: TypeId,
    cause: Cause,
    common_address: u16,
    address: u32,
    element: Element,
) -> Asdu {
    Asdu::new(type_id, Cot::new(cause), CommonAddress::new(common_address))
        .with_object(InformationObject::new(ioa(address), element))
}

pub(crate) fn interrogation(qualifier: u8) -> Asdu {
    request(
        TypeId::C_IC_NA_1,
        Cause::ACTIVATION,
        CA,
        0,
        Element::Interrogation { qualifier },
    )
}

/// Every object of the ASDUs, with the ASDU's type and cause.
pub(crate) fn objects_of(asdus: &[Asdu]) -> Vec<(TypeId, Cause, InformationObject)> {
    asdus
        .iter()
        .flat_map(|asdu| {
            asdu.objects
                .iter()
                .map(move |object| (asdu.type_id, asdu.cot.cause, object.clone()))
        })
        .collect()
}
