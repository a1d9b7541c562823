//! The in-memory record: what one `.cfg` + `.dat` pair holds.

use std::fmt;

use chrono::NaiveDateTime;

/// The revision of IEEE C37.111 a configuration file follows (its `rev_year` field).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Revision {
    /// IEEE C37.111-1999.
    R1999,
    /// IEEE C37.111-2013 / IEC 60255-24:2013: adds `time_code,local_code`,
    /// `tmq_code,leapsec`, BINARY32 data and empty (missing) ASCII values.
    R2013,
}

impl Revision {
    /// The `rev_year` as written in the `.cfg`.
    pub fn year(self) -> u16 {
        match self {
            Revision::R1999 => 1999,
            Revision::R2013 => 2013,
        }
    }
}

impl fmt::Display for Revision {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.year())
    }
}

/// The data file's format (the `.cfg`'s `ft` field).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DataFormat {
    /// Text: `n,timestamp,A1..Ak,D1..Dm` per line, CR/LF.
    Ascii,
    /// Per sample: `u32` number, `u32` timestamp, an `i16` per analog channel, the status
    /// channels packed 16 to a `u16` word; all little-endian.
    Binary,
    /// As [`DataFormat::Binary`] with an `i32` per analog channel (revision 2013 only).
    Binary32,
}

impl DataFormat {
    /// The `ft` keyword: `ASCII`, `BINARY` or `BINARY32`.
    pub fn keyword(self) -> &'static str {
        match self {
            DataFormat::Ascii => "ASCII",
            DataFormat::Binary => "BINARY",
            DataFormat::Binary32 => "BINARY32",
        }
    }
}

impl fmt::Display for DataFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.keyword())
    }
}

/// Which value `a * x + b` of an analog channel gives (its `PS` field).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Scaling {
    /// `P`: the primary value (the power system side of the instrument transformer).
    Primary,
    /// `S`: the secondary value (the relay's input).
    Secondary,
}

/// The leap second indicator of revision 2013 (`leapsec`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum LeapSecond {
    /// `0`: no leap second in the record.
    #[default]
    None,
    /// `1`: a leap second was added in the record.
    Added,
    /// `2`: a leap second was subtracted in the record.
    Subtracted,
    /// `3`: the time source cannot tell.
    Unknown,
}

impl LeapSecond {
    /// The `leapsec` digit.
    pub fn code(self) -> u8 {
        match self {
            LeapSecond::None => 0,
            LeapSecond::Added => 1,
            LeapSecond::Subtracted => 2,
            LeapSecond::Unknown => 3,
        }
    }

    /// The indicator of a `leapsec` digit.
    pub fn from_code(code: u8) -> Option<Self> {
        match code {
            0 => Some(LeapSecond::None),
            1 => Some(LeapSecond::Added),
            2 => Some(LeapSecond::Subtracted),
            3 => Some(LeapSecond::Unknown),
            _ => None,
        }
    }
}

/// One sampling rate of the record (a `samp,endsamp` line).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampleRate {
    /// Samples per second (`samp`); 0 when the timestamps alone place the samples.
    pub rate_hz: f64,
    /// The number of the last sample taken at this rate (`endsamp`), counted from the
    /// first sample of the record.
    pub end_sample: u64,
}

/// An analog channel (an `An,ch_id,ph,ccbm,uu,a,b,skew,min,max,primary,secondary,PS` line).
///
/// Its index `An` is its position in [`Record::analog`] plus one. A stored value `x`
/// stands for `multiplier * x + offset` in `unit`, a primary or a secondary value as
/// `scaling` says; `primary / secondary` is the instrument transformer's ratio.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct AnalogChannel {
    /// Channel identifier (`ch_id`), at most 64 characters.
    pub name: String,
    /// Phase (`ph`, e.g. `A`, `1`, `N`), at most 2 characters, may be empty.
    pub phase: String,
    /// Circuit component being monitored (`ccbm`), at most 64 characters, may be empty.
    pub circuit: String,
    /// Unit (`uu`: `A`, `kV`, ...), at most 32 characters.
    pub unit: String,
    /// Multiplier `a`.
    pub multiplier: f64,
    /// Offset `b`.
    pub offset: f64,
    /// Time skew of the channel from the start of the sample period, in microseconds.
    pub skew_us: f64,
    /// Smallest value of the channel's range (`min`), as stored in the data file.
    pub min: i32,
    /// Largest value of the channel's range (`max`), as stored in the data file.
    pub max: i32,
    /// Instrument transformer ratio, primary factor.
    pub primary: f64,
    /// Instrument transformer ratio, secondary factor.
    pub secondary: f64,
    /// Whether `a * x + b` is a primary or a secondary value (`PS`).
    pub scaling: Scaling,
}

impl AnalogChannel {
    /// A channel storing its values unscaled (`a = 1`, `b = 0`) as primary values, the
    /// 16-bit range `-32767..=32767`, no skew, ratio 1:1.
    pub fn new(name: impl Into<String>, unit: impl Into<String>) -> Self {
        AnalogChannel {
            name: name.into(),
            phase: String::new(),
            circuit: String::new(),
            unit: unit.into(),
            multiplier: 1.0,
            offset: 0.0,
            skew_us: 0.0,
            min: -32767,
            max: 32767,
            primary: 1.0,
            secondary: 1.0,
            scaling: Scaling::Primary,
        }
    }

