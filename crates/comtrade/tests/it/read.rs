//! Reading files back, and the reader's errors.

use comtrade::{DataFormat, LeapSecond, Problem, ReadError, Record, Revision, Scaling};

use crate::small_record;

fn round_trip(revision: Revision, format: DataFormat) {
    let record = small_record(revision, format);
    let cfg = record.write_cfg().unwrap();
    let dat = record.write_dat().unwrap();
    assert_eq!(Record::read(&cfg, &dat).unwrap(), record);
}

#[test]
fn ascii_round_trip() {
    round_trip(Revision::R2013, DataFormat::Ascii);
    let mut record = small_record(Revision::R1999, DataFormat::Ascii);
    record.samples[1].analog[1] = Some(-99_999);
    let read = Record::read(&record.write_cfg().unwrap(), &record.write_dat().unwrap()).unwrap();
    assert_eq!(read, record);
}

#[test]
fn binary_round_trip() {
    round_trip(Revision::R1999, DataFormat::Binary);
    round_trip(Revision::R2013, DataFormat::Binary);
    round_trip(Revision::R2013, DataFormat::Binary32);
}

#[test]
fn many_status_channels_fill_several_words() {
    let mut record = small_record(Revision::R1999, DataFormat::Binary);
    record.digital = (0..37)
        .map(|index| comtrade::DigitalChannel::new(format!("D{index}"), index % 3 == 0))
        .collect();
    for (position, sample) in record.samples.iter_mut().enumerate() {
        sample.digital = (0..37).map(|index| (index + position) % 5 == 0).collect();
    }
    let dat = record.write_dat().unwrap();
    assert_eq!(dat.len(), 3 * (8 + 2 * 2 + 3 * 2));
    assert_eq!(
        Record::read(&record.write_cfg().unwrap(), &dat).unwrap(),
        record
    );
}

/// A configuration as other tools write them: LF line ends, spaces around numbers,
/// lower-case keywords, an empty `lf` and `skew`, a byte order mark, min/max as reals,
/// no 2013 time lines, trailing empty lines.
#[test]
fn lenient_with_what_real_files_vary_in() {
    let cfg = "\u{feff}SMARTSTATION,IED123,2013\n\
               2, 1A, 1d\n\
               1,IA ,,Line123, A,0.1138916015625, 0.05,,-32768.0,32767,933,1,s\n\
               1,51A,,Line123, 0\n\
               \n\
               1\n\
               1200,2\n\
               12/01/2011,05:55:30.075011\n\
               12/01/2011,05:55:30.0782\n\
               ascii\n\
               1\n\n\n";
    let dat = b"1,72500,-83,0\r\n2,73333,-15,1\n\n";
    let record = Record::read(cfg, dat).unwrap();
    assert_eq!(record.station_name, "SMARTSTATION");
    assert_eq!(record.revision, Revision::R2013);
    assert_eq!(record.data_format, DataFormat::Ascii);
    assert_eq!(record.line_frequency, 0.0);
    let channel = &record.analog[0];
    assert_eq!(channel.name, "IA ");
    assert_eq!(channel.unit, " A");
    assert_eq!(channel.offset, 0.05);
    assert_eq!(channel.skew_us, 0.0);
    assert_eq!(channel.min, -32768);
    assert_eq!(channel.scaling, Scaling::Secondary);
    assert!(!record.digital[0].normal_state);
    assert_eq!(
        record.trigger.format("%H:%M:%S%.6f").to_string(),
        "05:55:30.078200"
    );
    // Absent 2013 time lines: the defaults.
    assert_eq!(record.time_code, "0");
    assert_eq!(record.leap_second, LeapSecond::None);
    assert_eq!(record.samples.len(), 2);
    assert_eq!(record.samples[1].timestamp, Some(73333));
    assert_eq!(record.samples[1].analog, [Some(-15)]);
    assert_eq!(record.samples[1].digital, [true]);
}

