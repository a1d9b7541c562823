//! Simulated time, and each node's own clock on top of it.
//!
//! One [`SimClock`] per process: simulated time is a `Duration` since the start, moved
//! only by the simulation thread; UTC is `start + simulated time`. Each node keeps its
//! own [`NodeClock`] = simulated UTC + an offset that clock synchronisation (C_CS_NA_1
//! from the node above) sets, as a controller's real-time clock would be set. PLC
//! cycles, time tags and store records of a node read its node clock.
//!
//! The nodes running in one process know each other's clocks ([`LocalClocks`]): a link
//! to a lower node of the same process sets its clock directly.

use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, AtomicI64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use chrono::{DateTime, Offset as _, TimeZone as _, Utc};
use chrono_tz::Tz;

use crate::config::{LinkConfig, LinkTarget};

use super::node::NodePoints;

/// Simulated time shared by every node of the process.
#[derive(Debug)]
pub struct SimClock {
    start: DateTime<Utc>,
    now_ns: AtomicI64,
}

impl SimClock {
    /// A clock whose time zero is `start` (UTC).
    pub fn new(start: DateTime<Utc>) -> Arc<SimClock> {
        Arc::new(SimClock {
            start,
            now_ns: AtomicI64::new(0),
        })
    }

    /// UTC of simulated time zero.
    pub fn start(&self) -> DateTime<Utc> {
        self.start
    }

    /// Current simulated time (since the start).
    pub fn now(&self) -> Duration {
        Duration::from_nanos(self.now_ns.load(Ordering::Acquire).max(0).unsigned_abs())
    }

    /// UTC at simulated time `t` (without any node's offset).
    pub fn utc_at(&self, t: Duration) -> DateTime<Utc> {
        self.start + chrono::Duration::from_std(t).unwrap_or(chrono::Duration::MAX)
    }

    /// Moves the clock (the simulation thread only).
    pub(crate) fn set(&self, t: Duration) {
        let ns = i64::try_from(t.as_nanos()).unwrap_or(i64::MAX);
        self.now_ns.store(ns, Ordering::Release);
    }
}

/// A node's clock: simulated UTC plus the offset set by clock synchronisation.
#[derive(Debug)]
pub struct NodeClock {
    sim: Arc<SimClock>,
    offset_ns: AtomicI64,
    synchronised: AtomicBool,
    zone: Tz,
    /// Clocks of lower nodes in this process that take this node's time.
    followers: Mutex<Vec<Arc<NodeClock>>>,
}

impl NodeClock {
    /// A node clock on `sim`, showing local time in `zone`.
    pub fn new(sim: Arc<SimClock>, zone: Tz) -> Arc<NodeClock> {
        Arc::new(NodeClock {
            sim,
            offset_ns: AtomicI64::new(0),
            synchronised: AtomicBool::new(false),
            zone,
            followers: Mutex::new(Vec::new()),
        })
    }

    /// The node's UTC time now.
    pub fn now(&self) -> DateTime<Utc> {
        self.at(self.sim.now())
    }

    /// The node's UTC time at simulated time `t`.
    pub fn at(&self, t: Duration) -> DateTime<Utc> {
        self.sim.utc_at(t) + chrono::Duration::nanoseconds(self.offset_ns.load(Ordering::Acquire))
    }

    /// The simulated clock under this node clock.
    pub fn sim(&self) -> &Arc<SimClock> {
        &self.sim
    }

    /// The local-time offset from UTC (ns) at `utc` in the node's time zone (DST aware).
    pub fn utc_offset_ns(&self, utc: DateTime<Utc>) -> i64 {
        let offset = self.zone.offset_from_utc_datetime(&utc.naive_utc()).fix();
        i64::from(offset.local_minus_utc()) * 1_000_000_000
    }

    /// Sets the clock so that it shows `utc` now (a clock synchronisation), and the clocks
    /// of its followers with it.
    pub fn synchronise(&self, utc: DateTime<Utc>) {
        let sim_utc = self.sim.utc_at(self.sim.now());
        let offset = (utc - sim_utc).num_nanoseconds().unwrap_or(0);
        self.offset_ns.store(offset, Ordering::Release);
        self.synchronised.store(true, Ordering::Release);
        let followers = self
            .followers
            .lock()
            .unwrap_or_else(|poison| poison.into_inner())
            .clone();
        for follower in followers {
            follower.synchronise(utc);
        }
    }

    /// Makes `lower` (a node below this one, in the same process) take this clock's time
    /// whenever it is synchronised. The link graph is acyclic, so the chain ends.
    pub(crate) fn add_follower(&self, lower: Arc<NodeClock>) {
        self.followers
            .lock()
            .unwrap_or_else(|poison| poison.into_inner())
            .push(lower);
    }

    /// Whether a synchronisation has been received since the start.
    pub fn is_synchronised(&self) -> bool {
        self.synchronised.load(Ordering::Acquire)
    }

    /// The offset against simulated UTC that synchronisation set.
    pub fn offset(&self) -> chrono::Duration {
        chrono::Duration::nanoseconds(self.offset_ns.load(Ordering::Acquire))
    }
}

/// The clocks of the nodes in this process, by name, for links that set them directly.
#[derive(Debug)]
pub(crate) struct LocalClocks(HashMap<String, Arc<NodeClock>>);

impl LocalClocks {
    /// The clocks of `nodes` (the running nodes with their project index).
    pub(crate) fn of(nodes: &[(usize, Arc<NodePoints>)]) -> LocalClocks {
        LocalClocks(
            nodes
                .iter()
                .map(|(_, points)| (points.name().to_owned(), Arc::clone(points.clock())))
                .collect(),
        )
    }

    /// The clock of the node `link` leads to, when that node runs in this process.
    pub(crate) fn lower(&self, link: &LinkConfig) -> Option<Arc<NodeClock>> {
        match &link.target {
            LinkTarget::Node(name) => self.0.get(name).cloned(),
            LinkTarget::Address(_) => None,
        }
    }
}

/// How the simulation thread moves simulated time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Pacing {
    /// Follows the wall clock, `speed` times faster (1.0 = real time).
    RealTime {
        /// Simulated seconds per real second, > 0.
        speed: f64,
    },
    /// Moves only when [`super::Runtime::advance`] says so, as fast as the CPU allows:
    /// for tests and scenario runs.
    Manual,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn node_clock_follows_sim_and_synchronisation() {
        let start = Utc.with_ymd_and_hms(2024, 3, 31, 0, 30, 0).unwrap();
        let sim = SimClock::new(start);
        let node = NodeClock::new(Arc::clone(&sim), chrono_tz::Europe::Prague);
        assert_eq!(node.now(), start);
        sim.set(Duration::from_secs(3600));
        assert_eq!(node.now(), start + chrono::Duration::hours(1));
        // 01:30 UTC on the DST day: CEST, +2 h.
        assert_eq!(node.utc_offset_ns(node.now()), 7_200_000_000_000);
        let set = start + chrono::Duration::hours(5);
        node.synchronise(set);
        assert!(node.is_synchronised());
        assert_eq!(node.now(), set);
        sim.set(Duration::from_secs(3601));
        assert_eq!(node.now(), set + chrono::Duration::seconds(1));
    }
}
