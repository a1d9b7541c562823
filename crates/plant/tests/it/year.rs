//! A whole year of simulated time with the lighting switched daily from the dusk sensors.

use std::time::{Duration, Instant};

use plant::sun::{Sky, SunConfig};
use plant::{lighting_boards, Plant, VsetinPlant};

use crate::{get, set};

#[test]
fn a_year_of_daily_lighting() {
    let wall = Instant::now();
    let mut p = VsetinPlant::new();
    let boards = lighting_boards();
    let year = Duration::from_secs(366 * 86_400); // 2024 is a leap year
    let mut switch_ons = 0usize;
    let mut on_time = Duration::ZERO;
    let mut on_since: Option<Duration> = None;
    let mut events = 0usize;
    let mut midnight_dark = 0;
    let mut noon_light = 0;
    let mut next_check = Duration::ZERO;
    loop {
        // The stand-in PLC: OvladanyQ := Cidlo on every board, evaluated at every plant event.
        let dark = get(&p, "ROV01_Cidlo");
        for b in &boards {
            assert_eq!(get(&p, &format!("{b}_Cidlo")), dark);
            set(&mut p, &format!("{b}_OvladanyQ"), dark);
        }
        let lit = get(&p, "ROV01_PrRele");
        match (lit, on_since) {
            (true, None) => {
                on_since = Some(p.now());
                switch_ons += 1;
            }
            (false, Some(t)) => {
                on_time += p.now() - t;
                on_since = None;
            }
            _ => {}
        }
        if p.now() >= year {
            break;
        }
        // Daily checks at 00:00 and 12:00 UTC, otherwise jump from event to event.
        let next = p.next_event().unwrap().min(next_check).min(year);
        if next == next_check {
            p.advance_to(next).unwrap();
            let hour = (next.as_secs() / 3600) % 24;
            let dark = get(&p, "ROV01_Cidlo");
            if hour == 0 && dark {
                midnight_dark += 1;
            }
            if hour == 12 && !dark && !get(&p, "ROV01_PrRele") {
                noon_light += 1;
            }
            next_check += Duration::from_secs(12 * 3600);
        } else {
            p.advance_to(next).unwrap();
        }
        events += 1;
    }
    if let Some(t) = on_since {
        on_time += p.now() - t;
    }
    let elapsed = wall.elapsed();
    println!(
        "one simulated year: {events} steps, {switch_ons} switch-ons, {:.0} h lit, in {elapsed:?}",
        on_time.as_secs_f64() / 3600.0
    );
    // Lit at the start (midnight, dark) and once every evening of the 366 days.
    assert_eq!(switch_ons, 367);
    // Every midnight from 2024-01-01 to 2025-01-01 inclusive was dark.
    assert_eq!(midnight_dark, 367);
    assert_eq!(noon_light, 366);
    // Nights (sunset to sunrise) at 49° N total about 4,330 h a year; a 20 lx sensor
    // switches about 29 min after sunset and before sunrise.
    let hours = on_time.as_secs_f64() / 3600.0;
    assert!((3_800.0..4_300.0).contains(&hours), "{hours}");
    // Exactly what the sky model says: the year minus the daylight of each day, less the
    // 80 ms (contactor 30 + relay 50) before each confirmation, plus the 20 ms contactor
    // drop-out after each switch-off command.
    let sky = Sky::new(SunConfig::default());
    let day0 = 1_704_067_200 / 86_400;
    let daylight: i128 = (day0..day0 + 366)
        .map(|d| {
            let (light, dark) = sky.crossings(d, 20.0);
            dark - light
        })
        .sum();
    let expected =
        i128::from(366 * 86_400) * 1_000_000_000 - daylight - 367 * 80_000_000 + 366 * 20_000_000;
    let got = on_time.as_nanos() as i128;
    assert!((got - expected).abs() <= 2, "{got} vs {expected}");
    // The ABB meters integrated exactly the lit time (less contactor/relay delays).
    let kwh = p.real("ROV01_Energie_kWh").unwrap();
    let expected = 2.4 * hours;
    assert!(
        (kwh - expected).abs() < 2.4 * 366.0 * 0.1 / 3600.0 + 1e-6,
        "{kwh} vs {expected}"
    );
    let or = p.real("OR_Energie_kWh").unwrap();
    assert!((or / kwh - 6.0 / 2.4).abs() < 1e-9);
    // Board meters ran all year.
    let rh2 = p.real("RH2_Energie_kWh").unwrap();
    assert!((rh2 - 5.0 * 366.0 * 24.0).abs() < 1e-6, "{rh2}");
    assert!(p.safety_log().is_empty());
}
