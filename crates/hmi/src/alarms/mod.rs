//! Alarms managed to ISA-18.2: raised and cleared by fault points, with priorities,
//! acknowledgement, shelving, suppression by design, out of service, the initial state
//! taken after a general interrogation, link-loss grouping, and chattering and flood
//! detection (docs/HMI.md, "Alarm management").
//!
//! An alarm is raised when its point takes the alarm value with good quality and cleared
//! when it leaves it (an invalid value changes nothing: the last known state stands). A
//! cleared alarm that needs acknowledgement stays listed until acknowledged. Shelving
//! hides an alarm from the alarm line and silences it; it never stops the station from
//! transmitting, nor the HMI from recording, the fault.
//!
//! ```text
//!  point value --> active? --held? (settling | suppressed | out of service | link lost)
//!                     |            yes: tracked, nothing waits for acknowledgement
//!                     |            no:  announced: unacknowledged, an activation logged
//!                     |                  --> chattering? flood? (system alarms of their own)
//!  clock (5 Hz) --> shelving ended? settle window over? hold ended while active? -> announced
//! ```
//!
//! A *held* alarm is active but not announced: it became active while a hold applied.
//! When the hold ends while it is still active it is announced then (raised at that
//! moment, waiting for acknowledgement); when it clears first nothing waits.

pub mod kpi;

use std::collections::{HashMap, HashSet, VecDeque};

use chrono::{DateTime, Duration, Utc};
use serde::Serialize;

use crate::config::AlarmConfig;

/// The settle time after the HMI's general interrogation (and after a link point
/// returns to normal): values arriving in it are the initial state.
pub const SETTLE: Duration = Duration::seconds(8);
/// Chattering: at least this many activations ...
pub const CHATTER_COUNT: usize = 3;
/// ... within this long.
pub const CHATTER_WINDOW: Duration = Duration::seconds(60);
/// Flood: at least this many activations ...
pub const FLOOD_COUNT: usize = 10;
/// ... within this long,
pub const FLOOD_WINDOW: Duration = Duration::minutes(10);
/// ... ending when fewer than this many remain in the window (ISA-18.2's hysteresis).
pub const FLOOD_END_COUNT: usize = 5;
/// Activations are kept this long for the KPI report.
pub const KEEP_ACTIVATIONS: Duration = Duration::days(35);
/// And at most this many.
const MAX_ACTIVATIONS: usize = 500_000;
/// The point the flood alarm names.
pub const FLOOD_POINT: &str = "alarm system";

/// Who took an alarm out of service, why and when.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct OutOfService {
    /// Why.
    pub reason: String,
    /// The user.
    pub user: String,
    /// Since when.
    pub since: DateTime<Utc>,
}

/// One alarm's state.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Alarm {
    /// Stable id: the index of its definition; then the chattering alarms of each
    /// definition (`definitions + index`); then the flood alarm.
    pub id: usize,
    /// The point (the chattering point for a chattering alarm; `alarm system` for the
    /// flood alarm).
    pub point: String,
    /// Text.
    pub text: String,
    /// 1 (highest) ..= 4.
    pub priority: u8,
    /// When it was last raised.
    pub raised: Option<DateTime<Utc>>,
    /// When it was last cleared (after it was raised).
    pub cleared: Option<DateTime<Utc>>,
    /// Whether it was acknowledged since it was raised.
    pub acknowledged: bool,
    /// A timed shelve ends then; `null` when not shelved or shelved one-shot.
    pub shelved_until: Option<DateTime<Utc>>,
    /// The fault is present.
    pub active: bool,
    /// Whether it needs acknowledgement.
    pub needs_acknowledgement: bool,
    /// Shelved (timed or one-shot).
    pub shelved: bool,
    /// Shelved until it returns to normal.
    pub oneshot: bool,
    /// Why it was shelved, if said.
    pub shelve_reason: Option<String>,
    /// Who shelved it.
    pub shelved_by: Option<String>,
    /// Suppressed by design: its condition holds now.
    pub suppressed: bool,
    /// Out of service, with why and who.
    pub out_of_service: Option<OutOfService>,
    /// Active as a consequence of a lost link: the id of the link's alarm.
    pub consequence_of: Option<usize>,
    /// Raised by the alarm system itself (chattering, flood).
    pub system: bool,
}

