//! From the balls' interval estimates to class limits (the sorting-lab thesis,
//! section 12.4), and the sorting reliability they promise.
//!
//! 1. **Coverage** of each ball: `⟨μ_d − z·σ_upper, μ_h + z·σ_upper⟩`, where ⟨μ_d, μ_h⟩
//!    is the confidence interval of its mean and σ_upper the upper bound of its σ: the
//!    share of its weighings given by the coverage falls inside even for the least
//!    favourable μ and σ the estimates allow.
//! 2. **Colour unions**: a colour's interval is the union of its balls' coverage
//!    intervals (the smallest interval holding them; the balls of one colour overlap).
//!    Colours are ordered by their mean weight (the mean of their balls' means).
//! 3. **Decision limits** lie midway between neighbouring colours' unions: between the
//!    upper end of the lighter colour's union and the lower end of the heavier one's
//!    (the middle of the gap, or of the overlap when they overlap). The lowest and
//!    highest (outer) limits are set by hand: 2.0 and 4.0 g by default (the
//!    sorting-lab thesis's note BS-A7; BS-A8: the lower one is red's, not
//!    yellow's). Each colour's decision interval runs from the limit below it to the
//!    limit above it.
//! 4. **Reliability**: for each ball the probability that a weighing falls within its
//!    colour's decision interval, with the weighings taken as normal with the ball's X̄
//!    and S — X̄ and S are the estimates of the ball's distribution, so this is the share
//!    of correct decisions to expect. The same with σ_upper in place of S is reported
//!    beside it as a pessimistic figure (σ as large as the confidence level allows; μ's
//!    own uncertainty is not in it, so it is no strict lower bound). The reliability of a
//!    colour and of the whole set is the average over their balls (each ball sorted
//!    equally often).
//!
//! When neighbouring unions overlap, the coverage asked for cannot be had with these
//! balls: [`Thresholds::overlaps`] lists where (the thesis at 99 %: the balls would need
//! larger weight differences).

use serde::Serialize;
use statrs::distribution::{ContinuousCDF as _, Normal};

use super::estimate::{BallStatistics, EstimateError};
use super::quantile::{Confidence, Coverage, QuantileError};
use super::samples::Samples;
use super::Interval;

/// The outer limits of the sorting-lab thesis's note BS-A7: 2.0 and 4.0 g.
pub const DEFAULT_OUTER_G: Interval = Interval::new(2.0, 4.0);

/// Why class limits could not be derived.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ThresholdsError {
    /// No balls at all.
    #[error("no balls to derive limits from")]
    NoBalls,
    /// A ball's statistics.
    #[error(transparent)]
    Estimate(#[from] EstimateError),
    /// A probability could not be computed.
    #[error(transparent)]
    Quantile(#[from] QuantileError),
    /// Outer limits that are not two finite numbers in order.
    #[error("the outer limits must be two finite numbers, the lower first, not {0}")]
    OuterLimits(Interval),
    /// A decision limit at or beyond an outer limit.
    #[error(
        "the decision limit between {below} and {above} ({limit_g:.3} g) lies outside the outer limits {outer_g}"
    )]
    LimitOutside {
        /// The lighter colour.
        below: String,
        /// The heavier colour.
        above: String,
        /// The limit.
        limit_g: f64,
        /// The outer limits.
        outer_g: Interval,
    },
    /// A colour's limits in the wrong order: its union lies within its neighbours'.
    #[error(
        "{colour} cannot be told from its neighbours: the limit below it ({lower_g:.3} g) is not below the one above it ({upper_g:.3} g)"
    )]
    LimitsOutOfOrder {
        /// The colour.
        colour: String,
        /// The limit below it.
        lower_g: f64,
        /// The limit above it.
        upper_g: f64,
    },
}

/// What to derive the limits with.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct ThresholdConfig {
    /// The confidence level of μ's interval and σ's bound (table 5.1: 99 %).
    pub confidence: Confidence,
    /// The coverage of the balls' intervals (default 99 %; the thesis settled for 90 %,
    /// z = 1.65, with μ and σ at 95 %).
    pub coverage: Coverage,
    /// The lowest and highest limits, set by hand (default ⟨2.0, 4.0⟩ g, BS-A7).
    pub outer_g: Interval,
}

