//! How well the sorter sorts: many seeded weighings of the thesis's eight balls on the
//! simulated balance (`devices::balance::simulator`, the scatter of table 5.1), each
//! classified as FC1 does, counted in a confusion matrix (true colour x decided colour).
//!
//! Each sorting is one ball landing on the pan and read after `weigh_after` (3 s, the
//! thesis's choice); the balls take turns, so every ball is weighed as often. The
//! mechanism does not change the weight a ball shows, so the classification's
//! reliability is the sorter's, routing faults aside.

use std::time::Duration;

use devices::balance::simulator::{BalanceConfig, BalanceSimulator, BALLS};
use serde::Serialize;

use crate::classify::{ClassLimits, Colour};

/// A confusion matrix: `counts[true][decided]`, decided 0 = none, 1-4 the colours.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Confusion {
    /// Rows: red, yellow, blue, green; columns: none, red, yellow, blue, green.
    pub counts: [[u64; 5]; 4],
}

impl Confusion {
    /// Sortings in all.
    pub fn total(&self) -> u64 {
        self.counts.iter().flatten().sum()
    }

    /// Sortings into the right shaft.
    pub fn correct(&self) -> u64 {
        Colour::ALL
            .iter()
            .enumerate()
            .map(|(row, colour)| {
                self.counts
                    .get(row)
                    .and_then(|r| r.get(usize::from(colour.code())))
                    .copied()
                    .unwrap_or(0)
            })
            .sum()
    }

    /// The share sorted right, 0..=1.
    pub fn reliability(&self) -> f64 {
        let total = self.total();
        if total == 0 {
            0.0
        } else {
            self.correct() as f64 / total as f64
        }
    }

    /// The share of `colour`'s balls sorted right.
    pub fn reliability_of(&self, colour: Colour) -> f64 {
        let Some(row) = self.counts.get(usize::from(colour.code()) - 1) else {
            return 0.0;
        };
        let total: u64 = row.iter().sum();
        let right = row.get(usize::from(colour.code())).copied().unwrap_or(0);
        if total == 0 {
            0.0
        } else {
            right as f64 / total as f64
        }
    }

    /// The matrix as a table for a terminal.
    pub fn table(&self) -> String {
        let mut out = String::from("true \\ decided   none    red  yellow   blue  green   right\n");
        for colour in Colour::ALL {
            let row = self
                .counts
                .get(usize::from(colour.code()) - 1)
                .copied()
                .unwrap_or_default();
            out.push_str(&format!(
                "{:<14} {:>6} {:>6} {:>7} {:>6} {:>6} {:>6.1} %\n",
                colour.name(),
                row[0],
                row[1],
                row[2],
                row[3],
                row[4],
                100.0 * self.reliability_of(colour)
            ));
        }
        out.push_str(&format!(
            "{} sortings, {} right: {:.2} %\n",
            self.total(),
            self.correct(),
            100.0 * self.reliability()
        ));
        out
    }
}

/// Sorts `sortings` balls (the eight in turn) weighed `weigh_after` after landing, the
/// balance seeded from `seed` onwards, classified by `limits`.
pub fn simulate(
    sortings: u64,
    seed: u64,
    weigh_after: Duration,
    limits: &ClassLimits,
) -> Confusion {
    let mut counts = [[0u64; 5]; 4];
    for n in 0..sortings {
        let Some(ball) = BALLS.get(usize::try_from(n % 8).unwrap_or(0)) else {
            continue;
        };
        let Some(colour) = Colour::of_ball(ball.name) else {
            continue;
        };
        // Only a base for the simulated balance's own times (landing, reading), never
        // compared with the host's clock.
        #[allow(clippy::disallowed_methods)]
        let t0 = std::time::Instant::now();
        let mut balance = BalanceSimulator::new(
            BalanceConfig {
                seed: seed.wrapping_add(n),
                ..BalanceConfig::default()
            },
            t0,
        );
        balance.put(*ball, t0);
        let weight = balance.reading(t0 + weigh_after).weight_g;
        let decided = limits.classify(weight).map_or(0, |c| usize::from(c.code()));
        if let Some(cell) = counts
            .get_mut(usize::from(colour.code()) - 1)
            .and_then(|row| row.get_mut(decided))
        {
            *cell += 1;
        }
    }
    Confusion { counts }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_thousand_sortings_beat_the_theses_ninety_percent() {
        let confusion = simulate(1000, 1, Duration::from_secs(3), &ClassLimits::DEFAULT);
        assert_eq!(confusion.total(), 1000);
        let reliability = confusion.reliability();
        assert!(reliability > 0.95, "{}", confusion.table());
        // ... and not 100 %: neighbouring colours overlap (section 12.4)
        let printed = simulate(8000, 1, Duration::from_secs(3), &ClassLimits::Printed);
        assert!(printed.reliability() < 1.0, "{}", printed.table());
    }

    #[test]
    fn the_same_seed_sorts_the_same() {
        let a = simulate(200, 7, Duration::from_secs(3), &ClassLimits::DEFAULT);
        let b = simulate(200, 7, Duration::from_secs(3), &ClassLimits::DEFAULT);
        assert_eq!(a, b);
    }
}
