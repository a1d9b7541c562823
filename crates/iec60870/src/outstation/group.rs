//! Redundancy groups and their event buffers.
//!
//! The connections of one group share one buffer of spontaneous events; only one of them
//! is started (carries user data) at a time. While no connection of the group is started
//! the buffer keeps the events with their time tags, and delivers them in order once a
//! connection starts. ASDUs that a lost or replaced connection sent but never got
//! acknowledged are put back at the front, so a switch-over loses nothing.

use std::collections::VecDeque;
use std::future::Future;
use std::net::IpAddr;
use std::sync::Mutex;
use std::task::{Poll, Waker};

use super::Peer;

use crate::asdu::{Cause, InformationObject, TypeId};

/// Which clients belong to a redundancy group.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub struct RedundancyGroupConfig {
    /// A name for logs and statistics (e.g. "dispatch-A").
    pub name: String,
    /// Client addresses of the group; a group without addresses takes every client that
    /// no other group names.
    pub clients: Vec<IpAddr>,
}

impl RedundancyGroupConfig {
    /// A group of the given clients.
    pub fn new(name: impl Into<String>, clients: Vec<IpAddr>) -> Self {
        Self {
            name: name.into(),
            clients,
        }
    }

    /// A group that takes every client.
    pub fn catch_all(name: impl Into<String>) -> Self {
        Self::new(name, Vec::new())
    }
}

/// How a server forms redundancy groups from its clients (the three modes of lib60870 and
/// of most outstations).
///
/// Only one connection of a group carries data at a time: a STARTDT on another
/// connection of the same group takes the data over (the previous connection stays open,
/// on standby, and the server logs the take-over naming both peers). Groups never take
/// data from each other: each has its own event buffer.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub enum RedundancyMode {
    /// Every client in one group with one event buffer: the standard's redundancy (one
    /// controlling station with a main and a standby connection). A second, independent
    /// master's STARTDT silently takes the data from the first.
    #[default]
    SingleGroup,
    /// Each connection is a group of its own with its own event buffer, filled from the
    /// moment it connects: independent masters never disturb each other, and nothing is
    /// kept for a connection that is gone.
    ConnectionIsGroup,
    /// Groups by client address: each group's clients share its buffer (main and standby
    /// of one control centre); a group without addresses takes every client no other
    /// group names, and a client no group takes is refused.
    GroupsByAddress(Vec<RedundancyGroupConfig>),
}

impl RedundancyMode {
    /// The names of the modes as the command line and project files spell them.
    pub const NAMES: [&'static str; 3] =
        ["single-group", "connection-is-group", "groups-by-address"];

    /// The mode's name as the command line and project files spell it.
    pub fn name(&self) -> &'static str {
        match self {
            RedundancyMode::SingleGroup => Self::NAMES[0],
            RedundancyMode::ConnectionIsGroup => Self::NAMES[1],
            RedundancyMode::GroupsByAddress(_) => Self::NAMES[2],
        }
    }

    /// The mode of a name (see [`RedundancyMode::NAMES`]), with the groups that
    /// `groups-by-address` forms; `None` for an unknown name.
    pub fn from_name(name: &str, groups: Vec<RedundancyGroupConfig>) -> Option<Self> {
        match name {
            "single-group" => Some(RedundancyMode::SingleGroup),
            "connection-is-group" => Some(RedundancyMode::ConnectionIsGroup),
            "groups-by-address" => Some(RedundancyMode::GroupsByAddress(groups)),
            _ => None,
        }
    }
}

/// What a full event buffer does with a new event.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum OverflowPolicy {
    /// Drop the oldest buffered event (the newest state wins; the default, as in
    /// lib60870).
    #[default]
    DropOldest,
    /// Drop the new event (the oldest history wins).
    DropNewest,
}

/// Statistics of one redundancy group.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct GroupStats {
    /// The group's name.
    pub name: String,
    /// Events waiting in the buffer.
    pub queued: usize,
    /// ASDUs sent but not yet acknowledged, or waiting to be sent again after a
    /// connection was lost or replaced.
    pub retransmit_queued: usize,
    /// Events lost to buffer overflow since the server started.
    pub dropped: u64,
    /// Whether a connection of the group is started.
    pub has_active: bool,
}

/// A spontaneous (or cyclic, or return-information) event waiting to be sent.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct QueuedEvent {
    pub(crate) type_id: TypeId,
    pub(crate) cause: Cause,
    pub(crate) object: InformationObject,
    /// The event's place in the group's sequence (set by [`Group::push`]): a command
    /// termination waits for the events queued before it.
    pub(crate) seq: u64,
}