impl Default for ThresholdConfig {
    fn default() -> Self {
        Self {
            confidence: Confidence::TABLE_5_1,
            coverage: Coverage::P99,
            outer_g: DEFAULT_OUTER_G,
        }
    }
}

/// The probability that a ball's weighing falls within its colour's decision interval.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Reliability {
    /// With the weighings normal with X̄ and S: the share of correct decisions to expect.
    pub expected: f64,
    /// With σ_upper in place of S: a pessimistic figure.
    pub with_sigma_upper: f64,
}

/// A ball's statistics, coverage, decision interval and reliability.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BallThresholds {
    /// n, X̄, S, the interval of μ and σ_upper.
    #[serde(flatten)]
    pub statistics: BallStatistics,
    /// ⟨μ_d − z·σ_upper, μ_h + z·σ_upper⟩, grams.
    pub coverage_g: Interval,
    /// Its colour's decision interval, grams.
    pub decision_g: Interval,
    /// The probability of its weighing falling within `decision_g`.
    pub reliability: Reliability,
}

/// A colour's balls, union, decision interval and reliability.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ColourThresholds {
    /// The colour (`red`).
    pub colour: String,
    /// Its balls, in input order.
    pub balls: Vec<String>,
    /// The mean of its balls' means, grams: the colours' order.
    pub mean_g: f64,
    /// The union of its balls' coverage intervals, grams.
    pub union_g: Interval,
    /// From the limit below it (or the lower outer limit) to the limit above it (or the
    /// upper outer limit), grams.
    pub decision_g: Interval,
    /// The average of its balls' reliabilities.
    pub reliability: Reliability,
}

/// The limit between two neighbouring colours.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DecisionLimit {
    /// The lighter colour.
    pub below: String,
    /// The heavier colour.
    pub above: String,
    /// Midway between the lighter union's upper end and the heavier one's lower end,
    /// grams.
    pub limit_g: f64,
    /// The heavier union's lower end minus the lighter one's upper end, grams: negative
    /// when the unions overlap.
    pub gap_g: f64,
}

/// The class limits derived from a set of balls, and what they promise.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Thresholds {
    /// The coverage of the balls' intervals.
    pub coverage: Coverage,
    /// The outer limits, grams.
    pub outer_g: Interval,
    /// The balls, in input order.
    pub balls: Vec<BallThresholds>,
    /// The colours, lightest first.
    pub colours: Vec<ColourThresholds>,
    /// The limits between neighbouring colours, lightest first.
    pub limits: Vec<DecisionLimit>,
    /// The average over all balls.
    pub reliability: Reliability,
}

/// ⟨μ_d − z·σ_upper, μ_h + z·σ_upper⟩: where a share of a ball's weighings falls, for
/// the least favourable μ within ⟨μ_d, μ_h⟩ and σ up to σ_upper.
#[must_use]
pub fn coverage_interval(mean_interval_g: Interval, sigma_upper_g: f64, z: f64) -> Interval {
    Interval::new(
        mean_interval_g.lower - z * sigma_upper_g,
        mean_interval_g.upper + z * sigma_upper_g,
    )
}

/// P(X within `interval`) for X normal with `mean` and standard deviation `sd` (sd = 0:
/// all weighings at the mean).
///
/// # Errors
///
/// [`QuantileError::Distribution`] for a negative or non-finite sd.
pub fn normal_probability(interval: Interval, mean: f64, sd: f64) -> Result<f64, QuantileError> {
    if sd == 0.0 {
        return Ok(if interval.contains(mean) { 1.0 } else { 0.0 });
    }
    let normal = Normal::new(mean, sd).map_err(|error| QuantileError::Distribution {
        distribution: "normal",
        message: error.to_string(),
    })?;
    Ok((normal.cdf(interval.upper) - normal.cdf(interval.lower)).max(0.0))
}

impl Thresholds {
    /// Estimates each ball at the configured confidence and derives the limits.
    ///
    /// # Errors
    ///
    /// A ball's [`EstimateError`]; see [`Thresholds::derive`].
    pub fn from_samples(
        samples: &Samples,
        config: &ThresholdConfig,
    ) -> Result<Self, ThresholdsError> {
        let balls = samples
            .balls()
            .iter()
            .map(|ball| BallStatistics::of_samples(ball, config.confidence))
            .collect::<Result<Vec<_>, _>>()?;
        Self::derive(balls, config.coverage, config.outer_g)
    }

