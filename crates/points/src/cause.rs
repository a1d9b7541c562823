//! Why a point changed.

/// Why an event was produced (the cause of transmission, as the station sees it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum EventCause {
    /// A spontaneous change (COT 3).
    Spontaneous,
    /// An answer to a (general or group) interrogation (COT 20..36).
    Interrogated,
    /// A cyclic or periodic transmission (COT 1).
    Cyclic,
    /// The result of a command (COT 11/12 as seen by the point database).
    Command,
    /// A local change at the node itself (local operation, PLC logic).
    Local,
    /// Return information caused by a remote command (COT 11).
    ReturnRemote,
    /// Return information caused by a local command (COT 12).
    ReturnLocal,
}

impl EventCause {
    /// Every cause, in code order.
    pub const ALL: [EventCause; 7] = [
        EventCause::Spontaneous,
        EventCause::Interrogated,
        EventCause::Cyclic,
        EventCause::Command,
        EventCause::Local,
        EventCause::ReturnRemote,
        EventCause::ReturnLocal,
    ];

    /// The cause's stable code (what a store keeps: reordering variants never changes
    /// stored data).
    pub fn code(self) -> i16 {
        match self {
            EventCause::Spontaneous => 1,
            EventCause::Interrogated => 2,
            EventCause::Cyclic => 3,
            EventCause::Command => 4,
            EventCause::Local => 5,
            EventCause::ReturnRemote => 6,
            EventCause::ReturnLocal => 7,
        }
    }

    /// The cause with this code, if any.
    pub fn from_code(code: i16) -> Option<EventCause> {
        EventCause::ALL.into_iter().find(|c| c.code() == code)
    }
}
