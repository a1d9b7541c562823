//! The control system's side of IEC 103, sans-IO: an FT1.2 primary that starts each
//! protection device it finds (time synchronisation, general interrogation), sends
//! general commands and follows their acknowledgements, and hands up every ASDU
//! decoded.

use std::collections::VecDeque;
use std::task::{Context, Poll};
use std::time::{Duration, Instant};

use chrono::NaiveDateTime;

use super::asdu::{Asdu, Body, DecodeError, Direction, FUN_GLOBAL};
use super::cause::Cause;
use super::disturbance::{DisturbanceReceiver, DisturbanceRecord, ReceiverStep, TOO_REQUEST_LIST};
use crate::ft12::{Answer, LineEndpoint, LineSettings, Primary, PrimaryError, PrimaryEvent};
use crate::time::Cp56Time2a;

/// What the master does when a device's link comes up.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StartUp {
    /// Synchronise the device's clock (ASDU 6, addressed, confirmed by the device).
    pub clock_sync: bool,
    /// Start a general interrogation (ASDU 7).
    pub interrogate: bool,
    /// Upload the disturbance records a device announces (ASDU 23) and ask for its
    /// list at start.
    pub disturbances: bool,
}

/// What the master saw.
#[derive(Debug, Clone, PartialEq)]
pub enum MasterEvent {
    /// An ASDU from a device.
    Asdu {
        /// The device's link address.
        address: u16,
        /// The ASDU.
        asdu: Asdu,
    },
    /// Octets from a device that are no 103 ASDU.
    Undecodable {
        /// The device's link address.
        address: u16,
        /// Why.
        error: DecodeError,
        /// The octets.
        raw: Vec<u8>,
    },
    /// A general interrogation ended (ASDU 8 with its scan number).
    InterrogationComplete {
        /// The device.
        address: u16,
        /// The scan number.
        scn: u8,
    },
    /// A general command was acknowledged (ASDU 1, COT 20) or refused (COT 21), or
    /// went unanswered (`positive: false, timed_out: true`).
    CommandResult {
        /// The device.
        address: u16,
        /// Function type.
        fun: u8,
        /// Information number.
        inf: u8,
        /// The return information identifier.
        rii: u8,
        /// Acknowledged positively.
        positive: bool,
        /// No acknowledgement within the command timeout.
        timed_out: bool,
    },
    /// A disturbance record uploaded completely.
    Disturbance {
        /// The device.
        address: u16,
        /// The record.
        record: Box<DisturbanceRecord>,
    },
    /// Everything on the link layer: exchanges, timeouts, link up and down, errors.
    Link(PrimaryEvent),
}

/// The clock a master synchronises devices to.
pub type Clock = Box<dyn FnMut() -> NaiveDateTime + Send>;

#[derive(Debug, Clone, Copy)]
struct PendingCommand {
    address: u16,
    fun: u8,
    inf: u8,
    rii: u8,
    deadline: Instant,
}

/// An IEC 103 master of one line.
pub struct Master {
    primary: Primary,
    start_up: StartUp,
    clock: Clock,
    scan_number: u8,
    return_information: u8,
    command_timeout: Duration,
    commands: Vec<PendingCommand>,
    disturbances: std::collections::HashMap<u16, DisturbanceReceiver>,
    events: VecDeque<MasterEvent>,
    now: Instant,
}

impl std::fmt::Debug for Master {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Master")
            .field("primary", &self.primary)
            .field("start_up", &self.start_up)
            .finish_non_exhaustive()
    }
}

impl Master {
    /// A master over `primary`.
    pub fn new(primary: Primary, start_up: StartUp, clock: Clock, now: Instant) -> Master {
        Master {
            primary,
            start_up,
            clock,
            scan_number: 0,
            return_information: 0,
            command_timeout: Duration::from_secs(10),
            commands: Vec::new(),
            disturbances: std::collections::HashMap::new(),
            events: VecDeque::new(),
            now,
        }
    }

    /// How long a general command waits for its acknowledgement (10 s by default).
    pub fn set_command_timeout(&mut self, timeout: Duration) {
        self.command_timeout = timeout;
    }

    /// Adds a device (link address = common address).
    pub fn add_device(&mut self, address: u8) -> Result<(), PrimaryError> {
        self.primary.add_station(address.into())
    }

