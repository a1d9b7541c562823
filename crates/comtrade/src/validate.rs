//! What a record must satisfy before it is written, and [`WriteError`].

use std::path::PathBuf;

use chrono::{Datelike, NaiveDateTime};
use thiserror::Error;

use crate::record::{DataFormat, Record, Revision};

/// Why a record cannot be written. Samples are counted from 0 (their position in
/// [`Record::samples`]), channels from 1 (their `An` / `Dn` index).
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum WriteError {
    /// A text field holds a separator or is too long.
    #[error("{field} {value:?}: {reason}")]
    Text {
        /// Which field (`station name`, `analog channel 2 unit`, ...).
        field: String,
        /// The offending text.
        value: String,
        /// What is wrong with it.
        reason: &'static str,
    },
    /// A number is infinite, NaN or outside what its field allows.
    #[error("{field}: {value} is not allowed ({allowed})")]
    Number {
        /// Which field.
        field: String,
        /// The offending value, as text.
        value: String,
        /// What the field allows.
        allowed: &'static str,
    },
    /// More channels than a `.cfg` can declare.
    #[error("{0} channels: a record holds at most 999999")]
    TooManyChannels(usize),
    /// The data format needs a later revision.
    #[error("{format} data files need revision 2013, not {revision}")]
    FormatNeedsRevision {
        /// The record's data format.
        format: DataFormat,
        /// The record's revision.
        revision: Revision,
    },
    /// A sample's value count differs from the channel count.
    #[error("sample {sample} has {analog} analog and {digital} status values for {analog_channels}A, {digital_channels}D")]
    SampleShape {
        /// The sample's position.
        sample: usize,
        /// Its analog values.
        analog: usize,
        /// Its status values.
        digital: usize,
        /// The record's analog channels.
        analog_channels: usize,
        /// The record's status channels.
        digital_channels: usize,
    },
    /// The sample rates' end samples go backwards.
    #[error("sample rate {index} ends at sample {end_sample}, before the rate ahead of it")]
    SampleRateOrder {
        /// The rate's position (from 1).
        index: usize,
        /// Its end sample.
        end_sample: u64,
    },
    /// The last rate's end sample is not the number of samples.
    #[error("the sample rates end at sample {declared} but the record holds {actual} samples")]
    SampleCount {
        /// The last rate's end sample.
        declared: u64,
        /// The number of samples.
        actual: usize,
    },
    /// A sample lacks its timestamp in a record without a fixed sample rate.
    #[error("sample {sample} has no timestamp, which a record without a fixed sample rate needs")]
    MissingTimestamp {
        /// The sample's position.
        sample: usize,
    },
    /// A timestamp is the BINARY missing-timestamp code 0xFFFFFFFF.
    #[error(
        "sample {sample}: timestamp 0xFFFFFFFF marks a missing timestamp in binary data files"
    )]
    ReservedTimestamp {
        /// The sample's position.
        sample: usize,
    },
    /// An analog value cannot be stored in the data format.
    #[error(
        "sample {sample}, analog channel {channel}: {value} does not fit {format} data ({allowed})"
    )]
    AnalogValue {
        /// The sample's position.
        sample: usize,
        /// The channel's index.
        channel: usize,
        /// The value.
        value: i32,
        /// The data format.
        format: DataFormat,
        /// What the format holds.
        allowed: &'static str,
    },
    /// A missing analog value in an ASCII data file of revision 1999, which has no way to
    /// write one.
    #[error("sample {sample}, analog channel {channel}: a missing value cannot be written in a revision 1999 ASCII data file (use BINARY or revision 2013)")]
    MissingValue {
        /// The sample's position.
        sample: usize,
        /// The channel's index.
        channel: usize,
    },
    /// A time outside the years `dd/mm/yyyy` can write.
    #[error("{field} {time} is outside the years 0000-9999")]
    Time {
        /// Which time (`start time`, `trigger time`).
        field: &'static str,
        /// The time.
        time: NaiveDateTime,
    },
    /// Writing a file failed.
    #[error("cannot write {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
}

/// Most channels one `.cfg` can declare (`TT` is at most six digits).
const MAX_CHANNELS: usize = 999_999;
/// Analog values of an ASCII data file, and `min` / `max` except in BINARY32 records: at
/// most six characters with the sign.
const ASCII_RANGE: (i32, i32) = (-99_999, 99_999);
/// Analog values of a BINARY data file: 0x8000 marks a missing value.
const BINARY_RANGE: (i32, i32) = (-32_767, 32_767);
/// Analog values of a BINARY32 data file: 0x80000000 marks a missing value.
const BINARY32_RANGE: (i32, i32) = (i32::MIN + 1, i32::MAX);

