//! A Modbus client (master) with timeouts and retries, over any transport of the
//! serial-line crate: Modbus TCP to a server, RTU over a serial port, a pseudo-terminal
//! or a terminal server's TCP port.
//!
//! The framing and the exchange are tokio-modbus's (`tokio_modbus::client::tcp` and
//! `::rtu`, attached to the line's stream); what is added here is what it leaves to its
//! caller: a timeout per attempt and repeats, the frame gap an RTU master keeps before
//! its next request, reopening a transport whose stream failed, checking that an answer
//! has the counts and echoes of its request, and errors that name the peer, the unit and
//! the time.

use std::borrow::Cow;
use std::fmt;
use std::io;
use std::pin::Pin;
use std::task::{Context as TaskContext, Poll};
use std::time::Duration;

use serial_line::io::{OpenError, OpenLine, Transport};
use serial_line::LineSettings;
use thiserror::Error;
use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};
use tokio::time::Instant;
use tokio_modbus::client::{Client as _, Context};
use tokio_modbus::slave::{Slave, SlaveContext as _};

use crate::model::{Table, Values};
use crate::pdu::{ExceptionCode, FunctionCode, PduError, Request, Response};
use crate::rtu::{frame_gap, DEFAULT_LINE};
use crate::server::Framing;

/// How a client talks.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub struct ClientConfig {
    /// Modbus TCP (MBAP) or RTU (CRC) frames.
    pub framing: Framing,
    /// How long an attempt waits for its answer.
    pub timeout: Duration,
    /// Repeats of a request that got no answer (or a garbled one).
    pub retries: u8,
    /// The serial line's settings, for the RTU frame gap (and for opening a serial port).
    pub line: LineSettings,
}

impl Default for ClientConfig {
    /// Modbus TCP, 1 s, 2 repeats.
    fn default() -> Self {
        ClientConfig {
            framing: Framing::Tcp,
            timeout: Duration::from_secs(1),
            retries: 2,
            line: DEFAULT_LINE,
        }
    }
}

impl ClientConfig {
    /// Modbus TCP with the default timeout and repeats.
    pub fn tcp() -> ClientConfig {
        ClientConfig::default()
    }

    /// RTU on a line of `line`'s settings with the default timeout and repeats.
    pub fn rtu(line: LineSettings) -> ClientConfig {
        ClientConfig {
            framing: Framing::Rtu,
            line,
            ..ClientConfig::default()
        }
    }
}

/// Why a request got no answer that could be used.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ClientError {
    /// The transport did not open (a refused setting is named).
    #[error(transparent)]
    Open(#[from] OpenError),
    /// A request outside its function's limits; it was not sent.
    #[error("request not sent: {0}")]
    Request(PduError),
    /// The server answered with an exception.
    #[error("unit {unit} on {peer} answered {function} with exception {code}")]
    Exception {
        /// The peer.
        peer: String,
        /// The unit asked.
        unit: u8,
        /// The request's function.
        function: FunctionCode,
        /// The exception.
        code: ExceptionCode,
    },
    /// No answer within the timeout, every attempt.
    #[error("no answer from unit {unit} on {peer} within {} ({attempts} attempt{})", DurationText(*timeout), if *attempts == 1 { "" } else { "s" })]
    Timeout {
        /// The peer.
        peer: String,
        /// The unit asked.
        unit: u8,
        /// The timeout of each attempt.
        timeout: Duration,
        /// How many were made.
        attempts: u32,
    },
    /// Answers that did not answer the request (another unit's, another function's, other
    /// counts), every attempt.
    #[error("unit {unit} on {peer}: {reason}")]
    Protocol {
        /// The peer.
        peer: String,
        /// The unit asked.
        unit: u8,
        /// What was wrong with the last one.
        reason: String,
    },
    /// The stream failed (and could not be reopened).
    #[error("{peer}: {reason}")]
    Io {
        /// The peer.
        peer: String,
        /// The system's reason.
        reason: io::Error,
    },
}

/// A duration as people write it: `300ms`, `1s`, `1.5s`.
struct DurationText(Duration);

