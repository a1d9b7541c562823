//! The files of small records, byte for byte.

use comtrade::{status_column, AnalogChannel, DataFormat, DigitalChannel, Record, Revision};

use crate::{at, small_record};

const CFG_1999: &str = "Substation Vsetin,REF630 F1,1999\r\n\
4,2A,2D\r\n\
1,IL1,1,Line 1,A,4,0,0,-32767,32767,400,1,P\r\n\
2,UL1,1,Line 1,kV,0.01,0,12.5,-32767,32767,110,0.1,S\r\n\
1,Trip,,,0\r\n\
2,CB closed,,Q0,1\r\n\
50\r\n\
1\r\n\
1000,3\r\n\
01/03/2024,12:00:00.250000\r\n\
01/03/2024,12:00:00.252000\r\n\
BINARY\r\n\
1\r\n";

const CFG_2013: &str = "Substation Vsetin,REF630 F1,2013\r\n\
4,2A,2D\r\n\
1,IL1,1,Line 1,A,4,0,0,-32767,32767,400,1,P\r\n\
2,UL1,1,Line 1,kV,0.01,0,12.5,-32767,32767,110,0.1,S\r\n\
1,Trip,,,0\r\n\
2,CB closed,,Q0,1\r\n\
50\r\n\
1\r\n\
1000,3\r\n\
01/03/2024,12:00:00.250000\r\n\
01/03/2024,12:00:00.252000\r\n\
ASCII\r\n\
1\r\n\
+1,x\r\n\
A,0\r\n";

/// Per sample: number, timestamp, IL1, UL1 (0x8000: missing), the status word.
const DAT_BINARY: [u8; 42] = [
    0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xE8, 0x03, 0x02, 0x00, //
    0x02, 0x00, 0x00, 0x00, 0xE8, 0x03, 0x00, 0x00, 0x8D, 0x00, 0x00, 0x80, 0x03, 0x00, //
    0x03, 0x00, 0x00, 0x00, 0xD0, 0x07, 0x00, 0x00, 0x73, 0xFF, 0x18, 0xFC, 0x01, 0x00, //
];

const DAT_ASCII_2013: &str = "1,0,0,1000,0,1\r\n2,1000,141,,1,1\r\n3,2000,-141,-1000,1,0\r\n";

#[test]
fn cfg_of_revision_1999() {
    let record = small_record(Revision::R1999, DataFormat::Binary);
    assert_eq!(record.write_cfg().unwrap(), CFG_1999);
}

#[test]
fn cfg_of_revision_2013() {
    let record = small_record(Revision::R2013, DataFormat::Ascii);
    assert_eq!(record.write_cfg().unwrap(), CFG_2013);
}

#[test]
fn binary_dat_bytes() {
    let record = small_record(Revision::R1999, DataFormat::Binary);
    assert_eq!(record.write_dat().unwrap(), DAT_BINARY);
}

#[test]
fn binary32_dat_bytes() {
    let record = small_record(Revision::R2013, DataFormat::Binary32);
    let dat = record.write_dat().unwrap();
    assert_eq!(dat.len(), 3 * (8 + 2 * 4 + 2));
    // Sample 2: number, timestamp 1000, IL1 141, UL1 missing (0x80000000), status 0b11.
    assert_eq!(
        dat[18..36],
        [
            0x02, 0x00, 0x00, 0x00, 0xE8, 0x03, 0x00, 0x00, 0x8D, 0x00, 0x00, 0x00, 0x00, 0x00,
            0x00, 0x80, 0x03, 0x00
        ]
    );
    assert!(record.write_cfg().unwrap().contains("\r\nBINARY32\r\n"));
}

#[test]
fn ascii_dat_text() {
    let record = small_record(Revision::R2013, DataFormat::Ascii);
    assert_eq!(record.write_dat().unwrap(), DAT_ASCII_2013.as_bytes());
}

/// The record `stanice iec103 master --comtrade 1999` writes today (its own unit test),
/// rebuilt with this crate: the same files, so the master can switch over without its
/// output changing.
#[test]
fn the_stanice_iec103_record_unchanged() {
    let recorded_at = at(9, 59, 30, 424_000);
    let mut record = Record::new("Feeder F1", "REF630 1", recorded_at);
    record.start = recorded_at - chrono::Duration::milliseconds(2);
    record.trigger = recorded_at;
    record.data_format = DataFormat::Ascii;
    let mut il1 = AnalogChannel::from_iec103("IL1", "A", 100.0, 1.0, 100.0);
    il1.phase = "1".to_owned();
    record.analog.push(il1);
    record
        .digital
        .push(DigitalChannel::new("FUN160_INF92", false));
    let sdv: [i16; 4] = [0, 141, -141, 707];
    record.set_columns(
        1000,
        &[sdv.iter().map(|&value| Some(i32::from(value))).collect()],
        &[status_column(false, &[(2, true)], sdv.len())],
    );
    let cfg = record.write_cfg().unwrap();
    let stanice = "Feeder F1,REF630 1,1999\n2,1A,1D\n1,IL1,1,,A,1,0,0,-32767,32767,100,1,P\n1,FUN160_INF92,,,0\n50\n1\n1000,4\n26/04/2017,09:59:30.422000\n26/04/2017,09:59:30.424000\nASCII\n1\n"
        .replace("26/04/2017", "01/03/2024")
        .replace('\n', "\r\n");
    assert_eq!(cfg, stanice);
    assert_eq!(
        record.write_dat().unwrap(),
        b"1,0,0,0\r\n2,1000,141,0\r\n3,2000,-141,1\r\n4,3000,707,1\r\n"
    );
}

#[test]
fn reals_stay_within_their_field() {
    let mut record = small_record(Revision::R1999, DataFormat::Binary);
    record.analog[0].multiplier = 1e-31;
    record.analog[0].offset = -1.5e300;
    record.analog[1].multiplier = 0.1138916015625;
    record.analog[1].offset = 1e-30;
    let cfg = record.write_cfg().unwrap();
    assert!(
        cfg.contains("\r\n1,IL1,1,Line 1,A,1e-31,-1.5e300,0,"),
        "{cfg}"
    );
    assert!(
        cfg.contains(",kV,0.1138916015625,0.000000000000000000000000000001,"),
        "{cfg}"
    );
    let read = Record::read(&cfg, &record.write_dat().unwrap()).unwrap();
    assert_eq!(read, record);
}
