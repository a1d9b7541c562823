//! The sorting lab's statistics: deriving the class limits from weighings (the
//! sorting-lab thesis, section 12).
//!
//! Each ball is weighed n times (the thesis: 16 times, the reading taken 3 s after the
//! ball landed). The weighings of a ball are taken as normally distributed; its mean and
//! scatter are estimated with a confidence level, each ball gets a coverage interval
//! (where a given share of its weighings falls even for the least favourable μ and σ
//! within their confidence bounds), a colour the union of its balls' coverage intervals,
//! and the decision limits lie midway between neighbouring colours' unions. The lowest
//! and highest (outer) limits are set by hand (the sorting-lab thesis's note BS-A7:
//! 2.0 and 4.0 g; BS-A8: the lower outer limit is red's).
//!
//! See the crate documentation for the data flow; [`limits::Thresholds::from_samples`]
//! runs all of it.

pub mod estimate;
pub mod limits;
pub mod plot;
pub mod quantile;
pub mod samples;

use std::fmt;

use serde::Serialize;

pub use estimate::{BallStatistics, EstimateError};
pub use limits::{ThresholdConfig, Thresholds, ThresholdsError};
pub use quantile::{Confidence, Coverage, QuantileError};
pub use samples::{BallSamples, Samples, SamplesError};

/// A closed interval ⟨lower, upper⟩ of grams (or of any other quantity).
///
/// Displays as `⟨2.240, 2.340⟩`, with three decimals unless the format asks for a
/// precision (`{:.2}`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Interval {
    /// The lower bound.
    pub lower: f64,
    /// The upper bound.
    pub upper: f64,
}

impl Interval {
    /// ⟨lower, upper⟩; the bounds are taken as given (a caller passing lower > upper gets
    /// an empty interval that contains nothing).
    #[must_use]
    pub const fn new(lower: f64, upper: f64) -> Self {
        Self { lower, upper }
    }

    /// The smallest interval holding both: a colour's union of its balls' intervals
    /// (their union, when they overlap, as the balls of one colour do).
    #[must_use]
    pub fn hull(self, other: Self) -> Self {
        Self {
            lower: self.lower.min(other.lower),
            upper: self.upper.max(other.upper),
        }
    }

    /// The point midway between the bounds.
    #[must_use]
    pub fn midpoint(self) -> f64 {
        (self.lower + self.upper) / 2.0
    }

    /// upper − lower.
    #[must_use]
    pub fn width(self) -> f64 {
        self.upper - self.lower
    }

    /// Whether `value` lies within the bounds (both included).
    #[must_use]
    pub fn contains(self, value: f64) -> bool {
        self.lower <= value && value <= self.upper
    }

    /// The gap from this interval up to `above`: `above.lower − self.upper`; negative
    /// when they overlap (by that much).
    #[must_use]
    pub fn gap_to(self, above: Self) -> f64 {
        above.lower - self.upper
    }
}

impl fmt::Display for Interval {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let decimals = f.precision().unwrap_or(3);
        write!(f, "⟨{:.decimals$}, {:.decimals$}⟩", self.lower, self.upper)
    }
}

/// A probability as a percentage for people: `99 %`, `99.5 %`, `90.25 %` (at most two
/// decimals, trailing zeros dropped).
#[must_use]
pub fn percent(probability: f64) -> String {
    let text = format!("{:.2}", probability * 100.0);
    let text = text.trim_end_matches('0').trim_end_matches('.');
    format!("{text} %")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn intervals_display_hull_and_gap() {
        let red = Interval::new(2.0926, 2.4876);
        let yellow = Interval::new(2.5032, 2.8168);
        assert_eq!(red.to_string(), "⟨2.093, 2.488⟩");
        assert_eq!(format!("{red:.2}"), "⟨2.09, 2.49⟩");
        assert_eq!(red.hull(yellow), Interval::new(2.0926, 2.8168));
        assert!((red.gap_to(yellow) - 0.0156).abs() < 1e-12);
        assert!(yellow.gap_to(red) < 0.0);
        assert!(red.contains(2.0926) && !red.contains(2.49));
        assert!((red.midpoint() - 2.2901).abs() < 1e-12);
    }

    #[test]
    fn percentages_drop_trailing_zeros() {
        assert_eq!(percent(0.99), "99 %");
        assert_eq!(percent(0.995), "99.5 %");
        assert_eq!(percent(0.90251), "90.25 %");
        assert_eq!(percent(1.0), "100 %");
    }
}
