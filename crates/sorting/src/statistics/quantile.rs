//! Confidence and coverage levels, and the quantiles behind formulas 5.3 and 5.4 of the
//! sorting-lab thesis (section 12.2): the Student t, chi-square and normal
//! quantiles, from `statrs`.
//!
//! For n = 16 weighings: t₀.₉₉₅(15) = 2.9467, χ²₀.₀₁(15) = 5.2293, so the upper bound of σ
//! at 99 % is 1.6936·S; at 95 %: t₀.₉₇₅(15) = 2.1314, χ²₀.₀₅(15) = 7.2609, 1.4373·S.

use std::fmt;

use serde::Serialize;
use statrs::distribution::{ChiSquared, ContinuousCDF as _, Normal, StudentsT};

use super::percent;

/// What went wrong with a level or a quantile.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum QuantileError {
    /// A confidence level or coverage probability outside (0, 1).
    #[error("the {what} must lie strictly between 0 and 1 (e.g. 0.99), not {value}")]
    NotAProbability {
        /// `confidence`, `coverage`, `probability`.
        what: &'static str,
        /// What was given.
        value: f64,
    },
    /// A coverage factor z that is not a positive finite number.
    #[error("the coverage factor z must be a positive number, not {0}")]
    NotAFactor(f64),
    /// Fewer than two values: no degrees of freedom for S.
    #[error("{0} value(s) leave no degree of freedom; at least 2 are needed")]
    TooFewValues(usize),
    /// statrs refused the distribution's parameters.
    #[error("the {distribution} distribution: {message}")]
    Distribution {
        /// `Student t`, `chi-square`, `normal`.
        distribution: &'static str,
        /// statrs's reason.
        message: String,
    },
}

/// The confidence level 1 − α of the estimates of μ and σ (formulas 5.3 and 5.4),
/// strictly between 0 and 1. The thesis's table 5.1 uses 99 %.
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd, Serialize)]
#[serde(transparent)]
pub struct Confidence(f64);

impl Confidence {
    /// 99 %, table 5.1's level.
    pub const TABLE_5_1: Self = Self(0.99);

    /// A level strictly between 0 and 1 (`0.99` for 99 %).
    ///
    /// # Errors
    ///
    /// [`QuantileError::NotAProbability`] outside (0, 1) or for NaN.
    pub fn try_new(level: f64) -> Result<Self, QuantileError> {
        if level > 0.0 && level < 1.0 {
            Ok(Self(level))
        } else {
            Err(QuantileError::NotAProbability {
                what: "confidence",
                value: level,
            })
        }
    }

    /// The level, e.g. 0.99.
    #[must_use]
    pub fn level(self) -> f64 {
        self.0
    }

    /// α = 1 − level, e.g. 0.01.
    #[must_use]
    pub fn alpha(self) -> f64 {
        1.0 - self.0
    }
}

impl TryFrom<f64> for Confidence {
    type Error = QuantileError;

    fn try_from(level: f64) -> Result<Self, Self::Error> {
        Self::try_new(level)
    }
}

impl fmt::Display for Confidence {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&percent(self.0))
    }
}

/// The share of a ball's weighings a coverage interval ⟨μ_d − z·σ, μ_h + z·σ⟩ is to hold,
/// as the probability and the two-sided normal quantile z for it.
///
/// The thesis writes z rounded: 2.58 for 99 % (2.5758), 1.65 for 90 % (1.6449);
/// [`Coverage::from_z`] takes its rounded factors as printed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Coverage {
    probability: f64,
    z: f64,
}

impl Coverage {
    /// 99 %, z = 2.5758 (the thesis rounds it to 2.58).
    pub const P99: Self = Self {
        probability: 0.99,
        z: 2.575_829_303_548_901,
    };

    /// The coverage of a probability strictly between 0 and 1, with
    /// z = Φ⁻¹((1 + probability) / 2).
    ///
    /// # Errors
    ///
    /// [`QuantileError::NotAProbability`] outside (0, 1) or for NaN.
    pub fn try_new(probability: f64) -> Result<Self, QuantileError> {
        if !(probability > 0.0 && probability < 1.0) {
            return Err(QuantileError::NotAProbability {
                what: "coverage",
                value: probability,
            });
        }
        let z = normal_quantile(f64::midpoint(1.0, probability))?;
        Ok(Self { probability, z })
    }