#[test]
fn a_leap_second_and_nanoseconds() {
    let mut record = small_record(Revision::R2013, DataFormat::Binary);
    let cfg = record
        .write_cfg()
        .unwrap()
        .replace("12:00:00.252000", "23:59:60.500000123")
        .replace("\r\n+1,x\r\nA,0", "\r\n-5h30,+1\r\nf,3");
    let read = Record::read(&cfg, &record.write_dat().unwrap()).unwrap();
    assert_eq!(read.trigger.format("%H:%M:%S").to_string(), "23:59:60");
    assert_eq!(read.time_code, "-5h30");
    assert_eq!(read.local_code, "+1");
    assert_eq!(read.time_quality, 0xF);
    assert_eq!(read.leap_second, LeapSecond::Unknown);
    // Written back with microseconds; the leap second stays second 60.
    record.trigger = read.trigger;
    assert!(record
        .write_cfg()
        .unwrap()
        .contains("01/03/2024,23:59:60.500000\r\n"));
}

fn cfg_error(cfg: &str, dat: &[u8]) -> (usize, Problem) {
    match Record::read(cfg, dat) {
        Err(ReadError::Cfg { line, problem }) => (line, problem),
        other => panic!("expected a .cfg error, got {other:?}"),
    }
}

fn valid() -> (String, Vec<u8>) {
    let record = small_record(Revision::R2013, DataFormat::Ascii);
    (record.write_cfg().unwrap(), record.write_dat().unwrap())
}

#[test]
fn cfg_errors_name_their_line() {
    let (cfg, dat) = valid();
    let (line, problem) = cfg_error(&cfg.replace(",A,4,0,", ",A,four,0,"), &dat);
    assert_eq!(line, 3);
    assert_eq!(
        problem,
        Problem::Invalid {
            field: "a",
            value: "four".to_owned(),
            expected: "a number"
        }
    );
    let error = Record::read(&cfg.replace(",A,4,0,", ",A,four,0,"), &dat).unwrap_err();
    assert_eq!(
        error.to_string(),
        ".cfg line 3: a: \"four\" is not a number"
    );

    let (line, problem) = cfg_error(&cfg.replace("2,CB closed,,Q0,1", "2,CB closed,Q0,1"), &dat);
    assert_eq!(line, 6);
    assert_eq!(
        problem,
        Problem::FieldCount {
            what: "status channel",
            expected: 5,
            found: 4
        }
    );

    let (line, problem) = cfg_error(&cfg.replace(",2013\r\n", ",1991\r\n"), &dat);
    assert_eq!((line, problem), (1, Problem::Revision("1991".to_owned())));
    let (line, problem) = cfg_error(&cfg.replace(",2013\r\n", "\r\n"), &dat);
    assert_eq!((line, problem), (1, Problem::Revision("1991".to_owned())));

    let (line, problem) = cfg_error(&cfg.replace("4,2A,2D", "5,2A,2D"), &dat);
    assert_eq!(line, 2);
    assert!(matches!(problem, Problem::ChannelTotal { total: 5, .. }));

    let (line, problem) = cfg_error(&cfg.replace("\r\nASCII\r\n", "\r\nFLOAT32\r\n"), &dat);
    assert_eq!(
        (line, problem),
        (12, Problem::FileType("FLOAT32".to_owned()))
    );

    let (line, problem) = cfg_error(
        &cfg.replace("01/03/2024,12:00:00.252", "31/02/2024,12:00:00.252"),
        &dat,
    );
    assert_eq!(line, 11);
    assert!(matches!(
        problem,
        Problem::Invalid {
            field: "trigger",
            ..
        }
    ));

    let (line, problem) = cfg_error(&cfg.replace("\r\nA,0\r\n", "\r\nA,4\r\n"), &dat);
    assert_eq!(line, 15);
    assert!(matches!(
        problem,
        Problem::Invalid {
            field: "leapsec",
            ..
        }
    ));
}