/// The range of stored analog values of a data format, and its description.
pub(crate) fn analog_range(format: DataFormat) -> ((i32, i32), &'static str) {
    match format {
        DataFormat::Ascii => (ASCII_RANGE, "-99999 to 99999"),
        DataFormat::Binary => (BINARY_RANGE, "-32767 to 32767"),
        DataFormat::Binary32 => (BINARY32_RANGE, "-2147483647 to 2147483647"),
    }
}

/// A text field's length limit in characters, and how to say it is exceeded.
type Limit = (usize, &'static str);
/// `station_name`, `rec_dev_id`, `ch_id`, `ccbm`.
const NAME: Limit = (64, "longer than 64 characters");
/// `uu`.
const UNIT: Limit = (32, "longer than 32 characters");
/// `time_code`, `local_code`.
const TIME_CODE: Limit = (6, "longer than 6 characters");
/// `ph`.
const PHASE: Limit = (2, "longer than 2 characters");

fn text(
    field: impl Into<String>,
    value: &str,
    (max_chars, too_long): Limit,
) -> Result<(), WriteError> {
    let reason = if value.contains([',', '\r', '\n']) {
        Some("commas and line breaks separate the fields of a .cfg")
    } else if value.chars().count() > max_chars {
        Some(too_long)
    } else {
        None
    };
    match reason {
        Some(reason) => Err(WriteError::Text {
            field: field.into(),
            value: value.to_owned(),
            reason,
        }),
        None => Ok(()),
    }
}

fn finite(field: impl Into<String>, value: f64) -> Result<(), WriteError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(WriteError::Number {
            field: field.into(),
            value: value.to_string(),
            allowed: "a finite number",
        })
    }
}

fn positive(field: impl Into<String>, value: f64) -> Result<(), WriteError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(WriteError::Number {
            field: field.into(),
            value: value.to_string(),
            allowed: "a finite number above 0",
        })
    }
}

fn not_negative(field: impl Into<String>, value: f64) -> Result<(), WriteError> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(WriteError::Number {
            field: field.into(),
            value: value.to_string(),
            allowed: "a finite number, 0 or more",
        })
    }
}

fn year(field: &'static str, time: NaiveDateTime) -> Result<(), WriteError> {
    if (0..=9999).contains(&time.year()) {
        Ok(())
    } else {
        Err(WriteError::Time { field, time })
    }
}

fn time_code(field: &'static str, value: &str) -> Result<(), WriteError> {
    text(field, value, TIME_CODE)?;
    if value.is_empty() || value.trim() != value {
        return Err(WriteError::Text {
            field: field.to_owned(),
            value: value.to_owned(),
            reason: "empty or with spaces around it",
        });
    }
    Ok(())
}

impl Record {
    /// Checks that the record can be written as it stands: text fields without separators
    /// and within their lengths, finite numbers, at most 999999 channels, every sample with
    /// a value per channel, values that fit the data format, sample rates that end at the
    /// last sample, timestamps where no fixed rate places the samples, BINARY32 only in
    /// revision 2013 and missing ASCII values only in revision 2013.
    ///
    /// The writers call it; they never write a record it refuses.
    pub fn validate(&self) -> Result<(), WriteError> {
        self.validate_header()?;
        self.validate_channels()?;
        self.validate_rates()?;
        self.validate_samples()
    }

    fn validate_header(&self) -> Result<(), WriteError> {
        text("station name", &self.station_name, NAME)?;
        text("recording device id", &self.device_id, NAME)?;
        if self.data_format == DataFormat::Binary32 && self.revision == Revision::R1999 {
            return Err(WriteError::FormatNeedsRevision {
                format: self.data_format,
                revision: self.revision,
            });
        }
        not_negative("line frequency", self.line_frequency)?;
        positive("timemult", self.timemult)?;
        year("start time", self.start)?;
        year("trigger time", self.trigger)?;
        if self.revision == Revision::R2013 {
            time_code("time code", &self.time_code)?;
            time_code("local code", &self.local_code)?;
            if self.time_quality > 0xF {
                return Err(WriteError::Number {
                    field: "time quality".to_owned(),
                    value: self.time_quality.to_string(),
                    allowed: "0 to 15",
                });
            }
        }
        Ok(())
    }

