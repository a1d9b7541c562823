//! Reading a `.cfg` + `.dat` pair back into a [`Record`], and [`ReadError`].
//!
//! The reader is lenient where real files vary and strict where a value would be guessed:
//! LF or CR/LF line ends, a UTF-8 byte order mark, spaces around numbers, lower-case
//! keywords, trailing empty lines, an empty `lf` or `skew`, absent 2013 time lines and
//! anything after them are accepted; a wrong field count, a number that does not parse,
//! an unknown revision or file type, or a sample count that differs from the `.cfg` is an
//! error naming its line. No input makes it panic.
//!
//! Text fields (names, units, phases) are kept as written, spaces included. The channel
//! numbers `An` and `Dn` must be numbers; a channel's index is its position.

use std::path::{Path, PathBuf};

use chrono::{NaiveDate, NaiveDateTime, NaiveTime};
use thiserror::Error;

use crate::record::{
    AnalogChannel, DataFormat, DigitalChannel, LeapSecond, Record, Revision, Sample, SampleRate,
    Scaling,
};
use crate::write::binary_sample_size;

/// Why a `.cfg` + `.dat` pair cannot be read. Line numbers count from 1.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ReadError {
    /// A line of the configuration file.
    #[error(".cfg line {line}: {problem}")]
    Cfg {
        /// The line.
        line: usize,
        /// What is wrong on it.
        problem: Problem,
    },
    /// A line of an ASCII data file.
    #[error(".dat line {line}: {problem}")]
    Dat {
        /// The line.
        line: usize,
        /// What is wrong on it.
        problem: Problem,
    },
    /// A binary data file that is not a whole number of samples.
    #[error(".dat: {length} bytes are not a whole number of {sample_size}-byte samples")]
    BinaryLength {
        /// The file's length.
        length: usize,
        /// The size of one sample.
        sample_size: usize,
    },
    /// The data file holds another number of samples than the configuration declares.
    #[error(".dat holds {found} samples, the .cfg declares {declared}")]
    SampleCount {
        /// The last `endsamp` of the `.cfg`.
        declared: u64,
        /// The samples in the `.dat`.
        found: usize,
    },
    /// A file could not be read.
    #[error("cannot read {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
}

/// What is wrong on a line.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[non_exhaustive]
pub enum Problem {
    /// The file ends before a line it needs.
    #[error("missing {0} (the file ends)")]
    Missing(&'static str),
    /// A line with too few or too many fields.
    #[error("{what}: expected {expected} fields, found {found}")]
    FieldCount {
        /// The line's meaning.
        what: &'static str,
        /// Fields it needs.
        expected: usize,
        /// Fields it has.
        found: usize,
    },
    /// A field that does not parse as what it holds.
    #[error("{field}: {value:?} is not {expected}")]
    Invalid {
        /// The field.
        field: &'static str,
        /// Its text (shortened).
        value: String,
        /// What it should be.
        expected: &'static str,
    },
    /// A `rev_year` other than 1999 or 2013.
    #[error("revision year {0:?}: this reader knows 1999 and 2013")]
    Revision(String),
    /// An `ft` other than ASCII, BINARY or BINARY32 (BINARY32 only in revision 2013).
    #[error("data file type {0:?}: this reader knows ASCII, BINARY and (2013) BINARY32")]
    FileType(String),
    /// `TT` is not `##A + ##D`.
    #[error("{total} channels declared as {analog}A + {digital}D")]
    ChannelTotal {
        /// `TT`.
        total: usize,
        /// `##A`.
        analog: usize,
        /// `##D`.
        digital: usize,
    },
    /// A line of the data file that is not UTF-8 text.
    #[error("not text")]
    NotText,
}

/// At most this many characters of a bad field go into an error.
const SHOWN_CHARS: usize = 40;

fn invalid(field: &'static str, value: &str, expected: &'static str) -> Problem {
    let mut shown: String = value.chars().take(SHOWN_CHARS).collect();
    if value.chars().nth(SHOWN_CHARS).is_some() {
        shown.push('…');
    }
    Problem::Invalid {
        field,
        value: shown,
        expected,
    }
}

fn fields<'a, const N: usize>(what: &'static str, text: &'a str) -> Result<[&'a str; N], Problem> {
    let parts: Vec<&str> = text.split(',').collect();
    let found = parts.len();
    parts.try_into().map_err(|_| Problem::FieldCount {
        what,
        expected: N,
        found,
    })
}

