//! The IEC 60870-5 adapter of the point model: the one place where a point meets the
//! protocol.
//!
//! Every part of the station that speaks IEC 60870-5 about points goes through here: a
//! node's IEC 104 server (the process image and each change published), a concentrator's
//! link to a lower node, the 101 and 103 lines of a gateway, the HMI's 104 client and the
//! project loader reading `type = "M_ME_NC_1"`. So the monitor types' families, the
//! element conversions and the causes of transmission are written once.
//!
//! | module      | what it maps                                                          |
//! |-------------|-----------------------------------------------------------------------|
//! | [`types`]   | monitor [`TypeId`](iec60870::asdu::TypeId) <-> [`PointType`](points::PointType) |
//! | [`element`] | [`Element`](iec60870::asdu::Element) <-> value and quality; addresses |
//! | [`cause`]   | [`Cause`](iec60870::asdu::Cause) <-> [`EventCause`](points::EventCause) |
//! | `server`    | a [`PointDb`](points::PointDb) as a 104 server's process image, a change published (feature `tokio`) |
//!
//! ```text
//!  lower node / outstation / relay                 dispatch
//!        | ASDU (TypeId, Element, TimeTag, Cause)      ^ ASDU
//!        v                                             |
//!  element::from_element, cause::event_cause     server::publish (element::to_element,
//!        |                                             |  cause::transmission_cause)
//!        v                                             |
//!  PointDb::update ---------- PointChange -------------+--> recorder, HMI, ...
//! ```

pub mod cause;
pub mod element;
#[cfg(feature = "tokio")]
mod server;
pub mod types;

pub use cause::{event_cause, received_as_event, transmission_cause};
pub use element::{command_value, from_element, ioa, to_element, ElementMismatch};
#[cfg(feature = "tokio")]
pub use server::{process_image, publish, time_tag, PublishError};
pub use types::{point_type, type_id};