    /// Coverage intervals, colour unions, decision limits and reliabilities from the
    /// balls' statistics (which may also come from a printed table).
    ///
    /// # Errors
    ///
    /// [`ThresholdsError::NoBalls`]; `OuterLimits` for outer limits not in order; a
    /// limit outside the outer limits or limits out of order (a colour lying within its
    /// neighbours).
    pub fn derive(
        balls: Vec<BallStatistics>,
        coverage: Coverage,
        outer_g: Interval,
    ) -> Result<Self, ThresholdsError> {
        if balls.is_empty() {
            return Err(ThresholdsError::NoBalls);
        }
        if !(outer_g.lower.is_finite()
            && outer_g.upper.is_finite()
            && outer_g.lower < outer_g.upper)
        {
            return Err(ThresholdsError::OuterLimits(outer_g));
        }
        let covered: Vec<(BallStatistics, Interval)> = balls
            .into_iter()
            .map(|ball| {
                let interval =
                    coverage_interval(ball.mean_interval_g, ball.sigma_upper_g, coverage.z());
                (ball, interval)
            })
            .collect();
        let mut colours = colour_unions(&covered);
        let limits: Vec<DecisionLimit> = colours
            .windows(2)
            .filter_map(|pair| match pair {
                [below, above] => Some(DecisionLimit {
                    below: below.colour.clone(),
                    above: above.colour.clone(),
                    limit_g: f64::midpoint(below.union_g.upper, above.union_g.lower),
                    gap_g: below.union_g.gap_to(above.union_g),
                }),
                _ => None,
            })
            .collect();
        for limit in &limits {
            if !(outer_g.lower < limit.limit_g && limit.limit_g < outer_g.upper) {
                return Err(ThresholdsError::LimitOutside {
                    below: limit.below.clone(),
                    above: limit.above.clone(),
                    limit_g: limit.limit_g,
                    outer_g,
                });
            }
        }
        for (index, colour) in colours.iter_mut().enumerate() {
            let lower = match index.checked_sub(1).and_then(|below| limits.get(below)) {
                Some(limit) => limit.limit_g,
                None => outer_g.lower,
            };
            let upper = limits
                .get(index)
                .map_or(outer_g.upper, |limit| limit.limit_g);
            if lower >= upper {
                return Err(ThresholdsError::LimitsOutOfOrder {
                    colour: colour.colour.clone(),
                    lower_g: lower,
                    upper_g: upper,
                });
            }
            colour.decision_g = Interval::new(lower, upper);
        }
        let mut balls = Vec::with_capacity(covered.len());
        for (statistics, coverage_g) in covered {
            let decision_g = colours
                .iter()
                .find(|colour| colour.colour == statistics.colour)
                .map_or(outer_g, |colour| colour.decision_g);
            let reliability = Reliability {
                expected: normal_probability(decision_g, statistics.mean_g, statistics.sd_g)?,
                with_sigma_upper: normal_probability(
                    decision_g,
                    statistics.mean_g,
                    statistics.sigma_upper_g,
                )?,
            };
            balls.push(BallThresholds {
                statistics,
                coverage_g,
                decision_g,
                reliability,
            });
        }
        for colour in &mut colours {
            colour.reliability = average(
                balls
                    .iter()
                    .filter(|ball| ball.statistics.colour == colour.colour)
                    .map(|ball| ball.reliability),
            );
        }
        let reliability = average(balls.iter().map(|ball| ball.reliability));
        Ok(Self {
            coverage,
            outer_g,
            balls,
            colours,
            limits,
            reliability,
        })
    }

    /// The limits whose neighbouring unions overlap: there the coverage asked for is
    /// not achievable with these balls.
    pub fn overlaps(&self) -> impl Iterator<Item = &DecisionLimit> {
        self.limits.iter().filter(|limit| limit.gap_g < 0.0)
    }
}