fn real(field: &'static str, text: &str) -> Result<f64, Problem> {
    text.trim()
        .parse::<f64>()
        .ok()
        .filter(|value| value.is_finite())
        .ok_or_else(|| invalid(field, text, "a number"))
}

/// A real that may be empty (then `default`).
fn real_or(field: &'static str, text: &str, default: f64) -> Result<f64, Problem> {
    if text.trim().is_empty() {
        Ok(default)
    } else {
        real(field, text)
    }
}

fn unsigned<T: std::str::FromStr>(field: &'static str, text: &str) -> Result<T, Problem> {
    text.trim()
        .parse::<T>()
        .map_err(|_| invalid(field, text, "a whole number"))
}

/// An integer, also written as a real without a fraction (`-32767.000`).
fn integer(field: &'static str, text: &str) -> Result<i32, Problem> {
    let trimmed = text.trim();
    if let Ok(value) = trimmed.parse::<i32>() {
        return Ok(value);
    }
    trimmed
        .parse::<f64>()
        .ok()
        .filter(|value| {
            value.fract() == 0.0 && *value >= f64::from(i32::MIN) && *value <= f64::from(i32::MAX)
        })
        // In range and integral: the conversion is exact.
        .map(|value| value as i32)
        .ok_or_else(|| invalid(field, text, "a whole number"))
}

/// A channel count `12A` / `3D`.
fn count(field: &'static str, text: &str, suffix: char) -> Result<usize, Problem> {
    let trimmed = text.trim();
    trimmed
        .strip_suffix(suffix)
        .or_else(|| trimmed.strip_suffix(suffix.to_ascii_lowercase()))
        .and_then(|digits| digits.trim().parse::<usize>().ok())
        .filter(|&value| value <= 999_999)
        .ok_or_else(|| {
            invalid(
                field,
                text,
                if suffix == 'A' {
                    "a count followed by A, at most 999999"
                } else {
                    "a count followed by D, at most 999999"
                },
            )
        })
}

fn state(field: &'static str, text: &str) -> Result<bool, Problem> {
    match text.trim() {
        "0" => Ok(false),
        "1" => Ok(true),
        _ => Err(invalid(field, text, "0 or 1")),
    }
}

/// `dd/mm/yyyy,hh:mm:ss[.fraction]`, the fraction up to nanoseconds, second 60 a leap
/// second.
fn date_time(field: &'static str, text: &str) -> Result<NaiveDateTime, Problem> {
    let parse = || -> Option<NaiveDateTime> {
        let (date, time) = text.trim().split_once(',')?;
        let mut date_parts = date.trim().split('/');
        let day: u32 = date_parts.next()?.trim().parse().ok()?;
        let month: u32 = date_parts.next()?.trim().parse().ok()?;
        let year_text = date_parts.next()?.trim();
        if date_parts.next().is_some() || year_text.starts_with(['+', '-']) {
            return None;
        }
        let year: i32 = year_text.parse().ok()?;
        let date = NaiveDate::from_ymd_opt(year, month, day)?;
        let (clock, fraction) = match time.trim().split_once('.') {
            Some((clock, fraction)) => (clock, fraction),
            None => (time.trim(), ""),
        };
        if fraction.len() > 9 || !fraction.bytes().all(|byte| byte.is_ascii_digit()) {
            return None;
        }
        let nanos: u32 = if fraction.is_empty() {
            0
        } else {
            format!("{fraction:0<9}").parse().ok()?
        };
        let mut clock_parts = clock.split(':');
        let hour: u32 = clock_parts.next()?.parse().ok()?;
        let minute: u32 = clock_parts.next()?.parse().ok()?;
        let second: u32 = clock_parts.next()?.parse().ok()?;
        if clock_parts.next().is_some() {
            return None;
        }
        let time = if second == 60 {
            NaiveTime::from_hms_nano_opt(hour, minute, 59, nanos.checked_add(1_000_000_000)?)?
        } else {
            NaiveTime::from_hms_nano_opt(hour, minute, second, nanos)?
        };
        Some(date.and_time(time))
    };
    parse().ok_or_else(|| invalid(field, text, "a time dd/mm/yyyy,hh:mm:ss.ssssss"))
}