    /// The link layer (single telegrams, statistics, link states).
    pub fn primary(&mut self) -> &mut Primary {
        &mut self.primary
    }

    /// The next event.
    pub fn poll_event(&mut self) -> Option<MasterEvent> {
        self.events.pop_front()
    }

    fn send(&mut self, address: u16, asdu: &Asdu) -> Result<(), PrimaryError> {
        let bytes = asdu
            .to_bytes()
            .map_err(|_| PrimaryError::BadAddress(address))?;
        self.primary.send(address, bytes)
    }

    /// Starts a general interrogation of a device; returns its scan number.
    pub fn general_interrogation(&mut self, address: u8) -> Result<u8, PrimaryError> {
        self.scan_number = self.scan_number.wrapping_add(1);
        let scn = self.scan_number;
        let asdu = Asdu::new(
            7,
            Cause::GENERAL_INTERROGATION,
            address,
            FUN_GLOBAL,
            0,
            Body::GiInitiation { scn },
        );
        self.send(address.into(), &asdu)?;
        Ok(scn)
    }

    /// Synchronises a device's clock to `time` (confirmed by the device with ASDU 6
    /// COT 8), or every device's with one broadcast (`address` None, no answer).
    pub fn clock_sync(
        &mut self,
        address: Option<u8>,
        time: NaiveDateTime,
    ) -> Result<(), PrimaryError> {
        let time = Cp56Time2a::from_naive(time).map_err(|_| PrimaryError::BadAddress(0))?;
        let asdu = Asdu::new(
            6,
            Cause::TIME_SYNC,
            address.unwrap_or(0xFF),
            FUN_GLOBAL,
            0,
            Body::TimeSync { time },
        );
        match address {
            Some(address) => self.send(address.into(), &asdu),
            None => self.primary.broadcast(
                asdu.to_bytes()
                    .map_err(|_| PrimaryError::BadAddress(0xFF))?,
            ),
        }
    }

    /// Sends a general command (ASDU 20, ON or OFF) to FUN/INF of a device; its result
    /// comes as [`MasterEvent::CommandResult`]. Returns the return information
    /// identifier.
    pub fn general_command(
        &mut self,
        address: u8,
        fun: u8,
        inf: u8,
        on: bool,
    ) -> Result<u8, PrimaryError> {
        self.return_information = self.return_information.wrapping_add(1);
        let rii = self.return_information;
        let asdu = Asdu::new(
            20,
            Cause::COMMAND_ACK,
            address,
            fun,
            inf,
            Body::GeneralCommand {
                dco: if on { 2 } else { 1 },
                rii,
            },
        );
        self.send(address.into(), &asdu)?;
        self.commands.push(PendingCommand {
            address: address.into(),
            fun,
            inf,
            rii,
            deadline: self.now + self.command_timeout,
        });
        Ok(rii)
    }

    /// Sends any ASDU to a device (generic services, disturbance orders).
    pub fn send_asdu(&mut self, address: u8, asdu: &Asdu) -> Result<(), PrimaryError> {
        self.send(address.into(), asdu)
    }

    fn process(&mut self) {
        let mut started = Vec::new();
        while let Some(event) = self.primary.poll_event() {
            match &event {
                PrimaryEvent::LinkUp { address } => started.push(*address),
                PrimaryEvent::LinkDown { address } => {
                    // Their acknowledgements will not come: the device was reset.
                    let (lost, kept): (Vec<_>, Vec<_>) = self
                        .commands
                        .drain(..)
                        .partition(|command| command.address == *address);
                    self.commands = kept;
                    for command in lost {
                        self.command_result(command, false, true);
                    }
                }
                PrimaryEvent::Exchange {
                    address,
                    answer: Answer::UserData(bytes),
                    ..
                } => self.received(*address, bytes),
                _ => {}
            }
            self.events.push_back(MasterEvent::Link(event));
        }
        for address in started {
            let Ok(device) = u8::try_from(address) else {
                continue;
            };
            if self.start_up.clock_sync {
                let time = (self.clock)();
                let _ = self.clock_sync(Some(device), time);
            }
            if self.start_up.interrogate {
                let _ = self.general_interrogation(device);
            }
            if self.start_up.disturbances {
                let list = Asdu::new(
                    24,
                    Cause::DISTURBANCE_DATA,
                    device,
                    FUN_GLOBAL,
                    0,
                    Body::DisturbanceOrder {
                        too: TOO_REQUEST_LIST,
                        tov: 0,
                        fan: 0,
                        acc: 0,
                    },
                );
                let _ = self.send_asdu(device, &list);
            }
        }
    }

