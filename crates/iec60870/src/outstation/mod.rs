//! The controlled station (outstation) without a transport: what an IEC 60870-5 slave
//! does whatever carries its ASDUs (IEC 104 over TCP, IEC 101 over an FT1.2 serial line,
//! a test or a fuzzer).
//!
//! # Shape
//!
//! ```text
//!  Outstation (shared by every link of the station)
//!   ├─ ProcessImage: the current value of every point; answers interrogation and read
//!   ├─ Groups: redundancy groups, each with its bounded event buffer
//!   ├─ selections (select-before-operate), the StationHandler (the application)
//!   └─ update()/set(): the application's values in, spontaneous events to every group
//!
//!  LinkCore (one per link: a TCP connection, a serial link)
//!   ASDU bytes in  ──> handle_asdu ──> answers, interrogation, commands to the handler
//!   fill(link)     ──> answers, then group events and interrogation data, as the link's
//!                      window allows (the `LinkLayer` trait: IEC 104's APCI session, the
//!                      FT1.2 link layer)
//!   poll_commands  ──> command outcomes: ACT_CON, return information, ACT_TERM in order
//! ```
//!
//! Nothing here reads a clock or touches a socket: time comes in as `Instant`s (and the
//! station's clock through [`StationHandler::now`]); links wait for their group's changes
//! with [`GroupChanges`], a plain `std` future.
//! The tokio adapters are `cs104::server` (and the serial slave to come).
//!
//! - [`image`]: the process image.
//! - [`group`]: redundancy groups ([`RedundancyMode`]) and their event buffers.
//! - [`handler`]: the application's hooks (commands, refusals, the station's clock, clock
//!   sync, reset, parameters, link news).
//! - `link`: the per-link core.
//!
//! # Commands
//!
//! A command is checked here first (known address, type, double-command state,
//! select-before-operate, the maximum command delay of a time-tagged command measured on
//! [`StationHandler::now`]); what fails gets its negative confirmation and goes to
//! [`StationHandler::command_refused`]. The rest go to
//! [`StationHandler::handle_command`], and the link keeps the standard's sequence whatever
//! the application does: ACT_CON, then the return information (cause 11) queued since the
//! command arrived, then ACT_TERM after every event queued before the application
//! terminated the command ([`CommandOutcome`]). Each event of a group carries a sequence
//! number for this.

pub mod group;
pub mod handler;
pub mod image;
mod link;

use std::collections::HashMap;
use std::fmt;
use std::net::{IpAddr, SocketAddr};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, RwLock};
use std::time::{Duration, Instant};

use crate::asdu::{
    AsduParams, Cause, CommonAddress, Element, InformationObject, Ioa, TimeTag, TypeId,
};
use crate::time::{Cp56Time2a, TimeZonePolicy};

pub use group::{GroupStats, OverflowPolicy, RedundancyGroupConfig, RedundancyMode};
pub use handler::{
    ready, Command, CommandFuture, CommandOutcome, CommandRefusal, ReadOnlyStation, StationHandler,
    TerminationFuture,
};
pub use image::{CommandPoint, ImageError, MonitorPoint, ProcessImage};
pub use link::{GroupChanges, LinkCore, LinkLayer};

use group::{Group, QueuedEvent};

/// The controlling station at the other end of a link.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum Peer {
    /// An IEC 104 client: its TCP address.
    Tcp(SocketAddr),
    /// A master on a serial line (IEC 101/103): the port and the link address.
    Serial {
        /// The serial port's name (`/dev/ttyS0`, `COM3`).
        port: Arc<str>,
        /// The link address of the station on that line.
        link_address: u16,
    },
}

impl Peer {
    /// The peer's IP address, for a TCP peer.
    pub fn ip(&self) -> Option<IpAddr> {
        match self {
            Peer::Tcp(address) => Some(address.ip().to_canonical()),
            Peer::Serial { .. } => None,
        }
    }