/// The lines of the `.cfg`: numbered from 1, CR dropped, trailing empty lines gone.
struct CfgLines<'a> {
    lines: Vec<&'a str>,
    next: usize,
}

impl<'a> CfgLines<'a> {
    fn new(text: &'a str) -> Self {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let mut lines: Vec<&str> = text
            .split('\n')
            .map(|line| line.strip_suffix('\r').unwrap_or(line))
            .collect();
        while lines.last().is_some_and(|line| line.trim().is_empty()) {
            lines.pop();
        }
        CfgLines { lines, next: 0 }
    }

    /// The next line and its number, or an error naming what was expected.
    fn next(&mut self, what: &'static str) -> Result<(usize, &'a str), ReadError> {
        let line = self.next + 1;
        match self.lines.get(self.next) {
            Some(text) => {
                self.next += 1;
                Ok((line, text))
            }
            None => Err(ReadError::Cfg {
                line,
                problem: Problem::Missing(what),
            }),
        }
    }

    /// The next line if there is one.
    fn optional(&mut self) -> Option<(usize, &'a str)> {
        let text = self.lines.get(self.next)?;
        self.next += 1;
        Some((self.next, text))
    }
}

/// Runs a line's parser, tagging its problem with the line number.
fn at<T>(line: usize, parsed: Result<T, Problem>) -> Result<T, ReadError> {
    parsed.map_err(|problem| ReadError::Cfg { line, problem })
}

fn analog_channel(text: &str) -> Result<AnalogChannel, Problem> {
    let [index, name, phase, circuit, unit, a, b, skew, min, max, primary, secondary, ps] =
        fields::<13>("analog channel", text)?;
    unsigned::<u32>("An", index)?;
    Ok(AnalogChannel {
        name: name.to_owned(),
        phase: phase.to_owned(),
        circuit: circuit.to_owned(),
        unit: unit.to_owned(),
        multiplier: real("a", a)?,
        offset: real("b", b)?,
        skew_us: real_or("skew", skew, 0.0)?,
        min: integer("min", min)?,
        max: integer("max", max)?,
        primary: real("primary", primary)?,
        secondary: real("secondary", secondary)?,
        scaling: match ps.trim() {
            "P" | "p" => Scaling::Primary,
            "S" | "s" => Scaling::Secondary,
            _ => return Err(invalid("PS", ps, "P or S")),
        },
    })
}

fn digital_channel(text: &str) -> Result<DigitalChannel, Problem> {
    let [index, name, phase, circuit, normal] = fields::<5>("status channel", text)?;
    unsigned::<u32>("Dn", index)?;
    Ok(DigitalChannel {
        name: name.to_owned(),
        phase: phase.to_owned(),
        circuit: circuit.to_owned(),
        normal_state: state("y", normal)?,
    })
}

