//! One ball's sample statistics and interval estimates (the sorting-lab thesis,
//! section 12.2):
//!
//! - mean `X̄ = (1/n) Σ Xᵢ` (5.1);
//! - sample standard deviation `S = √((1/(n−1)) Σ (Xᵢ − X̄)²)` (5.2);
//! - the two-sided 100(1−α) % confidence interval of μ,
//!   `X̄ ± t_{1−α/2}(n−1)·S/√n` (5.3);
//! - the one-sided upper bound of σ, `σ_upper = S·√((n−1)/χ²_α(n−1))` (5.4), with χ²_α
//!   the lower α-quantile.
//!
//! And, for tests and examples, [`synthetic_weighings`]: n values whose sample mean and S
//! are exactly the ones asked for.

use serde::Serialize;

use super::quantile::{normal_quantile, Confidence, IntervalFactors, QuantileError};
use super::samples::{colour_of, BallSamples};
use super::Interval;

/// Why a ball's statistics could not be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EstimateError {
    /// Fewer than 2 weighings.
    #[error("ball `{ball}` has {count} weighing(s); at least 2 are needed for its scatter")]
    TooFewWeighings {
        /// The ball.
        ball: String,
        /// Its weighings.
        count: usize,
    },
    /// A weighing that is not a finite number.
    #[error("ball `{ball}` has a weighing that is not a number ({value})")]
    NotANumber {
        /// The ball.
        ball: String,
        /// The value.
        value: f64,
    },
    /// A synthetic sample asked for with a negative or non-finite mean or S.
    #[error("a synthetic sample needs a finite mean and S ≥ 0, not {mean_g} and {sd_g}")]
    Synthetic {
        /// The mean asked for.
        mean_g: f64,
        /// The S asked for.
        sd_g: f64,
    },
    /// A quantile could not be computed.
    #[error(transparent)]
    Quantile(#[from] QuantileError),
}

/// A ball's n, X̄, S and the interval estimates of μ and σ at a confidence level.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BallStatistics {
    /// The ball (`red 1`).
    pub ball: String,
    /// Its colour, the name's first word in lower case (`red`).
    pub colour: String,
    /// The number of weighings.
    pub n: usize,
    /// X̄, the sample mean (5.1), grams.
    pub mean_g: f64,
    /// S, the sample standard deviation (5.2), grams.
    pub sd_g: f64,
    /// The confidence level of the two estimates below.
    pub confidence: Confidence,
    /// The quantiles and σ's factor for n at that level.
    pub factors: IntervalFactors,
    /// ⟨μ_d, μ_h⟩: the two-sided confidence interval of the mean (5.3), grams.
    pub mean_interval_g: Interval,
    /// σ_upper: the one-sided upper confidence bound of σ (5.4), grams.
    pub sigma_upper_g: f64,
}

impl BallStatistics {
    /// The statistics of one ball's weighings at `confidence`.
    ///
    /// # Errors
    ///
    /// [`EstimateError::TooFewWeighings`] for fewer than 2; `NotANumber` for a NaN or
    /// infinite weighing; a quantile's error.
    pub fn estimate(
        ball: &str,
        weighings_g: &[f64],
        confidence: Confidence,
    ) -> Result<Self, EstimateError> {
        if let Some(&value) = weighings_g.iter().find(|value| !value.is_finite()) {
            return Err(EstimateError::NotANumber {
                ball: ball.to_owned(),
                value,
            });
        }
        let (Some(mean_g), Some(sd_g)) = (mean(weighings_g), sample_sd(weighings_g)) else {
            return Err(EstimateError::TooFewWeighings {
                ball: ball.to_owned(),
                count: weighings_g.len(),
            });
        };
        let n = weighings_g.len();
        let factors = IntervalFactors::new(n, confidence)?;
        #[allow(clippy::cast_precision_loss)] // a count of weighings
        let half_width = factors.t * sd_g / (n as f64).sqrt();
        Ok(Self {
            ball: ball.to_owned(),
            colour: colour_of(ball),
            n,
            mean_g,
            sd_g,
            confidence,
            factors,
            mean_interval_g: Interval::new(mean_g - half_width, mean_g + half_width),
            sigma_upper_g: factors.sigma_factor * sd_g,
        })
    }

    /// The statistics of a ball read from CSV; see [`BallStatistics::estimate`].
    ///
    /// # Errors
    ///
    /// As [`BallStatistics::estimate`].
    pub fn of_samples(ball: &BallSamples, confidence: Confidence) -> Result<Self, EstimateError> {
        Self::estimate(&ball.ball, &ball.weighings_g, confidence)
    }
}

