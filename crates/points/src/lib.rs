//! The point model: what a station knows of a value, whatever brought it and whoever
//! reads it.
//!
//! A *point* is one named value of a node (a breaker's position, a feeder's current, a
//! lift's floor). Field sources (the node's PLC, a lower node's IEC 104 link, the devices
//! of a serial line, a lift board, next S7 and Modbus devices) write points; consumers
//! (the node's IEC 104 server, the event recorder, the HMI, next MQTT) read the changes.
//! This crate is the vocabulary between them and knows none of them: no protocol codec,
//! no store, no async runtime. Each protocol has one adapter to it (IEC 60870-5's is the
//! `points-iec` crate), and the store keeps its values as they are here.
//!
//! | module      | what it holds                                                            |
//! |-------------|--------------------------------------------------------------------------|
//! | [`value`]   | [`PointValue`], the typed value                                          |
//! | [`quality`] | [`Quality`] (IV NT SB BL OV) and [`SourceTime`], the time the source gave |
//! | [`kind`]    | [`PointKind`] (the value family), [`TimeStamp`], [`PointType`]; range checks and wire precision |
//! | [`cause`]   | [`EventCause`], why a change happened                                    |
//! | [`spec`]    | [`PointSpec`], [`PointSource`], [`Transmission`], the device signals     |
//! | [`profile`] | [`DeviceProfile`]: the points a kind of device brings, as data          |
//! | [`storage`] | [`StorageRule`] (deadband, storage rate limit) and [`StorageFilter`]: which changes the history keeps |
//! | [`db`]      | [`PointDb`]: a node's points, report by exception, invalidation, cyclic points; [`PointChange`] |
//!
//! # Data flow
//!
//! ```text
//!  field source --(PointValue, Quality, SourceTime)--> PointDb::update
//!                                                        | report by exception
//!                                                        v
//!                                                   PointChange --> sinks: IEC 104 server
//!                                                                   (through points-iec),
//!                                                                   recorder, HMI, MQTT
//! ```
//!
//! The quality flags are those of IEC 60870-5 (the richest of the field protocols the
//! station speaks; a Modbus or S7 source sets IV when its device fails), so the protocol
//! crate reads and writes this very type and a value crosses the IEC boundary without
//! conversion.

pub mod cause;
pub mod db;
pub mod kind;
pub mod profile;
pub mod quality;
pub mod spec;
pub mod storage;
pub mod value;

pub use cause::EventCause;
pub use db::{Point, PointChange, PointDb, PointDbError, PointId, PointKey};
pub use kind::{normalized, PointKind, PointType, TimeStamp};
pub use profile::{DeviceProfile, ProfileError, SignalProfile};
pub use quality::{Quality, SourceTime};
pub use spec::{LiftSignal, LineSignal, PointSource, PointSpec, Transmission};
pub use storage::{Deadband, StorageFilter, StorageRule};
pub use value::PointValue;