impl fmt::Display for DurationText {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let millis = self.0.as_millis();
        if millis < 1000 || millis % 100 != 0 {
            write!(f, "{millis}ms")
        } else if millis % 1000 == 0 {
            write!(f, "{}s", millis / 1000)
        } else {
            write!(f, "{}.{}s", millis / 1000, (millis % 1000) / 100)
        }
    }
}

/// A line's stream as tokio-modbus takes it (`Debug`); the whole [`OpenLine`] is kept,
/// so that a pseudo-terminal's other end stays open.
struct LineIo(OpenLine);

impl fmt::Debug for LineIo {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.0.fmt(f)
    }
}

impl AsyncRead for LineIo {
    fn poll_read(
        self: Pin<&mut Self>,
        context: &mut TaskContext<'_>,
        buf: &mut ReadBuf<'_>,
    ) -> Poll<io::Result<()>> {
        self.get_mut().0.stream.as_mut().poll_read(context, buf)
    }
}

impl AsyncWrite for LineIo {
    fn poll_write(
        self: Pin<&mut Self>,
        context: &mut TaskContext<'_>,
        buf: &[u8],
    ) -> Poll<io::Result<usize>> {
        self.get_mut().0.stream.as_mut().poll_write(context, buf)
    }

    fn poll_flush(self: Pin<&mut Self>, context: &mut TaskContext<'_>) -> Poll<io::Result<()>> {
        self.get_mut().0.stream.as_mut().poll_flush(context)
    }

    fn poll_shutdown(self: Pin<&mut Self>, context: &mut TaskContext<'_>) -> Poll<io::Result<()>> {
        self.get_mut().0.stream.as_mut().poll_shutdown(context)
    }
}

/// A Modbus client on one line or connection; one request at a time.
pub struct Client {
    context: Option<Context>,
    /// What to reopen after the stream failed (`None` for an attached line).
    transport: Option<Transport>,
    peer: String,
    config: ClientConfig,
    /// RTU: no request before the frame gap after the last exchange.
    quiet_until: Option<Instant>,
}

impl fmt::Debug for Client {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Client")
            .field("peer", &self.peer)
            .field("config", &self.config)
            .field("connected", &self.context.is_some())
            .finish_non_exhaustive()
    }
}

impl Client {
    /// Opens `transport` (a serial port with `config.line`'s settings, checked as the
    /// serial-line crate checks them; a TCP connection) and attaches a client to it. A
    /// stream that fails later is reopened by the next attempt.
    pub async fn open(transport: Transport, config: ClientConfig) -> Result<Client, ClientError> {
        let line = transport.open().await?;
        let mut client = Client::attach(line, config);
        client.peer = transport.to_string();
        client.transport = Some(transport);
        Ok(client)
    }

    /// A client on a line already open (a pseudo-terminal's end, an accepted
    /// connection); it is not reopened when it fails.
    pub fn attach(line: OpenLine, config: ClientConfig) -> Client {
        let peer = line.peer.clone();
        Client {
            context: Some(Self::context_on(line, config.framing)),
            transport: None,
            peer,
            config,
            quiet_until: None,
        }
    }

    fn context_on(line: OpenLine, framing: Framing) -> Context {
        let io = LineIo(line);
        match framing {
            Framing::Tcp => tokio_modbus::client::tcp::attach_slave(io, Slave(1)),
            Framing::Rtu => tokio_modbus::client::rtu::attach_slave(io, Slave(1)),
        }
    }

    /// What the client talks to (`tcp 10.0.0.5:502`, `serial /dev/ttyUSB0 19200 Bd 8E1`).
    pub fn peer(&self) -> &str {
        &self.peer
    }

    /// The configuration.
    pub fn config(&self) -> &ClientConfig {
        &self.config
    }

    /// Reads `count` entries of `table` from `address` (FC 1-4).
    pub async fn read(
        &mut self,
        unit: u8,
        table: Table,
        address: u16,
        count: u16,
    ) -> Result<Values, ClientError> {
        let response = self
            .call(unit, &Request::read(table, address, count))
            .await?;
        response.values().ok_or_else(|| ClientError::Protocol {
            peer: self.peer.clone(),
            unit,
            reason: "a read answered without values".to_owned(),
        })
    }