#[derive(Debug)]
pub(crate) struct GroupState {
    /// ASDUs to send again, before any buffered event.
    pub(crate) retransmit: VecDeque<Vec<u8>>,
    /// ASDUs the started connection sent from this group and that are not yet
    /// acknowledged, oldest first: on switch-over or connection loss they move to
    /// `retransmit`.
    pub(crate) in_flight: VecDeque<Vec<u8>>,
    pub(crate) events: VecDeque<QueuedEvent>,
    pub(crate) active: Option<u64>,
    /// The peer of the active connection (named in the take-over warning).
    pub(crate) active_peer: Option<Peer>,
    /// Started connections that lost the group's data to a take-over, most recent last:
    /// when the active connection stops or goes away, the last of them takes the data
    /// back (its controlling station never stopped data transfer, so it still waits
    /// for data).
    pub(crate) standby: Vec<(u64, Peer)>,
    /// The sequence number the next queued event gets.
    pub(crate) next_seq: u64,
    /// Counts changes the group's links wait for: an event queued, the group taken over.
    version: u64,
    /// Links waiting for the next change (see [`Group::changed`]).
    waiting: Vec<Waker>,
    dropped: u64,
    overflowing: bool,
}

/// One redundancy group, shared by its connections.
///
/// Links wait for the group's changes through [`Group::version`] and [`Group::changed`]
/// rather than a runtime's notification primitive, so the core needs no async runtime
/// (a tokio `Notify` would tie it to tokio).
#[derive(Debug)]
pub(crate) struct Group {
    pub(crate) config: RedundancyGroupConfig,
    pub(crate) state: Mutex<GroupState>,
    capacity: usize,
    policy: OverflowPolicy,
}

impl Group {
    pub(crate) fn new(
        config: RedundancyGroupConfig,
        capacity: usize,
        policy: OverflowPolicy,
    ) -> Self {
        Self {
            config,
            state: Mutex::new(GroupState {
                retransmit: VecDeque::new(),
                in_flight: VecDeque::new(),
                events: VecDeque::new(),
                active: None,
                active_peer: None,
                standby: Vec::new(),
                next_seq: 0,
                version: 0,
                waiting: Vec::new(),
                dropped: 0,
                overflowing: false,
            }),
            capacity: capacity.max(1),
            policy,
        }
    }

    pub(crate) fn lock(&self) -> std::sync::MutexGuard<'_, GroupState> {
        // A poisoned lock means a connection task panicked while holding it; the queue
        // itself is still consistent (every mutation is a single VecDeque call), so go on.
        self.state
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// Queues an event, applying the overflow policy.
    pub(crate) fn push(&self, mut event: QueuedEvent) {
        let mut state = self.lock();
        event.seq = state.next_seq;
        state.next_seq += 1;
        if state.events.len() >= self.capacity {
            state.dropped += 1;
            if !state.overflowing {
                state.overflowing = true;
                tracing::warn!(
                    group = %self.config.name,
                    capacity = self.capacity,
                    policy = ?self.policy,
                    "event buffer full: events are being dropped"
                );
            }
            match self.policy {
                OverflowPolicy::DropOldest => {
                    state.events.pop_front();
                    state.events.push_back(event);
                }
                OverflowPolicy::DropNewest => {}
            }
        } else {
            if state.overflowing && state.events.len() < self.capacity / 2 {
                state.overflowing = false;
            }
            state.events.push_back(event);
        }
        Self::wake_all(state);
    }

    /// Marks a change of the group (an event queued, the group taken over or given up)
    /// and wakes every link waiting for one. Every link waits: waking only one could wake
    /// a link that has just lost the group to another and leave the new one asleep.
    pub(crate) fn wake_all(mut state: std::sync::MutexGuard<'_, GroupState>) {
        state.version = state.version.wrapping_add(1);
        let waiting = std::mem::take(&mut state.waiting);
        drop(state);
        for waker in waiting {
            waker.wake();
        }
    }

    /// The group's change counter. A link reads it before it looks at the group and then
    /// waits with [`changed`](Self::changed): a change in between is not missed.
    pub(crate) fn version(&self) -> u64 {
        self.lock().version
    }

    /// Resolves once the group changed since `seen` (a [`version`](Self::version)).
    pub(crate) fn changed(&self, seen: u64) -> impl Future<Output = ()> + '_ {
        std::future::poll_fn(move |context| {
            let mut state = self.lock();
            if state.version != seen {
                return Poll::Ready(());
            }
            if !state.waiting.iter().any(|w| w.will_wake(context.waker())) {
                state.waiting.push(context.waker().clone());
            }
            Poll::Pending
        })
    }

    pub(crate) fn stats(&self) -> GroupStats {
        let state = self.lock();
        GroupStats {
            name: self.config.name.clone(),
            queued: state.events.len(),
            retransmit_queued: state.retransmit.len() + state.in_flight.len(),
            dropped: state.dropped,
            has_active: state.active.is_some(),
        }
    }

    pub(crate) fn accepts(&self, ip: IpAddr) -> bool {
        self.config.clients.contains(&ip)
    }

    pub(crate) fn is_catch_all(&self) -> bool {
        self.config.clients.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A group's buffer holds up to `event_buffer_capacity` of these (and a `VecDeque`
    /// rounds its allocation up to a power of two): the station documents a full
    /// buffer's memory from this size, so a larger event must be a decision.
    #[test]
    fn a_queued_event_stays_small() {
        let size = std::mem::size_of::<QueuedEvent>();
        assert!(size <= 80, "QueuedEvent is {size} bytes");
    }
}
