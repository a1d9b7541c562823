//! The railway-station lighting function block (spec railway-station.md §4) on a virtual
//! clock: acceptance scenarios L1-L16 and a simulated year with DST changes.

use plc::task::{ClockReading, TaskConfig};
use plc::Plc;

/// The function block, as the Vsetín example project ships it (one copy).
const FB: &str = include_str!("../../../../examples/vsetin/plc/osvetleni.st");
/// The test bench: one instance wired to globals.
const BENCH: &str = include_str!("../programs/railway_lighting.st");
const HOUR: i64 = 3_600_000_000_000;
const SEC: i64 = 1_000_000_000;
const DAY: i64 = 24 * HOUR;

struct Station {
    plc: Plc,
    mono: i64,
}

/// Days since 1970 of a date.
fn days(y: i64, m: u32, d: u32) -> i64 {
    plc::syntax::lexer::days_from_civil(y, m, d)
}

/// Europe/Prague offset for a UTC instant: CEST from the last Sunday of March 01:00 UTC to
/// the last Sunday of October 01:00 UTC.
fn prague_offset(utc: i64) -> i64 {
    let (y, _, _) = plc::syntax::lexer::civil_from_days(utc.div_euclid(DAY));
    let last_sunday = |m: u32| {
        let d31 = days(y, m, 31);
        d31 - ((d31 + 3).rem_euclid(7) + 1) % 7 // back to Sunday (0 = Monday .. 6 = Sunday)
    };
    let start = last_sunday(3) * DAY + HOUR;
    let end = last_sunday(10) * DAY + HOUR;
    if utc >= start && utc < end {
        2 * HOUR
    } else {
        HOUR
    }
}

impl Station {
    fn new() -> Self {
        let (sources, compiled) = crate::support::build_or_fail(
            &[
                ("osvetleni.st".into(), FB.into()),
                ("railway_lighting.st".into(), BENCH.into()),
            ],
            plc::CompileOptions::default(),
        );
        let mut plc = Plc::new(compiled, sources);
        plc.add_task(TaskConfig::cyclic("lighting", 0, &["Main"]))
            .unwrap();
        Station { plc, mono: 0 }
    }
    fn set(&mut self, path: &str, v: &str) {
        self.plc
            .write(path, v)
            .unwrap_or_else(|e| panic!("{path}: {e}"));
    }
    fn get(&self, path: &str) -> String {
        self.plc
            .read_text(path)
            .unwrap_or_else(|e| panic!("{path}: {e}"))
    }
    fn lit(&self) -> bool {
        self.get("Main.tower1.Vystupy.Osv_Zap") == "TRUE"
    }
    /// Runs one cycle at a UTC instant.
    fn at_utc(&mut self, utc: i64) {
        self.mono += SEC;
        let now = ClockReading {
            monotonic_ns: self.mono,
            utc_ns: utc,
            utc_offset_ns: prague_offset(utc),
        };
        let faults = self.plc.run_cycle(now);
        assert!(faults.is_empty(), "{:?}", faults);
    }
    /// Runs one cycle at local winter time `hh:mm:ss` on 2024-01-03 + `day` days.
    fn at(&mut self, day: i64, h: i64, m: i64, s: i64) {
        let local = (days(2024, 1, 3) + day) * DAY + h * HOUR + m * 60 * SEC + s * SEC;
        self.at_utc(local - HOUR);
    }
    fn astral() -> Self {
        let mut st = Station::new();
        st.set("\"DDTS\".W_Astral", "TRUE");
        st
    }
    fn windows(&mut self, z1: &str, v1: &str, z2: &str, v2: &str) {
        self.set("\"DDTS\".W_Cas", "TRUE");
        self.set("\"DDTS\".W_Cas1Zap", z1);
        self.set("\"DDTS\".W_Cas1Vyp", v1);
        self.set("\"DDTS\".W_Cas2Zap", z2);
        self.set("\"DDTS\".W_Cas2Vyp", v2);
        self.set("\"DDTS\".W_SetTime", "TRUE");
    }
}

#[test]
fn l1_l3_astral_switching_is_inclusive() {
    let mut st = Station::astral();
    st.at(0, 12, 0, 0);
    assert_eq!(st.get("Main.tower1.TODSunset"), "TOD#16:20:00");
    assert_eq!(st.get("Main.tower1.TODSunrise"), "TOD#07:35:00");
    st.at(0, 16, 19, 59);
    assert!(!st.lit(), "L1");
    st.at(0, 16, 20, 0);
    assert!(st.lit(), "L2");
    assert_eq!(st.get("\"Contactor\""), "TRUE");
    st.at(1, 7, 35, 0);
    assert!(st.lit(), "L3 at 07:35:00");
    st.at(1, 7, 35, 1);
    assert!(!st.lit(), "L3 at 07:35:01");
}

#[test]
fn l4_l7_dusk_sensor_only_within_an_hour_of_the_calendar() {
    let mut st = Station::new();
    st.set("\"DDTS\".W_Cidlo", "TRUE");
    st.set("\"Cidlo\"", "TRUE");
    st.at(0, 15, 19, 0);
    assert!(!st.lit(), "L4");
    st.at(0, 15, 20, 0);
    assert!(st.lit(), "L5");
    st.at(1, 8, 35, 0);
    assert!(st.lit(), "L6 08:35");
    st.at(1, 8, 36, 0);
    assert!(!st.lit(), "L6 08:36");
    st.set("\"Cidlo\"", "FALSE");
    st.at(1, 20, 0, 0);
    assert!(!st.lit(), "L7");
}

