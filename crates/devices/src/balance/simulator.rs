//! The balance without a line: the Sartorius 1612MP8 of the sorting-lab thesis
//! with its measured behaviour (sections 6.1, 12.3 and 13), sans-IO on the caller's
//! clock, sending a record 3 times a second (automatic output of unstable values).
//!
//! - **A ball on the pan** never reads stable (friction against the walls and the gate).
//!   Its reading settles within about a second of landing, then scatters as the thesis
//!   measured: each weighing draws its 3-s error from the ball's 3-s standard deviation
//!   and its 15-s error from the 15-s one (the balance keeps re-zeroing and jumps), and
//!   the reading moves from the first to the second between 3 s and 15 s. Consecutive
//!   records differ by a few tenths of a milligram.
//! - **An empty pan** reads zero (plus dust) and turns stable 5-10 s after the ball left.
//! - **Tare** (the relay on the Tare key) zeroes the balance, only when stable.
//! - **The blower** disturbs the balance for 30 s after it stops (air flow): readings
//!   scatter by 20 mg and are never stable.
//! - **Dust** settles at a configurable rate (grams a minute).
//!
//! The eight balls of table 5.1 are [`BALLS`], with the 3-s sample statistics of section
//! 12.3 and the 15-s ones back-computed from their printed intervals.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use rand::rngs::StdRng;
use rand::{RngExt as _, SeedableRng as _};
use serial_line::{LineEndpoint, LineSettings};

use super::reader::BALANCE_LINE;
use super::record::{format, Reading};

/// A ball of the thesis's set: its mean reading and scatter at 3 s and at 15 s after
/// landing (grams).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ball {
    /// Its name in the thesis (`red 1`).
    pub name: &'static str,
    /// Mean of the readings 3 s after landing.
    pub mean_3s: f64,
    /// Sample standard deviation at 3 s.
    pub sd_3s: f64,
    /// Mean at 15 s (the midpoint of the printed 99 % interval).
    pub mean_15s: f64,
    /// Sample standard deviation at 15 s (the printed upper bound of sigma over 1.6936,
    /// the factor of section 12.2 for n = 16 at 99 %).
    pub sd_15s: f64,
}

/// The eight balls of table 5.1.
pub const BALLS: [Ball; 8] = [
    Ball {
        name: "red 1",
        mean_3s: 2.290,
        sd_3s: 0.068,
        mean_15s: 2.340,
        sd_15s: 0.124,
    },
    Ball {
        name: "red 2",
        mean_3s: 2.295,
        sd_3s: 0.048,
        mean_15s: 2.325,
        sd_15s: 0.065,
    },
    Ball {
        name: "yellow 1",
        mean_3s: 2.665,
        sd_3s: 0.048,
        mean_15s: 2.745,
        sd_15s: 0.071,
    },
    Ball {
        name: "yellow 2",
        mean_3s: 2.660,
        sd_3s: 0.054,
        mean_15s: 2.680,
        sd_15s: 0.094,
    },
    Ball {
        name: "blue 1",
        mean_3s: 3.090,
        sd_3s: 0.027,
        mean_15s: 3.120,
        sd_15s: 0.065,
    },
    Ball {
        name: "blue 2",
        mean_3s: 3.105,
        sd_3s: 0.048,
        mean_15s: 3.130,
        sd_15s: 0.053,
    },
    Ball {
        name: "green 1",
        mean_3s: 3.520,
        sd_3s: 0.068,
        mean_15s: 3.575,
        sd_15s: 0.118,
    },
    Ball {
        name: "green 2",
        mean_3s: 3.615,
        sd_3s: 0.048,
        mean_15s: 3.630,
        sd_15s: 0.100,
    },
];

/// The ball called `name` (any case).
pub fn ball(name: &str) -> Option<Ball> {
    BALLS
        .iter()
        .find(|ball| ball.name.eq_ignore_ascii_case(name.trim()))
        .copied()
}

/// How the simulated balance behaves.
#[derive(Debug, Clone, PartialEq)]
pub struct BalanceConfig {
    /// Records a second (the thesis's balance sent 2-4).
    pub records_per_second: f64,
    /// Seed of the weighing errors.
    pub seed: u64,
    /// Dust settling on the pan, grams a minute (0: none).
    pub dust_g_per_min: f64,
    /// The line (1200 Bd, read as 8N1).
    pub line: LineSettings,
}

impl Default for BalanceConfig {
    fn default() -> BalanceConfig {
        BalanceConfig {
            records_per_second: 3.0,
            seed: 0,
            dust_g_per_min: 0.0,
            line: BALANCE_LINE,
        }
    }
}

