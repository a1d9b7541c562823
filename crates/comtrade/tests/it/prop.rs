//! Properties: random records survive writing and reading unchanged; no input makes the
//! reader panic.

use chrono::{NaiveDate, NaiveDateTime};
use comtrade::{
    AnalogChannel, DataFormat, DigitalChannel, LeapSecond, Record, Revision, Sample, SampleRate,
    Scaling,
};
use proptest::num::f64 as float;
use proptest::prelude::*;

fn finite() -> impl Strategy<Value = f64> {
    float::POSITIVE | float::NEGATIVE | float::NORMAL | float::SUBNORMAL | float::ZERO
}

fn positive() -> impl Strategy<Value = f64> {
    float::POSITIVE | float::NORMAL | float::SUBNORMAL
}

fn time() -> impl Strategy<Value = NaiveDateTime> {
    (
        0i32..=9999,
        1u32..=12,
        1u32..=28,
        0u32..24,
        0u32..60,
        0u32..60,
        0u32..1_000_000,
    )
        .prop_map(|(year, month, day, hour, minute, second, micro)| {
            NaiveDate::from_ymd_opt(year, month, day)
                .unwrap()
                .and_hms_micro_opt(hour, minute, second, micro)
                .unwrap()
        })
}

fn name() -> impl Strategy<Value = String> {
    "[A-Za-z0-9 _./+-]{0,20}"
}

fn analog_channel() -> impl Strategy<Value = AnalogChannel> {
    (
        (name(), "[A-Z0-9]{0,2}", name(), "[A-Za-z]{0,4}"),
        (finite(), finite(), finite()),
        (-99_999i32..=99_999, -99_999i32..=99_999),
        (positive(), positive(), any::<bool>()),
    )
        .prop_map(
            |((name, phase, circuit, unit), (a, b, skew), (min, max), (primary, secondary, ps))| {
                let mut channel = AnalogChannel::new(name, unit);
                channel.phase = phase;
                channel.circuit = circuit;
                channel.multiplier = a;
                channel.offset = b;
                channel.skew_us = skew;
                channel.min = min;
                channel.max = max;
                channel.primary = primary;
                channel.secondary = secondary;
                channel.scaling = if ps {
                    Scaling::Primary
                } else {
                    Scaling::Secondary
                };
                channel
            },
        )
}

fn digital_channel() -> impl Strategy<Value = DigitalChannel> {
    (name(), "[A-Z0-9]{0,2}", name(), any::<bool>()).prop_map(|(name, phase, circuit, normal)| {
        let mut channel = DigitalChannel::new(name, normal);
        channel.phase = phase;
        channel.circuit = circuit;
        channel
    })
}

/// What an analog value may be in a format (missing only where it can be written).
fn analog_value(revision: Revision, format: DataFormat) -> BoxedStrategy<Option<i32>> {
    let range = match format {
        DataFormat::Ascii => -99_999..=99_999,
        DataFormat::Binary => -32_767..=32_767,
        DataFormat::Binary32 => (i32::MIN + 1)..=i32::MAX,
    };
    if format == DataFormat::Ascii && revision == Revision::R1999 {
        range.prop_map(Some).boxed()
    } else {
        proptest::option::weighted(0.9, range).boxed()
    }
}

fn format_of(revision: Revision) -> BoxedStrategy<DataFormat> {
    match revision {
        Revision::R1999 => prop_oneof![Just(DataFormat::Ascii), Just(DataFormat::Binary)].boxed(),
        Revision::R2013 => prop_oneof![
            Just(DataFormat::Ascii),
            Just(DataFormat::Binary),
            Just(DataFormat::Binary32)
        ]
        .boxed(),
    }
}

