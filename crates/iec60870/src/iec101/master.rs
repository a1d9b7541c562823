//! The IEC 101 controlling station on an unbalanced line: an FT1.2 primary that starts
//! each outstation it finds (clock synchronisation, interrogation) and hands up their
//! ASDUs.

use std::collections::VecDeque;
use std::task::{Context, Poll};
use std::time::Instant;

use chrono::NaiveDateTime;

use crate::asdu::{AsduParams, CommonAddress};
use crate::controlling::start_requests;
use crate::ft12::{
    Answer, Balanced, BalancedEvent, LineEndpoint, LineSettings, Primary, PrimaryError,
    PrimaryEvent,
};
use crate::time::Cp56Time2a;

/// What the master does when an outstation's link comes up.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StartUp {
    /// Synchronise the outstation's clock (C_CS_NA_1).
    pub clock_sync: bool,
    /// Interrogate the station (C_IC_NA_1, QOI 20).
    pub interrogate: bool,
    /// The originator address of our requests (with 2-octet causes).
    pub originator: u8,
}

/// What the master saw.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum MasterEvent {
    /// An ASDU from an outstation.
    Asdu {
        /// The outstation's link address.
        address: u16,
        /// The ASDU as received (decode it with the line's [`AsduParams`]).
        asdu: Vec<u8>,
    },
    /// Everything on the link layer (for a protocol log): exchanges, timeouts, link up
    /// and down, line errors.
    Link(PrimaryEvent),
    /// The same on a balanced link.
    Balanced(BalancedEvent),
}

/// The link layer under the master.
#[derive(Debug)]
enum Link {
    /// Unbalanced: we poll one or many outstations.
    Unbalanced(Primary),
    /// Balanced: one outstation at the link address, both sending when they like.
    Balanced(Balanced, u16),
}

/// The clock a master synchronises outstations to.
pub type Clock = Box<dyn FnMut() -> NaiveDateTime + Send>;

/// An IEC 101 master polling one or many outstations on one line.
pub struct Master {
    link: Link,
    params: AsduParams,
    start_up: StartUp,
    common_addresses: Vec<(u16, CommonAddress)>,
    clock: Clock,
    events: VecDeque<MasterEvent>,
}

impl std::fmt::Debug for Master {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Master")
            .field("link", &self.link)
            .field("params", &self.params)
            .finish_non_exhaustive()
    }
}

impl Master {
    /// A master over `primary` with the line's ASDU field sizes.
    pub fn new(primary: Primary, params: AsduParams, start_up: StartUp, clock: Clock) -> Master {
        Master::with_link(Link::Unbalanced(primary), params, start_up, clock)
    }

    /// A master on a balanced link to the outstation at `address` (its link address,
    /// as events name it) with `common_address`.
    pub fn balanced(
        link: Balanced,
        address: u16,
        common_address: CommonAddress,
        params: AsduParams,
        start_up: StartUp,
        clock: Clock,
    ) -> Master {
        let mut master = Master::with_link(Link::Balanced(link, address), params, start_up, clock);
        master.common_addresses.push((address, common_address));
        master
    }

    fn with_link(link: Link, params: AsduParams, start_up: StartUp, clock: Clock) -> Master {
        Master {
            link,
            params,
            start_up,
            common_addresses: Vec::new(),
            clock,
            events: VecDeque::new(),
        }
    }

    /// Adds an outstation at a link address with its common address (unbalanced lines;
    /// a balanced link has its one outstation from the start).
    pub fn add_station(
        &mut self,
        address: u16,
        common_address: CommonAddress,
    ) -> Result<(), PrimaryError> {
        if let Link::Unbalanced(primary) = &mut self.link {
            primary.add_station(address)?;
        }
        self.common_addresses.push((address, common_address));
        Ok(())
    }

    /// The ASDU field sizes of the line.
    pub fn params(&self) -> &AsduParams {
        &self.params
    }