    /// A channel of an IEC 60870-5-103 disturbance record (ASDU 27 gives RPV, RSV and RFA
    /// per channel), storing the single disturbance values (SDV, ASDU 30) unchanged.
    ///
    /// The reference factor RFA is the number of SDV counts per secondary unit, so
    ///
    /// ```text
    /// secondary = SDV / RFA
    /// primary   = SDV / RFA * RPV / RSV = SDV * a,   a = RPV / (RSV * RFA)
    /// ```
    ///
    /// which is how `iec60870::iec103::RecordChannel::primary` reads a channel and what
    /// `stanice iec103 master --comtrade` has written so far: the channel gets
    /// `a = RPV / (RSV * RFA)`, `b = 0`, `PS = P`, `primary = RPV`, `secondary = RSV` and the
    /// range `-32767..=32767`. Example: a 100 A / 1 A CT with RFA 100 stores 1 A secondary
    /// as SDV 100; `a = 1`, so SDV 141 is 141 A primary, 1.41 A secondary.
    ///
    /// A zero RSV or RFA gives a non-finite multiplier, which [`Record::validate`] refuses.
    /// SDV -32768 cannot be stored in a BINARY data file (0x8000 marks a missing value):
    /// saturate it to -32767 or write ASCII or BINARY32.
    pub fn from_iec103(
        name: impl Into<String>,
        unit: impl Into<String>,
        rpv: f32,
        rsv: f32,
        rfa: f32,
    ) -> Self {
        let (rpv, rsv, rfa) = (f64::from(rpv), f64::from(rsv), f64::from(rfa));
        AnalogChannel {
            multiplier: rpv / (rsv * rfa),
            primary: rpv,
            secondary: rsv,
            ..AnalogChannel::new(name, unit)
        }
    }

    /// `multiplier * raw + offset`: the value in `unit`, primary or secondary as
    /// `scaling` says.
    pub fn value(&self, raw: i32) -> f64 {
        self.multiplier * f64::from(raw) + self.offset
    }

    /// The primary value of a stored value.
    pub fn primary_value(&self, raw: i32) -> f64 {
        match self.scaling {
            Scaling::Primary => self.value(raw),
            Scaling::Secondary => self.value(raw) * self.primary / self.secondary,
        }
    }

    /// The secondary value of a stored value.
    pub fn secondary_value(&self, raw: i32) -> f64 {
        match self.scaling {
            Scaling::Primary => self.value(raw) * self.secondary / self.primary,
            Scaling::Secondary => self.value(raw),
        }
    }
}

/// A status (digital) channel (a `Dn,ch_id,ph,ccbm,y` line). Its index `Dn` is its
/// position in [`Record::digital`] plus one.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub struct DigitalChannel {
    /// Channel identifier (`ch_id`), at most 64 characters.
    pub name: String,
    /// Phase (`ph`), at most 2 characters, may be empty.
    pub phase: String,
    /// Circuit component being monitored (`ccbm`), at most 64 characters, may be empty.
    pub circuit: String,
    /// The state of the input when the primary equipment is in its normal (steady) state
    /// (`y`).
    pub normal_state: bool,
}

impl DigitalChannel {
    /// A status channel with no phase or circuit.
    pub fn new(name: impl Into<String>, normal_state: bool) -> Self {
        DigitalChannel {
            name: name.into(),
            phase: String::new(),
            circuit: String::new(),
            normal_state,
        }
    }
}

/// One sample: a row of the data file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Sample {
    /// Sample number (`n`), normally 1 for the first sample and counting up.
    pub number: u32,
    /// Time since the first sample, in microseconds times [`Record::timemult`]; `None` is
    /// a missing timestamp (allowed when the sample rates place the samples).
    pub timestamp: Option<u32>,
    /// A value per analog channel as stored (before `a * x + b`); `None` is a missing value.
    pub analog: Vec<Option<i32>>,
    /// A state per status channel.
    pub digital: Vec<bool>,
}

