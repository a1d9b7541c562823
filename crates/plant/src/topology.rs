//! Energisation through a network of buses, links and sources, and the safety monitor.
//!
//! A bus is live if and only if a path of closed links joins it to a live source. Links
//! are undirected, so a wrong closure back-feeds exactly as it would in the field.

use std::collections::VecDeque;

use crate::core::SimTime;

/// One source of energy connected to a bus.
#[derive(Debug, Clone, PartialEq)]
pub struct SourceState {
    /// Source name (`TNS_USTI`, `UTILITY`, `DA`...).
    pub name: String,
    /// Index of its bus in [`TopologySnapshot::buses`].
    pub bus: usize,
    /// Producing voltage.
    pub live: bool,
    /// Sources of one group may run in parallel (the public grid); sources of different
    /// groups must never be connected to one another (grid and diesel).
    pub group: &'static str,
}

/// One link (breaker, contactor, transformer, cable) between two buses.
#[derive(Debug, Clone, PartialEq)]
pub struct LinkState {
    /// Link name (the device name for switching devices).
    pub name: String,
    /// Bus index of one side.
    pub a: usize,
    /// Bus index of the other side.
    pub b: usize,
    /// Conducting.
    pub closed: bool,
}

/// One bus (a board's busbar, a transformer secondary, a feeder).
#[derive(Debug, Clone, PartialEq)]
pub struct BusState {
    /// Bus name.
    pub name: String,
    /// Energised.
    pub live: bool,
}

/// The energisation picture at one instant.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TopologySnapshot {
    /// Buses.
    pub buses: Vec<BusState>,
    /// Links.
    pub links: Vec<LinkState>,
    /// Sources.
    pub sources: Vec<SourceState>,
}

/// What the safety monitor saw.
#[derive(Debug, Clone, PartialEq)]
pub enum SafetyKind {
    /// Sources of different groups joined by closed links (e.g. mains and diesel both
    /// closed onto RZS). `both_live` tells whether at least two of them were producing
    /// (true paralleling) rather than one back-feeding a dead one.
    SourcesConnected {
        /// Buses of the joined network, sorted.
        buses: Vec<String>,
        /// The sources joined, sorted.
        sources: Vec<String>,
        /// Two or more of them live.
        both_live: bool,
    },
    /// The condition above ended.
    SourcesSeparated {
        /// The sources that had been joined.
        sources: Vec<String>,
    },
    /// A breaker's close and trip coils were energised at the same time.
    BothCoils {
        /// Breaker name.
        breaker: String,
    },
}

/// One record of the safety monitor.
#[derive(Debug, Clone, PartialEq)]
pub struct SafetyEvent {
    /// When.
    pub at: SimTime,
    /// What.
    pub kind: SafetyKind,
}

/// The static network plus the live flags of the last computation.
#[derive(Debug, Clone, Default)]
pub(crate) struct Network {
    pub(crate) snap: TopologySnapshot,
    adj: Vec<Vec<(usize, usize)>>, // bus -> (link, other bus)
    supply: Vec<Option<usize>>,    // bus -> first live source of its component
}

impl Network {
    pub(crate) fn add_bus(&mut self, name: &str) -> usize {
        self.snap.buses.push(BusState {
            name: name.to_string(),
            live: false,
        });
        self.adj.push(Vec::new());
        self.supply.push(None);
        self.snap.buses.len() - 1
    }

    pub(crate) fn add_link(&mut self, name: &str, a: usize, b: usize) -> usize {
        let id = self.snap.links.len();
        self.snap.links.push(LinkState {
            name: name.to_string(),
            a,
            b,
            closed: true,
        });
        if let Some(v) = self.adj.get_mut(a) {
            v.push((id, b));
        }
        if let Some(v) = self.adj.get_mut(b) {
            v.push((id, a));
        }
        id
    }

    pub(crate) fn add_source(&mut self, name: &str, bus: usize, group: &'static str) -> usize {
        self.snap.sources.push(SourceState {
            name: name.to_string(),
            bus,
            live: false,
            group,
        });
        self.snap.sources.len() - 1
    }