#[test]
fn l8_l10_l15_time_windows_invert_and_cross_midnight() {
    let mut st = Station::astral();
    st.windows(
        "TOD#10:00:00",
        "TOD#11:00:00",
        "TOD#00:00:00",
        "TOD#00:00:00",
    );
    st.at(0, 10, 30, 0);
    assert!(st.lit(), "L8 daytime test lighting");
    assert_eq!(st.get("\"DDTS\".W_SetTime"), "FALSE", "L15 strobe reset");
    assert_eq!(st.get("Main.tower1.Vystupy.Set_Cas1Zap"), "TOD#10:00:00");

    let mut st = Station::astral();
    st.windows(
        "TOD#01:00:00",
        "TOD#04:00:00",
        "TOD#00:00:00",
        "TOD#00:00:00",
    );
    st.at(0, 2, 0, 0);
    assert!(!st.lit(), "L9 night switch-off");

    let mut st = Station::new();
    st.windows(
        "TOD#00:00:00",
        "TOD#00:00:00",
        "TOD#22:00:00",
        "TOD#02:00:00",
    );
    st.at(0, 23, 0, 0);
    assert!(st.lit(), "L10 23:00");
    st.at(1, 1, 0, 0);
    assert!(st.lit(), "L10 01:00");
    st.at(1, 3, 0, 0);
    assert!(!st.lit(), "L10 03:00");
}

#[test]
fn l11_l12_manual_mode() {
    let mut st = Station::new();
    st.set("Main.delay", "T#5s");
    st.set("\"DDTS\".W_Rucne", "TRUE");
    st.set("\"DDTS\".W_ZapRucne", "TRUE");
    st.at(0, 12, 0, 0);
    assert!(st.lit(), "L11 immediately");
    assert_eq!(st.get("Main.tower1.StavBloku.StateOfFB"), "1");
    st.set("\"DDTS\".W_Rucne", "FALSE");
    st.at(0, 12, 0, 1);
    assert!(!st.lit(), "L12");
    assert_eq!(
        st.get("\"DDTS\".W_ZapRucne"),
        "FALSE",
        "L12 request discarded"
    );
}

#[test]
fn l13_switch_on_delay_and_immediate_switch_off() {
    let mut st = Station::astral();
    st.set("Main.delay", "T#5s");
    st.at(0, 16, 19, 59);
    for s in 0..5 {
        st.at(0, 16, 20, s);
        assert!(!st.lit(), "L13 still off at 16:20:0{s}");
    }
    st.at(0, 16, 20, 5);
    assert!(st.lit(), "L13 on at 16:20:05");
    st.at(1, 7, 35, 1);
    assert!(!st.lit(), "L13 switch-off immediate");
}

#[test]
fn l14_circuit_fault_after_preset() {
    let mut st = Station::astral();
    st.set("\"PrRele\"", "FALSE");
    for s in 0..5 {
        st.at(0, 18, 0, s);
        assert_eq!(st.get("Main.tower1.Vystupy.Osv_Por"), "FALSE");
    }
    st.at(0, 18, 0, 5);
    assert_eq!(st.get("Main.tower1.Vystupy.Osv_Por"), "TRUE", "L14");
    st.set("\"PrRele\"", "TRUE");
    st.at(0, 18, 0, 6);
    assert_eq!(
        st.get("Main.tower1.Vystupy.Osv_Por"),
        "FALSE",
        "clears with feedback"
    );
}

#[test]
fn l16_and_a_simulated_year_with_dst() {
    let mut st = Station::astral();
    let start = days(2024, 1, 1) * DAY;
    let mut zone_changes = Vec::new();
    let mut last_zone = String::new();
    for hour in 0..(366 * 24) {
        let utc = start + hour * HOUR;
        st.at_utc(utc);
        let zone = st.get("Main.tower1.TimeZone");
        if zone != last_zone {
            zone_changes.push((plc::vm::format::dt(utc + prague_offset(utc)), zone.clone()));
            last_zone = zone;
        }
        let local_hour = (utc + prague_offset(utc)).rem_euclid(DAY) / HOUR;
        // lit at midnight, dark at noon, every day of the year
        if local_hour == 0 {
            assert!(st.lit(), "dark at {}", plc::vm::format::dt(utc));
        }
        if local_hour == 12 {
            assert!(!st.lit(), "lit at noon {}", plc::vm::format::dt(utc));
        }
    }
    // the offset is adopted at 10:00 local after each DST change (L16)
    assert_eq!(
        zone_changes,
        vec![
            ("DT#2024-01-01-01:00:00".to_string(), "1".to_string()),
            ("DT#2024-03-31-10:00:00".to_string(), "2".to_string()),
            ("DT#2024-10-27-10:00:00".to_string(), "1".to_string()),
        ]
    );
}

#[test]
fn day_of_year_and_week_index_match_the_spec_vectors() {
    // §4.5 test vectors: date -> (N, i)
    let vectors = [
        ((2024, 1, 1), 1, 0),
        ((2023, 1, 3), 3, 0),
        ((2023, 1, 4), 4, 1),
        ((2023, 3, 1), 60, 9),
        ((2024, 3, 1), 61, 9),
        ((2024, 6, 21), 173, 25),
        ((2023, 7, 15), 196, 28),
        ((2023, 12, 31), 365, 52),
        ((2024, 12, 31), 366, 52),
    ];
    for ((y, m, d), n, i) in vectors {
        let mut st = Station::new();
        // first cycle initialises at 12:00 local winter time
        st.at_utc(days(y, m, d) * DAY + 11 * HOUR);
        assert_eq!(st.get("Main.tower1.N"), n.to_string(), "{y}-{m}-{d}");
        assert_eq!(st.get("Main.tower1.i"), i.to_string(), "{y}-{m}-{d}");
    }
}
