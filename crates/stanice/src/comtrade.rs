//! Disturbance records written as COMTRADE (IEEE C37.111 / IEC 60255-24), revision 1999
//! or 2013, ASCII data: what every fault-analysis tool opens.
//!
//! Written here rather than with a crate: the COMTRADE crates on crates.io read files;
//! writing the two text files of one record is a page of code.
//!
//! Analog channels carry the IEC 103 single disturbance values (SDV) unchanged; the
//! multiplier `a` turns them into primary values (`a = RPV / (RSV * RFA)`, see
//! [`iec60870::iec103::RecordChannel`]). Each binary signal of the record's tags becomes a
//! status channel: 1 from the tag position where its double point is ON, 0 where OFF.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Context as _;
use chrono::NaiveDateTime;
use iec60870::iec103::DisturbanceRecord;

/// The revision year of the configuration file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum Revision {
    /// IEEE C37.111-1999.
    #[value(name = "1999")]
    R1999,
    /// IEEE C37.111-2013 / IEC 60255-24:2013.
    #[value(name = "2013")]
    R2013,
}

/// dd/mm/yyyy,hh:mm:ss.ssssss
fn timestamp(time: NaiveDateTime) -> String {
    time.format("%d/%m/%Y,%H:%M:%S%.6f").to_string()
}

/// The status channels: each (FUN, INF) of the tags, with its state at each sample.
fn status_channels(record: &DisturbanceRecord, samples: usize) -> Vec<((u8, u8), Vec<u8>)> {
    let mut signals: Vec<(u8, u8)> = Vec::new();
    for tag in &record.tags {
        let signal = (tag.tag.fun, tag.tag.inf);
        if !signals.contains(&signal) {
            signals.push(signal);
        }
    }
    signals
        .into_iter()
        .map(|signal| {
            let mut tags: Vec<_> = record
                .tags
                .iter()
                .filter(|tag| (tag.tag.fun, tag.tag.inf) == signal)
                .collect();
            tags.sort_by_key(|tag| tag.position);
            // Before its first tag a signal was in the other state.
            let mut state = u8::from(tags.first().is_some_and(|tag| tag.tag.dpi != 2));
            let mut next = tags.into_iter().peekable();
            let states = (0..samples)
                .map(|sample| {
                    while let Some(tag) = next.peek() {
                        if usize::from(tag.position) > sample {
                            break;
                        }
                        state = u8::from(tag.tag.dpi == 2);
                        next.next();
                    }
                    state
                })
                .collect();
            (signal, states)
        })
        .collect()
}

/// The `.cfg` text.
pub(crate) fn configuration(
    record: &DisturbanceRecord,
    station: &str,
    device: &str,
    revision: Revision,
) -> String {
    let samples = record.elements();
    let status = status_channels(record, samples);
    let mut cfg = String::new();
    let year = match revision {
        Revision::R1999 => 1999,
        Revision::R2013 => 2013,
    };
    let _ = writeln!(cfg, "{station},{device},{year}");
    let analog = record.channels.len();
    let _ = writeln!(cfg, "{},{analog}A,{}D", analog + status.len(), status.len());
    for (index, channel) in record.channels.iter().enumerate() {
        let multiplier = if channel.rfa == 0.0 || channel.rsv == 0.0 {
            0.0
        } else {
            f64::from(channel.rpv) / (f64::from(channel.rsv) * f64::from(channel.rfa))
        };
        let phase = channel
            .name()
            .chars()
            .last()
            .filter(char::is_ascii_digit)
            .map(String::from)
            .unwrap_or_else(|| "N".to_owned());
        let _ = writeln!(
            cfg,
            "{},{},{phase},,{},{multiplier},0,0,-32767,32767,{},{},P",
            index + 1,
            channel.name(),
            channel.unit(),
            channel.rpv,
            channel.rsv
        );
    }
    for (index, ((fun, inf), states)) in status.iter().enumerate() {
        let normal = states.first().copied().unwrap_or(0);
        let _ = writeln!(cfg, "{},FUN{fun}_INF{inf},,,{normal}", index + 1);
    }
    let _ = writeln!(cfg, "50");
    let _ = writeln!(cfg, "1");
    let rate = if record.interval_us == 0 {
        0.0
    } else {
        1_000_000.0 / f64::from(record.interval_us)
    };
    let _ = writeln!(cfg, "{rate},{samples}");
    let _ = writeln!(cfg, "{}", timestamp(record.first_sample));
    let _ = writeln!(cfg, "{}", timestamp(record.recorded_at));
    let _ = writeln!(cfg, "ASCII");
    let _ = writeln!(cfg, "1");
    if revision == Revision::R2013 {
        // UTC, no local offset; time quality unknown (the relay's clock may be off),
        // no leap second.
        let _ = writeln!(cfg, "+0h00,+0h00");
        let _ = writeln!(cfg, "F,0");
    }
    cfg
}