/// The colours of the balls with their unions, lightest first; decision intervals and
/// reliabilities still to be filled in.
fn colour_unions(covered: &[(BallStatistics, Interval)]) -> Vec<ColourThresholds> {
    let mut colours: Vec<ColourThresholds> = Vec::new();
    for (ball, interval) in covered {
        match colours
            .iter_mut()
            .find(|colour| colour.colour == ball.colour)
        {
            Some(colour) => {
                colour.balls.push(ball.ball.clone());
                colour.union_g = colour.union_g.hull(*interval);
                colour.mean_g += ball.mean_g; // summed here, averaged below
            }
            None => colours.push(ColourThresholds {
                colour: ball.colour.clone(),
                balls: vec![ball.ball.clone()],
                mean_g: ball.mean_g,
                union_g: *interval,
                decision_g: *interval,
                reliability: Reliability {
                    expected: 0.0,
                    with_sigma_upper: 0.0,
                },
            }),
        }
    }
    for colour in &mut colours {
        #[allow(clippy::cast_precision_loss)] // a count of balls
        let count = colour.balls.len().max(1) as f64;
        colour.mean_g /= count;
    }
    colours.sort_by(|a, b| a.mean_g.total_cmp(&b.mean_g));
    colours
}

fn average(reliabilities: impl Iterator<Item = Reliability>) -> Reliability {
    let (mut expected, mut pessimistic, mut count) = (0.0, 0.0, 0.0_f64);
    for reliability in reliabilities {
        expected += reliability.expected;
        pessimistic += reliability.with_sigma_upper;
        count += 1.0;
    }
    let count = count.max(1.0);
    Reliability {
        expected: expected / count,
        with_sigma_upper: pessimistic / count,
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn normal_probability_of_an_interval() {
        let within_one_sd = normal_probability(Interval::new(-1.0, 1.0), 0.0, 1.0).unwrap();
        assert!((within_one_sd - 0.682_689_492).abs() < 1e-8);
        assert_eq!(
            normal_probability(Interval::new(2.0, 3.0), 2.5, 0.0).unwrap(),
            1.0
        );
        assert_eq!(
            normal_probability(Interval::new(2.0, 3.0), 3.5, 0.0).unwrap(),
            0.0
        );
        assert!(normal_probability(Interval::new(2.0, 3.0), 2.5, -1.0).is_err());
    }

    fn ball(name: &str, mean: f64, sd: f64) -> BallStatistics {
        let values = crate::statistics::estimate::synthetic_weighings(mean, sd, 16).unwrap();
        BallStatistics::estimate(name, &values, Confidence::TABLE_5_1).unwrap()
    }

    #[test]
    fn outer_limits_must_hold_the_decision_limits() {
        let balls = vec![ball("red 1", 2.29, 0.068), ball("yellow 1", 2.665, 0.048)];
        let error = Thresholds::derive(balls.clone(), Coverage::P99, Interval::new(2.6, 4.0));
        assert!(
            matches!(error, Err(ThresholdsError::LimitOutside { .. })),
            "{error:?}"
        );
        let error = Thresholds::derive(balls.clone(), Coverage::P99, Interval::new(4.0, 2.0));
        assert!(
            matches!(error, Err(ThresholdsError::OuterLimits(_))),
            "{error:?}"
        );
        assert_eq!(
            Thresholds::derive(Vec::new(), Coverage::P99, DEFAULT_OUTER_G),
            Err(ThresholdsError::NoBalls)
        );
    }

    /// A colour whose union lies within its neighbours' cannot be told apart.
    #[test]
    fn a_colour_between_two_wide_ones_is_refused() {
        let balls = vec![
            ball("red 1", 2.5, 0.2),
            ball("yellow 1", 2.6, 0.005),
            ball("blue 1", 2.7, 0.2),
        ];
        let error = Thresholds::derive(balls, Coverage::P99, DEFAULT_OUTER_G).unwrap_err();
        assert!(
            matches!(&error, ThresholdsError::LimitsOutOfOrder { colour, .. } if colour == "yellow"),
            "{error:?}"
        );
    }

    #[test]
    fn one_colour_decides_between_the_outer_limits() {
        let thresholds = Thresholds::derive(
            vec![ball("red 1", 2.29, 0.068)],
            Coverage::P99,
            DEFAULT_OUTER_G,
        )
        .unwrap();
        assert!(thresholds.limits.is_empty());
        assert_eq!(thresholds.colours[0].decision_g, DEFAULT_OUTER_G);
        assert!(thresholds.reliability.expected > 0.999);
    }
}