    /// Writes coils from `address`: FC 5 for one value, FC 15 for several.
    pub async fn write_coils(
        &mut self,
        unit: u8,
        address: u16,
        values: &[bool],
    ) -> Result<(), ClientError> {
        let request = match values {
            [value] => Request::WriteSingleCoil {
                address,
                value: *value,
            },
            _ => Request::WriteMultipleCoils {
                address,
                values: values.to_vec(),
            },
        };
        self.call(unit, &request).await.map(|_| ())
    }

    /// Writes holding registers from `address`: FC 6 for one value, FC 16 for several.
    pub async fn write_registers(
        &mut self,
        unit: u8,
        address: u16,
        values: &[u16],
    ) -> Result<(), ClientError> {
        let request = match values {
            [value] => Request::WriteSingleRegister {
                address,
                value: *value,
            },
            _ => Request::WriteMultipleRegisters {
                address,
                values: values.to_vec(),
            },
        };
        self.call(unit, &request).await.map(|_| ())
    }

    /// Writes holding registers from `write_address`, then reads `read_count` from
    /// `read_address`, in one request (FC 23).
    pub async fn read_write_registers(
        &mut self,
        unit: u8,
        read_address: u16,
        read_count: u16,
        write_address: u16,
        values: &[u16],
    ) -> Result<Vec<u16>, ClientError> {
        let request = Request::ReadWriteMultipleRegisters {
            read_address,
            read_count,
            write_address,
            values: values.to_vec(),
        };
        match self.call(unit, &request).await? {
            Response::ReadWriteMultipleRegisters(values) => Ok(values),
            _ => Err(ClientError::Protocol {
                peer: self.peer.clone(),
                unit,
                reason: "FC 23 answered without registers".to_owned(),
            }),
        }
    }

    /// Sends a request of a function code that is not one of the supported ones (a
    /// device's own, diagnostics, device identification): `data` follows the function
    /// code; the answer's octets after its function code are returned, or its exception.
    /// Timeouts and repeats as for [`Client::call`]. Over RTU the answer is taken to end
    /// where the octets read at once end (its length is not known here).
    pub async fn call_custom(
        &mut self,
        unit: u8,
        function: u8,
        data: &[u8],
    ) -> Result<Vec<u8>, ClientError> {
        if function == 0
            || function >= 0x80
            || FunctionCode::SUPPORTED.contains(&FunctionCode(function))
        {
            return Err(ClientError::Request(PduError::UnsupportedFunction(
                function,
            )));
        }
        let outgoing = tokio_modbus::Request::Custom(function, Cow::Owned(data.to_vec()));
        match self
            .exchange(unit, FunctionCode(function), outgoing)
            .await?
        {
            tokio_modbus::Response::Custom(got, octets) if got == function => Ok(octets.to_vec()),
            other => Err(ClientError::Protocol {
                peer: self.peer.clone(),
                unit,
                reason: format!(
                    "an answer of FC {} to FC {function}",
                    other.function_code().value()
                ),
            }),
        }
    }

    /// Sends `request` to `unit` and waits for its answer: up to `retries` repeats after
    /// a timeout, a garbled answer or one that is not the request's; an exception is an
    /// answer and is not repeated.
    pub async fn call(&mut self, unit: u8, request: &Request) -> Result<Response, ClientError> {
        request.validate().map_err(ClientError::Request)?;
        let response = self
            .exchange(unit, request.function(), to_tokio_modbus(request))
            .await?;
        from_tokio_modbus(request, response).map_err(|reason| ClientError::Protocol {
            peer: self.peer.clone(),
            unit,
            reason,
        })
    }