    fn validate_channels(&self) -> Result<(), WriteError> {
        let total = self.analog.len().saturating_add(self.digital.len());
        if total > MAX_CHANNELS {
            return Err(WriteError::TooManyChannels(total));
        }
        let (min_max, allowed) = match self.data_format {
            DataFormat::Binary32 => (BINARY32_RANGE, "-2147483647 to 2147483647"),
            DataFormat::Ascii | DataFormat::Binary => (ASCII_RANGE, "-99999 to 99999"),
        };
        for (position, channel) in self.analog.iter().enumerate() {
            let at = |what: &str| format!("analog channel {} {what}", position + 1);
            text(at("name"), &channel.name, NAME)?;
            text(at("phase"), &channel.phase, PHASE)?;
            text(at("circuit"), &channel.circuit, NAME)?;
            text(at("unit"), &channel.unit, UNIT)?;
            finite(at("multiplier"), channel.multiplier)?;
            finite(at("offset"), channel.offset)?;
            finite(at("skew"), channel.skew_us)?;
            positive(at("primary"), channel.primary)?;
            positive(at("secondary"), channel.secondary)?;
            for (what, value) in [("min", channel.min), ("max", channel.max)] {
                if value < min_max.0 || value > min_max.1 {
                    return Err(WriteError::Number {
                        field: at(what),
                        value: value.to_string(),
                        allowed,
                    });
                }
            }
        }
        for (position, channel) in self.digital.iter().enumerate() {
            let at = |what: &str| format!("status channel {} {what}", position + 1);
            text(at("name"), &channel.name, NAME)?;
            text(at("phase"), &channel.phase, PHASE)?;
            text(at("circuit"), &channel.circuit, NAME)?;
        }
        Ok(())
    }

    fn validate_rates(&self) -> Result<(), WriteError> {
        if self.sample_rates.len() > 999 {
            return Err(WriteError::Number {
                field: "number of sample rates".to_owned(),
                value: self.sample_rates.len().to_string(),
                allowed: "at most 999",
            });
        }
        let mut previous = 0;
        for (position, rate) in self.sample_rates.iter().enumerate() {
            not_negative(format!("sample rate {}", position + 1), rate.rate_hz)?;
            if rate.end_sample < previous {
                return Err(WriteError::SampleRateOrder {
                    index: position + 1,
                    end_sample: rate.end_sample,
                });
            }
            previous = rate.end_sample;
        }
        if let Some(last) = self.sample_rates.last() {
            if u64::try_from(self.samples.len()).ok() != Some(last.end_sample) {
                return Err(WriteError::SampleCount {
                    declared: last.end_sample,
                    actual: self.samples.len(),
                });
            }
        }
        Ok(())
    }

    fn validate_samples(&self) -> Result<(), WriteError> {
        let timestamps_needed = self.sample_rates.is_empty()
            || self.sample_rates.iter().any(|rate| rate.rate_hz == 0.0);
        let binary = self.data_format != DataFormat::Ascii;
        let missing_allowed = binary || self.revision == Revision::R2013;
        let ((low, high), allowed) = analog_range(self.data_format);
        for (position, sample) in self.samples.iter().enumerate() {
            if sample.analog.len() != self.analog.len()
                || sample.digital.len() != self.digital.len()
            {
                return Err(WriteError::SampleShape {
                    sample: position,
                    analog: sample.analog.len(),
                    digital: sample.digital.len(),
                    analog_channels: self.analog.len(),
                    digital_channels: self.digital.len(),
                });
            }
            match sample.timestamp {
                None if timestamps_needed => {
                    return Err(WriteError::MissingTimestamp { sample: position })
                }
                Some(u32::MAX) if binary => {
                    return Err(WriteError::ReservedTimestamp { sample: position })
                }
                _ => {}
            }
            for (index, value) in sample.analog.iter().enumerate() {
                match *value {
                    None if !missing_allowed => {
                        return Err(WriteError::MissingValue {
                            sample: position,
                            channel: index + 1,
                        })
                    }
                    Some(value) if value < low || value > high => {
                        return Err(WriteError::AnalogValue {
                            sample: position,
                            channel: index + 1,
                            value,
                            format: self.data_format,
                            allowed,
                        })
                    }
                    _ => {}
                }
            }
        }
        Ok(())
    }
}
