//! The declaration of a point: its name, address, type, how it is transmitted and where
//! its value comes from.

use std::time::Duration;

use crate::{PointKind, PointType, TimeStamp};

/// Where a point's value comes from.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum PointSource {
    /// A PLC variable path of the node.
    Variable(String),
    /// Point `ioa` received over the node's client link `link`.
    Link {
        /// The link's name.
        link: String,
        /// The information object address on the lower node.
        ioa: u32,
    },
    /// The state of the node's client link with this name (TRUE = link down), for a point
    /// named by the link's `status_point`; such a point has no `source`.
    LinkStatus(String),
    /// Whether a controlling station of the server's redundancy group with this name is
    /// connected (TRUE = none is), for a point named by the group's `status_point`.
    ClientStatus(String),
    /// A signal of a device on one of the node's serial lines (`line:LINE/DEVICE/...`).
    Line {
        /// The line's name.
        line: String,
        /// The device's name on the line.
        device: String,
        /// Which of the device's signals.
        signal: LineSignal,
    },
    /// Whether any device on a serial line answers (TRUE = none does), for a point named
    /// by the line's `status_point`.
    LineStatus {
        /// The line's name.
        line: String,
    },
    /// Whether a device on a serial line answers (TRUE = it does not), for a point named
    /// by the device's `status_point`.
    DeviceStatus {
        /// The line's name.
        line: String,
        /// The device's name.
        device: String,
    },
    /// A signal of a profiled device (`[[node.device]]`): the points its kind's
    /// [`DeviceProfile`](crate::DeviceProfile) brings.
    Device {
        /// The device's name.
        device: String,
        /// The signal's name in the profile.
        signal: String,
    },
    /// The communication status of a profiled device (TRUE = it does not answer), for a
    /// point named by the device's `status_point`.
    DeviceComm {
        /// The device's name.
        device: String,
    },
    /// A value of a watched lift (`[[node.lift]]`): the points each lift brings.
    Lift {
        /// The lift's name.
        lift: String,
        /// Which of its values.
        signal: LiftSignal,
    },
}

/// A value of a lift watched through its controller board (the points of a
/// `[[node.lift]]`, one per signal, at the lift's `ioa_base` + [`LiftSignal::offset`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LiftSignal {
    /// The board's status code.
    Status,
    /// The status's colour class: 0 normal (green), 1 attention (orange), 2 fault (red).
    Colour,
    /// The car's floor.
    Position,
    /// The target floor of the trip.
    Target,
    /// 0 stopped, 1 up, 2 down (whatever the board's own coding).
    Direction,
    /// 0 unknown, 1 closed, 2 partly open, 3 open, 4 door fault.
    Door,
    /// TRUE while the board does not answer (the communication alarm).
    NotAnswering,
    /// TRUE while the lift is out of service (a fault status).
    OutOfService,
    /// TRUE while the lift is in inspection (maintenance) mode.
    Inspection,
    /// The code of the newest fault archived.
    LastFault,
    /// Line errors counted by the poller (time-outs, invalid frames).
    Errors,
    /// Faults archived from the board's log.
    Faults,
    /// Trips, all floors together.
    Trips,
    /// Trips to floor N (1-based).
    FloorTrips(u8),
}

impl LiftSignal {
    /// Which changes of the signal's point the history keeps: at most one a minute for
    /// the signals that change on every poll while something is wrong (a silent board's
    /// line-error count grew every 0.5 s, 170,000 stored events a day per cut cable).
    /// The point is still sent on every change; the store keeps the first change of each
    /// interval (and every change of quality). Every change of the other signals.
    pub fn storage(self) -> crate::StorageRule {
        match self {
            LiftSignal::Errors => {
                crate::StorageRule::default().with_min_interval(std::time::Duration::from_secs(60))
            }
            _ => crate::StorageRule::default(),
        }
    }

    /// The signals every lift has, in IOA order (the floors' trip counters follow them).
    pub const COMMON: [LiftSignal; 13] = [
        LiftSignal::Status,
        LiftSignal::Colour,
        LiftSignal::Position,
        LiftSignal::Target,
        LiftSignal::Direction,
        LiftSignal::Door,
        LiftSignal::NotAnswering,
        LiftSignal::OutOfService,
        LiftSignal::Inspection,
        LiftSignal::LastFault,
        LiftSignal::Errors,
        LiftSignal::Faults,
        LiftSignal::Trips,
    ];

    /// The first offset of the floors' trip counters: the common signals leave room for
    /// three more before them.
    pub const FLOOR_TRIPS_OFFSET: u32 = 16;

    /// Its IOA's offset from the lift's `ioa_base`.
    pub fn offset(self) -> u32 {
        match self {
            LiftSignal::Status => 0,
            LiftSignal::Colour => 1,
            LiftSignal::Position => 2,
            LiftSignal::Target => 3,
            LiftSignal::Direction => 4,
            LiftSignal::Door => 5,
            LiftSignal::NotAnswering => 6,
            LiftSignal::OutOfService => 7,
            LiftSignal::Inspection => 8,
            LiftSignal::LastFault => 9,
            LiftSignal::Errors => 10,
            LiftSignal::Faults => 11,
            LiftSignal::Trips => 12,
            LiftSignal::FloorTrips(floor) => {
                Self::FLOOR_TRIPS_OFFSET + u32::from(floor.saturating_sub(1))
            }
        }
    }

    /// The signal of a point name's suffix after `LIFT.` (the reverse of
    /// [`LiftSignal::suffix`]).
    pub fn from_suffix(suffix: &str) -> Option<LiftSignal> {
        if let Some(floor) = suffix
            .strip_prefix("floor")
            .and_then(|rest| rest.strip_suffix("_trips"))
        {
            return floor
                .parse::<u8>()
                .ok()
                .filter(|floor| *floor >= 1)
                .map(LiftSignal::FloorTrips);
        }
        LiftSignal::COMMON
            .into_iter()
            .find(|signal| signal.suffix() == suffix)
    }