impl Alarm {
    /// Whether it waits for acknowledgement.
    pub fn waiting(&self) -> bool {
        self.needs_acknowledgement && !self.acknowledged && self.raised.is_some()
    }

    /// Whether the alarm list shows it: active, waiting for acknowledgement, shelved or
    /// out of service.
    pub fn listed(&self) -> bool {
        self.active || self.waiting() || self.shelved || self.out_of_service.is_some()
    }
}

/// One announced activation, by the HMI's receive time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Activation {
    /// When.
    pub time: DateTime<Utc>,
    /// The alarm.
    pub id: usize,
}

/// How long a shelve lasts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shelve {
    /// Until then (the server ends it, and the alarm returns unacknowledged if active).
    Until(DateTime<Utc>),
    /// Until the alarm returns to normal.
    OneShot,
}

/// Why an alarm request was refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum AlarmRefusal {
    /// No alarm with that id.
    #[error("no such alarm")]
    NoAlarm,
    /// One-shot shelving is for an active alarm.
    #[error(
        "one-shot shelving needs an active alarm (it lasts until the alarm returns to normal)"
    )]
    NotActive,
    /// The alarm is not shelved.
    #[error("the alarm is not shelved")]
    NotShelved,
    /// The alarm is not out of service.
    #[error("the alarm is not out of service")]
    InService,
}

/// Why an active alarm is not announced.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Hold {
    OutOfService,
    Settling,
    Suppressed,
    Consequence(Option<usize>),
}

#[derive(Debug, Clone, Default)]
struct Definition {
    when: bool,
    suppress: Option<(String, bool)>,
    link: Option<String>,
    /// Active but not announced.
    held: bool,
}

/// Every alarm: the configured ones, a chattering alarm for each, and the flood alarm.
#[derive(Debug, Clone, Default)]
pub struct Alarms {
    alarms: Vec<Alarm>,
    definitions: Vec<Definition>,
    /// The last good value of each point a suppression or link names.
    conditions: HashMap<String, bool>,
    /// The settle window after the HMI's general interrogation.
    settle_until: Option<DateTime<Utc>>,
    /// The settle window after a link point returned to normal, by link point.
    link_recovery: HashMap<String, DateTime<Utc>>,
    activations: VecDeque<Activation>,
    /// Activations are logged from then (the HMI's start, or the oldest kept).
    log_start: DateTime<Utc>,
}

impl Alarms {
    /// The alarms of the configuration, all quiet.
    pub fn new(config: &[AlarmConfig]) -> Alarms {
        let quiet = |id: usize, point: &str, text: &str, priority: u8, ack: bool| Alarm {
            id,
            point: point.to_owned(),
            text: text.to_owned(),
            priority,
            raised: None,
            cleared: None,
            acknowledged: false,
            shelved_until: None,
            active: false,
            needs_acknowledgement: ack,
            shelved: false,
            oneshot: false,
            shelve_reason: None,
            shelved_by: None,
            suppressed: false,
            out_of_service: None,
            consequence_of: None,
            system: false,
        };
        let mut alarms: Vec<Alarm> = config
            .iter()
            .enumerate()
            .map(|(id, c)| quiet(id, &c.point, &c.text, c.priority, c.acknowledge))
            .collect();
        let count = config.len();
        for (index, c) in config.iter().enumerate() {
            let mut alarm = quiet(
                count + index,
                &c.point,
                &format!("Chattering: {}", c.text),
                c.priority,
                true,
            );
            alarm.system = true;
            alarms.push(alarm);
        }
        let mut flood = quiet(2 * count, FLOOD_POINT, "Alarm flood", 2, true);
        flood.system = true;
        alarms.push(flood);
        let mut definitions: Vec<Definition> = config
            .iter()
            .map(|c| Definition {
                when: c.when,
                suppress: c.suppress_when.as_ref().map(|s| (s.point.clone(), s.state)),
                link: c.link.clone(),
                held: false,
            })
            .collect();
        definitions.resize(alarms.len(), Definition::default());
        let conditions = config
            .iter()
            .flat_map(|c| {
                c.suppress_when
                    .iter()
                    .map(|s| s.point.clone())
                    .chain(c.link.iter().cloned())
            })
            .collect::<HashSet<String>>()
            .into_iter()
            .map(|point| (point, false))
            .collect();
        Alarms {
            alarms,
            definitions,
            conditions,
            settle_until: None,
            link_recovery: HashMap::new(),
            activations: VecDeque::new(),
            log_start: Utc::now(),
        }
    }

