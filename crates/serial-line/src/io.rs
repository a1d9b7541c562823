//! The tokio adapter of line endpoints: serial ports, pseudo-terminals and TCP.
//!
//! [`Transport::open`] gives a byte stream; [`drive`] runs a [`LineEndpoint`] on it,
//! feeding it octets and the clock and writing what it transmits. The endpoint stays
//! sans-IO: everything here is the loop around it.
//!
//! A serial port's settings are read back after they are applied: termios takes what a
//! driver cannot do without an error and keeps something else (a pseudo-terminal keeps
//! no parity), and a line whose two ends disagree on the character format only shows
//! it as broken frames. A setting the port did not keep is an [`OpenError::Refused`]
//! naming it.

use std::fmt;
use std::io;
use std::ops::ControlFlow;
use std::pin::Pin;
use std::time::Duration;

use thiserror::Error;
use tokio::io::{AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt};
use tokio::sync::mpsc;
use tokio::time::Instant;

use crate::endpoint::LineEndpoint;
use crate::settings::{LineSettings, Parity, Refused, SettingsError};

/// A byte stream a line endpoint runs on.
pub trait LineStream: AsyncRead + AsyncWrite + Send + Unpin {}

impl<T: AsyncRead + AsyncWrite + Send + Unpin> LineStream for T {}

/// Where the line is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Transport {
    /// A serial port device (`/dev/ttyUSB0`), set to the line's speed and format.
    Serial {
        /// The device path.
        path: String,
        /// Speed and character format.
        line: LineSettings,
    },
    /// A new pseudo-terminal pair: this end is kept, the other end's path is printed
    /// for the peer to open as a serial port.
    Pty,
    /// A TCP connection to a terminal server or gateway (`host:port`).
    Connect(String),
    /// A TCP listener that takes one peer at a time (`addr:port`).
    Listen(String),
}

impl fmt::Display for Transport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Transport::Serial { path, line } => write!(f, "serial {path} {line}"),
            Transport::Pty => f.write_str("pseudo-terminal"),
            Transport::Connect(address) => write!(f, "tcp {address}"),
            Transport::Listen(address) => write!(f, "tcp listen {address}"),
        }
    }
}

/// An open transport.
pub struct OpenLine {
    /// The byte stream.
    pub stream: Pin<Box<dyn LineStream>>,
    /// The path of the pseudo-terminal's other end, for [`Transport::Pty`].
    pub pty_path: Option<String>,
    /// What the stream is connected to.
    pub peer: String,
    /// The pseudo-terminal's other end, held open so that the line does not hang up
    /// between two peers; never read.
    _pty_peer_end: Option<tokio_serial::SerialStream>,
}

impl fmt::Debug for OpenLine {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("OpenLine")
            .field("pty_path", &self.pty_path)
            .field("peer", &self.peer)
            .finish_non_exhaustive()
    }
}

/// A bound TCP listener of [`Transport::Listen`], for a caller that wants the address
/// before the peer connects.
pub struct LineListener(tokio::net::TcpListener);

impl LineListener {
    /// Binds the address.
    pub async fn bind(address: &str) -> io::Result<LineListener> {
        Ok(LineListener(tokio::net::TcpListener::bind(address).await?))
    }

    /// The bound address.
    pub fn local_addr(&self) -> io::Result<std::net::SocketAddr> {
        self.0.local_addr()
    }

    /// Waits for the next peer.
    pub async fn accept(&self) -> io::Result<OpenLine> {
        let (stream, peer) = self.0.accept().await?;
        stream.set_nodelay(true)?;
        Ok(OpenLine {
            stream: Box::pin(stream),
            pty_path: None,
            peer: peer.to_string(),
            _pty_peer_end: None,
        })
    }
}