    /// The name of lift `lift`'s point of this signal: `L1.status`.
    pub fn point_name(self, lift: &str) -> String {
        format!("{lift}.{}", self.suffix())
    }

    /// The point name's suffix after `LIFT.`: `status`, `floor3_trips` ...
    pub fn suffix(self) -> String {
        match self {
            LiftSignal::Status => "status".into(),
            LiftSignal::Colour => "colour".into(),
            LiftSignal::Position => "position".into(),
            LiftSignal::Target => "target".into(),
            LiftSignal::Direction => "direction".into(),
            LiftSignal::Door => "door".into(),
            LiftSignal::NotAnswering => "not_answering".into(),
            LiftSignal::OutOfService => "out_of_service".into(),
            LiftSignal::Inspection => "inspection".into(),
            LiftSignal::LastFault => "last_fault".into(),
            LiftSignal::Errors => "errors".into(),
            LiftSignal::Faults => "faults".into(),
            LiftSignal::Trips => "trips".into(),
            LiftSignal::FloorTrips(floor) => format!("floor{floor}_trips"),
        }
    }

    /// The type its point is declared with: indications as single points, codes and
    /// floors as scaled values, counts as integrated totals, all with full time stamps.
    pub fn point_type(self) -> PointType {
        let kind = match self {
            LiftSignal::NotAnswering | LiftSignal::OutOfService | LiftSignal::Inspection => {
                PointKind::Single
            }
            LiftSignal::Errors
            | LiftSignal::Faults
            | LiftSignal::Trips
            | LiftSignal::FloorTrips(_) => PointKind::Total,
            _ => PointKind::Scaled,
        };
        PointType::new(kind, TimeStamp::Full)
    }

    /// What the point shows, for the point list.
    pub fn description(self) -> String {
        match self {
            LiftSignal::Status => "status code (EKM66 Appendix A)".into(),
            LiftSignal::Colour => "status colour: 0 normal, 1 attention, 2 fault".into(),
            LiftSignal::Position => "car floor".into(),
            LiftSignal::Target => "target floor".into(),
            LiftSignal::Direction => "direction: 0 stopped, 1 up, 2 down".into(),
            LiftSignal::Door => "doors: 0 unknown, 1 closed, 2 partly open, 3 open, 4 fault".into(),
            LiftSignal::NotAnswering => "board not answering (communication alarm)".into(),
            LiftSignal::OutOfService => "out of service".into(),
            LiftSignal::Inspection => "inspection mode".into(),
            LiftSignal::LastFault => "newest archived fault code (Appendix B)".into(),
            LiftSignal::Errors => "line errors (time-outs, invalid replies)".into(),
            LiftSignal::Faults => "faults archived".into(),
            LiftSignal::Trips => "trips, all floors".into(),
            LiftSignal::FloorTrips(floor) => format!("trips to floor {floor}"),
        }
    }
}

/// A signal of a device on a serial line, as its protocol names it.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum LineSignal {
    /// A protection device (IEC 103): the indication FUN/INF, or with `index` the
    /// index-th value of the measurand set FUN/INF.
    Iec103 {
        /// Function type.
        fun: u8,
        /// Information number.
        inf: u8,
        /// The position in a measurand set; `None` for an indication.
        index: Option<u8>,
    },
    /// An outstation (IEC 101): its information object at this address.
    Iec101 {
        /// The outstation's information object address.
        ioa: u32,
    },
}

/// How a point is transmitted upward.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Transmission {
    /// Sent spontaneously (COT 3) on every reported change.
    Spontaneous,
    /// Sent periodically (COT 1) with this period; changes only update the image.
    Cyclic(Duration),
    /// Only answered to interrogations; changes only update the image.
    InterrogationOnly,
}

/// The declaration of one point of a node.
#[derive(Debug, Clone, PartialEq)]
pub struct PointSpec {
    /// Unique name within the node.
    pub name: String,
    /// The value family and the stamp its changes are sent with (`M_SP_TB_1` in a
    /// project: single point, full time stamp).
    pub point_type: PointType,
    /// Unique information object address within the node (the point's number to every
    /// consumer; IEC 104 sends it as the IOA, 1..=16,777,215).
    pub address: u32,
    /// How the point is transmitted.
    pub transmission: Transmission,
    /// Interrogation groups 1..=16, bit 0 = group 1.
    pub groups: u16,
    /// Deadband for measured values (normalized, scaled, float), in the value's unit
    /// (a fraction for normalized values); `None` reports every change.
    pub deadband: Option<f64>,
    /// Where the value comes from (a PLC variable, a point over a link, a status), typed
    /// as the project says it: invalidation on a link's loss picks its points by it.
    pub source: PointSource,
    /// Which of its changes the history keeps (see [`crate::storage`]); every change is
    /// still sent.
    pub storage: crate::StorageRule,
    /// Free description.
    pub description: String,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lift_signals_are_found_by_their_suffix() {
        for signal in LiftSignal::COMMON
            .into_iter()
            .chain([LiftSignal::FloorTrips(1), LiftSignal::FloorTrips(60)])
        {
            assert_eq!(LiftSignal::from_suffix(&signal.suffix()), Some(signal));
        }
        assert_eq!(LiftSignal::from_suffix("floor0_trips"), None);
        assert_eq!(LiftSignal::from_suffix("colour "), None);
        assert_eq!(LiftSignal::Faults.point_name("L1"), "L1.faults");
    }
}
