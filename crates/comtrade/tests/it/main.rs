//! Integration tests of the comtrade crate: one binary, one module per area.
// Helpers used by the tests panic on error: their panics are the failure report.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod golden;
mod prop;
mod read;
mod write;

use chrono::{NaiveDate, NaiveDateTime};
use comtrade::{
    AnalogChannel, DataFormat, DigitalChannel, Record, Revision, Sample, SampleRate, Scaling,
};

/// A time of 1 March 2024.
fn at(hour: u32, minute: u32, second: u32, micro: u32) -> NaiveDateTime {
    NaiveDate::from_ymd_opt(2024, 3, 1)
        .unwrap()
        .and_hms_micro_opt(hour, minute, second, micro)
        .unwrap()
}

/// Two analog channels (one from IEC 103 scaling, one secondary with skew), two status
/// channels, three samples at 1 kHz with a missing value in the second.
fn small_record(revision: Revision, format: DataFormat) -> Record {
    let mut record = Record::new("Substation Vsetin", "REF630 F1", at(12, 0, 0, 250_000));
    record.revision = revision;
    record.data_format = format;
    record.trigger = at(12, 0, 0, 252_000);
    if revision == Revision::R2013 {
        record.time_code = "+1".to_owned();
        record.local_code = "x".to_owned();
        record.time_quality = 0xA;
    }

    let mut il1 = AnalogChannel::from_iec103("IL1", "A", 400.0, 1.0, 100.0);
    il1.phase = "1".to_owned();
    il1.circuit = "Line 1".to_owned();
    let mut ul1 = AnalogChannel::new("UL1", "kV");
    ul1.phase = "1".to_owned();
    ul1.circuit = "Line 1".to_owned();
    ul1.multiplier = 0.01;
    ul1.skew_us = 12.5;
    ul1.primary = 110.0;
    ul1.secondary = 0.1;
    ul1.scaling = Scaling::Secondary;
    record.analog = vec![il1, ul1];

    let mut breaker = DigitalChannel::new("CB closed", true);
    breaker.circuit = "Q0".to_owned();
    record.digital = vec![DigitalChannel::new("Trip", false), breaker];

    record.sample_rates = vec![SampleRate {
        rate_hz: 1000.0,
        end_sample: 3,
    }];
    record.samples = vec![
        Sample {
            number: 1,
            timestamp: Some(0),
            analog: vec![Some(0), Some(1000)],
            digital: vec![false, true],
        },
        Sample {
            number: 2,
            timestamp: Some(1000),
            analog: vec![Some(141), None],
            digital: vec![true, true],
        },
        Sample {
            number: 3,
            timestamp: Some(2000),
            analog: vec![Some(-141), Some(-1000)],
            digital: vec![true, false],
        },
    ];
    record
}
