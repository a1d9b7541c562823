//! A deterministic sky: sunrise and sunset from coordinates (NOAA approximation) and a
//! piecewise-linear outdoor illuminance around them, so dusk sensors switch at exact,
//! computable instants.

use std::f64::consts::PI;

const DAY: i64 = 86_400;
const NANOS: i128 = 1_000_000_000;

/// Site and sky parameters.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct SunConfig {
    /// Latitude, degrees north.
    pub latitude: f64,
    /// Longitude, degrees east.
    pub longitude: f64,
    /// Illuminance at sunrise + 30 min / sunset − 30 min, lux. It rises linearly from 0 lx
    /// at sunrise − 30 min (civil twilight) to this value, then to `day_lux` at
    /// sunrise + 2 h (mirrored in the evening).
    pub twilight_lux: f64,
    /// Full daylight, lux.
    pub day_lux: f64,
}

impl Default for SunConfig {
    fn default() -> Self {
        // Vsetín railway station.
        SunConfig {
            latitude: 49.3387,
            longitude: 17.9962,
            twilight_lux: 1_000.0,
            day_lux: 20_000.0,
        }
    }
}

/// Proleptic Gregorian (year, month, day) of a count of days since 1970-01-01.
pub fn civil_from_days(z: i64) -> (i64, u32, u32) {
    let z = z + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let y = yoe + era * 400;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    (if m <= 2 { y + 1 } else { y }, m, d)
}

/// Day of the year, 1-based, of a count of days since 1970-01-01.
pub fn day_of_year(days: i64) -> u32 {
    let (y, _, _) = civil_from_days(days);
    let jan1 = days_from_civil(y, 1, 1);
    (days - jan1 + 1) as u32
}

/// Days since 1970-01-01 of a proleptic Gregorian date.
pub fn days_from_civil(y: i64, m: u32, d: u32) -> i64 {
    let y = if m <= 2 { y - 1 } else { y };
    let era = y.div_euclid(400);
    let yoe = y.rem_euclid(400);
    let m = i64::from(m);
    let mp = if m > 2 { m - 3 } else { m + 9 };
    let doy = (153 * mp + 2) / 5 + i64::from(d) - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    era * 146_097 + doe - 719_468
}

/// The sky over the site.
#[derive(Debug, Clone)]
pub struct Sky {
    cfg: SunConfig,
}

impl Sky {
    /// A sky for the given site.
    pub fn new(cfg: SunConfig) -> Self {
        Sky { cfg }
    }

    /// Sunrise and sunset of a UTC day (days since 1970-01-01) as UTC nanoseconds since
    /// the Unix epoch. Polar day/night clamps to a 24 h / 0 h day.
    pub fn sunrise_sunset(&self, day: i64) -> (i128, i128) {
        let n = f64::from(day_of_year(day));
        let g = 2.0 * PI / 365.0 * (n - 1.0);
        let eqtime = 229.18
            * (0.000075 + 0.001868 * g.cos()
                - 0.032077 * g.sin()
                - 0.014615 * (2.0 * g).cos()
                - 0.040849 * (2.0 * g).sin());
        let decl = 0.006918 - 0.399912 * g.cos() + 0.070257 * g.sin() - 0.006758 * (2.0 * g).cos()
            + 0.000907 * (2.0 * g).sin()
            - 0.002697 * (3.0 * g).cos()
            + 0.00148 * (3.0 * g).sin();
        let lat = self.cfg.latitude.to_radians();
        let cos_ha = (90.833f64.to_radians().cos() / (lat.cos() * decl.cos())
            - lat.tan() * decl.tan())
        .clamp(-1.0, 1.0);
        let ha = cos_ha.acos().to_degrees();
        let rise_min = 720.0 - 4.0 * (self.cfg.longitude + ha) - eqtime;
        let set_min = 720.0 - 4.0 * (self.cfg.longitude - ha) - eqtime;
        let base = i128::from(day * DAY) * NANOS;
        let to_ns = |m: f64| base + (m * 60.0 * 1e9).round() as i128;
        (to_ns(rise_min), to_ns(set_min))
    }

    /// Outdoor illuminance (lux) at a UTC instant (nanoseconds since the Unix epoch).
    pub fn illuminance(&self, unix_ns: i128) -> f64 {
        let day = unix_ns.div_euclid(i128::from(DAY) * NANOS) as i64;
        let (rise, set) = self.sunrise_sunset(day);
        let half = 30 * 60 * NANOS;
        let two_h = 2 * 3600 * NANOS;
        let c = &self.cfg;
        let ramp = |t: i128, t0: i128, v0: f64, t1: i128, v1: f64| {
            let x = (t - t0) as f64 / (t1 - t0).max(1) as f64;
            v0 + (v1 - v0) * x.clamp(0.0, 1.0)
        };
        let t = unix_ns;
        if t <= rise - half || t >= set + half {
            0.0
        } else if t < rise + half {
            ramp(t, rise - half, 0.0, rise + half, c.twilight_lux)
        } else if t > set - half {
            ramp(t, set - half, c.twilight_lux, set + half, 0.0)
        } else if t < rise + two_h {
            ramp(t, rise + half, c.twilight_lux, rise + two_h, c.day_lux)
        } else if t > set - two_h {
            ramp(t, set - two_h, c.day_lux, set - half, c.twilight_lux)
        } else {
            c.day_lux
        }
    }

    /// The instants of a UTC day when the illuminance crosses `threshold` lux, as
    /// (morning: becomes light, evening: becomes dark), UTC nanoseconds. Crossings are
    /// taken on the twilight ramps (threshold clamped into them).
    pub fn crossings(&self, day: i64, threshold: f64) -> (i128, i128) {
        let (rise, set) = self.sunrise_sunset(day);
        let half = 30 * 60 * NANOS;
        let frac = if self.cfg.twilight_lux > 0.0 {
            (threshold / self.cfg.twilight_lux).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let offset = ((2 * half) as f64 * frac).round() as i128;
        (rise - half + offset, set + half - offset)
    }

    /// Whether a dusk sensor with this threshold reports "dark" at `unix_ns`, and the next
    /// instant (strictly later) at which that changes.
    pub fn dark_and_next(&self, unix_ns: i128, threshold: f64) -> (bool, i128) {
        let day = unix_ns.div_euclid(i128::from(DAY) * NANOS) as i64;
        let mut edges: Vec<(i128, bool)> = Vec::with_capacity(6);
        for d in day - 1..=day + 1 {
            let (light, dark) = self.crossings(d, threshold);
            edges.push((light, false));
            edges.push((dark, true));
        }
        edges.sort_by_key(|e| e.0);
        let mut state = true;
        let mut next = unix_ns + i128::from(DAY) * NANOS;
        for (t, becomes_dark) in &edges {
            if *t <= unix_ns {
                state = *becomes_dark;
            } else {
                next = *t;
                break;
            }
        }
        (state, next)
    }
}