/// Why a transport did not open. Each message names the transport; the system's reason
/// is part of the message (not a separate `source`), so that a log line of `{error}`
/// says it all.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum OpenError {
    /// Settings no line takes; the port was not opened.
    #[error("serial {path}: {reason}")]
    Settings {
        /// The device path.
        path: String,
        /// What is wrong with them.
        reason: SettingsError,
    },
    /// The system did not open the port or apply or report its settings.
    #[error("serial {path}: {reason}")]
    Serial {
        /// The device path.
        path: String,
        /// The system's reason ("No such file or directory", "Permission denied").
        reason: io::Error,
    },
    /// The port took the settings without an error but kept another value of one.
    #[error("serial {path}: {refused}")]
    Refused {
        /// The device path.
        path: String,
        /// The setting, asked and kept.
        refused: Refused,
    },
    /// No pseudo-terminal pair.
    #[error("pseudo-terminal: {reason}")]
    Pty {
        /// The system's reason.
        reason: io::Error,
    },
    /// No TCP connection or listener.
    #[error("tcp {address}: {reason}")]
    Tcp {
        /// The address.
        address: String,
        /// The system's reason.
        reason: io::Error,
    },
}

impl From<OpenError> for io::Error {
    /// For callers that handle every failure of a line as an `io::Error`; the message
    /// stays, the `OpenError` is the error's inner one.
    fn from(error: OpenError) -> io::Error {
        let kind = match &error {
            OpenError::Settings { .. } | OpenError::Refused { .. } => io::ErrorKind::InvalidInput,
            OpenError::Serial { reason, .. }
            | OpenError::Pty { reason }
            | OpenError::Tcp { reason, .. } => reason.kind(),
        };
        io::Error::new(kind, error)
    }
}

impl Transport {
    /// Opens the transport; [`Transport::Listen`] waits for one peer.
    pub async fn open(&self) -> Result<OpenLine, OpenError> {
        match self {
            Transport::Serial { path, line } => open_serial(path, line),
            Transport::Pty => {
                use tokio_serial::SerialPort as _;
                let pty = |reason: io::Error| OpenError::Pty { reason };
                let (ours, theirs) = tokio_serial::SerialStream::pair()
                    .map_err(|error| pty(io::Error::from(error)))?;
                let path = theirs
                    .name()
                    .ok_or_else(|| pty(io::Error::other("no path for the other end")))?;
                Ok(OpenLine {
                    stream: Box::pin(ours),
                    pty_path: Some(path.clone()),
                    peer: path,
                    _pty_peer_end: Some(theirs),
                })
            }
            Transport::Connect(address) => {
                let tcp = |reason| OpenError::Tcp {
                    address: address.clone(),
                    reason,
                };
                let stream = tokio::net::TcpStream::connect(address).await.map_err(tcp)?;
                stream.set_nodelay(true).map_err(tcp)?;
                Ok(OpenLine {
                    stream: Box::pin(stream),
                    pty_path: None,
                    peer: address.clone(),
                    _pty_peer_end: None,
                })
            }
            Transport::Listen(address) => {
                let tcp = |reason| OpenError::Tcp {
                    address: address.clone(),
                    reason,
                };
                LineListener::bind(address)
                    .await
                    .map_err(tcp)?
                    .accept()
                    .await
                    .map_err(tcp)
            }
        }
    }
}