/// X̄ = (1/n) Σ Xᵢ (5.1); `None` for no values.
#[must_use]
pub fn mean(values: &[f64]) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    #[allow(clippy::cast_precision_loss)] // a count of weighings
    Some(values.iter().sum::<f64>() / values.len() as f64)
}

/// S = √((1/(n−1)) Σ (Xᵢ − X̄)²) (5.2), from the deviations from the mean (two passes, so
/// that weights near 3 g with milligram scatter lose no digits); `None` for fewer than 2.
#[must_use]
pub fn sample_sd(values: &[f64]) -> Option<f64> {
    if values.len() < 2 {
        return None;
    }
    let mean = mean(values)?;
    let squares: f64 = values.iter().map(|value| (value - mean).powi(2)).sum();
    #[allow(clippy::cast_precision_loss)] // a count of weighings
    Some((squares / (values.len() - 1) as f64).sqrt())
}

/// n synthetic weighings whose sample mean is exactly `mean_g` and whose S is exactly
/// `sd_g` (to rounding of f64), shaped like a normal sample.
///
/// The values are Blom's normal scores Φ⁻¹((i − 0.375)/(n + 0.25)), i = 1..n (symmetric
/// about zero, the expected order statistics of a normal sample), centred and scaled to
/// the mean and S asked for. They come in an unsorted but fixed order (the i-th is the
/// (7·i mod n)-th smallest when 7 and n are coprime) so that a file of them reads like
/// weighings rather than a sorted list; the order changes neither mean nor S.
///
/// # Errors
///
/// [`EstimateError::TooFewWeighings`] for n < 2; `Synthetic` for a non-finite mean or a
/// negative or non-finite S.
pub fn synthetic_weighings(mean_g: f64, sd_g: f64, n: usize) -> Result<Vec<f64>, EstimateError> {
    if n < 2 {
        return Err(EstimateError::TooFewWeighings {
            ball: "synthetic".to_owned(),
            count: n,
        });
    }
    if !(mean_g.is_finite() && sd_g.is_finite() && sd_g >= 0.0) {
        return Err(EstimateError::Synthetic { mean_g, sd_g });
    }
    #[allow(clippy::cast_precision_loss)] // a count of weighings
    let scores = (1..=n)
        .map(|i| normal_quantile((i as f64 - 0.375) / (n as f64 + 0.25)))
        .collect::<Result<Vec<f64>, _>>()?;
    let (Some(centre), Some(spread)) = (mean(&scores), sample_sd(&scores)) else {
        return Err(EstimateError::TooFewWeighings {
            ball: "synthetic".to_owned(),
            count: n,
        });
    };
    let stride = if gcd(7, n) == 1 { 7 } else { 1 };
    Ok((0..n)
        .filter_map(|i| scores.get(i * stride % n))
        .map(|score| mean_g + (score - centre) * sd_g / spread)
        .collect())
}

fn gcd(a: usize, b: usize) -> usize {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn mean_and_sd_of_a_small_sample() {
        let values = [2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0];
        assert_eq!(mean(&values), Some(5.0));
        // Σ(x − 5)² = 32, n − 1 = 7
        assert!((sample_sd(&values).unwrap() - (32.0_f64 / 7.0).sqrt()).abs() < 1e-12);
        assert_eq!(mean(&[]), None);
        assert_eq!(sample_sd(&[1.0]), None);
    }

    #[test]
    fn synthetic_samples_have_exactly_the_mean_and_s_asked_for() {
        for n in [2, 3, 7, 14, 16, 30] {
            let values = synthetic_weighings(2.29, 0.068, n).unwrap();
            assert_eq!(values.len(), n);
            assert!((mean(&values).unwrap() - 2.29).abs() < 1e-12, "n {n}");
            assert!((sample_sd(&values).unwrap() - 0.068).abs() < 1e-12, "n {n}");
        }
        let sixteen = synthetic_weighings(0.0, 1.0, 16).unwrap();
        assert!(
            sixteen.windows(2).any(|pair| pair[0] > pair[1]),
            "not sorted"
        );
        assert!(synthetic_weighings(2.0, -0.1, 16).is_err());
        assert!(synthetic_weighings(2.0, 0.1, 1).is_err());
    }

    #[test]
    fn estimates_refuse_one_weighing_and_nan() {
        let one = BallStatistics::estimate("red 1", &[2.29], Confidence::TABLE_5_1);
        assert_eq!(
            one.unwrap_err().to_string(),
            "ball `red 1` has 1 weighing(s); at least 2 are needed for its scatter"
        );
        let nan = BallStatistics::estimate("red 1", &[2.29, f64::NAN], Confidence::TABLE_5_1);
        assert!(matches!(nan, Err(EstimateError::NotANumber { .. })));
    }
}