/// A COMTRADE disturbance record: the configuration and the samples.
///
/// Built with [`Record::new`] and its public fields, checked by [`Record::validate`],
/// written by [`Record::write_cfg`], [`Record::write_dat`] and [`Record::write_files`], read
/// back by [`Record::read`].
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct Record {
    /// Station name (`station_name`), at most 64 characters.
    pub station_name: String,
    /// Recording device identification (`rec_dev_id`), at most 64 characters.
    pub device_id: String,
    /// The standard revision the `.cfg` follows (`rev_year`).
    pub revision: Revision,
    /// The data file's format (`ft`).
    pub data_format: DataFormat,
    /// Nominal line frequency in hertz (`lf`).
    pub line_frequency: f64,
    /// The sampling rates (`nrates` and its `samp,endsamp` lines). Empty, or a rate of 0:
    /// no fixed rate, every sample needs its timestamp.
    pub sample_rates: Vec<SampleRate>,
    /// Time of the first sample.
    pub start: NaiveDateTime,
    /// Time of the trigger.
    pub trigger: NaiveDateTime,
    /// Multiplication factor of the timestamps (`timemult`): a timestamp `t` is
    /// `t * timemult` microseconds after the first sample.
    pub timemult: f64,
    /// Revision 2013 (not written in 1999, read from a 1999 file as the defaults of
    /// [`Record::new`]): the offset of the recording's time stamps from UTC (`time_code`,
    /// e.g. `0`, `-5`, `+5h30`), at most 6 characters.
    pub time_code: String,
    /// Revision 2013: the offset of local time from UTC when the time stamps are UTC
    /// (`local_code`; `x` when not applicable), at most 6 characters.
    pub local_code: String,
    /// Revision 2013: the time quality of the recording's clock (`tmq_code`, the IEEE
    /// C37.118 code 0-15: 0 locked, 0xF unreliable).
    pub time_quality: u8,
    /// Revision 2013: the leap second indicator (`leapsec`).
    pub leap_second: LeapSecond,
    /// The analog channels, in index order.
    pub analog: Vec<AnalogChannel>,
    /// The status channels, in index order.
    pub digital: Vec<DigitalChannel>,
    /// The samples, in order.
    pub samples: Vec<Sample>,
}

impl Record {
    /// An empty record of revision 1999 with BINARY data (what every viewer opens), 50 Hz,
    /// the trigger at the first sample, `timemult` 1, and for revision 2013 the time codes
    /// `0,0` (UTC), time quality 0xF (unreliable: a relay's clock is not known to be locked)
    /// and no leap second.
    pub fn new(
        station_name: impl Into<String>,
        device_id: impl Into<String>,
        start: NaiveDateTime,
    ) -> Self {
        Record {
            station_name: station_name.into(),
            device_id: device_id.into(),
            revision: Revision::R1999,
            data_format: DataFormat::Binary,
            line_frequency: 50.0,
            sample_rates: Vec::new(),
            start,
            trigger: start,
            timemult: 1.0,
            time_code: "0".to_owned(),
            local_code: "0".to_owned(),
            time_quality: 0xF,
            leap_second: LeapSecond::None,
            analog: Vec::new(),
            digital: Vec::new(),
            samples: Vec::new(),
        }
    }

    /// Fills [`Record::samples`] and [`Record::sample_rates`] from per-channel columns taken
    /// every `interval_us` microseconds: the shape an IEC 103 upload arrives in (ASDU 26
    /// gives the interval, ASDU 30 the values of one channel after the other).
    ///
    /// The record gets as many samples as its longest column, numbered from 1, timestamps
    /// `i * interval_us` (`timemult` is not changed), and one rate of `1e6 / interval_us`
    /// (none for an interval of 0). A short analog column ends in missing values, a short
    /// status column in its channel's normal state. Columns beyond the channels are kept,
    /// so [`Record::validate`] reports them.
    pub fn set_columns(
        &mut self,
        interval_us: u32,
        analog: &[Vec<Option<i32>>],
        digital: &[Vec<bool>],
    ) {
        let count = analog
            .iter()
            .map(Vec::len)
            .chain(digital.iter().map(Vec::len))
            .max()
            .unwrap_or(0);
        let normal: Vec<bool> = (0..digital.len())
            .map(|channel| {
                self.digital
                    .get(channel)
                    .is_some_and(|channel| channel.normal_state)
            })
            .collect();
        self.samples = (0..count)
            .map(|index| {
                let position = u32::try_from(index).ok();
                Sample {
                    number: position.map_or(u32::MAX, |position| position.saturating_add(1)),
                    timestamp: position.and_then(|position| position.checked_mul(interval_us)),
                    analog: analog
                        .iter()
                        .map(|column| column.get(index).copied().flatten())
                        .collect(),
                    digital: digital
                        .iter()
                        .zip(&normal)
                        .map(|(column, normal)| column.get(index).copied().unwrap_or(*normal))
                        .collect(),
                }
            })
            .collect();
        self.sample_rates = if interval_us == 0 {
            Vec::new()
        } else {
            vec![SampleRate {
                rate_hz: 1e6 / f64::from(interval_us),
                end_sample: u64::try_from(count).unwrap_or(u64::MAX),
            }]
        };
    }
}

/// The states of a status channel at `len` samples, from its state at the first sample
/// and its changes `(sample index, new state)` (in any order; the index counts from 0).
///
/// For an IEC 103 tag list: a signal's (FUN, INF) is the channel, each tag a change at its
/// position, DPI 2 (ON) `true`, DPI 1 (OFF) `false`.
pub fn status_column(initial: bool, changes: &[(usize, bool)], len: usize) -> Vec<bool> {
    let mut changes = changes.to_vec();
    changes.sort_by_key(|&(index, _)| index);
    let mut pending = changes.into_iter().peekable();
    let mut state = initial;
    (0..len)
        .map(|index| {
            while let Some(&(at, new_state)) = pending.peek() {
                if at > index {
                    break;
                }
                state = new_state;
                pending.next();
            }
            state
        })
        .collect()
}
