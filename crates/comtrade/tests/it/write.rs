//! Validation before writing, the IEC 103 helpers and the files on disk.

use comtrade::{
    status_column, AnalogChannel, DataFormat, DigitalChannel, Record, Revision, SampleRate,
    WriteError,
};

use crate::{at, small_record};

fn refused(record: &Record) -> WriteError {
    let error = record.validate().unwrap_err();
    // Neither writer writes what validation refuses.
    assert!(record.write_cfg().is_err());
    assert!(record.write_dat().is_err());
    error
}

#[test]
fn a_comma_in_a_name_is_refused() {
    let mut record = small_record(Revision::R1999, DataFormat::Binary);
    record.analog[1].name = "UL1, busbar".to_owned();
    let error = refused(&record);
    assert!(matches!(&error, WriteError::Text { field, .. } if field == "analog channel 2 name"));
    assert_eq!(
        error.to_string(),
        "analog channel 2 name \"UL1, busbar\": commas and line breaks separate the fields of a .cfg"
    );
}

#[test]
fn text_lengths_are_the_standards() {
    let mut record = small_record(Revision::R1999, DataFormat::Binary);
    record.digital[0].phase = "L1N".to_owned();
    assert!(matches!(refused(&record), WriteError::Text { .. }));
    let mut record = small_record(Revision::R1999, DataFormat::Binary);
    record.station_name = "x".repeat(65);
    assert!(matches!(refused(&record), WriteError::Text { .. }));
    record.station_name = "x".repeat(64);
    record.validate().unwrap();
}

#[test]
fn a_value_outside_sixteen_bits_is_refused_in_binary() {
    let mut record = small_record(Revision::R1999, DataFormat::Binary);
    record.samples[2].analog[0] = Some(-32768);
    assert!(matches!(
        refused(&record),
        WriteError::AnalogValue {
            sample: 2,
            channel: 1,
            value: -32768,
            ..
        }
    ));
    // ASCII and BINARY32 hold it.
    record.data_format = DataFormat::Ascii;
    record.samples[1].analog[1] = Some(0);
    record.validate().unwrap();
    record.revision = Revision::R2013;
    record.data_format = DataFormat::Binary32;
    record.samples[2].analog[0] = Some(i32::MIN + 1);
    record.validate().unwrap();
    record.samples[2].analog[0] = Some(i32::MIN);
    assert!(matches!(refused(&record), WriteError::AnalogValue { .. }));
}

#[test]
fn ascii_1999_cannot_write_a_missing_value() {
    let record = small_record(Revision::R1999, DataFormat::Ascii);
    let error = refused(&record);
    assert!(matches!(
        error,
        WriteError::MissingValue {
            sample: 1,
            channel: 2
        }
    ));
    small_record(Revision::R2013, DataFormat::Ascii)
        .validate()
        .unwrap();
}

#[test]
fn binary32_needs_revision_2013() {
    let record = small_record(Revision::R1999, DataFormat::Binary32);
    assert!(matches!(
        refused(&record),
        WriteError::FormatNeedsRevision { .. }
    ));
}

#[test]
fn every_sample_has_a_value_per_channel() {
    let mut record = small_record(Revision::R1999, DataFormat::Binary);
    record.samples[1].digital.pop();
    assert!(matches!(
        refused(&record),
        WriteError::SampleShape {
            sample: 1,
            digital: 1,
            digital_channels: 2,
            ..
        }
    ));
}

#[test]
fn the_rates_end_at_the_last_sample() {
    let mut record = small_record(Revision::R1999, DataFormat::Binary);
    record.samples.pop();
    assert!(matches!(
        refused(&record),
        WriteError::SampleCount {
            declared: 3,
            actual: 2
        }
    ));
    let mut record = small_record(Revision::R1999, DataFormat::Binary);
    record.sample_rates = vec![
        SampleRate {
            rate_hz: 1000.0,
            end_sample: 2,
        },
        SampleRate {
            rate_hz: 500.0,
            end_sample: 1,
        },
    ];
    assert!(matches!(
        refused(&record),
        WriteError::SampleRateOrder { index: 2, .. }
    ));
}

#[test]
fn without_a_rate_every_sample_needs_its_timestamp() {
    let mut record = small_record(Revision::R1999, DataFormat::Binary);
    record.samples[1].timestamp = None;
    record.validate().unwrap();
    record.sample_rates.clear();
    assert!(matches!(
        refused(&record),
        WriteError::MissingTimestamp { sample: 1 }
    ));
    record.samples[1].timestamp = Some(1000);
    let cfg = record.write_cfg().unwrap();
    assert!(cfg.contains("\r\n50\r\n0\r\n0,3\r\n"), "{cfg}");
}

#[test]
fn the_binary_missing_timestamp_code_is_not_a_timestamp() {
    let mut record = small_record(Revision::R1999, DataFormat::Binary);
    record.samples[2].timestamp = Some(u32::MAX);
    assert!(matches!(
        refused(&record),
        WriteError::ReservedTimestamp { sample: 2 }
    ));
}

