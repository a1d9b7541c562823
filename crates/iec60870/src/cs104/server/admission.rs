//! Connection slots: who may take one of the server's connections.
//!
//! A controlled station has few slots (lib60870 and most outstations: a handful), and a
//! client that connects and never starts data transfer holds one as long as it answers
//! TESTFR. Three rules keep the slots for the controlling stations they are meant for:
//! - at most [`ServerConfig::max_connections_per_address`] connections from one address,
//!   and at most [`ServerConfig::max_connections_per_group`] in one redundancy group (by
//!   address: a catch-all group's crowd cannot take every slot either);
//! - [`ServerConfig::reserved_per_group`] slots kept for each redundancy group that names
//!   its clients' addresses: clients no such group names never take them, so a configured
//!   control centre always gets in;
//! - a connection of a client no group names that does not start data transfer within
//!   [`ServerConfig::start_timeout`] is closed (a named group's standby connection may
//!   wait as long as it likes: that is what it is for);
//! - when the table, or a group's share of it, is full, a newcomer evicts the
//!   longest-idle connection that never started data transfer, beyond the
//!   [`ServerConfig::standbys_per_group`] such connections each group keeps; a started
//!   connection is never evicted by a newcomer. Idle clients that answer TESTFR can then
//!   no longer lock a catch-all group's controlling station out until their start
//!   timeout runs out.

use std::collections::HashMap;
use std::net::IpAddr;
use std::sync::{Arc, Mutex};
use tokio::time::Instant;

use tokio::sync::Notify;

use super::{RedundancyMode, ServerConfig};

/// Why a connection was refused a slot.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub(crate) enum SlotRefusal {
    #[error("connection limit reached ({0} open)")]
    Full(usize),
    #[error("the remaining slots are reserved for the named redundancy groups")]
    Reserved,
    #[error("{count} connections from this address already (at most {limit})")]
    PerAddress { count: usize, limit: usize },
    #[error("{count} connections in redundancy group `{group}` already (at most {limit})")]
    PerGroup {
        group: String,
        count: usize,
        limit: usize,
    },
}

impl SlotRefusal {
    /// The kind of refusal (its log lines are rate-limited per kind).
    pub(crate) fn kind(&self) -> &'static str {
        match self {
            SlotRefusal::Full(_) => "full",
            SlotRefusal::Reserved => "reserved",
            SlotRefusal::PerAddress { .. } => "per-address",
            SlotRefusal::PerGroup { .. } => "per-group",
        }
    }
}

#[derive(Debug, Default)]
struct Counts {
    open: usize,
    per_address: HashMap<IpAddr, usize>,
    /// Open connections per configured group (by index in the configured groups).
    per_group: HashMap<usize, usize>,
    /// The connections holding slots, for eviction.
    members: Vec<Member>,
    next_member: u64,
}

/// A connection holding a slot.
#[derive(Debug)]
struct Member {
    id: u64,
    ip: IpAddr,
    group: Option<usize>,
    /// When it connected: a connection that never started has been idle since.
    since: Instant,
    /// It started data transfer at least once.
    started: bool,
    /// Told to go; its slot is already given back.
    evicted: bool,
    evict: Arc<Notify>,
}

impl Counts {
    /// Gives back a member's share of the counts.
    fn release(&mut self, ip: IpAddr, group: Option<usize>) {
        self.open = self.open.saturating_sub(1);
        if let Some(count) = self.per_address.get_mut(&ip) {
            *count = count.saturating_sub(1);
            if *count == 0 {
                self.per_address.remove(&ip);
            }
        }
        if let Some(group) = group {
            if let Some(count) = self.per_group.get_mut(&group) {
                *count = count.saturating_sub(1);
            }
        }
    }

    /// Evicts the longest-idle connection that never started data transfer, of `group`
    /// when given, beyond the `keep` such connections each group keeps; says whom.
    fn evict_idle(&mut self, group: Option<Option<usize>>, keep: usize) -> Option<IpAddr> {
        let idle_in = |members: &[Member], of: Option<usize>| {
            members
                .iter()
                .filter(|m| !m.started && !m.evicted && m.group == of)
                .count()
        };
        let victim = self
            .members
            .iter()
            .enumerate()
            .filter(|(_, m)| !m.started && !m.evicted)
            .filter(|(_, m)| group.is_none_or(|group| m.group == group))
            .filter(|(_, m)| idle_in(&self.members, m.group) > keep)
            .min_by_key(|(_, m)| m.since)
            .map(|(index, _)| index)?;
        let (ip, of) = {
            let member = self.members.get_mut(victim)?;
            member.evicted = true;
            member.evict.notify_one();
            (member.ip, member.group)
        };
        self.release(ip, of);
        Some(ip)
    }
}

