//! COMTRADE disturbance records (IEEE C37.111, IEC 60255-24), revisions 1999 and 2013:
//! written from memory and read back.
//!
//! COMTRADE (Common Format for Transient Data Exchange) is how protection relays and
//! fault recorders hand over what they saw around a fault: the sampled currents and
//! voltages and the binary signals (pick-up, trip, breaker position), in a form every
//! fault-analysis tool opens. A record is a pair of files with one base name:
//!
//! - `NAME.cfg`, text: station and device, the channels with their names, units and
//!   scaling, the line frequency, the sample rates, the times of the first sample and of
//!   the trigger, the data file's format;
//! - `NAME.dat`, the samples: per sample its number, its timestamp, a value per analog
//!   channel and a state per status channel; ASCII text or BINARY (16-bit values, BINARY32
//!   in 2013 with 32-bit ones).
//!
//! A stored analog value `x` stands for `a * x + b` in the channel's unit, primary or
//! secondary as its `PS` field says. The optional `.hdr` and `.inf` files and the 2013
//! single-file `.cff` form are not handled here, nor FLOAT32 data.
//!
//! # Layout
//!
//! | module     | what it holds                                                        |
//! |------------|----------------------------------------------------------------------|
//! | `record`   | the record in memory: [`Record`], [`AnalogChannel`] (with [`AnalogChannel::from_iec103`]), [`DigitalChannel`], [`Sample`], [`SampleRate`], [`Revision`], [`DataFormat`], [`Scaling`], [`LeapSecond`], [`status_column`] |
//! | `validate` | [`Record::validate`] and [`WriteError`]: what a record must satisfy to be written |
//! | `write`    | [`Record::write_cfg`], [`Record::write_dat`], [`Record::write_files`] |
//! | `read`     | [`Record::read`], [`Record::read_files`] and [`ReadError`] with line numbers |
//!
//! ```text
//!  IEC 103 upload (ASDU 26-30) --> Record::new + AnalogChannel::from_iec103
//!                                  + Record::set_columns + status_column
//!                                        | validate
//!                                        v
//!       write_cfg (CR/LF text) + write_dat (ASCII | BINARY | BINARY32) --> NAME.cfg, NAME.dat
//!                                        |
//!                    Record::read (cfg text, dat bytes) <--+
//! ```
//!
//! # Mapping an IEC 60870-5-103 disturbance record
//!
//! ASDU 26 gives the interval between samples (µs) and the time of the first one, ASDU 27
//! each channel's rated primary and secondary values and reference factor, ASDU 30 the
//! single disturbance values (`i16`), ASDU 29 the tags: a signal (FUN, INF) changing its
//! double point (DPI) at a sample position. The values go into the `.dat` unchanged and
//! [`AnalogChannel::from_iec103`] sets the scaling; each tagged signal becomes a status
//! channel.
//!
//! ```
//! use chrono::NaiveDate;
//! use comtrade::{AnalogChannel, DataFormat, DigitalChannel, Record, Revision, status_column};
//!
//! let first = NaiveDate::from_ymd_opt(2024, 3, 1)
//!     .and_then(|day| day.and_hms_micro_opt(12, 0, 0, 250_000))
//!     .ok_or("bad date")?;
//! let mut record = Record::new("Substation Vsetin", "feeder relay F1", first);
//! record.revision = Revision::R2013;
//! record.data_format = DataFormat::Binary;
//! record.trigger = first + chrono::Duration::milliseconds(2);
//! // ACC 1: IL1 of a 400 A / 1 A CT, RFA 100: SDV 100 is 1 A secondary, 400 A primary.
//! let mut il1 = AnalogChannel::from_iec103("IL1", "A", 400.0, 1.0, 100.0);
//! il1.phase = "1".to_owned();
//! record.analog.push(il1);
//! record.digital.push(DigitalChannel::new("FUN160_INF68 trip", false));
//! let sdv: Vec<i16> = vec![0, 141, 200, -141];
//! let trip = status_column(false, &[(2, true)], sdv.len());
//! record.set_columns(
//!     1000, // µs between samples: 1 kHz
//!     &[sdv.iter().map(|&value| Some(i32::from(value))).collect()],
//!     &[trip],
//! );
//!
//! let cfg = record.write_cfg()?;
//! assert!(cfg.contains("1,IL1,1,,A,4,0,0,-32767,32767,400,1,P\r\n"));
//! let dat = record.write_dat()?;
//! assert_eq!(Record::read(&cfg, &dat)?, record);
//! assert_eq!(record.analog[0].primary_value(141), 564.0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]
#![cfg_attr(not(test), deny(clippy::indexing_slicing))]

mod read;
mod record;
mod validate;
mod write;

pub use read::{Problem, ReadError};
pub use record::{
    status_column, AnalogChannel, DataFormat, DigitalChannel, LeapSecond, Record, Revision, Sample,
    SampleRate, Scaling,
};
pub use validate::WriteError;