    fn configured(&self) -> usize {
        self.alarms.len().saturating_sub(1) / 2
    }

    fn flood_id(&self) -> usize {
        2 * self.configured()
    }

    /// Values arriving until `until` are the initial state (after the HMI's general
    /// interrogation): an alarm that comes and goes in it waits for nothing; one active
    /// at its end is raised then.
    pub fn settle(&mut self, until: DateTime<Utc>) {
        self.settle_until = Some(self.settle_until.map_or(until, |u| u.max(until)));
    }

    /// Whether values are being taken as the initial state now.
    pub fn settling(&self, now: DateTime<Utc>) -> bool {
        self.settle_until.is_some_and(|until| now < until)
    }

    /// A single point changed; returns the alarms whose state changed.
    pub fn point(&mut self, name: &str, on: bool, invalid: bool, now: DateTime<Utc>) -> Vec<Alarm> {
        if invalid {
            return Vec::new();
        }
        let mut changed = Vec::new();
        let is_condition = if let Some(value) = self.conditions.get_mut(name) {
            if *value && !on {
                // The link is back: what it brings in the next seconds is its image.
                self.link_recovery.insert(name.to_owned(), now + SETTLE);
            }
            *value = on;
            true
        } else {
            false
        };
        for id in 0..self.configured() {
            let Some(alarm) = self.alarms.get(id) else {
                continue;
            };
            if alarm.point != name {
                continue;
            }
            let active = self.definitions.get(id).is_some_and(|d| d.when == on);
            if active == alarm.active {
                continue;
            }
            if active {
                let hold = self.hold(id, now);
                if let Some(alarm) = self.alarms.get_mut(id) {
                    alarm.active = true;
                }
                match hold {
                    None => self.announce(id, now, &mut changed),
                    Some(hold) => self.hold_alarm(id, hold, now),
                }
            } else {
                self.return_to_normal(id, now);
            }
            // The suppression flag follows the condition point's last value.
            self.reconcile(id, now, &mut changed);
            changed.push(id);
        }
        if is_condition {
            for id in 0..self.configured() {
                let names = self.definitions.get(id).is_some_and(|d| {
                    d.link.as_deref() == Some(name)
                        || d.suppress.as_ref().is_some_and(|(p, _)| p == name)
                });
                if names && self.reconcile(id, now, &mut changed) {
                    changed.push(id);
                }
            }
        }
        self.collect(changed)
    }