/// The server's slots.
#[derive(Debug, Default)]
pub(crate) struct Slots {
    counts: Arc<Mutex<Counts>>,
}

/// A slot held by a connection; given back when dropped.
#[derive(Debug)]
pub(crate) struct Slot {
    counts: Arc<Mutex<Counts>>,
    id: u64,
    ip: IpAddr,
    /// The configured group (groups by address) the client belongs to.
    group: Option<usize>,
    named: bool,
    evict: Arc<Notify>,
}

impl Slot {
    /// Whether the client is named by a configured redundancy group.
    pub(crate) fn is_named(&self) -> bool {
        self.named
    }

    /// The connection started data transfer: no newcomer evicts it from now on.
    pub(crate) fn started(&self) {
        let mut counts = lock(&self.counts);
        if let Some(member) = counts.members.iter_mut().find(|m| m.id == self.id) {
            member.started = true;
        }
    }

    /// Resolves when a newcomer evicted this connection (its slot is already given back).
    pub(crate) async fn evicted(&self) {
        self.evict.notified().await;
    }
}

impl Drop for Slot {
    fn drop(&mut self) {
        let mut counts = lock(&self.counts);
        let Some(index) = counts.members.iter().position(|m| m.id == self.id) else {
            return;
        };
        let member = counts.members.swap_remove(index);
        if !member.evicted {
            counts.release(self.ip, self.group);
        }
    }
}

fn lock(counts: &Mutex<Counts>) -> std::sync::MutexGuard<'_, Counts> {
    // Counters only: a panic elsewhere cannot leave them half-updated.
    counts
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

impl Slots {
    /// Connections open now.
    pub(crate) fn open(&self) -> usize {
        lock(&self.counts).open
    }

