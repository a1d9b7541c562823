//! IEC 60870-5-103: the informative interface of protection equipment, over FT1.2.
//!
//! # Layout
//!
//! | Module | Content |
//! |---|---|
//! | `asdu` | [`Asdu`] = [`Header`] (`TYP VSQ COT CA FUN INF`) + [`Body`]: the standard messages of both directions (time-tagged messages, measurands, identification, time sync, GI, general command, disturbance data transfer 23-31), generic services (10, 11, 21) passed through |
//! | `cause` | [`Cause`]: the 103 causes of transmission |
//! | `measurand` | [`Measurand`]: the 13-bit fraction of a configured limit with OV and ER |
//! | `disturbance` | transmission of disturbance data (ASDU 23-31): [`DisturbanceRecord`], the device's [`DisturbanceSender`] and the master's [`DisturbanceReceiver`] |
//! | `master` | [`Master`]: the control system's side over an [`crate::ft12::Primary`]: start-up (clock sync, GI), general commands followed to their acknowledgement, every ASDU decoded |
//!
//! # Data flow
//!
//! ```text
//! master: Master::general_command -> ASDU 20 -> Primary (send/confirm) -> line
//!         line -> Primary -> class 1/2 user data -> Asdu::decode -> MasterEvent
//! device: line -> Secondary -> a SecondaryApplication (the simulated REF630 of the
//!         `simulators` crate: class 1 acks, events, GI; class 2 measurands every cycle)
//! ```
//!
//! The link layer is [`crate::ft12`] (unbalanced only, one-octet link address); the
//! time tag of the messages is [`crate::time::Cp32Time2a`] (no date: resolve it against
//! the time of reception, [`crate::time::Cp32Time2a::resolve`]).
//!
//! # Wire format
//!
//! ```text
//! TYP | VSQ | COT | CA | FUN | INF | elements         (COT and CA one octet each)
//! 1   time-tagged message        DPI  CP32  SIN
//! 3/9 measurands I / II          N x (13-bit value << 3 | ER << 1 | OV)
//! 5   identification             COL  8 x ASCII  4 octets software id
//! 6   time synchronisation       CP56 (broadcast, or answered with COT 8)
//! 7/8 GI initiation / termination  SCN            (FUN 255, INF 0)
//! 20  general command            DCO  RII         (answered by ASDU 1, COT 20/21, SIN = RII)
//! ```
//!
//! # Strictness
//!
//! Decoding is strict about structure (every element's length, nothing left over,
//! time fields in range) and lenient about meaning: any cause, FUN, INF, DPI or
//! qualifier decodes, so a master can print what a device sends and a device can
//! refuse what it does not know. Nothing panics on input.

mod asdu;
mod cause;
mod disturbance;
mod master;
mod measurand;

pub use asdu::{
    dpi_text, type_name, Asdu, Body, DecodeError, Direction, DisturbanceTag, EncodeError, Header,
    RecordedDisturbance, FUN_GENERIC, FUN_GLOBAL, INF_GENERIC_GI, INF_MEASURANDS_II, INF_POWER_ON,
    INF_RESET_CU, INF_RESET_FCB, INF_START_RESTART,
};
pub use cause::Cause;
pub use disturbance::{
    DisturbanceReceiver, DisturbanceRecord, DisturbanceSender, ReceiverStep, RecordChannel,
    RecordTag, SOF_TRANSMITTED, SOF_TRIP, TOO_ABORT_DATA, TOO_CHANNEL_RECEIVED, TOO_DATA_RECEIVED,
    TOO_END_OF_CHANNEL, TOO_END_OF_DATA, TOO_END_OF_TAGS, TOO_REQUEST_CHANNEL, TOO_REQUEST_DATA,
    TOO_REQUEST_LIST, TOO_REQUEST_TAGS, TOO_SELECT_FAULT, TOO_TAGS_RECEIVED, TOV_INSTANTANEOUS,
};
pub use master::{Clock, Master, MasterEvent, StartUp};
pub use measurand::Measurand;