/// The configuration, and the number of samples it declares.
fn configuration(text: &str) -> Result<(Record, u64), ReadError> {
    let mut lines = CfgLines::new(text);

    let (line, header) = lines.next("station_name,rec_dev_id,rev_year")?;
    if header.split(',').count() == 2 {
        // No rev_year: the original 1991 format.
        return at(line, Err(Problem::Revision("1991".to_owned())));
    }
    let [station, device, year] = at(
        line,
        fields::<3>("station_name,rec_dev_id,rev_year", header),
    )?;
    let revision = match year.trim() {
        "1999" => Revision::R1999,
        "2013" => Revision::R2013,
        other => return at(line, Err(Problem::Revision(other.to_owned()))),
    };

    let (line, counts) = lines.next("TT,##A,##D")?;
    let [total, analog, digital] = at(line, fields::<3>("TT,##A,##D", counts))?;
    let total: usize = at(line, unsigned("TT", total))?;
    let analog = at(line, count("##A", analog, 'A'))?;
    let digital = at(line, count("##D", digital, 'D'))?;
    if analog.checked_add(digital) != Some(total) {
        return at(
            line,
            Err(Problem::ChannelTotal {
                total,
                analog,
                digital,
            }),
        );
    }

    let mut analog_channels = Vec::new();
    for _ in 0..analog {
        let (line, text) = lines.next("analog channel")?;
        analog_channels.push(at(line, analog_channel(text))?);
    }
    let mut digital_channels = Vec::new();
    for _ in 0..digital {
        let (line, text) = lines.next("status channel")?;
        digital_channels.push(at(line, digital_channel(text))?);
    }

    let (line, frequency) = lines.next("lf")?;
    let line_frequency = at(line, real_or("lf", frequency, 0.0))?;
    let (line, nrates) = lines.next("nrates")?;
    let nrates: usize = at(line, unsigned::<u16>("nrates", nrates).map(usize::from))?;
    if nrates > 999 {
        return at(
            line,
            Err(invalid("nrates", &nrates.to_string(), "at most 999")),
        );
    }
    let mut sample_rates = Vec::new();
    let mut declared = 0;
    for _ in 0..nrates.max(1) {
        let (line, text) = lines.next("samp,endsamp")?;
        let [rate, end] = at(line, fields::<2>("samp,endsamp", text))?;
        let rate = SampleRate {
            rate_hz: at(line, real("samp", rate))?,
            end_sample: at(line, unsigned("endsamp", end))?,
        };
        declared = rate.end_sample;
        if nrates > 0 {
            sample_rates.push(rate);
        }
    }

    let (line, start) = lines.next("time of the first sample")?;
    let start = at(line, date_time("first sample", start))?;
    let (line, trigger) = lines.next("time of the trigger")?;
    let trigger = at(line, date_time("trigger", trigger))?;
    let (line, ft) = lines.next("ft")?;
    let data_format = match ft.trim().to_ascii_uppercase().as_str() {
        "ASCII" => DataFormat::Ascii,
        "BINARY" => DataFormat::Binary,
        "BINARY32" if revision == Revision::R2013 => DataFormat::Binary32,
        _ => return at(line, Err(Problem::FileType(ft.trim().to_owned()))),
    };
    let (line, timemult) = lines.next("timemult")?;
    let timemult = at(line, real("timemult", timemult))?;

    let mut record = Record::new(station, device, start);
    record.revision = revision;
    record.data_format = data_format;
    record.line_frequency = line_frequency;
    record.sample_rates = sample_rates;
    record.trigger = trigger;
    record.timemult = timemult;
    record.analog = analog_channels;
    record.digital = digital_channels;

    if revision == Revision::R2013 {
        if let Some((line, text)) = lines.optional() {
            let [time_code, local_code] = at(line, fields::<2>("time_code,local_code", text))?;
            record.time_code = time_code.trim().to_owned();
            record.local_code = local_code.trim().to_owned();
        }
        if let Some((line, text)) = lines.optional() {
            let [quality, leap] = at(line, fields::<2>("tmq_code,leapsec", text))?;
            record.time_quality = at(
                line,
                u8::from_str_radix(quality.trim(), 16)
                    .ok()
                    .filter(|&code| code <= 0xF)
                    .ok_or_else(|| invalid("tmq_code", quality, "a hexadecimal digit")),
            )?;
            record.leap_second = at(
                line,
                leap.trim()
                    .parse::<u8>()
                    .ok()
                    .and_then(LeapSecond::from_code)
                    .ok_or_else(|| invalid("leapsec", leap, "0, 1, 2 or 3")),
            )?;
        }
    }
    Ok((record, declared))
}

fn ascii_samples(record: &Record, dat: &[u8]) -> Result<Vec<Sample>, ReadError> {
    let analog = record.analog.len();
    let digital = record.digital.len();
    let expected = analog.saturating_add(digital).saturating_add(2);
    let mut samples = Vec::new();
    for (index, raw) in dat.split(|&byte| byte == b'\n').enumerate() {
        let line = index + 1;
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        let error = |problem| ReadError::Dat { line, problem };
        let text = std::str::from_utf8(raw).map_err(|_| error(Problem::NotText))?;
        if text.trim().is_empty() {
            continue;
        }
        let parts: Vec<&str> = text.split(',').collect();
        if parts.len() != expected {
            return Err(error(Problem::FieldCount {
                what: "sample",
                expected,
                found: parts.len(),
            }));
        }
        let parse = || -> Result<Sample, Problem> {
            let mut parts = parts.iter();
            let number = unsigned::<u32>("n", parts.next().copied().unwrap_or_default())?;
            let timestamp = match parts.next().map(|field| field.trim()) {
                None | Some("") => None,
                Some(field) => Some(unsigned::<u32>("timestamp", field)?),
            };
            let analog_values = parts
                .by_ref()
                .take(analog)
                .map(|field| match field.trim() {
                    "" => Ok(None),
                    value => integer("analog value", value).map(Some),
                })
                .collect::<Result<Vec<_>, _>>()?;
            let digital_values = parts
                .map(|field| state("status value", field))
                .collect::<Result<Vec<_>, _>>()?;
            Ok(Sample {
                number,
                timestamp,
                analog: analog_values,
                digital: digital_values,
            })
        };
        samples.push(parse().map_err(error)?);
    }
    Ok(samples)
}