    /// The peer's socket address, for a TCP peer.
    pub fn socket_addr(&self) -> Option<SocketAddr> {
        match self {
            Peer::Tcp(address) => Some(*address),
            Peer::Serial { .. } => None,
        }
    }
}

impl From<SocketAddr> for Peer {
    fn from(address: SocketAddr) -> Self {
        Peer::Tcp(address)
    }
}

impl fmt::Display for Peer {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Peer::Tcp(address) => write!(f, "{address}"),
            Peer::Serial { port, link_address } => write!(f, "{port} link {link_address}"),
        }
    }
}

/// What an outstation does, whatever its transport.
#[derive(Debug, Clone)]
#[non_exhaustive]
pub struct OutstationConfig {
    /// The station's common address.
    pub common_address: CommonAddress,
    /// ASDU field sizes (IEC 104: COT 2, CA 2, IOA 3 octets; IEC 101 per project).
    pub asdu: AsduParams,
    /// How links form redundancy groups.
    pub redundancy: RedundancyMode,
    /// Events each redundancy group buffers.
    pub event_buffer_capacity: usize,
    /// What a full event buffer does.
    pub overflow_policy: OverflowPolicy,
    /// How long a selection (select-before-operate) waits for its execute.
    pub select_timeout: Duration,
    /// The largest age of a time-tagged command (the interoperability list's maximum
    /// command delay), measured on [`StationHandler::now`] with the time tag read in
    /// [`time_zone`](Self::time_zone): an older command, or one further in the future,
    /// gets a negative confirmation. A command point may set its own. `None`: not checked.
    pub max_command_age: Option<Duration>,
    /// Accept commands with cause 5 (request) as activation, as some gateways do
    /// (spec IEC-A3). Off by default: such commands get a negative confirmation with
    /// cause 45.
    pub accept_request_as_activation: bool,
    /// Send an end of initialisation (M_EI_NA_1) to the first started link.
    pub send_end_of_initialisation: bool,
    /// The zone of every time tag the outstation reads or stamps itself.
    pub time_zone: TimeZonePolicy,
}

impl OutstationConfig {
    /// The standard's defaults for a station with the given address and field sizes.
    pub fn new(common_address: CommonAddress, asdu: AsduParams) -> Self {
        Self {
            common_address,
            asdu,
            redundancy: RedundancyMode::SingleGroup,
            event_buffer_capacity: 100_000,
            overflow_policy: OverflowPolicy::DropOldest,
            select_timeout: Duration::from_secs(10),
            max_command_age: None,
            accept_request_as_activation: false,
            send_end_of_initialisation: true,
            time_zone: TimeZonePolicy::Utc,
        }
    }
}

/// Why an outstation could not be set up or a point update failed.
#[derive(Debug, thiserror::Error)]
pub enum OutstationError {
    /// The configuration is inconsistent.
    #[error("invalid outstation configuration: {0}")]
    Config(String),
    /// A point update did not fit the process image.
    #[error(transparent)]
    Image(#[from] ImageError),
}

/// A selection waiting for its execute.
#[derive(Debug, Clone)]
pub(crate) struct Selection {
    link: u64,
    originator: u8,
    type_id: TypeId,
    element: Element,
    deadline: Instant,
}

/// A controlled station's state, shared by its links: the process image, the redundancy
/// groups with their event buffers, the selections and the application.
pub struct Outstation {
    config: OutstationConfig,
    image: RwLock<ProcessImage>,
    /// The redundancy groups: fixed at start (one group, or the configured groups by
    /// address), or one per open link.
    groups: RwLock<Vec<Arc<Group>>>,
    /// Whether the end of initialisation still has to go to the first link's own group (a
    /// group per link: no group exists at start to queue it in).
    end_of_initialisation_pending: AtomicBool,
    handler: Arc<dyn StationHandler>,
    selections: Mutex<HashMap<u32, Selection>>,
}

impl fmt::Debug for Outstation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Outstation")
            .field("common_address", &self.config.common_address)
            .finish_non_exhaustive()
    }
}

