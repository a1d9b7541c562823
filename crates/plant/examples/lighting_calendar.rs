//! Prints a station's weekly lighting calendar as CSV (`week,off_utc,on_utc`), the table the
//! lighting function block reads (railway-station spec 4.4-4.6): one row per week index
//! `i = ROUND(N / 7)` (0..=52), times of day in UTC.
//!
//! Algorithm: sunrise and sunset of day `N = 7 i` (day 1 for week 0) of a common year from
//! the NOAA approximation in `plant::sun` for the site's coordinates; the lamps go off at
//! sunrise and on 20 minutes after sunset, both rounded to 5 minutes as the SŽDC E 11
//! calendar is. For Vsetín this reproduces the E 11 region III excerpt of the spec within a
//! few minutes (week 1: off 07:35, on 16:20 CET in E 11; 07:40 and 16:25 here). The
//! official E 11 table, once available, replaces the generated file as it is.
//!
//! `cargo run -p plant --example lighting_calendar [-- LATITUDE LONGITUDE]`
//! (default: Vsetín railway station, 49.3387 N, 17.9962 E).

use plant::sun::{days_from_civil, Sky, SunConfig};

fn main() {
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let mut config = SunConfig::default();
    if let [latitude, longitude] = args.as_slice() {
        config.latitude = *latitude;
        config.longitude = *longitude;
    }
    let sky = Sky::new(config.clone());
    println!(
        "# weekly lighting calendar, UTC; lat {} lon {}; off = sunrise, on = sunset + 20 min, 5-min steps",
        config.latitude, config.longitude
    );
    println!("week,off_utc,on_utc");
    // 2025 is a common year; the week index is the same every year.
    let first = days_from_civil(2025, 1, 1);
    for week in 0..=52i64 {
        let n = (7 * week).max(1);
        let day = first + n - 1;
        let (rise, set) = sky.sunrise_sunset(day);
        let minutes = |ns: i128, add: i128| {
            let of_day = (ns - i128::from(day) * 86_400_000_000_000) / 60_000_000_000 + add;
            ((of_day + 2) / 5 * 5).rem_euclid(24 * 60)
        };
        let off = minutes(rise, 0);
        let on = minutes(set, 20);
        println!(
            "{week},{:02}:{:02},{:02}:{:02}",
            off / 60,
            off % 60,
            on / 60,
            on % 60
        );
    }
}