    /// The coverage of a given factor z (the thesis's 2.58 or 1.65), with the probability
    /// 2Φ(z) − 1 it stands for.
    ///
    /// # Errors
    ///
    /// [`QuantileError::NotAFactor`] unless z is positive and finite.
    pub fn from_z(z: f64) -> Result<Self, QuantileError> {
        if !(z > 0.0 && z.is_finite()) {
            return Err(QuantileError::NotAFactor(z));
        }
        let probability = 2.0 * standard_normal()?.cdf(z) - 1.0;
        Ok(Self { probability, z })
    }

    /// The share of weighings covered, e.g. 0.99.
    #[must_use]
    pub fn probability(self) -> f64 {
        self.probability
    }

    /// The factor z of σ, e.g. 2.5758.
    #[must_use]
    pub fn z(self) -> f64 {
        self.z
    }
}

impl fmt::Display for Coverage {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} (z = {:.4})", percent(self.probability), self.z)
    }
}

/// The factors of formulas 5.3 and 5.4 for n values at a confidence level.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct IntervalFactors {
    /// The number of values.
    pub n: usize,
    /// t_{1−α/2}(n − 1): the interval of μ is X̄ ± t·S/√n.
    pub t: f64,
    /// χ²_α(n − 1), the lower α-quantile.
    pub chi_square: f64,
    /// √((n − 1) / χ²_α(n − 1)): σ_upper = factor·S.
    pub sigma_factor: f64,
}

impl IntervalFactors {
    /// The factors for `n` values (at least 2) at `confidence`.
    ///
    /// # Errors
    ///
    /// [`QuantileError::TooFewValues`] for n < 2; a quantile's error.
    pub fn new(n: usize, confidence: Confidence) -> Result<Self, QuantileError> {
        if n < 2 {
            return Err(QuantileError::TooFewValues(n));
        }
        // n is a count of weighings: far below 2^52, exact as f64.
        #[allow(clippy::cast_precision_loss)]
        let freedom = (n - 1) as f64;
        let alpha = confidence.alpha();
        let t = student_t_quantile(1.0 - alpha / 2.0, freedom)?;
        let chi_square = chi_square_quantile(alpha, freedom)?;
        Ok(Self {
            n,
            t,
            chi_square,
            sigma_factor: (freedom / chi_square).sqrt(),
        })
    }
}

fn check_probability(p: f64) -> Result<(), QuantileError> {
    if p > 0.0 && p < 1.0 {
        Ok(())
    } else {
        Err(QuantileError::NotAProbability {
            what: "probability",
            value: p,
        })
    }
}

fn standard_normal() -> Result<Normal, QuantileError> {
    Normal::new(0.0, 1.0).map_err(|error| QuantileError::Distribution {
        distribution: "normal",
        message: error.to_string(),
    })
}

/// Φ⁻¹(p), the standard normal quantile (p strictly between 0 and 1).
///
/// # Errors
///
/// [`QuantileError::NotAProbability`] outside (0, 1).
pub fn normal_quantile(p: f64) -> Result<f64, QuantileError> {
    check_probability(p)?;
    Ok(standard_normal()?.inverse_cdf(p))
}

/// The Student t quantile t_p(ν) with ν degrees of freedom.
///
/// # Errors
///
/// [`QuantileError::NotAProbability`] outside (0, 1); `Distribution` for ν ≤ 0.
pub fn student_t_quantile(p: f64, freedom: f64) -> Result<f64, QuantileError> {
    check_probability(p)?;
    let t = StudentsT::new(0.0, 1.0, freedom).map_err(|error| QuantileError::Distribution {
        distribution: "Student t",
        message: error.to_string(),
    })?;
    Ok(t.inverse_cdf(p))
}