/// Opens a serial port with the line's settings and checks that it kept them.
fn open_serial(path: &str, line: &LineSettings) -> Result<OpenLine, OpenError> {
    use tokio_serial::{SerialPort as _, SerialPortBuilderExt as _};
    line.validate().map_err(|reason| OpenError::Settings {
        path: path.to_owned(),
        reason,
    })?;
    let serial = |error: tokio_serial::Error| OpenError::Serial {
        path: path.to_owned(),
        reason: io::Error::from(error),
    };
    let parity = match line.parity {
        Parity::Even => tokio_serial::Parity::Even,
        Parity::Odd => tokio_serial::Parity::Odd,
        Parity::None => tokio_serial::Parity::None,
    };
    let stop_bits = if line.stop_bits == 2 {
        tokio_serial::StopBits::Two
    } else {
        tokio_serial::StopBits::One
    };
    let port = tokio_serial::new(path, line.baud)
        .data_bits(tokio_serial::DataBits::Eight)
        .parity(parity)
        .stop_bits(stop_bits)
        .flow_control(tokio_serial::FlowControl::None)
        .open_native_async()
        .map_err(serial)?;
    let kept = LineSettings {
        baud: port.baud_rate().map_err(serial)?,
        parity: match port.parity().map_err(serial)? {
            tokio_serial::Parity::Even => Parity::Even,
            tokio_serial::Parity::Odd => Parity::Odd,
            tokio_serial::Parity::None => Parity::None,
        },
        stop_bits: match port.stop_bits().map_err(serial)? {
            tokio_serial::StopBits::One => 1,
            tokio_serial::StopBits::Two => 2,
        },
    };
    let kept_data_bits = match port.data_bits().map_err(serial)? {
        tokio_serial::DataBits::Five => 5,
        tokio_serial::DataBits::Six => 6,
        tokio_serial::DataBits::Seven => 7,
        tokio_serial::DataBits::Eight => 8,
    };
    if let Some(refused) = line.refused_by(&kept, kept_data_bits) {
        return Err(OpenError::Refused {
            path: path.to_owned(),
            refused,
        });
    }
    Ok(OpenLine {
        stream: Box::pin(port),
        pty_path: None,
        peer: path.to_owned(),
        _pty_peer_end: None,
    })
}

/// Something to do to the endpoint from outside the loop (a command, a request).
pub type EndpointAction<E> = Box<dyn FnOnce(&mut E) + Send>;

/// Why [`drive`] returned.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DriveEnd {
    /// The observer asked to stop.
    Stopped,
    /// The peer closed the stream.
    Closed,
}

/// Runs `endpoint` on `stream` until the observer breaks, the stream closes or fails.
///
/// After every wake-up (octets, a deadline, an action) `observe` sees the endpoint, to
/// take its events; then everything the endpoint has to send is written. Read and
/// write errors end the loop with the error; a pseudo-terminal whose other end is not
/// open yet reads as an error on some systems, so the caller decides whether to retry.
pub async fn drive<E: LineEndpoint>(
    mut stream: Pin<Box<dyn LineStream>>,
    endpoint: &mut E,
    actions: &mut mpsc::UnboundedReceiver<EndpointAction<E>>,
    mut observe: impl FnMut(&mut E) -> ControlFlow<()>,
) -> io::Result<DriveEnd> {
    let line = endpoint.line();
    // A frame may not pause inside; allow the scheduling jitter of a busy machine and a
    // USB adapter on top of four character times.
    let pause = line.transmit_time(4) + Duration::from_millis(50);
    let mut buf = [0u8; 1024];
    let mut pause_at: Option<Instant> = None;
    let mut actions_open = true;
    loop {
        let now = Instant::now();
        endpoint.handle_timeout(now.into_std());
        if observe(endpoint).is_break() {
            return Ok(DriveEnd::Stopped);
        }
        while let Some(bytes) = endpoint.poll_transmit(Instant::now().into_std()) {
            stream.write_all(&bytes).await?;
            stream.flush().await?;
        }
        if observe(endpoint).is_break() {
            return Ok(DriveEnd::Stopped);
        }
        let deadline = endpoint.next_deadline().map(Instant::from_std);
        let wake = match (deadline, pause_at) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
        tokio::select! {
            read = stream.read(&mut buf) => {
                let count = read?;
                if count == 0 {
                    return Ok(DriveEnd::Closed);
                }
                let now = Instant::now();
                endpoint.handle_bytes(now.into_std(), buf.get(..count).unwrap_or_default());
                pause_at = Some(now + pause);
            }
            _ = sleep_until(wake) => {
                let now = Instant::now();
                if pause_at.is_some_and(|at| at <= now) {
                    endpoint.handle_line_pause(now.into_std());
                    pause_at = None;
                }
            }
            () = std::future::poll_fn(|context| endpoint.poll_wake(context)) => {}
            action = actions.recv(), if actions_open => {
                match action {
                    Some(action) => action(endpoint),
                    None => actions_open = false,
                }
            }
        }
    }
}

async fn sleep_until(at: Option<Instant>) {
    match at {
        Some(at) => tokio::time::sleep_until(at).await,
        None => std::future::pending().await,
    }
}