#[test]
fn binary32_is_not_a_1999_format() {
    let record = small_record(Revision::R2013, DataFormat::Binary32);
    let cfg = record
        .write_cfg()
        .unwrap()
        .replace(",2013\r\n", ",1999\r\n");
    let (line, problem) = cfg_error(&cfg, &record.write_dat().unwrap());
    assert_eq!(
        (line, problem),
        (12, Problem::FileType("BINARY32".to_owned()))
    );
}

#[test]
fn a_truncated_cfg_says_what_is_missing() {
    let (cfg, dat) = valid();
    let cut: String = cfg.split_inclusive("\r\n").take(8).collect();
    let (line, problem) = cfg_error(&cut, &dat);
    assert_eq!((line, problem), (9, Problem::Missing("samp,endsamp")));
    let (line, problem) = cfg_error("", &dat);
    assert_eq!(
        (line, problem),
        (1, Problem::Missing("station_name,rec_dev_id,rev_year"))
    );
}

#[test]
fn ascii_dat_errors_name_their_line() {
    let (cfg, dat) = valid();
    let dat = String::from_utf8(dat).unwrap();
    let error = Record::read(
        &cfg,
        dat.replace("2,1000,141,,1,1", "2,1000,141,,1,2").as_bytes(),
    )
    .unwrap_err();
    assert!(matches!(error, ReadError::Dat { line: 2, .. }), "{error:?}");
    assert_eq!(
        error.to_string(),
        ".dat line 2: status value: \"2\" is not 0 or 1"
    );
    let error = Record::read(
        &cfg,
        dat.replace("3,2000,-141,-1000,1,0", "3,2000,-141,1,0")
            .as_bytes(),
    )
    .unwrap_err();
    assert!(matches!(
        error,
        ReadError::Dat {
            line: 3,
            problem: Problem::FieldCount {
                expected: 6,
                found: 5,
                ..
            }
        }
    ));
    let mut bytes = dat.into_bytes();
    bytes[0] = 0xFF;
    assert!(matches!(
        Record::read(&cfg, &bytes),
        Err(ReadError::Dat {
            line: 1,
            problem: Problem::NotText
        })
    ));
}

#[test]
fn the_sample_count_must_match() {
    let (cfg, dat) = valid();
    let dat = String::from_utf8(dat).unwrap();
    let two: String = dat.split_inclusive("\r\n").take(2).collect();
    let error = Record::read(&cfg, two.as_bytes()).unwrap_err();
    assert!(matches!(
        error,
        ReadError::SampleCount {
            declared: 3,
            found: 2
        }
    ));
    assert_eq!(
        error.to_string(),
        ".dat holds 2 samples, the .cfg declares 3"
    );
}

#[test]
fn binary_dat_of_partial_samples() {
    let record = small_record(Revision::R1999, DataFormat::Binary);
    let cfg = record.write_cfg().unwrap();
    let mut dat = record.write_dat().unwrap();
    dat.pop();
    let error = Record::read(&cfg, &dat).unwrap_err();
    assert!(matches!(
        error,
        ReadError::BinaryLength {
            length: 41,
            sample_size: 14
        }
    ));
}

#[test]
fn huge_channel_counts_read_nothing_unreasonable() {
    let cfg = "s,d,1999\r\n1999998,999999A,999999D\r\n";
    assert!(matches!(
        Record::read(cfg, &[]),
        Err(ReadError::Cfg {
            line: 3,
            problem: Problem::Missing("analog channel")
        })
    ));
    let cfg = "s,d,1999\r\n2000000,1000000A,1000000D\r\n";
    assert!(matches!(
        Record::read(cfg, &[]),
        Err(ReadError::Cfg { line: 2, .. })
    ));
}

#[test]
fn long_bad_fields_are_shortened_in_errors() {
    let (cfg, dat) = valid();
    let long = "9".repeat(500);
    let error = Record::read(
        &cfg.replace("\r\n50\r\n", &format!("\r\n5{long}x\r\n")),
        &dat,
    )
    .unwrap_err();
    let text = error.to_string();
    assert!(text.len() < 120, "{text}");
    assert!(text.contains('…'), "{text}");
}
