//! Causes of transmission and why a point changed.

use iec60870::asdu::Cause;
use points::EventCause;

/// Why a monitor value received from an outstation was sent, by its cause of
/// transmission; `None` for causes that carry no process value (activation,
/// confirmations, the negative mirrors 44..47, initialisation).
///
/// Every receiver of monitor data (a concentrator's link, the HMI, a gateway's line)
/// classifies with this one table.
pub fn event_cause(cause: Cause) -> Option<EventCause> {
    match cause.value() {
        1 => Some(EventCause::Cyclic),
        2 | 3 | 5 => Some(EventCause::Spontaneous),
        11 => Some(EventCause::ReturnRemote),
        12 => Some(EventCause::ReturnLocal),
        20..=36 => Some(EventCause::Interrogated),
        _ => None,
    }
}

/// Whether a monitor value received with this cause of transmission is an event in its
/// own right, to be passed on even when equal to the last value: a spontaneous change (3)
/// or return information (11, 12). An interrogated, cyclic, background or read value
/// that did not change is no news.
pub fn received_as_event(cause: Cause) -> bool {
    matches!(cause.value(), 3 | 11 | 12)
}

/// The cause of transmission a change is sent upward with.
pub fn transmission_cause(cause: EventCause) -> Cause {
    match cause {
        EventCause::Cyclic => Cause::PERIODIC,
        EventCause::ReturnRemote | EventCause::Command => Cause::RETURN_REMOTE,
        EventCause::ReturnLocal => Cause::RETURN_LOCAL,
        EventCause::Interrogated => Cause::INTERROGATED_BY_STATION,
        EventCause::Spontaneous | EventCause::Local => Cause::SPONTANEOUS,
    }
}