/// How long the air of the blower disturbs the balance after it stops.
pub const BLOWER_DISTURBANCE: Duration = Duration::from_secs(30);

#[derive(Debug, Clone, Copy)]
enum Pan {
    Empty {
        /// When the reading turns stable.
        stable_from: Instant,
    },
    Ball {
        ball: Ball,
        landed: Instant,
        /// This weighing's errors at 3 s and at 15 s.
        error_3s: f64,
        error_15s: f64,
    },
}

/// What the simulator reports besides its records.
#[derive(Debug, Clone, PartialEq)]
pub enum BalanceEvent {
    /// A record went out.
    Sent(Reading),
}

/// Why a tare was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("the balance zeroes only on a stable reading (the pan must be empty and settled)")]
pub struct TareRefused;

/// A simulated balance.
#[derive(Debug)]
pub struct BalanceSimulator {
    config: BalanceConfig,
    rng: StdRng,
    pan: Pan,
    zero: f64,
    started: Instant,
    next_record: Instant,
    blower_until: Option<Instant>,
    events: VecDeque<BalanceEvent>,
}

impl BalanceSimulator {
    /// A balance with an empty, settled pan at `now`.
    pub fn new(config: BalanceConfig, now: Instant) -> BalanceSimulator {
        let rng = StdRng::seed_from_u64(config.seed);
        BalanceSimulator {
            rng,
            pan: Pan::Empty { stable_from: now },
            zero: 0.0,
            started: now,
            next_record: now,
            blower_until: None,
            events: VecDeque::new(),
            config,
        }
    }

    /// A normal deviate (Box-Muller: two uniforms, no distribution crate for one line).
    fn normal(&mut self, sd: f64) -> f64 {
        let u1: f64 = self.rng.random_range(f64::EPSILON..1.0);
        let u2: f64 = self.rng.random();
        sd * (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }

    /// A ball lands on the pan.
    pub fn put(&mut self, ball: Ball, now: Instant) {
        let error_3s = self.normal(ball.sd_3s);
        let error_15s = self.normal(ball.sd_15s);
        self.pan = Pan::Ball {
            ball,
            landed: now,
            error_3s,
            error_15s,
        };
    }

    /// The ball leaves the pan; the reading is stable again 5-10 s later.
    pub fn remove(&mut self, now: Instant) {
        let settle = Duration::from_secs_f64(self.rng.random_range(5.0..=10.0));
        self.pan = Pan::Empty {
            stable_from: now + settle,
        };
    }

    /// The blower stopped: 30 s of disturbed readings.
    pub fn blower_stopped(&mut self, now: Instant) {
        self.blower_until = Some(now + BLOWER_DISTURBANCE);
    }

    /// The Tare key: zeroes on a stable reading only.
    pub fn tare(&mut self, now: Instant) -> Result<(), TareRefused> {
        if !self.stable(now) {
            return Err(TareRefused);
        }
        self.zero = self.load(now);
        Ok(())
    }

    /// Sets the dust rate (grams a minute).
    pub fn set_dust(&mut self, g_per_min: f64) {
        self.config.dust_g_per_min = g_per_min.max(0.0);
    }

    /// The ball on the pan, if any.
    pub fn ball(&self) -> Option<Ball> {
        match self.pan {
            Pan::Ball { ball, .. } => Some(ball),
            Pan::Empty { .. } => None,
        }
    }

    /// The next event.
    pub fn poll_event(&mut self) -> Option<BalanceEvent> {
        self.events.pop_front()
    }

    fn disturbed(&self, now: Instant) -> bool {
        self.blower_until.is_some_and(|until| now < until)
    }

    fn stable(&self, now: Instant) -> bool {
        matches!(self.pan, Pan::Empty { stable_from } if now >= stable_from) && !self.disturbed(now)
    }

    /// The load on the pan without the zero, the scatter of the records or the blower.
    fn load(&self, now: Instant) -> f64 {
        let dust = self.config.dust_g_per_min
            * now.saturating_duration_since(self.started).as_secs_f64()
            / 60.0;
        let ball = match self.pan {
            Pan::Empty { .. } => 0.0,
            Pan::Ball {
                ball,
                landed,
                error_3s,
                error_15s,
            } => {
                let t = now.saturating_duration_since(landed).as_secs_f64();
                let at_3s = ball.mean_3s + error_3s;
                let at_15s = ball.mean_15s + error_15s;
                if t < 1.0 {
                    // landing: the reading rises to the load with some overshoot
                    at_3s * (1.0 - (-t / 0.2).exp() * (t * 12.0).cos())
                } else {
                    let drift = ((t - 3.0) / 12.0).clamp(0.0, 1.0);
                    at_3s + (at_15s - at_3s) * drift
                }
            }
        };
        dust + ball
    }

    /// What the balance shows at `now`.
    pub fn reading(&mut self, now: Instant) -> Reading {
        let stable = self.stable(now);
        let mut weight = self.load(now) - self.zero;
        if !stable {
            // the last digits of an unstable reading wander
            weight += self.normal(0.0003);
        }
        if self.disturbed(now) {
            weight += self.normal(0.02);
        }
        Reading {
            weight_g: (weight * 1000.0).round() / 1000.0,
            stable,
        }
    }
}

impl LineEndpoint for BalanceSimulator {
    fn handle_bytes(&mut self, _now: Instant, _bytes: &[u8]) {
        // The balance's RxD is not connected.
    }