    /// The unbalanced link layer (for single telegrams, statistics and link states).
    pub fn primary(&mut self) -> Option<&mut Primary> {
        match &mut self.link {
            Link::Unbalanced(primary) => Some(primary),
            Link::Balanced(..) => None,
        }
    }

    /// Sends an ASDU to an outstation (send/confirm once its link is up).
    pub fn send(&mut self, address: u16, asdu: Vec<u8>) -> Result<(), PrimaryError> {
        match &mut self.link {
            Link::Unbalanced(primary) => primary.send(address, asdu),
            Link::Balanced(link, own) if *own == address => {
                link.send(asdu);
                Ok(())
            }
            Link::Balanced(..) => Err(PrimaryError::UnknownStation(address)),
        }
    }

    fn endpoint(&mut self) -> &mut dyn LineEndpoint {
        match &mut self.link {
            Link::Unbalanced(primary) => primary,
            Link::Balanced(link, _) => link,
        }
    }

    /// The next event.
    pub fn poll_event(&mut self) -> Option<MasterEvent> {
        self.events.pop_front()
    }

    fn process(&mut self) {
        if let Link::Balanced(link, address) = &mut self.link {
            let address = *address;
            let mut up = false;
            while let Some(event) = link.poll_event() {
                match &event {
                    BalancedEvent::LinkUp => up = true,
                    BalancedEvent::UserData(asdu) => self.events.push_back(MasterEvent::Asdu {
                        address,
                        asdu: asdu.clone(),
                    }),
                    _ => {}
                }
                self.events.push_back(MasterEvent::Balanced(event));
            }
            if up {
                self.start_station(address);
            }
            return;
        }
        let Link::Unbalanced(primary) = &mut self.link else {
            return;
        };
        let mut started = Vec::new();
        while let Some(event) = primary.poll_event() {
            match &event {
                PrimaryEvent::LinkUp { address } => started.push(*address),
                PrimaryEvent::Exchange {
                    address,
                    answer: Answer::UserData(asdu),
                    ..
                } => self.events.push_back(MasterEvent::Asdu {
                    address: *address,
                    asdu: asdu.clone(),
                }),
                _ => {}
            }
            self.events.push_back(MasterEvent::Link(event));
        }
        for address in started {
            self.start_station(address);
        }
    }

    fn start_station(&mut self, address: u16) {
        let Some(common_address) = self
            .common_addresses
            .iter()
            .find(|(link, _)| *link == address)
            .map(|(_, common_address)| *common_address)
        else {
            return;
        };
        let clock = if self.start_up.clock_sync {
            Cp56Time2a::from_naive((self.clock)()).ok()
        } else {
            None
        };
        for request in start_requests(
            common_address,
            self.start_up.originator,
            clock,
            self.start_up.interrogate,
        ) {
            if let Ok(bytes) = request.to_bytes(&self.params) {
                // The station is known (its link just came up); nothing to report.
                let _ = self.send(address, bytes);
            }
        }
    }
}

impl LineEndpoint for Master {
    fn handle_bytes(&mut self, now: Instant, bytes: &[u8]) {
        self.endpoint().handle_bytes(now, bytes);
        self.process();
    }

    fn handle_line_pause(&mut self, now: Instant) {
        self.endpoint().handle_line_pause(now);
        self.process();
    }

    fn handle_timeout(&mut self, now: Instant) {
        self.endpoint().handle_timeout(now);
        self.process();
    }

    fn poll_transmit(&mut self, now: Instant) -> Option<Vec<u8>> {
        let bytes = self.endpoint().poll_transmit(now);
        self.process();
        bytes
    }

    fn next_deadline(&self) -> Option<Instant> {
        match &self.link {
            Link::Unbalanced(primary) => primary.next_deadline(),
            Link::Balanced(link, _) => link.next_deadline(),
        }
    }

    fn line(&self) -> LineSettings {
        match &self.link {
            Link::Unbalanced(primary) => primary.config().line,
            Link::Balanced(link, _) => link.line(),
        }
    }

    fn poll_wake(&mut self, _context: &mut Context<'_>) -> Poll<()> {
        Poll::Pending
    }
}