#[test]
fn numbers_must_be_finite() {
    let mut record = small_record(Revision::R1999, DataFormat::Binary);
    record.analog[0] = AnalogChannel::from_iec103("IL1", "A", 400.0, 1.0, 0.0);
    assert!(
        matches!(refused(&record), WriteError::Number { field, .. } if field == "analog channel 1 multiplier")
    );
    let mut record = small_record(Revision::R1999, DataFormat::Binary);
    record.timemult = 0.0;
    assert!(matches!(refused(&record), WriteError::Number { field, .. } if field == "timemult"));
}

#[test]
fn years_beyond_four_digits_are_refused() {
    let mut record = small_record(Revision::R1999, DataFormat::Binary);
    record.trigger = chrono::NaiveDate::from_ymd_opt(10_000, 1, 1)
        .unwrap()
        .and_hms_opt(0, 0, 0)
        .unwrap();
    assert!(matches!(
        refused(&record),
        WriteError::Time {
            field: "trigger time",
            ..
        }
    ));
}

#[test]
fn the_2013_time_fields_are_checked() {
    let mut record = small_record(Revision::R2013, DataFormat::Binary);
    record.time_quality = 16;
    assert!(matches!(refused(&record), WriteError::Number { .. }));
    record.time_quality = 0;
    record.time_code = "+10h300".to_owned();
    assert!(matches!(refused(&record), WriteError::Text { .. }));
    record.time_code = String::new();
    assert!(matches!(refused(&record), WriteError::Text { .. }));
    // Revision 1999 does not write them.
    record.revision = Revision::R1999;
    record.validate().unwrap();
}

#[test]
fn iec103_scaling_gives_primary_and_secondary_values() {
    // 400 A / 1 A CT, 100 disturbance values per secondary ampere.
    let channel = AnalogChannel::from_iec103("IL1", "A", 400.0, 1.0, 100.0);
    assert_eq!(channel.multiplier, 4.0);
    assert_eq!(channel.offset, 0.0);
    assert_eq!((channel.primary, channel.secondary), (400.0, 1.0));
    assert_eq!((channel.min, channel.max), (-32767, 32767));
    assert_eq!(channel.primary_value(141), 564.0);
    assert!((channel.secondary_value(141) - 1.41).abs() < 1e-12);
    // 20 kV / 100 V VT, 10 values per secondary volt: a = 20000 / (100 * 10) = 20 V.
    let voltage = AnalogChannel::from_iec103("UL1E", "V", 20_000.0, 100.0, 10.0);
    assert_eq!(voltage.primary_value(577), 11_540.0);
    assert!((voltage.secondary_value(577) - 57.7).abs() < 1e-9);
}

#[test]
fn columns_become_samples() {
    let mut record = Record::new("S", "D", at(0, 0, 0, 0));
    record.analog = vec![AnalogChannel::new("A", "A"), AnalogChannel::new("B", "A")];
    record.digital = vec![
        DigitalChannel::new("X", false),
        DigitalChannel::new("Y", true),
    ];
    record.set_columns(
        833,
        &[vec![Some(1), Some(2), Some(3)], vec![Some(4)]],
        &[status_column(false, &[(1, true)], 3), vec![false]],
    );
    assert_eq!(record.samples.len(), 3);
    assert_eq!(record.samples[2].number, 3);
    assert_eq!(record.samples[2].timestamp, Some(1666));
    assert_eq!(record.samples[2].analog, [Some(3), None]);
    // The short status column continues in its channel's normal state.
    assert_eq!(record.samples[2].digital, [true, true]);
    assert_eq!(record.samples[0].digital, [false, false]);
    assert_eq!(record.sample_rates.len(), 1);
    assert_eq!(record.sample_rates[0].end_sample, 3);
    assert!((record.sample_rates[0].rate_hz - 1200.48).abs() < 0.01);
    record.validate().unwrap();
}

#[test]
fn status_columns_follow_their_changes_in_any_order() {
    assert_eq!(
        status_column(true, &[(4, true), (1, false), (6, false)], 6),
        [true, false, false, false, true, true]
    );
    assert_eq!(status_column(false, &[(0, true)], 2), [true, true]);
    assert!(status_column(false, &[], 0).is_empty());
}

#[test]
fn files_on_disk_read_back() {
    let dir = std::env::temp_dir().join(format!("comtrade-it-{}", std::process::id()));
    let record = small_record(Revision::R2013, DataFormat::Binary);
    let (cfg, dat) = record.write_files(&dir.join("fault"), "FAN7").unwrap();
    assert_eq!(cfg, dir.join("fault").join("FAN7.cfg"));
    assert_eq!(dat, dir.join("fault").join("FAN7.dat"));
    assert_eq!(Record::read_files(&cfg, &dat).unwrap(), record);
    let missing = Record::read_files(&dir.join("none.cfg"), &dat).unwrap_err();
    assert!(missing.to_string().starts_with("cannot read "), "{missing}");
    std::fs::remove_dir_all(&dir).unwrap();
}
