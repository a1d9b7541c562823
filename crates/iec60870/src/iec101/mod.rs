//! IEC 60870-5-101: the 101/104 application layer over FT1.2 serial lines.
//!
//! IEC 101 carries the same ASDUs as IEC 104 ([`crate::asdu`], with the line's own
//! field sizes in [`AsduParams`](crate::asdu::AsduParams): COT 1 or 2 octets, common
//! address 1 or 2, IOA 1 to 3) over the FT1.2 link layer ([`crate::ft12`]) instead of
//! APCI and TCP. The application cores are the ones IEC 104 uses:
//!
//! | Module | Role | Built from |
//! |---|---|---|
//! | `slave` | [`Slave`]: the controlled station behind an unbalanced secondary | [`crate::outstation::LinkCore`] (interrogation, commands with select/execute, clock sync, counters, event buffering with time tags) and a class 1 queue as its [`LinkLayer`](crate::outstation::LinkLayer) |
//! | `slave` | [`BalancedSlave`]: the same on a balanced point-to-point link, sending as a primary | the outstation core with [`crate::ft12::Balanced`] as its link layer |
//! | `master` | [`Master`]: the controlling station as an unbalanced primary for one or many outstations | [`crate::ft12::Primary`] and [`crate::controlling::start_requests`] (clock sync and interrogation when a link comes up) |
//!
//! # Data flow
//!
//! ```text
//! master: Master::send(asdu) -> Primary (FC3 send/confirm) -> line
//!         line -> Primary -> Exchange{UserData} -> MasterEvent::Asdu
//! slave:  line -> Secondary -> Slave::user_data -> LinkCore::handle_asdu
//!         LinkCore::fill -> class 1 queue -> ACD -> master's class 1 poll -> line
//! ```
//!
//! Differences from IEC 104 handled here: no STARTDT (the master's reset of the remote
//! link starts data transfer), no k/w window (one ASDU per poll, FCB repeats instead of
//! sequence numbers), the link address beside the common address.

mod master;
mod slave;

pub use master::{Clock, Master, MasterEvent, StartUp};
pub use slave::{BalancedSlave, Slave};