/// The ASCII `.dat` text: sample number, time in microseconds, analog values, status.
pub(crate) fn data(record: &DisturbanceRecord) -> String {
    let samples = record.elements();
    let status = status_channels(record, samples);
    let mut dat = String::new();
    for sample in 0..samples {
        let micros = u64::try_from(sample).unwrap_or(u64::MAX) * u64::from(record.interval_us);
        let _ = write!(dat, "{},{micros}", sample + 1);
        for channel in &record.channels {
            match channel.samples.get(sample) {
                Some(value) => {
                    let _ = write!(dat, ",{value}");
                }
                None => dat.push(','),
            }
        }
        for (_, states) in &status {
            let _ = write!(dat, ",{}", states.get(sample).copied().unwrap_or(0));
        }
        dat.push_str("\r\n");
    }
    dat
}

/// Writes `DIR/NAME.cfg` and `DIR/NAME.dat`; returns their paths.
pub(crate) fn write(
    directory: &Path,
    name: &str,
    record: &DisturbanceRecord,
    station: &str,
    device: &str,
    revision: Revision,
) -> anyhow::Result<(PathBuf, PathBuf)> {
    std::fs::create_dir_all(directory)
        .with_context(|| format!("cannot create {}", directory.display()))?;
    let cfg_path = directory.join(format!("{name}.cfg"));
    let dat_path = directory.join(format!("{name}.dat"));
    std::fs::write(
        &cfg_path,
        configuration(record, station, device, revision).replace('\n', "\r\n"),
    )
    .with_context(|| format!("cannot write {}", cfg_path.display()))?;
    std::fs::write(&dat_path, data(record))
        .with_context(|| format!("cannot write {}", dat_path.display()))?;
    Ok((cfg_path, dat_path))
}

#[cfg(test)]
mod tests {
    use super::*;
    use iec60870::iec103::{DisturbanceTag, RecordChannel, RecordTag};

    fn record() -> DisturbanceRecord {
        let at = chrono::NaiveDate::from_ymd_opt(2017, 4, 26)
            .unwrap_or_default()
            .and_hms_micro_opt(9, 59, 30, 424_000)
            .unwrap_or_default();
        DisturbanceRecord {
            fan: 3,
            sof: 1,
            recorded_at: at,
            first_sample: at - chrono::Duration::milliseconds(2),
            interval_us: 1000,
            channels: vec![RecordChannel {
                acc: 1,
                rpv: 100.0,
                rsv: 1.0,
                rfa: 100.0,
                samples: vec![0, 141, -141, 707],
            }],
            tags: vec![RecordTag {
                position: 2,
                tag: DisturbanceTag {
                    fun: 160,
                    inf: 92,
                    dpi: 2,
                },
            }],
        }
    }

    #[test]
    fn configuration_and_data_of_both_revisions() {
        let record = record();
        let cfg = configuration(&record, "Feeder F1", "REF630 1", Revision::R1999);
        assert_eq!(
            cfg,
            "Feeder F1,REF630 1,1999\n2,1A,1D\n1,IL1,1,,A,1,0,0,-32767,32767,100,1,P\n1,FUN160_INF92,,,0\n50\n1\n1000,4\n26/04/2017,09:59:30.422000\n26/04/2017,09:59:30.424000\nASCII\n1\n"
        );
        let cfg2013 = configuration(&record, "Feeder F1", "REF630 1", Revision::R2013);
        assert!(cfg2013.starts_with("Feeder F1,REF630 1,2013\n"));
        assert!(cfg2013.ends_with("ASCII\n1\n+0h00,+0h00\nF,0\n"));
        assert_eq!(
            data(&record),
            "1,0,0,0\r\n2,1000,141,0\r\n3,2000,-141,1\r\n4,3000,707,1\r\n"
        );
    }
}