    /// The clock: ends timed shelves, settle windows, chattering and floods. Returns the
    /// alarms whose state changed.
    pub fn tick(&mut self, now: DateTime<Utc>) -> Vec<Alarm> {
        let mut changed = Vec::new();
        if self.settle_until.is_some_and(|until| now >= until) {
            self.settle_until = None;
        }
        self.link_recovery.retain(|_, until| now < *until);
        for id in 0..self.configured() {
            if self.reconcile(id, now, &mut changed) {
                changed.push(id);
            }
        }
        for alarm in &mut self.alarms {
            let ended = alarm.shelved
                && !alarm.oneshot
                && alarm.shelved_until.is_some_and(|until| now >= until);
            if ended {
                end_shelve(alarm);
                // ISA-18.2: a shelve ended by its timer returns the alarm unacknowledged.
                if alarm.active && alarm.needs_acknowledgement {
                    alarm.acknowledged = false;
                }
                changed.push(alarm.id);
            }
        }
        let configured = self.configured();
        for index in 0..configured {
            let chatter_id = configured + index;
            if self.alarms.get(chatter_id).is_some_and(|a| a.active)
                && self.count_since(Some(index), now - CHATTER_WINDOW) < CHATTER_COUNT
            {
                self.return_to_normal(chatter_id, now);
                changed.push(chatter_id);
            }
        }
        let flood_id = self.flood_id();
        if self.alarms.get(flood_id).is_some_and(|a| a.active)
            && self.count_since(None, now - FLOOD_WINDOW) < FLOOD_END_COUNT
        {
            self.return_to_normal(flood_id, now);
            changed.push(flood_id);
        }
        while self
            .activations
            .front()
            .is_some_and(|a| a.time < now - KEEP_ACTIVATIONS)
        {
            if let Some(dropped) = self.activations.pop_front() {
                self.log_start = self.log_start.max(dropped.time);
            }
        }
        self.collect(changed)
    }

    /// Acknowledges an alarm.
    pub fn acknowledge(&mut self, id: usize) -> Option<Alarm> {
        let alarm = self.alarms.get_mut(id)?;
        alarm.acknowledged = true;
        Some(alarm.clone())
    }

    /// Shelves an alarm (`user` and `reason` are kept with it).
    pub fn shelve(
        &mut self,
        id: usize,
        how: Shelve,
        reason: Option<String>,
        user: &str,
    ) -> Result<Alarm, AlarmRefusal> {
        let alarm = self.alarms.get_mut(id).ok_or(AlarmRefusal::NoAlarm)?;
        match how {
            Shelve::OneShot if !alarm.active => return Err(AlarmRefusal::NotActive),
            Shelve::OneShot => {
                alarm.shelved_until = None;
                alarm.oneshot = true;
            }
            Shelve::Until(until) => {
                alarm.shelved_until = Some(until);
                alarm.oneshot = false;
            }
        }
        alarm.shelved = true;
        alarm.shelve_reason = reason;
        alarm.shelved_by = Some(user.to_owned());
        Ok(alarm.clone())
    }

    /// Unshelves an alarm by hand: ISA-18.2 returns it acknowledged.
    pub fn unshelve(&mut self, id: usize) -> Result<Alarm, AlarmRefusal> {
        let alarm = self.alarms.get_mut(id).ok_or(AlarmRefusal::NoAlarm)?;
        if !alarm.shelved {
            return Err(AlarmRefusal::NotShelved);
        }
        end_shelve(alarm);
        alarm.acknowledged = true;
        Ok(alarm.clone())
    }

    /// Takes an alarm out of service: while out, it is not announced and waits for
    /// nothing; a shelve ends.
    pub fn out_of_service(
        &mut self,
        id: usize,
        reason: String,
        user: &str,
        now: DateTime<Utc>,
    ) -> Result<Alarm, AlarmRefusal> {
        let alarm = self.alarms.get_mut(id).ok_or(AlarmRefusal::NoAlarm)?;
        alarm.out_of_service = Some(OutOfService {
            reason,
            user: user.to_owned(),
            since: now,
        });
        end_shelve(alarm);
        alarm.acknowledged = true;
        Ok(alarm.clone())
    }