/// A valid record of any revision and format.
fn record() -> impl Strategy<Value = Record> {
    prop_oneof![Just(Revision::R1999), Just(Revision::R2013)]
        .prop_flat_map(|revision| (Just(revision), format_of(revision)))
        .prop_flat_map(|(revision, format)| {
            (
                Just(revision),
                Just(format),
                proptest::collection::vec(analog_channel(), 0..4),
                proptest::collection::vec(digital_channel(), 0..35),
                0usize..10,
                any::<bool>(),
            )
        })
        .prop_flat_map(|(revision, format, analog, digital, count, fixed_rate)| {
            let timestamp = if fixed_rate {
                proptest::option::of(0u32..u32::MAX).boxed()
            } else {
                (0u32..u32::MAX).prop_map(Some).boxed()
            };
            let sample = (
                any::<u32>(),
                timestamp,
                proptest::collection::vec(analog_value(revision, format), analog.len()),
                proptest::collection::vec(any::<bool>(), digital.len()),
            )
                .prop_map(|(number, timestamp, analog, digital)| Sample {
                    number,
                    timestamp,
                    analog,
                    digital,
                });
            let rates = if fixed_rate {
                proptest::collection::vec((positive(), 0..=count as u64), 1..4)
                    .prop_map(move |mut rates| {
                        rates.sort_by_key(|&(_, end)| end);
                        if let Some(last) = rates.last_mut() {
                            last.1 = count as u64;
                        }
                        rates
                            .into_iter()
                            .map(|(rate_hz, end_sample)| SampleRate {
                                rate_hz,
                                end_sample,
                            })
                            .collect()
                    })
                    .boxed()
            } else {
                Just(Vec::new()).boxed()
            };
            (
                (Just(revision), Just(format), Just(analog), Just(digital)),
                proptest::collection::vec(sample, count),
                rates,
                (name(), name(), time(), time()),
                (finite().prop_map(f64::abs), positive()),
                (
                    "0|[+-][0-9]{1,2}(h[0-9]{2})?|x",
                    "0|[+-][0-9]{1,2}(h[0-9]{2})?|x",
                    0u8..=15,
                    0u8..=3,
                ),
            )
        })
        .prop_map(
            |(
                (revision, format, analog, digital),
                samples,
                rates,
                (station, device, start, trigger),
                (frequency, timemult),
                (time_code, local_code, quality, leap),
            )| {
                let mut record = Record::new(station, device, start);
                record.revision = revision;
                record.data_format = format;
                record.trigger = trigger;
                record.line_frequency = frequency;
                record.timemult = timemult;
                record.analog = analog;
                record.digital = digital;
                record.samples = samples;
                record.sample_rates = rates;
                if revision == Revision::R2013 {
                    record.time_code = time_code;
                    record.local_code = local_code;
                    record.time_quality = quality;
                    record.leap_second = LeapSecond::from_code(leap).unwrap();
                }
                record
            },
        )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn records_survive_writing_and_reading(record in record()) {
        record.validate().unwrap();
        let cfg = record.write_cfg().unwrap();
        let dat = record.write_dat().unwrap();
        let read = Record::read(&cfg, &dat).unwrap();
        prop_assert_eq!(&read, &record);
        // Written again, the files are the same bytes.
        prop_assert_eq!(read.write_cfg().unwrap(), cfg);
        prop_assert_eq!(read.write_dat().unwrap(), dat);
    }

    #[test]
    fn the_reader_never_panics_on_arbitrary_input(
        cfg in any::<String>(),
        dat in proptest::collection::vec(any::<u8>(), 0..256),
    ) {
        let _ = Record::read(&cfg, &dat);
    }

    #[test]
    fn the_reader_never_panics_on_damaged_files(
        record in record(),
        line in any::<prop::sample::Index>(),
        replacement in "[0-9A-Za-z,:./ +-]{0,30}",
        cut in any::<prop::sample::Index>(),
        flips in proptest::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 0..4),
    ) {
        let cfg = record.write_cfg().unwrap();
        let mut dat = record.write_dat().unwrap();
        // One line of the .cfg replaced by noise.
        let mut lines: Vec<&str> = cfg.split("\r\n").collect();
        let replaced = line.index(lines.len());
        lines[replaced] = &replacement;
        let damaged = lines.join("\r\n");
        let _ = Record::read(&damaged, &dat);
        // The .cfg cut short.
        let end = cut.index(cfg.len() + 1);
        let _ = Record::read(&cfg[..end], &dat);
        // Bytes of the .dat changed, then the .dat cut short.
        if !dat.is_empty() {
            for (at, byte) in &flips {
                let at = at.index(dat.len());
                dat[at] = *byte;
            }
        }
        let _ = Record::read(&cfg, &dat);
        let end = cut.index(dat.len() + 1);
        let _ = Record::read(&cfg, &dat[..end]);
    }
}
