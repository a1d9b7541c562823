//! The sky model: calendar arithmetic and sunrise/sunset over Vsetín.

use plant::sun::{civil_from_days, day_of_year, days_from_civil, Sky, SunConfig};

#[test]
fn calendar_vectors() {
    assert_eq!(civil_from_days(0), (1970, 1, 1));
    assert_eq!(civil_from_days(19_723), (2024, 1, 1));
    assert_eq!(civil_from_days(-1), (1969, 12, 31));
    assert_eq!(days_from_civil(2000, 2, 29), 11_016);
    // Spec §4.5 day-of-year vectors.
    for (y, m, d, n) in [
        (2024, 1, 1, 1),
        (2023, 3, 1, 60),
        (2024, 3, 1, 61),
        (2024, 6, 21, 173),
        (2023, 7, 15, 196),
        (2023, 12, 31, 365),
        (2024, 12, 31, 366),
    ] {
        assert_eq!(day_of_year(days_from_civil(y, m, d)), n, "{y}-{m}-{d}");
    }
    for z in -800_000..800_000 {
        let (y, m, d) = civil_from_days(z);
        assert_eq!(days_from_civil(y, m, d), z);
    }
}

fn hm(ns: i128, day: i64) -> f64 {
    (ns - i128::from(day) * 86_400 * 1_000_000_000) as f64 / 3.6e12
}

#[test]
fn sunrise_sunset_over_vsetin() {
    let sky = Sky::new(SunConfig::default());
    // Physical invariants rather than remembered tables: solar noon sits at
    // 12:00 − 4 min per degree of longitude (10:48 UTC) within the equation of time
    // (±16.5 min); the longest day at 49.3° N is about 16 h 10 min, the shortest about
    // 8 h 15 min, and the equinox days (with refraction) a few minutes over 12 h.
    let mut longest = (0.0, 0);
    let mut shortest = (24.0, 0);
    for day in days_from_civil(2024, 1, 1)..days_from_civil(2025, 1, 1) {
        let (r, s) = sky.sunrise_sunset(day);
        let noon = (hm(r, day) + hm(s, day)) / 2.0;
        assert!((noon - 10.8).abs() < 16.6 / 60.0, "noon {noon}");
        let len = hm(s, day) - hm(r, day);
        if len > longest.0 {
            longest = (len, day_of_year(day));
        }
        if len < shortest.0 {
            shortest = (len, day_of_year(day));
        }
    }
    assert!(
        (16.0..16.4).contains(&longest.0) && (170..=175).contains(&longest.1),
        "{longest:?}"
    );
    assert!(
        (8.1..8.4).contains(&shortest.0) && (353..=358).contains(&shortest.1),
        "{shortest:?}"
    );
    let eq = days_from_civil(2024, 3, 20);
    let (r, s) = sky.sunrise_sunset(eq);
    assert!((12.0..12.3).contains(&(hm(s, eq) - hm(r, eq))));
    // A 20 lx sensor switches close to the ČSD calendar of spec §4.4, region III, week 1
    // (off 07:35, on 16:20 CET = 06:35, 15:20 UTC).
    let day = days_from_civil(2024, 1, 3);
    let (light, dark) = sky.crossings(day, 20.0);
    assert!(
        (hm(light, day) - 6.0 - 35.0 / 60.0).abs() < 0.4,
        "{}",
        hm(light, day)
    );
    assert!(
        (hm(dark, day) - 15.0 - 20.0 / 60.0).abs() < 0.4,
        "{}",
        hm(dark, day)
    );
    // The illuminance at a crossing is the threshold; dark and next agree with crossings.
    assert!((sky.illuminance(dark) - 20.0).abs() < 1e-6);
    let (is_dark, next) = sky.dark_and_next(dark - 1, 20.0);
    assert!(!is_dark);
    assert_eq!(next, dark);
    let (is_dark, next) = sky.dark_and_next(dark, 20.0);
    assert!(is_dark);
    assert_eq!(next, sky.crossings(day + 1, 20.0).0);
}