    fn received(&mut self, address: u16, bytes: &[u8]) {
        let asdu = match Asdu::decode(bytes, Direction::Monitor) {
            Ok(asdu) => asdu,
            Err(error) => {
                self.events.push_back(MasterEvent::Undecodable {
                    address,
                    error,
                    raw: bytes.to_vec(),
                });
                return;
            }
        };
        match (&asdu.body, asdu.header.cause) {
            (Body::GiTermination { scn }, _) => {
                self.events.push_back(MasterEvent::Asdu {
                    address,
                    asdu: asdu.clone(),
                });
                self.events
                    .push_back(MasterEvent::InterrogationComplete { address, scn: *scn });
                return;
            }
            (Body::TimeTagged { sin, .. }, Cause::COMMAND_ACK | Cause::COMMAND_NACK) => {
                let positive = asdu.header.cause == Cause::COMMAND_ACK;
                let position = self.commands.iter().position(|command| {
                    command.address == address
                        && command.rii == *sin
                        && command.fun == asdu.header.fun
                        && command.inf == asdu.header.inf
                });
                self.events.push_back(MasterEvent::Asdu {
                    address,
                    asdu: asdu.clone(),
                });
                if let Some(position) = position {
                    let command = self.commands.remove(position);
                    self.command_result(command, positive, false);
                }
                return;
            }
            _ => {}
        }
        if self.start_up.disturbances && (23..=31).contains(&asdu.header.type_id) {
            let reference = (self.clock)();
            let step = self
                .disturbances
                .entry(address)
                .or_default()
                .handle(&asdu, reference);
            self.events.push_back(MasterEvent::Asdu { address, asdu });
            let reply = match step {
                ReceiverStep::Wait => return,
                ReceiverStep::Send(reply) => reply,
                ReceiverStep::Complete(record, reply) => {
                    self.events
                        .push_back(MasterEvent::Disturbance { address, record });
                    reply
                }
            };
            if let Ok(bytes) = reply.to_bytes() {
                let _ = self.primary.send(address, bytes);
            }
            return;
        }
        self.events.push_back(MasterEvent::Asdu { address, asdu });
    }

    fn command_result(&mut self, command: PendingCommand, positive: bool, timed_out: bool) {
        self.events.push_back(MasterEvent::CommandResult {
            address: command.address,
            fun: command.fun,
            inf: command.inf,
            rii: command.rii,
            positive,
            timed_out,
        });
    }

    fn expire_commands(&mut self, now: Instant) {
        self.now = now;
        let (expired, kept): (Vec<_>, Vec<_>) = self
            .commands
            .drain(..)
            .partition(|command| command.deadline <= now);
        self.commands = kept;
        for command in expired {
            self.command_result(command, false, true);
        }
    }
}

impl LineEndpoint for Master {
    fn handle_bytes(&mut self, now: Instant, bytes: &[u8]) {
        self.now = now;
        self.primary.handle_bytes(now, bytes);
        self.process();
    }

    fn handle_line_pause(&mut self, now: Instant) {
        self.primary.handle_line_pause(now);
        self.process();
    }

    fn handle_timeout(&mut self, now: Instant) {
        self.primary.handle_timeout(now);
        self.expire_commands(now);
        self.process();
    }

    fn poll_transmit(&mut self, now: Instant) -> Option<Vec<u8>> {
        let bytes = self.primary.poll_transmit(now);
        self.process();
        bytes
    }

    fn next_deadline(&self) -> Option<Instant> {
        self.primary
            .next_deadline()
            .into_iter()
            .chain(self.commands.iter().map(|command| command.deadline))
            .min()
    }

    fn line(&self) -> LineSettings {
        self.primary.config().line
    }

    fn poll_wake(&mut self, _context: &mut Context<'_>) -> Poll<()> {
        Poll::Pending
    }
}
