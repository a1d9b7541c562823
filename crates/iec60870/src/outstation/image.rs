//! The process image: the current value of every point a station serves, and the command
//! points it accepts.
//!
//! Interrogation and read requests are answered from here, so a general interrogation
//! always returns the newest value of each point, whatever is still waiting in an event
//! buffer.

use std::collections::BTreeMap;
use std::ops::Bound;

use crate::asdu::{Element, InformationObject, Ioa, TimeTag, TypeId};

/// A monitored point: its address, its type and the interrogation groups it belongs to.
#[derive(Debug, Clone, PartialEq)]
pub struct MonitorPoint {
    /// Information object address.
    pub ioa: Ioa,
    /// The type used for spontaneous transmission. Interrogation answers use its form
    /// without time tag (`M_SP_TB_1` is interrogated as `M_SP_NA_1`).
    pub event_type: TypeId,
    /// Membership of the interrogation groups 1..=16, bit 0 = group 1.
    pub groups: u16,
    /// The current value.
    pub element: Element,
    /// The time tag of the current value, if it has one.
    pub time: Option<TimeTag>,
}

impl MonitorPoint {
    /// The point as an information object, without time tag (for interrogation).
    pub fn as_object(&self) -> InformationObject {
        InformationObject {
            ioa: self.ioa,
            element: self.element.clone(),
            time: None,
        }
    }

    /// Whether the point answers an interrogation with the given qualifier
    /// (20 = station, 21..=36 = group 1..=16).
    pub fn answers_interrogation(&self, qualifier: u8) -> bool {
        match qualifier {
            20 => true,
            21..=36 => self.groups & (1 << (qualifier - 21)) != 0,
            _ => false,
        }
    }
}

/// A point that accepts commands.
#[derive(Debug, Clone, PartialEq)]
pub struct CommandPoint {
    /// Information object address.
    pub ioa: Ioa,
    /// The command type accepted (`C_SC_NA_1` also accepts its time-tagged twin
    /// `C_SC_TA_1`, and so on).
    pub command_type: TypeId,
    /// Whether an execute must be preceded by a select (select-before-operate).
    pub select_required: bool,
    /// The largest age of a time-tagged command to this point (the interoperability
    /// list's maximum command delay); `None` takes the server's
    /// [`OutstationConfig::max_command_age`](super::OutstationConfig::max_command_age).
    pub max_age: Option<std::time::Duration>,
}

/// Why a point could not be added or updated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ImageError {
    /// The address is already used by another point.
    #[error("information object address {0} is already used")]
    DuplicateAddress(Ioa),
    /// The type is not a monitor-direction process type.
    #[error("{0} is not a monitor-direction process information type")]
    NotMonitorType(TypeId),
    /// The type is not a control-direction process type.
    #[error("{0} is not a command type")]
    NotCommandType(TypeId),
    /// The element does not fit the point's type.
    #[error("the value given for {ioa} does not fit its type {type_id}")]
    ElementMismatch {
        /// Address of the point.
        ioa: Ioa,
        /// The point's type.
        type_id: TypeId,
    },
    /// No monitor point has that address.
    #[error("no monitor point has address {0}")]
    UnknownPoint(Ioa),
}

/// The station's monitor and command points, ordered by address.
#[derive(Debug, Default, Clone)]
pub struct ProcessImage {
    monitor: BTreeMap<u32, MonitorPoint>,
    commands: BTreeMap<u32, CommandPoint>,
}

impl ProcessImage {
    /// An empty image.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a monitor point.
    pub fn add_monitor(&mut self, point: MonitorPoint) -> Result<(), ImageError> {
        if !point.event_type.is_monitor() {
            return Err(ImageError::NotMonitorType(point.event_type));
        }
        if !point.element.family_matches(point.event_type) {
            return Err(ImageError::ElementMismatch {
                ioa: point.ioa,
                type_id: point.event_type,
            });
        }
        let key = point.ioa.get();
        if self.monitor.contains_key(&key) {
            return Err(ImageError::DuplicateAddress(point.ioa));
        }
        self.monitor.insert(key, point);
        Ok(())
    }

    /// Adds a command point. A command point may share its address with a monitor point
    /// (some stations report a command's state at the command's address).
    pub fn add_command(&mut self, point: CommandPoint) -> Result<(), ImageError> {
        if !point.command_type.is_command() {
            return Err(ImageError::NotCommandType(point.command_type));
        }
        let key = point.ioa.get();
        if self.commands.contains_key(&key) {
            return Err(ImageError::DuplicateAddress(point.ioa));
        }
        self.commands.insert(key, point);
        Ok(())
    }

    /// Sets a monitor point's value; returns the point's event type and whether the value
    /// (element or quality) changed.
    pub fn set(
        &mut self,
        ioa: Ioa,
        element: Element,
        time: Option<TimeTag>,
    ) -> Result<(TypeId, bool), ImageError> {
        let point = self
            .monitor
            .get_mut(&ioa.get())
            .ok_or(ImageError::UnknownPoint(ioa))?;
        if !element.family_matches(point.event_type) {
            return Err(ImageError::ElementMismatch {
                ioa,
                type_id: point.event_type,
            });
        }
        let changed = point.element != element;
        point.element = element;
        point.time = time;
        Ok((point.event_type, changed))
    }

    /// The monitor point at an address.
    pub fn monitor(&self, ioa: Ioa) -> Option<&MonitorPoint> {
        self.monitor.get(&ioa.get())
    }

    /// The command point at an address.
    pub fn command(&self, ioa: Ioa) -> Option<&CommandPoint> {
        self.commands.get(&ioa.get())
    }

    /// Monitor points with an address greater than `after` (or all, for `None`), in
    /// address order: an interrogation walks the image with this, a chunk at a time.
    pub fn monitor_after(&self, after: Option<Ioa>) -> impl Iterator<Item = &MonitorPoint> {
        let lower = match after {
            Some(ioa) => Bound::Excluded(ioa.get()),
            None => Bound::Unbounded,
        };
        self.monitor
            .range((lower, Bound::Unbounded))
            .map(|(_, point)| point)
    }

    /// All monitor points in address order.
    pub fn monitor_points(&self) -> impl Iterator<Item = &MonitorPoint> {
        self.monitor.values()
    }

    /// All command points in address order.
    pub fn command_points(&self) -> impl Iterator<Item = &CommandPoint> {
        self.commands.values()
    }

    /// Number of monitor points.
    pub fn monitor_len(&self) -> usize {
        self.monitor.len()
    }
}