    /// Returns an alarm to service; active, it is announced (unacknowledged) if it became
    /// active while out of service.
    pub fn in_service(&mut self, id: usize, now: DateTime<Utc>) -> Result<Alarm, AlarmRefusal> {
        let alarm = self.alarms.get_mut(id).ok_or(AlarmRefusal::NoAlarm)?;
        if alarm.out_of_service.take().is_none() {
            return Err(AlarmRefusal::InService);
        }
        let mut changed = Vec::new();
        self.reconcile(id, now, &mut changed);
        self.alarms.get(id).cloned().ok_or(AlarmRefusal::NoAlarm)
    }

    /// The alarms the list shows, highest priority and newest first.
    pub fn listed(&self) -> Vec<Alarm> {
        let mut list: Vec<Alarm> = self.alarms.iter().filter(|a| a.listed()).cloned().collect();
        list.sort_by(|a, b| a.priority.cmp(&b.priority).then(b.raised.cmp(&a.raised)));
        list
    }

    /// One alarm.
    pub fn get(&self, id: usize) -> Option<&Alarm> {
        self.alarms.get(id)
    }

    /// Every alarm, listed or not.
    pub fn all(&self) -> &[Alarm] {
        &self.alarms
    }

    /// The announced activations kept, oldest first.
    pub fn activations(&self) -> impl Iterator<Item = &Activation> {
        self.activations.iter()
    }

    /// Activations are logged from then: the HMI's start, later when old ones were
    /// dropped.
    pub fn log_start(&self) -> DateTime<Utc> {
        self.log_start
    }

    fn collect(&self, mut ids: Vec<usize>) -> Vec<Alarm> {
        ids.sort_unstable();
        ids.dedup();
        ids.iter()
            .filter_map(|id| self.alarms.get(*id).cloned())
            .collect()
    }

    fn hold(&self, id: usize, now: DateTime<Utc>) -> Option<Hold> {
        let alarm = self.alarms.get(id)?;
        let definition = self.definitions.get(id)?;
        if alarm.out_of_service.is_some() {
            return Some(Hold::OutOfService);
        }
        if self.settling(now) {
            return Some(Hold::Settling);
        }
        if let Some((point, state)) = &definition.suppress {
            if self.conditions.get(point) == Some(state) {
                return Some(Hold::Suppressed);
            }
        }
        if let Some(link) = &definition.link {
            let lost = self.conditions.get(link) == Some(&true);
            if lost || self.link_recovery.contains_key(link) {
                let link_alarm = self
                    .alarms
                    .iter()
                    .take(self.configured())
                    .zip(&self.definitions)
                    .find(|(a, d)| &a.point == link && d.when)
                    .map(|(a, _)| a.id);
                return Some(Hold::Consequence(link_alarm));
            }
        }
        None
    }

    fn hold_alarm(&mut self, id: usize, hold: Hold, now: DateTime<Utc>) {
        if let (Some(alarm), Some(definition)) =
            (self.alarms.get_mut(id), self.definitions.get_mut(id))
        {
            definition.held = true;
            alarm.raised = Some(now);
            alarm.cleared = None;
            // Nothing waits for acknowledgement until it is announced.
            alarm.acknowledged = true;
            alarm.consequence_of = match hold {
                Hold::Consequence(link) => link,
                _ => None,
            };
        }
    }

    /// Re-evaluates a held alarm's hold and the suppression flag; true when it changed.
    fn reconcile(&mut self, id: usize, now: DateTime<Utc>, changed: &mut Vec<usize>) -> bool {
        let hold = self.hold(id, now);
        let Some(alarm) = self.alarms.get(id) else {
            return false;
        };
        let held = self.definitions.get(id).is_some_and(|d| d.held);
        let suppressed = self.definitions.get(id).is_some_and(|d| {
            d.suppress
                .as_ref()
                .is_some_and(|(p, s)| self.conditions.get(p) == Some(s))
        });
        let mut any = false;
        if alarm.suppressed != suppressed {
            if let Some(alarm) = self.alarms.get_mut(id) {
                alarm.suppressed = suppressed;
            }
            any = true;
        }
        let active = self.alarms.get(id).is_some_and(|a| a.active);
        if active && held {
            match hold {
                None => {
                    self.announce(id, now, changed);
                    any = true;
                }
                Some(Hold::Consequence(link)) => {
                    if let Some(alarm) = self.alarms.get_mut(id) {
                        if alarm.consequence_of != link {
                            alarm.consequence_of = link;
                            any = true;
                        }
                    }
                }
                Some(_) => {}
            }
        }
        any
    }