    fn handle_line_pause(&mut self, _now: Instant) {}

    fn handle_timeout(&mut self, _now: Instant) {}

    fn poll_transmit(&mut self, now: Instant) -> Option<Vec<u8>> {
        if now < self.next_record {
            return None;
        }
        let period = Duration::from_secs_f64(1.0 / self.config.records_per_second.clamp(0.1, 10.0));
        // After a pause of the caller, send one record, not the backlog.
        self.next_record = (self.next_record + period).max(now);
        let reading = self.reading(now);
        self.events.push_back(BalanceEvent::Sent(reading));
        Some(format(reading.weight_g, reading.stable).to_vec())
    }

    fn next_deadline(&self) -> Option<Instant> {
        Some(self.next_record)
    }

    fn line(&self) -> LineSettings {
        self.config.line
    }
}

/// The simulator's console (one operation a line).
pub const HELP: &str =
    "  ball NAME|GRAMS     a ball lands on the pan (red 1 .. green 2 of table 5.1, or a mass)
  remove              the ball leaves the pan (stable again 5-10 s later)
  blower              the blower stopped: 30 s of disturbed readings
  tare                the Tare key (refused unless stable)
  dust G_PER_MIN      dust settling on the pan
  status              what is on the pan";

/// Runs a console operation at `now`; what happened, or why not.
pub fn operate(balance: &mut BalanceSimulator, now: Instant, line: &str) -> Result<String, String> {
    let words: Vec<&str> = line.split_whitespace().collect();
    match words.as_slice() {
        ["ball", rest @ ..] if !rest.is_empty() => {
            let name = rest.join(" ");
            let chosen = match ball(&name) {
                Some(ball) => ball,
                None => match name.parse::<f64>() {
                    Ok(mass) if mass.is_finite() && (0.0..=160.0).contains(&mass) => Ball {
                        name: "custom",
                        mean_3s: mass,
                        sd_3s: 0.0,
                        mean_15s: mass,
                        sd_15s: 0.0,
                    },
                    _ => {
                        let names: Vec<&str> = BALLS.iter().map(|b| b.name).collect();
                        return Err(format!(
                            "no ball `{name}`: name one of {} or give a mass in grams (0-160)",
                            names.join(", ")
                        ));
                    }
                },
            };
            balance.put(chosen, now);
            Ok(format!("{} on the pan", chosen.name))
        }
        ["remove"] => {
            balance.remove(now);
            Ok("the pan is empty".into())
        }
        ["blower"] => {
            balance.blower_stopped(now);
            Ok("the blower stopped: disturbed for 30 s".into())
        }
        ["tare"] => balance
            .tare(now)
            .map(|()| "zeroed".to_owned())
            .map_err(|refused| refused.to_string()),
        ["dust", rate] => match rate.parse::<f64>() {
            Ok(rate) if rate.is_finite() && rate >= 0.0 => {
                balance.set_dust(rate);
                Ok(format!("dust at {rate} g/min"))
            }
            _ => Err(format!("`{rate}` is no rate in grams a minute")),
        },
        ["status"] => {
            let reading = balance.reading(now);
            Ok(match balance.ball() {
                Some(ball) => format!("{} on the pan, reading {reading}", ball.name),
                None => format!("empty pan, reading {reading}"),
            })
        }
        _ => Err(format!(
            "unknown operation `{line}`; the operations:\n{HELP}"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::super::reader::{BalanceReader, ReaderEvent};
    use super::*;

    fn sample_at(seconds: f64, ball: Ball, seed: u64) -> f64 {
        let t0 = tokio::time::Instant::now().into_std();
        let mut balance = BalanceSimulator::new(
            BalanceConfig {
                seed,
                ..BalanceConfig::default()
            },
            t0,
        );
        balance.put(ball, t0);
        balance
            .reading(t0 + Duration::from_secs_f64(seconds))
            .weight_g
    }

    fn mean_sd(samples: &[f64]) -> (f64, f64) {
        let n = samples.len() as f64;
        let mean = samples.iter().sum::<f64>() / n;
        let var = samples.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
        (mean, var.sqrt())
    }

    #[test]
    fn weighings_scatter_as_the_thesis_measured() {
        for ball in BALLS {
            let at_3s: Vec<f64> = (0..2000).map(|seed| sample_at(3.0, ball, seed)).collect();
            let at_15s: Vec<f64> = (0..2000).map(|seed| sample_at(15.0, ball, seed)).collect();
            let (mean, sd) = mean_sd(&at_3s);
            assert!((mean - ball.mean_3s).abs() < 0.01, "{} {mean}", ball.name);
            assert!((sd - ball.sd_3s).abs() < 0.01, "{} {sd}", ball.name);
            let (mean, sd) = mean_sd(&at_15s);
            assert!((mean - ball.mean_15s).abs() < 0.01, "{} {mean}", ball.name);
            assert!((sd - ball.sd_15s).abs() < 0.01, "{} {sd}", ball.name);
        }
    }

    #[test]
    fn never_stable_with_a_ball_stable_5_to_10_s_after_and_tare_only_then() {
        let t0 = tokio::time::Instant::now().into_std();
        let mut balance = BalanceSimulator::new(BalanceConfig::default(), t0);
        assert!(balance.reading(t0).stable);
        let blue = ball("blue 1").unwrap();
        balance.put(blue, t0);
        for s in 0..300 {
            assert!(!balance.reading(t0 + Duration::from_secs(s)).stable);
        }
        assert_eq!(balance.tare(t0 + Duration::from_secs(10)), Err(TareRefused));
        let off = t0 + Duration::from_secs(300);
        balance.remove(off);
        assert!(!balance.reading(off + Duration::from_secs(4)).stable);
        assert!(balance.reading(off + Duration::from_secs(10)).stable);
        assert_eq!(balance.tare(off + Duration::from_secs(10)), Ok(()));
        // the blower's air: 30 s unstable
        let blown = off + Duration::from_secs(20);
        balance.blower_stopped(blown);
        assert!(!balance.reading(blown + Duration::from_secs(29)).stable);
        assert!(balance.reading(blown + Duration::from_secs(30)).stable);
    }

    #[test]
    fn dust_settles_and_tare_takes_it_away() {
        let t0 = tokio::time::Instant::now().into_std();
        let mut balance = BalanceSimulator::new(
            BalanceConfig {
                dust_g_per_min: 0.001,
                ..BalanceConfig::default()
            },
            t0,
        );
        let later = t0 + Duration::from_secs(600);
        assert_eq!(balance.reading(later).weight_g, 0.010);
        balance.tare(later).unwrap();
        assert_eq!(balance.reading(later).weight_g, 0.0);
    }

    #[test]
    fn records_three_a_second_read_back_by_the_reader() {
        let t0 = tokio::time::Instant::now().into_std();
        let mut balance = BalanceSimulator::new(BalanceConfig::default(), t0);
        let mut reader = BalanceReader::new(BALANCE_LINE, t0);
        balance.put(ball("green 2").unwrap(), t0);
        let mut sent = 0;
        let mut now = t0;
        // records at 0, 1/3, 2/3 ... s: 30 of them before 9.9 s
        while now < t0 + Duration::from_millis(9_900) {
            if let Some(bytes) = balance.poll_transmit(now) {
                reader.handle_bytes(now, &bytes);
                sent += 1;
            }
            now = balance.next_deadline().unwrap();
        }
        assert_eq!(sent, 30);
        let readings: Vec<Reading> = std::iter::from_fn(|| reader.poll_event())
            .filter_map(|e| match e {
                ReaderEvent::Record(r) => Some(r),
                _ => None,
            })
            .collect();
        assert_eq!(readings.len(), 30);
        let last = readings.last().unwrap();
        assert!(
            (last.weight_g - 3.62).abs() < 0.3 && !last.stable,
            "{last:?}"
        );
    }

    #[test]
    fn the_console() {
        let t0 = tokio::time::Instant::now().into_std();
        let mut balance = BalanceSimulator::new(BalanceConfig::default(), t0);
        assert_eq!(
            operate(&mut balance, t0, "ball Red 1"),
            Ok("red 1 on the pan".into())
        );
        assert!(operate(&mut balance, t0, "ball 2.5").is_ok());
        assert!(operate(&mut balance, t0, "ball purple")
            .unwrap_err()
            .contains("red 1, red 2"));
        assert!(operate(&mut balance, t0, "tare")
            .unwrap_err()
            .contains("stable"));
        assert!(operate(&mut balance, t0, "fly")
            .unwrap_err()
            .contains("ball NAME|GRAMS"));
    }
}