impl Outstation {
    /// An outstation serving `image` for `handler`.
    pub fn new(
        config: OutstationConfig,
        image: ProcessImage,
        handler: Arc<dyn StationHandler>,
    ) -> Result<Self, OutstationError> {
        let groups: Vec<Arc<Group>> = match &config.redundancy {
            RedundancyMode::SingleGroup => vec![RedundancyGroupConfig::catch_all("default")],
            RedundancyMode::ConnectionIsGroup => Vec::new(),
            RedundancyMode::GroupsByAddress(groups) if groups.is_empty() => {
                return Err(OutstationError::Config(
                    "redundancy groups by client address need at least one group".to_owned(),
                ))
            }
            RedundancyMode::GroupsByAddress(groups) => groups.clone(),
        }
        .into_iter()
        .map(|group| {
            Arc::new(Group::new(
                group,
                config.event_buffer_capacity,
                config.overflow_policy,
            ))
        })
        .collect();
        if config.send_end_of_initialisation {
            for group in &groups {
                group.push(end_of_initialisation());
            }
        }
        let end_of_initialisation_pending = config.send_end_of_initialisation
            && config.redundancy == RedundancyMode::ConnectionIsGroup;
        Ok(Self {
            config,
            image: RwLock::new(image),
            groups: RwLock::new(groups),
            end_of_initialisation_pending: AtomicBool::new(end_of_initialisation_pending),
            handler,
            selections: Mutex::new(HashMap::new()),
        })
    }

    /// The outstation's configuration.
    pub fn config(&self) -> &OutstationConfig {
        &self.config
    }

    /// The application.
    pub fn handler(&self) -> &Arc<dyn StationHandler> {
        &self.handler
    }

    pub(crate) fn read_image(&self) -> std::sync::RwLockReadGuard<'_, ProcessImage> {
        self.image
            .read()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    fn write_image(&self) -> std::sync::RwLockWriteGuard<'_, ProcessImage> {
        self.image
            .write()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    pub(crate) fn lock_selections(&self) -> std::sync::MutexGuard<'_, HashMap<u32, Selection>> {
        self.selections
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    fn read_groups(&self) -> std::sync::RwLockReadGuard<'_, Vec<Arc<Group>>> {
        self.groups
            .read()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    fn write_groups(&self) -> std::sync::RwLockWriteGuard<'_, Vec<Arc<Group>>> {
        self.groups
            .write()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// The core of a new link from `peer`, numbered `id` (unique among the outstation's
    /// links), in its redundancy group: in a group per link a new group of its own;
    /// otherwise the first group naming its address, else the first catch-all group.
    /// `None` when no group takes the peer.
    pub fn open_link(self: &Arc<Self>, id: u64, peer: Peer) -> Option<LinkCore> {
        let group = self.group_for(&peer, id)?;
        Some(LinkCore::new(Arc::clone(self), id, group, peer))
    }

    /// Whether a redundancy group takes links from `peer` (see [`open_link`](Self::open_link)).
    pub fn takes(&self, peer: &Peer) -> bool {
        self.config.redundancy == RedundancyMode::ConnectionIsGroup
            || self
                .read_groups()
                .iter()
                .any(|group| group.is_catch_all() || peer.ip().is_some_and(|ip| group.accepts(ip)))
    }

    fn group_for(&self, peer: &Peer, id: u64) -> Option<Arc<Group>> {
        if self.config.redundancy == RedundancyMode::ConnectionIsGroup {
            let group = Arc::new(Group::new(
                RedundancyGroupConfig::new(
                    format!("connection-{id}"),
                    peer.ip().into_iter().collect(),
                ),
                self.config.event_buffer_capacity,
                self.config.overflow_policy,
            ));
            if self
                .end_of_initialisation_pending
                .swap(false, Ordering::Relaxed)
            {
                group.push(end_of_initialisation());
            }
            self.write_groups().push(Arc::clone(&group));
            return Some(group);
        }
        let groups = self.read_groups();
        groups
            .iter()
            .find(|group| peer.ip().is_some_and(|ip| group.accepts(ip)))
            .or_else(|| groups.iter().find(|group| group.is_catch_all()))
            .cloned()
    }