    fn return_to_normal(&mut self, id: usize, now: DateTime<Utc>) {
        if let Some(definition) = self.definitions.get_mut(id) {
            definition.held = false;
        }
        if let Some(alarm) = self.alarms.get_mut(id) {
            alarm.active = false;
            alarm.cleared = Some(now);
            alarm.consequence_of = None;
            if alarm.oneshot {
                // A one-shot shelve lasts until the alarm returns to normal.
                end_shelve(alarm);
                alarm.acknowledged = true;
            }
        }
    }

    /// Raises an active alarm for the operator: unacknowledged, logged as an activation,
    /// then looks for chattering and a flood.
    fn announce(&mut self, id: usize, now: DateTime<Utc>, changed: &mut Vec<usize>) {
        if let Some(definition) = self.definitions.get_mut(id) {
            definition.held = false;
        }
        let Some(alarm) = self.alarms.get_mut(id) else {
            return;
        };
        alarm.raised = Some(now);
        alarm.cleared = None;
        alarm.acknowledged = false;
        alarm.consequence_of = None;
        self.activations.push_back(Activation { time: now, id });
        if self.activations.len() > MAX_ACTIVATIONS {
            if let Some(dropped) = self.activations.pop_front() {
                self.log_start = self.log_start.max(dropped.time);
            }
        }
        let configured = self.configured();
        let recent = self.count_since(Some(id), now - CHATTER_WINDOW);
        let chatter_id = configured + id;
        if recent >= CHATTER_COUNT {
            let source = self
                .alarms
                .get(id)
                .map(|a| a.text.clone())
                .unwrap_or_default();
            if let Some(chatter) = self.alarms.get_mut(chatter_id) {
                chatter.text = format!("Chattering: {source} ({recent} activations within 60 s)");
                if !chatter.active {
                    raise_system(chatter, now);
                }
                changed.push(chatter_id);
            }
        }
        let flood_count = self.count_since(None, now - FLOOD_WINDOW);
        let flood_id = self.flood_id();
        if flood_count >= FLOOD_COUNT {
            if let Some(flood) = self.alarms.get_mut(flood_id) {
                flood.text = format!("Alarm flood: {flood_count} alarms within 10 min");
                if !flood.active {
                    raise_system(flood, now);
                }
                changed.push(flood_id);
            }
        }
    }

    /// Activations since `since` (exclusive), of one alarm or of all.
    fn count_since(&self, id: Option<usize>, since: DateTime<Utc>) -> usize {
        self.activations
            .iter()
            .rev()
            .take_while(|a| a.time > since)
            .filter(|a| id.is_none_or(|id| a.id == id))
            .count()
    }
}

fn raise_system(alarm: &mut Alarm, now: DateTime<Utc>) {
    alarm.active = true;
    alarm.raised = Some(now);
    alarm.cleared = None;
    alarm.acknowledged = false;
}