    /// Takes a slot for a client, or says why not.
    pub(crate) fn admit(&self, config: &ServerConfig, ip: IpAddr) -> Result<Slot, SlotRefusal> {
        let groups: &[super::RedundancyGroupConfig] = match &config.outstation.redundancy {
            RedundancyMode::GroupsByAddress(groups) => groups,
            _ => &[],
        };
        // The group the server will put the client in: the first naming it, else the
        // first catch-all (as `Shared::group_for` chooses).
        let named_group = groups.iter().position(|group| group.clients.contains(&ip));
        let group = named_group.or_else(|| groups.iter().position(|g| g.clients.is_empty()));
        let mut counts = lock(&self.counts);
        if counts.open >= config.max_connections {
            match counts.evict_idle(None, config.standbys_per_group) {
                Some(victim) => tracing::warn!(
                    %ip, %victim,
                    "connection table full: the longest-idle connection that never started data transfer is closed for the newcomer"
                ),
                None => return Err(SlotRefusal::Full(counts.open)),
            }
        }
        if named_group.is_none() {
            let unused_reserve: usize = groups
                .iter()
                .enumerate()
                .filter(|(_, group)| !group.clients.is_empty())
                .map(|(index, _)| {
                    let open = counts.per_group.get(&index).copied().unwrap_or(0);
                    config.reserved_per_group.saturating_sub(open)
                })
                .sum();
            if counts.open + unused_reserve >= config.max_connections {
                return Err(SlotRefusal::Reserved);
            }
        }
        if let (Some(index), Some(limit)) = (group, config.max_connections_per_group) {
            let full = counts.per_group.get(&index).copied().unwrap_or(0) >= limit;
            if full {
                if let Some(victim) =
                    counts.evict_idle(Some(Some(index)), config.standbys_per_group)
                {
                    tracing::warn!(
                        %ip, %victim,
                        "redundancy group's share of the connections full: its longest-idle connection that never started data transfer is closed for the newcomer"
                    );
                }
            }
            let count = counts.per_group.get(&index).copied().unwrap_or(0);
            if count >= limit {
                let name = groups
                    .get(index)
                    .map(|g| g.name.clone())
                    .unwrap_or_default();
                return Err(SlotRefusal::PerGroup {
                    group: name,
                    count,
                    limit,
                });
            }
        }
        let from_address = counts.per_address.get(&ip).copied().unwrap_or(0);
        if let Some(limit) = config.max_connections_per_address {
            if from_address >= limit {
                return Err(SlotRefusal::PerAddress {
                    count: from_address,
                    limit,
                });
            }
        }
        counts.open += 1;
        counts.per_address.insert(ip, from_address + 1);
        if let Some(group) = group {
            *counts.per_group.entry(group).or_insert(0) += 1;
        }
        let id = counts.next_member;
        counts.next_member += 1;
        let evict = Arc::new(Notify::new());
        counts.members.push(Member {
            id,
            ip,
            group,
            since: Instant::now(),
            started: false,
            evicted: false,
            evict: Arc::clone(&evict),
        });
        Ok(Slot {
            counts: Arc::clone(&self.counts),
            id,
            ip,
            group,
            named: named_group.is_some(),
            evict,
        })
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::super::RedundancyGroupConfig;
    use super::*;

    fn ip(last: u8) -> IpAddr {
        IpAddr::from([127, 0, 0, last])
    }

    fn config() -> ServerConfig {
        let mut config = ServerConfig::new("127.0.0.1:0".parse().unwrap(), Default::default());
        config.max_connections = 4;
        config.max_connections_per_address = Some(2);
        config.reserved_per_group = 1;
        config.outstation.redundancy = RedundancyMode::GroupsByAddress(vec![
            RedundancyGroupConfig::new("dispatch", vec![ip(10)]),
            RedundancyGroupConfig::new("hmi", vec![ip(20)]),
            RedundancyGroupConfig::catch_all("others"),
        ]);
        config
    }

    #[test]
    fn reserved_slots_stay_for_the_named_groups() {
        let config = config();
        let slots = Slots::default();
        let a = slots.admit(&config, ip(1)).unwrap();
        let b = slots.admit(&config, ip(2)).unwrap();
        // Two left, both reserved (one per named group).
        assert_eq!(
            slots.admit(&config, ip(3)).unwrap_err(),
            SlotRefusal::Reserved
        );
        let dispatch = slots.admit(&config, ip(10)).unwrap();
        assert!(dispatch.is_named());
        let hmi = slots.admit(&config, ip(20)).unwrap();
        assert_eq!(
            slots.admit(&config, ip(10)).unwrap_err(),
            SlotRefusal::Full(4)
        );
        drop((a, b, dispatch, hmi));
        assert_eq!(slots.open(), 0);
    }

    #[test]
    fn one_group_takes_at_most_its_share() {
        let mut config = config();
        config.max_connections = 10;
        config.max_connections_per_address = None;
        config.max_connections_per_group = Some(3);
        let slots = Slots::default();
        let crowd: Vec<Slot> = (1..=3)
            .map(|last| slots.admit(&config, ip(last)).unwrap())
            .collect();
        // Started connections: no newcomer evicts them.
        crowd.iter().for_each(Slot::started);
        assert_eq!(
            slots.admit(&config, ip(4)).unwrap_err(),
            SlotRefusal::PerGroup {
                group: "others".into(),
                count: 3,
                limit: 3
            }
        );
        assert!(slots.admit(&config, ip(10)).is_ok());
        drop(crowd);
    }

    #[test]
    fn a_newcomer_evicts_the_longest_idle_connection_beyond_the_standbys() {
        let mut config = config();
        config.max_connections = 10;
        config.max_connections_per_address = None;
        config.max_connections_per_group = Some(4);
        config.standbys_per_group = 2;
        let slots = Slots::default();
        // The catch-all group's share taken: one started connection and three idle ones.
        let started = slots.admit(&config, ip(1)).unwrap();
        started.started();
        let idle: Vec<Slot> = (2..=4)
            .map(|last| slots.admit(&config, ip(last)).unwrap())
            .collect();
        // A newcomer evicts the oldest idle one (three idle, two kept as standbys).
        let newcomer = slots.admit(&config, ip(5)).unwrap();
        let evicted = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
            .unwrap()
            .block_on(async {
                tokio::time::timeout(std::time::Duration::from_secs(1), idle[0].evicted())
                    .await
                    .is_ok()
            });
        assert!(evicted, "the longest-idle connection was not told to go");
        newcomer.started();
        drop(idle);
        // Two started connections and two idle ones, the group's standbys: a newcomer
        // evicts no one and is refused.
        let standby_a = slots.admit(&config, ip(6)).unwrap();
        let standby_b = slots.admit(&config, ip(7)).unwrap();
        assert!(matches!(
            slots.admit(&config, ip(8)).unwrap_err(),
            SlotRefusal::PerGroup { .. }
        ));
        drop((started, newcomer, standby_a, standby_b));
        assert_eq!(slots.open(), 0);
    }

    #[test]
    fn one_address_takes_at_most_its_share() {
        let mut config = config();
        config.max_connections = 10;
        let slots = Slots::default();
        let _first = slots.admit(&config, ip(1)).unwrap();
        let second = slots.admit(&config, ip(1)).unwrap();
        assert_eq!(
            slots.admit(&config, ip(1)).unwrap_err(),
            SlotRefusal::PerAddress { count: 2, limit: 2 }
        );
        drop(second);
        assert!(slots.admit(&config, ip(1)).is_ok());
    }
}