    pub(crate) fn set_link(&mut self, link: usize, closed: bool) {
        if let Some(l) = self.snap.links.get_mut(link) {
            l.closed = closed;
        }
    }

    pub(crate) fn set_source(&mut self, src: usize, live: bool) {
        if let Some(s) = self.snap.sources.get_mut(src) {
            s.live = live;
        }
    }

    /// The source (index) feeding a bus: the first live source of its network.
    pub(crate) fn supply(&self, bus: usize) -> Option<usize> {
        self.supply.get(bus).copied().flatten()
    }

    pub(crate) fn live(&self, bus: usize) -> bool {
        self.snap.buses.get(bus).is_some_and(|b| b.live)
    }

    /// Connected components over closed links: component id per bus.
    fn components(&self) -> Vec<usize> {
        let n = self.snap.buses.len();
        let mut comp = vec![usize::MAX; n];
        let mut q = VecDeque::new();
        for start in 0..n {
            if comp.get(start) != Some(&usize::MAX) {
                continue;
            }
            if let Some(c) = comp.get_mut(start) {
                *c = start;
            }
            q.push_back(start);
            while let Some(b) = q.pop_front() {
                for &(link, other) in self.adj.get(b).map(Vec::as_slice).unwrap_or(&[]) {
                    let closed = self.snap.links.get(link).is_some_and(|l| l.closed);
                    if closed {
                        if let Some(c) = comp.get_mut(other) {
                            if *c == usize::MAX {
                                *c = start;
                                q.push_back(other);
                            }
                        }
                    }
                }
            }
        }
        comp
    }

    /// Recomputes the live flags. Returns the list of source sets of different groups that
    /// are joined, each as (buses, sources, both_live), sorted.
    pub(crate) fn energise(&mut self) -> Vec<(Vec<String>, Vec<String>, bool)> {
        let comp = self.components();
        let n = self.snap.buses.len();
        let mut comp_src: Vec<Option<usize>> = vec![None; n];
        for (si, s) in self.snap.sources.iter().enumerate() {
            if s.live {
                if let Some(&c) = comp.get(s.bus) {
                    if let Some(l) = comp_src.get_mut(c) {
                        if l.is_none() {
                            *l = Some(si);
                        }
                    }
                }
            }
        }
        for (i, b) in self.snap.buses.iter_mut().enumerate() {
            let src = comp
                .get(i)
                .and_then(|&c| comp_src.get(c))
                .copied()
                .flatten();
            b.live = src.is_some();
            if let Some(x) = self.supply.get_mut(i) {
                *x = src;
            }
        }
        let mut out = Vec::new();
        let mut seen = vec![false; n];
        for s in &self.snap.sources {
            let Some(&c) = comp.get(s.bus) else { continue };
            if seen.get(c).copied().unwrap_or(true) {
                continue;
            }
            if let Some(x) = seen.get_mut(c) {
                *x = true;
            }
            let members: Vec<&SourceState> = self
                .snap
                .sources
                .iter()
                .filter(|o| comp.get(o.bus) == Some(&c))
                .collect();
            let mixed = members.iter().any(|m| m.group != s.group);
            if !mixed {
                continue;
            }
            let mut sources: Vec<String> = members.iter().map(|m| m.name.clone()).collect();
            sources.sort();
            let live_groups = {
                let mut g: Vec<&str> = members.iter().filter(|m| m.live).map(|m| m.group).collect();
                g.sort_unstable();
                g.dedup();
                g.len()
            };
            let mut buses: Vec<String> = self
                .snap
                .buses
                .iter()
                .enumerate()
                .filter(|(i, _)| comp.get(*i) == Some(&c))
                .map(|(_, b)| b.name.clone())
                .collect();
            buses.sort();
            out.push((buses, sources, live_groups >= 2));
        }
        out.sort_by(|a, b| a.1.cmp(&b.1));
        out
    }
}