fn end_shelve(alarm: &mut Alarm) {
    alarm.shelved = false;
    alarm.oneshot = false;
    alarm.shelved_until = None;
    alarm.shelve_reason = None;
    alarm.shelved_by = None;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::AlarmCondition;

    fn alarm(point: &str, when: bool, priority: u8, acknowledge: bool) -> AlarmConfig {
        AlarmConfig {
            point: point.into(),
            when,
            priority,
            text: format!("{point} alarm"),
            acknowledge,
            suppress_when: None,
            link: None,
        }
    }

    fn config() -> Vec<AlarmConfig> {
        vec![
            AlarmConfig {
                text: "fault".into(),
                ..alarm("FAULT", true, 1, true)
            },
            AlarmConfig {
                text: "not ready".into(),
                ..alarm("READY", false, 3, false)
            },
        ]
    }

    fn waiting(alarms: &Alarms) -> usize {
        alarms.all().iter().filter(|a| a.waiting()).count()
    }

    #[test]
    fn raise_clear_acknowledge_and_invalid_values() {
        let now = Utc::now();
        let mut alarms = Alarms::new(&config());
        assert_eq!(alarms.point("FAULT", true, false, now).len(), 1);
        assert_eq!(alarms.point("FAULT", true, false, now).len(), 0);
        // An invalid value does not clear it.
        assert!(alarms.point("FAULT", false, true, now).is_empty());
        assert_eq!(alarms.listed().len(), 1);
        alarms.point("FAULT", false, false, now);
        // Cleared but not acknowledged: still listed.
        assert_eq!(alarms.listed().len(), 1);
        alarms.acknowledge(0);
        assert!(alarms.listed().is_empty());
        // `when = false` and no acknowledgement: listed exactly while active.
        alarms.point("READY", false, false, now);
        assert_eq!(alarms.listed()[0].text, "not ready");
        alarms.point("READY", true, false, now);
        assert!(alarms.listed().is_empty());
    }

    #[test]
    fn values_in_the_settle_window_are_the_initial_state() {
        let start = Utc::now();
        let mut alarms = Alarms::new(&[alarm("A", true, 1, true), alarm("B", true, 2, true)]);
        alarms.settle(start + SETTLE);
        // A comes and goes in the window: nothing waits. B stays active.
        alarms.point("A", true, false, start);
        alarms.point("A", false, false, start + Duration::seconds(1));
        alarms.point("B", true, false, start + Duration::seconds(2));
        assert_eq!(waiting(&alarms), 0);
        assert!(alarms.get(1).is_some_and(|b| b.active && b.listed()));
        // At the end of the window B is raised then.
        let end = start + SETTLE;
        let raised = alarms.tick(end);
        assert_eq!(raised.iter().map(|a| a.id).collect::<Vec<_>>(), vec![1]);
        assert_eq!(waiting(&alarms), 1);
        assert_eq!(alarms.get(1).and_then(|b| b.raised), Some(end));
        assert_eq!(alarms.activations().count(), 1);
    }

    #[test]
    fn shelving_timed_by_hand_and_one_shot() {
        let now = Utc::now();
        let mut alarms = Alarms::new(&[alarm("A", true, 1, true)]);
        alarms.point("A", true, false, now);
        // Timed: its timer returns it unacknowledged.
        alarms.acknowledge(0);
        let until = now + Duration::seconds(1);
        let shelved = alarms.shelve(0, Shelve::Until(until), None, "op").unwrap();
        assert!(shelved.shelved && shelved.listed());
        assert!(alarms.tick(now).is_empty());
        let ended = alarms.tick(until);
        assert_eq!(ended.len(), 1);
        assert!(!ended[0].shelved && ended[0].shelved_until.is_none() && !ended[0].acknowledged);
        // By hand: returns acknowledged.
        alarms
            .shelve(0, Shelve::Until(until), Some("work".into()), "op")
            .unwrap();
        let back = alarms.unshelve(0).unwrap();
        assert!(!back.shelved && back.acknowledged);
        assert_eq!(alarms.unshelve(0), Err(AlarmRefusal::NotShelved));
        // One-shot: until it returns to normal.
        let one = alarms.shelve(0, Shelve::OneShot, None, "op").unwrap();
        assert!(one.oneshot && one.shelved_until.is_none());
        alarms.point("A", false, false, now);
        assert!(alarms.get(0).is_some_and(|a| !a.shelved && !a.oneshot));
        assert_eq!(
            alarms.shelve(0, Shelve::OneShot, None, "op"),
            Err(AlarmRefusal::NotActive)
        );
    }

    #[test]
    fn suppression_by_design_and_out_of_service() {
        let now = Utc::now();
        let mut config = alarm("FEEDER", true, 2, true);
        config.suppress_when = Some(AlarmCondition {
            point: "LOCAL".into(),
            state: true,
        });
        let mut alarms = Alarms::new(&[config]);
        alarms.point("LOCAL", true, false, now);
        alarms.point("FEEDER", true, false, now);
        let feeder = alarms.get(0).cloned().unwrap();
        assert!(feeder.suppressed && feeder.active && !feeder.waiting());
        // The condition ends with the fault still there: raised then.
        alarms.point("LOCAL", false, false, now);
        assert!(alarms.get(0).is_some_and(|a| !a.suppressed && a.waiting()));
        alarms.acknowledge(0);
        alarms.point("FEEDER", false, false, now);
        // Out of service: an activation waits for nothing, back in service it is raised.
        alarms
            .out_of_service(0, "sensor broken".into(), "op", now)
            .unwrap();
        alarms.point("FEEDER", true, false, now);
        assert_eq!(waiting(&alarms), 0);
        let back = alarms.in_service(0, now).unwrap();
        assert!(back.waiting() && back.out_of_service.is_none());
    }

    #[test]
    fn a_link_loss_groups_the_alarms_behind_it() {
        let now = Utc::now();
        let mut board = alarm("BOARD_FUSE", true, 3, true);
        board.link = Some("COMM_BOARD".into());
        let mut alarms = Alarms::new(&[alarm("COMM_BOARD", true, 2, true), board]);
        alarms.point("COMM_BOARD", true, false, now);
        alarms.point("BOARD_FUSE", true, false, now);
        let fuse = alarms.get(1).cloned().unwrap();
        assert_eq!(fuse.consequence_of, Some(0));
        assert!(!fuse.waiting());
        // The link comes back and its image clears the fuse: only the link alarm waits.
        alarms.point("COMM_BOARD", false, false, now);
        alarms.point("BOARD_FUSE", false, false, now + Duration::seconds(1));
        alarms.tick(now + SETTLE + Duration::seconds(1));
        assert_eq!(waiting(&alarms), 1);
    }

    #[test]
    fn chattering_and_flood_raise_alarms_of_their_own() {
        let now = Utc::now();
        let configs: Vec<AlarmConfig> = (0..10)
            .map(|i| alarm(&format!("P{i}"), true, 3, true))
            .collect();
        let mut alarms = Alarms::new(&configs);
        for second in 0..3 {
            let t = now + Duration::seconds(second * 10);
            alarms.point("P0", true, false, t);
            alarms.point("P0", false, false, t + Duration::seconds(1));
        }
        let chatter = alarms.get(10).cloned().unwrap();
        assert!(chatter.active && chatter.system && chatter.point == "P0");
        assert!(chatter.text.contains("P0 alarm"), "{}", chatter.text);
        // The individual activations still raised the alarm itself.
        assert!(alarms.get(0).is_some_and(Alarm::waiting));
        for i in 1..7 {
            alarms.point(&format!("P{i}"), true, false, now + Duration::seconds(40));
        }
        let flood = alarms.get(20).cloned().unwrap();
        assert!(!flood.active);
        alarms.point("P7", true, false, now + Duration::seconds(41));
        let flood = alarms.get(20).cloned().unwrap();
        assert!(
            flood.active && flood.text.contains("10 alarms"),
            "{}",
            flood.text
        );
        // Both end when the rate falls.
        alarms.tick(now + Duration::minutes(11));
        assert!(alarms.get(10).is_some_and(|a| !a.active));
        assert!(alarms.get(20).is_some_and(|a| !a.active));
    }
}
