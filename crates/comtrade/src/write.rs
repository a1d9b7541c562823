//! Writing the `.cfg` text and the `.dat` bytes.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use chrono::{Datelike, NaiveDateTime, Timelike};

use crate::record::{DataFormat, Record, Revision, Sample, Scaling};
use crate::validate::WriteError;

/// The longest real number a `.cfg` field takes.
const REAL_CHARS: usize = 32;

/// A real number as the shortest text that reads back to the same `f64`: plain notation
/// (`0.1138916015625`, `50`), exponent notation (`1e-30`) where plain would exceed a
/// field's 32 characters.
pub(crate) fn real(value: f64) -> String {
    let plain = format!("{value}");
    if plain.len() <= REAL_CHARS {
        plain
    } else {
        format!("{value:e}")
    }
}

/// `dd/mm/yyyy,hh:mm:ss.ssssss`; sub-microsecond digits are dropped.
pub(crate) fn date_time(time: NaiveDateTime) -> String {
    let nanos = time.nanosecond();
    // chrono keeps a leap second as second 59 with 1e9 nanoseconds and more.
    let (second, nanos) = if nanos >= 1_000_000_000 {
        (60, nanos - 1_000_000_000)
    } else {
        (time.second(), nanos)
    };
    format!(
        "{:02}/{:02}/{:04},{:02}:{:02}:{:02}.{:06}",
        time.day(),
        time.month(),
        time.year(),
        time.hour(),
        time.minute(),
        second,
        nanos / 1000
    )
}

/// Appends a line and its CR/LF.
fn line(out: &mut String, text: std::fmt::Arguments<'_>) {
    let _ = out.write_fmt(text);
    out.push_str("\r\n");
}

impl Record {
    /// The `.cfg` text, lines ended by CR/LF.
    ///
    /// ```text
    /// station_name,rec_dev_id,rev_year
    /// TT,##A,##D
    /// An,ch_id,ph,ccbm,uu,a,b,skew,min,max,primary,secondary,PS   (per analog channel)
    /// Dn,ch_id,ph,ccbm,y                                           (per status channel)
    /// lf
    /// nrates
    /// samp,endsamp                                                 (per rate; 0,N without one)
    /// dd/mm/yyyy,hh:mm:ss.ssssss                                   (first sample)
    /// dd/mm/yyyy,hh:mm:ss.ssssss                                   (trigger)
    /// ft
    /// timemult
    /// time_code,local_code                                         (2013)
    /// tmq_code,leapsec                                             (2013)
    /// ```
    pub fn write_cfg(&self) -> Result<String, WriteError> {
        self.validate()?;
        let mut cfg = String::new();
        line(
            &mut cfg,
            format_args!(
                "{},{},{}",
                self.station_name,
                self.device_id,
                self.revision.year()
            ),
        );
        line(
            &mut cfg,
            format_args!(
                "{},{}A,{}D",
                self.analog.len() + self.digital.len(),
                self.analog.len(),
                self.digital.len()
            ),
        );
        for (position, channel) in self.analog.iter().enumerate() {
            line(
                &mut cfg,
                format_args!(
                    "{},{},{},{},{},{},{},{},{},{},{},{},{}",
                    position + 1,
                    channel.name,
                    channel.phase,
                    channel.circuit,
                    channel.unit,
                    real(channel.multiplier),
                    real(channel.offset),
                    real(channel.skew_us),
                    channel.min,
                    channel.max,
                    real(channel.primary),
                    real(channel.secondary),
                    match channel.scaling {
                        Scaling::Primary => 'P',
                        Scaling::Secondary => 'S',
                    }
                ),
            );
        }
        for (position, channel) in self.digital.iter().enumerate() {
            line(
                &mut cfg,
                format_args!(
                    "{},{},{},{},{}",
                    position + 1,
                    channel.name,
                    channel.phase,
                    channel.circuit,
                    u8::from(channel.normal_state)
                ),
            );
        }
        line(&mut cfg, format_args!("{}", real(self.line_frequency)));
        line(&mut cfg, format_args!("{}", self.sample_rates.len()));
        if self.sample_rates.is_empty() {
            line(&mut cfg, format_args!("0,{}", self.samples.len()));
        }
        for rate in &self.sample_rates {
            line(
                &mut cfg,
                format_args!("{},{}", real(rate.rate_hz), rate.end_sample),
            );
        }
        line(&mut cfg, format_args!("{}", date_time(self.start)));
        line(&mut cfg, format_args!("{}", date_time(self.trigger)));
        line(&mut cfg, format_args!("{}", self.data_format.keyword()));
        line(&mut cfg, format_args!("{}", real(self.timemult)));
        if self.revision == Revision::R2013 {
            line(
                &mut cfg,
                format_args!("{},{}", self.time_code, self.local_code),
            );
            line(
                &mut cfg,
                format_args!("{:X},{}", self.time_quality, self.leap_second.code()),
            );
        }
        Ok(cfg)
    }