/// `N` bytes as an array (the callers' chunks have exactly `N`).
fn array<const N: usize>(bytes: &[u8]) -> [u8; N] {
    bytes.try_into().unwrap_or([0; N])
}

/// One binary sample of `analog` values `width` bytes wide and `digital` status bits.
fn binary_sample(chunk: &[u8], analog: usize, width: usize, digital: usize) -> Sample {
    let (number, rest) = chunk.split_at(4.min(chunk.len()));
    let (timestamp, rest) = rest.split_at(4.min(rest.len()));
    let (values, words) = rest.split_at(analog.saturating_mul(width).min(rest.len()));
    let timestamp = u32::from_le_bytes(array(timestamp));
    Sample {
        number: u32::from_le_bytes(array(number)),
        timestamp: (timestamp != u32::MAX).then_some(timestamp),
        analog: values
            .chunks_exact(width)
            .map(|bytes| {
                if width == 4 {
                    let value = i32::from_le_bytes(array(bytes));
                    (value != i32::MIN).then_some(value)
                } else {
                    let value = i16::from_le_bytes(array(bytes));
                    (value != i16::MIN).then_some(i32::from(value))
                }
            })
            .collect(),
        digital: words
            .chunks_exact(2)
            .flat_map(|bytes| {
                let bits = u16::from_le_bytes(array(bytes));
                (0..16).map(move |bit| bits & (1 << bit) != 0)
            })
            .take(digital)
            .collect(),
    }
}

fn binary_samples(record: &Record, dat: &[u8]) -> Result<Vec<Sample>, ReadError> {
    let wide = record.data_format == DataFormat::Binary32;
    let analog = record.analog.len();
    let digital = record.digital.len();
    // Channel counts are at most 999999 each: the size cannot overflow.
    let size = binary_sample_size(analog, digital, wide).unwrap_or(usize::MAX);
    if dat.len() % size != 0 {
        return Err(ReadError::BinaryLength {
            length: dat.len(),
            sample_size: size,
        });
    }
    let width = if wide { 4 } else { 2 };
    Ok(dat
        .chunks_exact(size)
        .map(|chunk| binary_sample(chunk, analog, width, digital))
        .collect())
}

impl Record {
    /// Reads a record from its `.cfg` text and `.dat` bytes.
    pub fn read(cfg: &str, dat: &[u8]) -> Result<Record, ReadError> {
        let (mut record, declared) = configuration(cfg)?;
        record.samples = match record.data_format {
            DataFormat::Ascii => ascii_samples(&record, dat)?,
            DataFormat::Binary | DataFormat::Binary32 => binary_samples(&record, dat)?,
        };
        if u64::try_from(record.samples.len()).ok() != Some(declared) {
            return Err(ReadError::SampleCount {
                declared,
                found: record.samples.len(),
            });
        }
        Ok(record)
    }

    /// Reads a record from its `.cfg` and `.dat` files.
    pub fn read_files(cfg_path: &Path, dat_path: &Path) -> Result<Record, ReadError> {
        let io = |path: &Path| {
            let path = path.to_owned();
            move |source| ReadError::Io { path, source }
        };
        let cfg = std::fs::read(cfg_path).map_err(io(cfg_path))?;
        let dat = std::fs::read(dat_path).map_err(io(dat_path))?;
        // A .cfg in a legacy 8-bit code page: its bytes above 0x7F become U+FFFD.
        let cfg = String::from_utf8_lossy(&cfg);
        Record::read(&cfg, &dat)
    }
}
