//! The sorting crate's integration tests, one binary: table 5.1 of the sorting-lab
//! thesis reproduced from synthetic weighings, the 95 % reconstruction of its class
//! limits, the 99 % overlap, the blue 2 discrepancy, CSV errors, the plot and the
//! shipped example file; the supervisor's protection blocks on the soft PLC.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod example;
mod plot;
mod rig;
mod samples;
mod supervisor;
mod table51;

use sorting::statistics::estimate::synthetic_weighings;
use sorting::statistics::{BallSamples, Samples};

/// A row of table 5.1 (3-s columns, 99 % confidence) with the sample statistics section
/// 12.3 derives from it.
pub(crate) struct Row {
    pub(crate) ball: &'static str,
    /// X̄, grams (section 12.3's derived table).
    pub(crate) mean: f64,
    /// S, grams (section 12.3's derived table).
    pub(crate) sd: f64,
    /// The printed interval of μ at 3 s.
    pub(crate) mu: (f64, f64),
    /// The printed upper bound of σ at 3 s.
    pub(crate) sigma_upper: f64,
}

/// Table 5.1's 3-s columns and section 12.3's X̄ and S.
#[allow(clippy::approx_constant)] // blue 2's 3.14 g is a weight, not π
#[rustfmt::skip]
pub(crate) const TABLE_5_1: [Row; 8] = [
    //    ball         X̄      S      printed μ interval   printed σ upper
    row("red 1",    2.290, 0.068, (2.24, 2.34), 0.12),
    row("red 2",    2.295, 0.048, (2.26, 2.33), 0.08),
    row("yellow 1", 2.665, 0.048, (2.63, 2.70), 0.08),
    row("yellow 2", 2.660, 0.054, (2.62, 2.70), 0.10),
    row("blue 1",   3.090, 0.027, (3.07, 3.11), 0.05),
    row("blue 2",   3.105, 0.048, (3.07, 3.14), 0.07),
    row("green 1",  3.520, 0.068, (3.47, 3.57), 0.11),
    row("green 2",  3.615, 0.048, (3.58, 3.65), 0.08),
];

const fn row(ball: &'static str, mean: f64, sd: f64, mu: (f64, f64), sigma_upper: f64) -> Row {
    Row {
        ball,
        mean,
        sd,
        mu,
        sigma_upper,
    }
}

/// 16 synthetic 3-s weighings per ball with exactly section 12.3's X̄ and S.
pub(crate) fn thesis_samples() -> Samples {
    Samples::new(
        TABLE_5_1
            .iter()
            .map(|row| {
                BallSamples::new(row.ball, synthetic_weighings(row.mean, row.sd, 16).unwrap())
            })
            .collect(),
    )
}

/// |actual − expected| ≤ tolerance, with both in the message.
#[track_caller]
pub(crate) fn assert_close(what: &str, actual: f64, expected: f64, tolerance: f64) {
    assert!(
        (actual - expected).abs() <= tolerance,
        "{what}: {actual:.4}, expected {expected} ± {tolerance}"
    );
}
