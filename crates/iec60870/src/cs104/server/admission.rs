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
//!   wait as long as it likes: that is what it is for).

use std::collections::HashMap;
use std::net::IpAddr;
use std::sync::{Arc, Mutex};

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
    ip: IpAddr,
    /// The configured group (groups by address) the client belongs to.
    group: Option<usize>,
    named: bool,
}

impl Slot {
    /// Whether the client is named by a configured redundancy group.
    pub(crate) fn is_named(&self) -> bool {
        self.named
    }
}

impl Drop for Slot {
    fn drop(&mut self) {
        let mut counts = lock(&self.counts);
        counts.open = counts.open.saturating_sub(1);
        if let Some(count) = counts.per_address.get_mut(&self.ip) {
            *count = count.saturating_sub(1);
            if *count == 0 {
                counts.per_address.remove(&self.ip);
            }
        }
        if let Some(group) = self.group {
            if let Some(count) = counts.per_group.get_mut(&group) {
                *count = count.saturating_sub(1);
            }
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
            return Err(SlotRefusal::Full(counts.open));
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
        Ok(Slot {
            counts: Arc::clone(&self.counts),
            ip,
            group,
            named: named_group.is_some(),
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