    /// One request and its answer through tokio-modbus, with the timeouts and repeats.
    async fn exchange(
        &mut self,
        unit: u8,
        function: FunctionCode,
        outgoing: tokio_modbus::Request<'static>,
    ) -> Result<tokio_modbus::Response, ClientError> {
        let attempts = u32::from(self.config.retries) + 1;
        let mut failure = None;
        for attempt in 1..=attempts {
            let context = match self.context.take() {
                Some(context) => context,
                None => match &self.transport {
                    Some(transport) => {
                        tracing::debug!(peer = %self.peer, "reopening");
                        match transport.open().await {
                            Ok(line) => Self::context_on(line, self.config.framing),
                            Err(error) => return Err(ClientError::Open(error)),
                        }
                    }
                    None => {
                        return Err(failure.unwrap_or_else(|| ClientError::Io {
                            peer: self.peer.clone(),
                            reason: io::Error::from(io::ErrorKind::NotConnected),
                        }))
                    }
                },
            };
            let mut context = context;
            if let Some(quiet_until) = self.quiet_until {
                tokio::time::sleep_until(quiet_until).await;
            }
            context.set_slave(Slave(unit));
            let result =
                tokio::time::timeout(self.config.timeout, context.call(outgoing.clone())).await;
            if self.config.framing == Framing::Rtu {
                self.quiet_until = Some(Instant::now() + frame_gap(&self.config.line));
            }
            match result {
                Err(_elapsed) => {
                    tracing::debug!(peer = %self.peer, unit, attempt, "no answer");
                    self.context = Some(context);
                    failure = Some(ClientError::Timeout {
                        peer: self.peer.clone(),
                        unit,
                        timeout: self.config.timeout,
                        attempts: attempt,
                    });
                }
                Ok(Ok(Ok(response))) => {
                    self.context = Some(context);
                    return Ok(response);
                }
                Ok(Ok(Err(exception))) => {
                    self.context = Some(context);
                    return Err(ClientError::Exception {
                        peer: self.peer.clone(),
                        unit,
                        function,
                        code: ExceptionCode(u8::from(exception)),
                    });
                }
                // pymodbus 3.16 answers a function it does not know with `80 01`: the
                // exception of function 0. It is the exception all the same.
                Ok(Err(tokio_modbus::Error::Protocol(
                    tokio_modbus::ProtocolError::FunctionCodeMismatch {
                        result: Err(exception),
                        ..
                    },
                ))) if exception.function.value() == 0 => {
                    self.context = Some(context);
                    return Err(ClientError::Exception {
                        peer: self.peer.clone(),
                        unit,
                        function,
                        code: ExceptionCode(u8::from(exception.exception)),
                    });
                }
                Ok(Err(tokio_modbus::Error::Protocol(error))) => {
                    tracing::debug!(peer = %self.peer, unit, attempt, %error, "answer not the request's");
                    self.context = Some(context);
                    failure = Some(ClientError::Protocol {
                        peer: self.peer.clone(),
                        unit,
                        reason: protocol_reason(&error),
                    });
                }
                Ok(Err(tokio_modbus::Error::Transport(error))) => {
                    // The framed stream ends after an error: a new one is needed.
                    tracing::debug!(peer = %self.peer, unit, attempt, %error, "stream failed");
                    drop(context);
                    failure = Some(ClientError::Io {
                        peer: self.peer.clone(),
                        reason: error,
                    });
                }
            }
        }
        Err(failure.unwrap_or_else(|| ClientError::Timeout {
            peer: self.peer.clone(),
            unit,
            timeout: self.config.timeout,
            attempts,
        }))
    }
}

fn protocol_reason(error: &tokio_modbus::ProtocolError) -> String {
    match error {
        tokio_modbus::ProtocolError::HeaderMismatch { message, .. } => {
            format!("an answer of another unit or transaction ({message})")
        }
        tokio_modbus::ProtocolError::FunctionCodeMismatch { request, .. } => {
            format!("an answer of another function than FC {request}")
        }
    }
}