/// The chi-square quantile χ²_p(ν): the value below which a share p of the distribution
/// with ν degrees of freedom lies (the lower p-quantile; formula 5.4 uses p = α).
///
/// statrs 0.18 finds it by a few bisection and Newton steps, which diverge to NaN for
/// ν = 1 (two weighings) at small p (statrs issues 361 and 373, fixed in 0.19, which needs
/// a newer Rust than the workspace's). Its answer is used when it is finite and its cdf
/// matches p; otherwise a bisection on statrs's cdf finds the quantile.
///
/// # Errors
///
/// [`QuantileError::NotAProbability`] outside (0, 1); `Distribution` for ν ≤ 0.
pub fn chi_square_quantile(p: f64, freedom: f64) -> Result<f64, QuantileError> {
    check_probability(p)?;
    let chi = ChiSquared::new(freedom).map_err(|error| QuantileError::Distribution {
        distribution: "chi-square",
        message: error.to_string(),
    })?;
    let guess = chi.inverse_cdf(p);
    if guess.is_finite() && guess > 0.0 && (chi.cdf(guess) - p).abs() <= 1e-9 * p {
        return Ok(guess);
    }
    // cdf(0) = 0 < p; double the upper end until cdf(high) ≥ p.
    let (mut low, mut high) = (0.0_f64, freedom.max(1.0));
    while chi.cdf(high) < p && high < f64::MAX / 4.0 {
        high *= 2.0;
    }
    for _ in 0..200 {
        let middle = f64::midpoint(low, high);
        if chi.cdf(middle) < p {
            low = middle;
        } else {
            high = middle;
        }
        if high - low <= 1e-15 * high {
            break;
        }
    }
    Ok(f64::midpoint(low, high))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    fn close(a: f64, b: f64, tolerance: f64) -> bool {
        (a - b).abs() <= tolerance
    }

    /// Section 12.2's figures for n = 16.
    #[test]
    fn the_thesis_factors_for_sixteen_weighings() {
        let at99 = IntervalFactors::new(16, Confidence::try_new(0.99).unwrap()).unwrap();
        assert!(close(at99.t, 2.9467, 5e-5), "{at99:?}");
        assert!(close(at99.chi_square, 5.2293, 5e-5), "{at99:?}");
        assert!(close(at99.sigma_factor, 1.6936, 5e-5), "{at99:?}");
        let at95 = IntervalFactors::new(16, Confidence::try_new(0.95).unwrap()).unwrap();
        assert!(close(at95.t, 2.1314, 5e-5), "{at95:?}");
        assert!(close(at95.chi_square, 7.2609, 5e-5), "{at95:?}");
        assert!(close(at95.sigma_factor, 1.4373, 5e-5), "{at95:?}");
    }

    #[test]
    fn coverage_factors_as_the_thesis_rounds_them() {
        let at99 = Coverage::try_new(0.99).unwrap();
        assert!(close(at99.z(), 2.5758, 5e-5));
        assert!(close(at99.z(), 2.58, 0.005));
        let at90 = Coverage::try_new(0.90).unwrap();
        assert!(close(at90.z(), 1.6449, 5e-5));
        let printed = Coverage::from_z(1.65).unwrap();
        assert!(close(printed.probability(), 0.901, 5e-4), "{printed:?}");
        assert_eq!(at99.to_string(), "99 % (z = 2.5758)");
        assert!((Coverage::P99.z() - at99.z()).abs() < 1e-12);
    }

    /// Two weighings: one degree of freedom, where statrs 0.18's own search gives NaN.
    #[test]
    fn chi_square_with_one_degree_of_freedom() {
        // χ²_p(1) = (Φ⁻¹((1 + p) / 2))²
        for p in [0.001, 0.01, 0.05, 0.5] {
            let z = normal_quantile(f64::midpoint(1.0, p)).unwrap();
            let chi = chi_square_quantile(p, 1.0).unwrap();
            assert!(
                close(chi, z * z, 1e-9 * (z * z) + 1e-15),
                "p {p}: {chi} vs {}",
                z * z
            );
        }
        let two = IntervalFactors::new(2, Confidence::TABLE_5_1).unwrap();
        assert!(
            two.sigma_factor.is_finite() && two.sigma_factor > 60.0,
            "{two:?}"
        );
    }

    #[test]
    fn levels_outside_zero_one_are_refused() {
        for bad in [0.0, 1.0, -0.5, 99.0, f64::NAN] {
            assert!(Confidence::try_new(bad).is_err());
            assert!(Coverage::try_new(bad).is_err());
        }
        assert!(Coverage::from_z(0.0).is_err());
        assert!(Coverage::from_z(f64::INFINITY).is_err());
        assert_eq!(
            IntervalFactors::new(1, Confidence::TABLE_5_1),
            Err(QuantileError::TooFewValues(1))
        );
        assert_eq!(
            Confidence::try_new(99.0).unwrap_err().to_string(),
            "the confidence must lie strictly between 0 and 1 (e.g. 0.99), not 99"
        );
    }
}