    /// Forgets a link's own group when the link ends (a group per link).
    pub(crate) fn release_link_group(&self, group: &Arc<Group>) {
        if self.config.redundancy == RedundancyMode::ConnectionIsGroup {
            self.write_groups()
                .retain(|other| !Arc::ptr_eq(other, group));
        }
    }

    /// The station's time as a time tag in the outstation's zone.
    pub(crate) fn now_time_tag(&self) -> Cp56Time2a {
        self.config.time_zone.to_cp56(self.handler.now())
    }

    /// Sets a point's value and queues it spontaneously (cause 3) for every redundancy
    /// group. A point whose type carries a time tag and is given none is stamped now.
    pub fn update(
        &self,
        ioa: Ioa,
        element: Element,
        time: Option<Cp56Time2a>,
    ) -> Result<(), OutstationError> {
        self.update_with_cause(ioa, element, time, Cause::SPONTANEOUS)
    }

    /// As [`update`](Self::update), with another cause: 1 periodic, 11 return information
    /// after a remote command, 12 after a local command.
    pub fn update_with_cause(
        &self,
        ioa: Ioa,
        element: Element,
        time: Option<Cp56Time2a>,
        cause: Cause,
    ) -> Result<(), OutstationError> {
        let type_id = self
            .read_image()
            .monitor(ioa)
            .map(|point| point.event_type)
            .ok_or(ImageError::UnknownPoint(ioa))?;
        let time = match type_id.time_tag() {
            crate::asdu::TimeTagKind::Cp56 => {
                Some(TimeTag::Cp56(time.unwrap_or_else(|| self.now_time_tag())))
            }
            crate::asdu::TimeTagKind::Cp24 => {
                let full = time.unwrap_or_else(|| self.now_time_tag());
                Some(TimeTag::Cp24(
                    match crate::time::Cp24Time2a::new(full.minute(), full.millisecond()) {
                        Ok(short) => short.with_invalid(full.is_invalid()),
                        Err(_) => {
                            crate::time::Cp24Time2a::from_naive(chrono::NaiveDateTime::default())
                                .with_invalid(true)
                        }
                    },
                ))
            }
            crate::asdu::TimeTagKind::None => None,
        };
        // Queue while still holding the image's lock: concurrent updates of one point
        // then reach the links in the order the image took them, so the last event a
        // master gets agrees with what interrogation and read report. (No code path takes
        // the image's lock while holding a group's, so this nesting cannot deadlock.)
        let mut image = self.write_image();
        image.set(ioa, element.clone(), time)?;
        let object = InformationObject { ioa, element, time };
        for group in self.read_groups().iter() {
            group.push(QueuedEvent {
                type_id,
                cause,
                object: object.clone(),
                seq: 0,
            });
        }
        drop(image);
        Ok(())
    }

    /// Sets a point's value without sending it: interrogation and read will show it.
    pub fn set(
        &self,
        ioa: Ioa,
        element: Element,
        time: Option<TimeTag>,
    ) -> Result<(), OutstationError> {
        self.write_image().set(ioa, element, time)?;
        Ok(())
    }

    /// The current value of a monitor point.
    pub fn get(&self, ioa: Ioa) -> Option<MonitorPoint> {
        self.read_image().monitor(ioa).cloned()
    }

    /// Statistics of every redundancy group.
    pub fn group_stats(&self) -> Vec<GroupStats> {
        self.read_groups()
            .iter()
            .map(|group| group.stats())
            .collect()
    }
}

/// The end of initialisation (M_EI_NA_1, cause 4) an outstation sends after its start.
fn end_of_initialisation() -> QueuedEvent {
    QueuedEvent {
        type_id: TypeId::M_EI_NA_1,
        cause: Cause::INITIALISED,
        object: InformationObject {
            ioa: Ioa::default(),
            element: Element::EndOfInitialisation {
                cause: 0,
                after_parameter_change: false,
            },
            time: None,
        },
        seq: 0,
    }
}