    /// The `.dat` bytes in the record's data format.
    ///
    /// ASCII: `n,timestamp,A1..Ak,D1..Dm` per sample, CR/LF; a missing timestamp or (in
    /// revision 2013) analog value is an empty field. BINARY / BINARY32: per sample `u32`
    /// number, `u32` timestamp (0xFFFFFFFF missing), an `i16` / `i32` per analog channel
    /// (0x8000 / 0x80000000 missing), then the status channels 16 to a `u16` word, channel
    /// 1 in bit 0 of the first word, unused bits 0; all little-endian.
    pub fn write_dat(&self) -> Result<Vec<u8>, WriteError> {
        self.validate()?;
        Ok(match self.data_format {
            DataFormat::Ascii => self.ascii_dat(),
            DataFormat::Binary | DataFormat::Binary32 => self.binary_dat(),
        })
    }

    fn ascii_dat(&self) -> Vec<u8> {
        let mut dat = String::new();
        for sample in &self.samples {
            let _ = write!(dat, "{},", sample.number);
            if let Some(timestamp) = sample.timestamp {
                let _ = write!(dat, "{timestamp}");
            }
            for value in &sample.analog {
                dat.push(',');
                if let Some(value) = value {
                    let _ = write!(dat, "{value}");
                }
            }
            for &state in &sample.digital {
                dat.push_str(if state { ",1" } else { ",0" });
            }
            dat.push_str("\r\n");
        }
        dat.into_bytes()
    }

    fn binary_dat(&self) -> Vec<u8> {
        let wide = self.data_format == DataFormat::Binary32;
        let size = binary_sample_size(self.analog.len(), self.digital.len(), wide).unwrap_or(0);
        let mut dat = Vec::with_capacity(size.saturating_mul(self.samples.len()));
        for sample in &self.samples {
            binary_sample(&mut dat, sample, wide);
        }
        dat
    }

    /// Writes `DIR/BASE.cfg` and `DIR/BASE.dat` (creating DIR) and returns their paths.
    pub fn write_files(
        &self,
        dir: &Path,
        base_name: &str,
    ) -> Result<(PathBuf, PathBuf), WriteError> {
        let cfg = self.write_cfg()?;
        let dat = self.write_dat()?;
        std::fs::create_dir_all(dir).map_err(|source| WriteError::Io {
            path: dir.to_owned(),
            source,
        })?;
        let cfg_path = dir.join(format!("{base_name}.cfg"));
        let dat_path = dir.join(format!("{base_name}.dat"));
        for (path, bytes) in [(&cfg_path, cfg.as_bytes()), (&dat_path, dat.as_slice())] {
            std::fs::write(path, bytes).map_err(|source| WriteError::Io {
                path: path.clone(),
                source,
            })?;
        }
        Ok((cfg_path, dat_path))
    }
}

/// The bytes of one binary sample: 8 for number and timestamp, 2 (4 wide) per analog
/// channel, 2 per 16 status channels. `None` if it overflows.
pub(crate) fn binary_sample_size(analog: usize, digital: usize, wide: bool) -> Option<usize> {
    let width = if wide { 4 } else { 2 };
    analog
        .checked_mul(width)?
        .checked_add(digital.div_ceil(16).checked_mul(2)?)?
        .checked_add(8)
}

fn binary_sample(dat: &mut Vec<u8>, sample: &Sample, wide: bool) {
    dat.extend_from_slice(&sample.number.to_le_bytes());
    dat.extend_from_slice(&sample.timestamp.unwrap_or(u32::MAX).to_le_bytes());
    for value in &sample.analog {
        if wide {
            dat.extend_from_slice(&value.unwrap_or(i32::MIN).to_le_bytes());
        } else {
            // Validation keeps values within -32767..=32767.
            let value = value.map_or(i16::MIN, |value| {
                i16::try_from(value).unwrap_or(if value < 0 { -i16::MAX } else { i16::MAX })
            });
            dat.extend_from_slice(&value.to_le_bytes());
        }
    }
    for word in sample.digital.chunks(16) {
        let bits = word
            .iter()
            .enumerate()
            .filter(|(_, &state)| state)
            .fold(0u16, |bits, (bit, _)| bits | (1 << bit));
        dat.extend_from_slice(&bits.to_le_bytes());
    }
}
