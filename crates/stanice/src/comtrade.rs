//! IEC 103 disturbance records written as COMTRADE with the `comtrade` crate: the
//! relay's disturbance values go into the `.dat` unchanged, [`AnalogChannel::from_iec103`]
//! sets the multiplier to primary units, each tagged binary signal becomes a status
//! channel (1 from a tag where its double point is ON, 0 where OFF).

use std::path::{Path, PathBuf};

use anyhow::Context as _;
use comtrade::{status_column, AnalogChannel, DataFormat, DigitalChannel, Record};
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

/// The COMTRADE record of an uploaded disturbance record.
pub(crate) fn record(
    upload: &DisturbanceRecord,
    station: &str,
    device: &str,
    revision: Revision,
) -> Record {
    let mut record = Record::new(station, device, upload.first_sample);
    record.revision = match revision {
        Revision::R1999 => comtrade::Revision::R1999,
        Revision::R2013 => comtrade::Revision::R2013,
    };
    record.data_format = DataFormat::Ascii;
    record.trigger = upload.recorded_at;
    for channel in &upload.channels {
        let mut analog = AnalogChannel::from_iec103(
            channel.name(),
            channel.unit(),
            channel.rpv,
            channel.rsv,
            channel.rfa,
        );
        analog.phase = channel
            .name()
            .chars()
            .last()
            .filter(char::is_ascii_digit)
            .map_or_else(|| "N".to_owned(), String::from);
        record.analog.push(analog);
    }
    let samples = upload.elements();
    let mut signals: Vec<(u8, u8)> = Vec::new();
    for tag in &upload.tags {
        if !signals.contains(&(tag.tag.fun, tag.tag.inf)) {
            signals.push((tag.tag.fun, tag.tag.inf));
        }
    }
    let mut digital = Vec::new();
    for (fun, inf) in signals {
        let changes: Vec<(usize, bool)> = upload
            .tags
            .iter()
            .filter(|tag| (tag.tag.fun, tag.tag.inf) == (fun, inf))
            .map(|tag| (usize::from(tag.position), tag.tag.dpi == 2))
            .collect();
        // Before its first tag a signal was in the other state.
        let initial = changes
            .iter()
            .min_by_key(|(at, _)| *at)
            .is_some_and(|(_, on)| !on);
        let column = status_column(initial, &changes, samples);
        record.digital.push(DigitalChannel::new(
            format!("FUN{fun}_INF{inf}"),
            column.first().copied().unwrap_or(false),
        ));
        digital.push(column);
    }
    let analog: Vec<Vec<Option<i32>>> = upload
        .channels
        .iter()
        .map(|channel| {
            channel
                .samples
                .iter()
                .map(|value| Some(i32::from(*value)))
                .collect()
        })
        .collect();
    record.set_columns(u32::from(upload.interval_us), &analog, &digital);
    record
}

/// Writes `DIR/NAME.cfg` and `DIR/NAME.dat`; returns their paths.
pub(crate) fn write(
    directory: &Path,
    name: &str,
    upload: &DisturbanceRecord,
    station: &str,
    device: &str,
    revision: Revision,
) -> anyhow::Result<(PathBuf, PathBuf)> {
    std::fs::create_dir_all(directory)
        .with_context(|| format!("cannot create {}", directory.display()))?;
    record(upload, station, device, revision)
        .write_files(directory, name)
        .with_context(|| {
            format!(
                "cannot write the record {name} into {}",
                directory.display()
            )
        })
}