fn to_tokio_modbus(request: &Request) -> tokio_modbus::Request<'static> {
    use tokio_modbus::Request as T;
    match request {
        Request::Read {
            table,
            address,
            count,
        } => match table {
            Table::Coils => T::ReadCoils(*address, *count),
            Table::DiscreteInputs => T::ReadDiscreteInputs(*address, *count),
            Table::HoldingRegisters => T::ReadHoldingRegisters(*address, *count),
            Table::InputRegisters => T::ReadInputRegisters(*address, *count),
        },
        Request::WriteSingleCoil { address, value } => T::WriteSingleCoil(*address, *value),
        Request::WriteSingleRegister { address, value } => T::WriteSingleRegister(*address, *value),
        Request::WriteMultipleCoils { address, values } => {
            T::WriteMultipleCoils(*address, Cow::Owned(values.clone()))
        }
        Request::WriteMultipleRegisters { address, values } => {
            T::WriteMultipleRegisters(*address, Cow::Owned(values.clone()))
        }
        Request::ReadWriteMultipleRegisters {
            read_address,
            read_count,
            write_address,
            values,
        } => T::ReadWriteMultipleRegisters(
            *read_address,
            *read_count,
            *write_address,
            Cow::Owned(values.clone()),
        ),
    }
}

/// tokio-modbus's response as this crate's, held to the request's counts and echoes
/// (tokio-modbus checks the function code and the header only).
fn from_tokio_modbus(
    request: &Request,
    response: tokio_modbus::Response,
) -> Result<Response, String> {
    use tokio_modbus::Response as T;
    let bits = |mut bits: Vec<bool>, count: u16| {
        let count = usize::from(count);
        if bits.len() < count || bits.len() >= count + 8 {
            return Err(format!("{} bits answered, {count} asked", bits.len()));
        }
        bits.truncate(count);
        Ok(bits)
    };
    let registers = |registers: Vec<u16>, count: u16| {
        if registers.len() != usize::from(count) {
            return Err(format!(
                "{} registers answered, {count} asked",
                registers.len()
            ));
        }
        Ok(registers)
    };
    let echo = |same: bool, what: &str| {
        if same {
            Ok(())
        } else {
            Err(format!("the answer's {what} is not the request's"))
        }
    };
    Ok(match (request, response) {
        (Request::Read { count, .. }, T::ReadCoils(values)) => {
            Response::ReadCoils(bits(values, *count)?)
        }
        (Request::Read { count, .. }, T::ReadDiscreteInputs(values)) => {
            Response::ReadDiscreteInputs(bits(values, *count)?)
        }
        (Request::Read { count, .. }, T::ReadHoldingRegisters(values)) => {
            Response::ReadHoldingRegisters(registers(values, *count)?)
        }
        (Request::Read { count, .. }, T::ReadInputRegisters(values)) => {
            Response::ReadInputRegisters(registers(values, *count)?)
        }
        (Request::WriteSingleCoil { address, value }, T::WriteSingleCoil(got_address, got)) => {
            echo(*address == got_address && *value == got, "echo")?;
            Response::WriteSingleCoil {
                address: *address,
                value: *value,
            }
        }
        (
            Request::WriteSingleRegister { address, value },
            T::WriteSingleRegister(got_address, got),
        ) => {
            echo(*address == got_address && *value == got, "echo")?;
            Response::WriteSingleRegister {
                address: *address,
                value: *value,
            }
        }
        (
            Request::WriteMultipleCoils { address, values },
            T::WriteMultipleCoils(got_address, count),
        ) => {
            echo(
                *address == got_address && usize::from(count) == values.len(),
                "address or quantity",
            )?;
            Response::WriteMultipleCoils {
                address: *address,
                count,
            }
        }
        (
            Request::WriteMultipleRegisters { address, values },
            T::WriteMultipleRegisters(got_address, count),
        ) => {
            echo(
                *address == got_address && usize::from(count) == values.len(),
                "address or quantity",
            )?;
            Response::WriteMultipleRegisters {
                address: *address,
                count,
            }
        }
        (
            Request::ReadWriteMultipleRegisters { read_count, .. },
            T::ReadWriteMultipleRegisters(values),
        ) => Response::ReadWriteMultipleRegisters(registers(values, *read_count)?),
        (request, response) => {
            return Err(format!(
                "an answer of FC {} to {}",
                response.function_code().value(),
                request.function()
            ))
        }
    })
}
