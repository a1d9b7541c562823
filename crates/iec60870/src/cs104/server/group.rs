//! Redundancy groups and their event buffers.
//!
//! The connections of one group share one buffer of spontaneous events; only one of them
//! is started (carries user data) at a time. While no connection of the group is started
//! the buffer keeps the events with their time tags, and delivers them in order once a
//! connection starts. ASDUs that a lost or replaced connection sent but never got
//! acknowledged are put back at the front, so a switch-over loses nothing.

use std::collections::VecDeque;
use std::net::IpAddr;
use std::sync::Mutex;

use tokio::sync::Notify;

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
    dropped: u64,
    overflowing: bool,
}

/// One redundancy group, shared by its connections.
#[derive(Debug)]
pub(crate) struct Group {
    pub(crate) config: RedundancyGroupConfig,
    pub(crate) state: Mutex<GroupState>,
    /// Wakes the group's connections when something was queued or the group changed
    /// hands (`notify_waiters`: connections register before looking at the queue).
    pub(crate) notify: Notify,
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
                dropped: 0,
                overflowing: false,
            }),
            notify: Notify::new(),
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
    pub(crate) fn push(&self, event: QueuedEvent) {
        let mut state = self.lock();
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
        drop(state);
        // Every connection of the group registers for this before it looks at the queue,
        // so waking all of them loses nothing; waking one (notify_one) could wake a
        // connection that has just lost the group to another and leave the new one asleep.
        self.notify.notify_waiters();
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
