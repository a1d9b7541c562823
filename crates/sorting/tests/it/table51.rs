//! Table 5.1 and section 12.4 of the sorting-lab thesis, reproduced.

use sorting::statistics::estimate::BallStatistics;
use sorting::statistics::limits::{coverage_interval, Thresholds, DEFAULT_OUTER_G};
use sorting::statistics::quantile::IntervalFactors;
use sorting::statistics::{Confidence, Coverage, Interval, ThresholdConfig};

use crate::{assert_close, thesis_samples, Row, TABLE_5_1};

fn config(confidence: f64, coverage: Coverage) -> ThresholdConfig {
    let mut config = ThresholdConfig::default();
    config.confidence = Confidence::try_new(confidence).unwrap();
    config.coverage = coverage;
    config
}

/// (a) Synthetic samples with section 12.3's X̄ and S reproduce table 5.1's 3-s columns
/// at 99 % to ±0.01 g: every interval of μ and every upper bound of σ but blue 2's,
/// which the table misprints (see `blue_2s_printed_sigma_disagrees_with_its_own_interval`).
#[test]
fn table_5_1_three_second_columns_from_synthetic_weighings() {
    let thresholds =
        Thresholds::from_samples(&thesis_samples(), &ThresholdConfig::default()).unwrap();
    assert_eq!(thresholds.balls.len(), 8);
    for (ball, row) in thresholds.balls.iter().zip(&TABLE_5_1) {
        let statistics = &ball.statistics;
        assert_eq!(statistics.ball, row.ball);
        assert_eq!(statistics.n, 16);
        assert_close(row.ball, statistics.mean_g, row.mean, 1e-9);
        assert_close(row.ball, statistics.sd_g, row.sd, 1e-9);
        assert_close(row.ball, statistics.mean_interval_g.lower, row.mu.0, 0.01);
        assert_close(row.ball, statistics.mean_interval_g.upper, row.mu.1, 0.01);
        if row.ball != "blue 2" {
            assert_close(row.ball, statistics.sigma_upper_g, row.sigma_upper, 0.01);
        }
    }
    // the printed bounds are these rounded to two decimals
    let red_1 = &thresholds.balls[0].statistics;
    assert_eq!(format!("{:.2}", red_1.mean_interval_g), "⟨2.24, 2.34⟩");
    assert_close("red 1 σ upper", red_1.sigma_upper_g, 0.1152, 5e-5);
}

/// (b) The 95 % reconstruction of section 12.4: μ and σ at 95 % confidence, coverage
/// z = 1.65 (90 %), colour unions and the limits midway between them.
#[test]
fn ninety_five_percent_reconstruction_of_the_class_limits() {
    let printed_z = Coverage::from_z(1.65).unwrap();
    let computed_z = Coverage::try_new(0.90).unwrap();
    for coverage in [printed_z, computed_z] {
        let thresholds =
            Thresholds::from_samples(&thesis_samples(), &config(0.95, coverage)).unwrap();
        let unions: Vec<(&str, Interval)> = thresholds
            .colours
            .iter()
            .map(|colour| (colour.colour.as_str(), colour.union_g))
            .collect();
        let expected = [
            ("red", 2.09, 2.49),
            ("yellow", 2.50, 2.82),
            ("blue", 2.97, 3.24),
            ("green", 3.32, 3.75),
        ];
        assert_eq!(unions.len(), 4);
        for ((colour, union), (name, lower, upper)) in unions.iter().zip(expected) {
            assert_eq!(*colour, name);
            assert_close(name, union.lower, lower, 0.01);
            assert_close(name, union.upper, upper, 0.01);
        }
        let limits: Vec<f64> = thresholds
            .limits
            .iter()
            .map(|limit| limit.limit_g)
            .collect();
        for (limit, expected) in limits.iter().zip([2.495, 2.892, 3.283]) {
            assert_close("limit", *limit, expected, 0.01);
        }
        // against §8.3's printed limits 2.50/2.51, 2.91/2.92, 3.30/3.31 (read from a plot)
        for (limit, printed) in limits.iter().zip([2.505, 2.915, 3.305]) {
            assert_close("printed limit", *limit, printed, 0.025);
        }
        assert_eq!(thresholds.overlaps().count(), 0);
        // The unions do not overlap, so every ball's 90 % coverage interval lies within
        // its colour's decision interval: even with σ_upper at least 90 % of its
        // weighings are sorted right, the thesis's "about 90 %".
        for ball in &thresholds.balls {
            assert!(
                ball.reliability.with_sigma_upper >= 0.90,
                "{}: {:?}",
                ball.statistics.ball,
                ball.reliability
            );
            assert!(ball.reliability.expected >= ball.reliability.with_sigma_upper);
        }
        assert!(
            thresholds.reliability.expected > 0.99,
            "{:?}",
            thresholds.reliability
        );
    }
}

/// A row of the printed table as statistics: X̄ the interval's middle, S back-computed
/// from the printed σ bound, the printed bounds as they are.
fn printed(row: &Row) -> BallStatistics {
    let factors = IntervalFactors::new(16, Confidence::TABLE_5_1).unwrap();
    BallStatistics {
        ball: row.ball.to_owned(),
        colour: row.ball.split(' ').next().unwrap().to_owned(),
        n: 16,
        mean_g: f64::midpoint(row.mu.0, row.mu.1),
        sd_g: row.sigma_upper / factors.sigma_factor,
        confidence: Confidence::TABLE_5_1,
        factors,
        mean_interval_g: Interval::new(row.mu.0, row.mu.1),
        sigma_upper_g: row.sigma_upper,
    }
}

/// (c) 99 % coverage, z = 2.58: red 1 ⟨1.930, 2.650⟩ and the colours' unions of section
/// 12.4 come from the printed (rounded) table; from the weighings themselves red 1 is
/// ⟨1.943, 2.637⟩, the difference being the table's rounding of σ_upper 0.1152 up to
/// 0.12 (2.58 · 0.0048 = 0.012 g at each end). Either way neighbouring colours overlap:
/// 99 % reliability is not achievable with these balls.
#[test]
fn ninety_nine_percent_coverage_overlaps() {
    let red_1 = coverage_interval(Interval::new(2.24, 2.34), 0.12, 2.58);
    assert_close("red 1 lower", red_1.lower, 1.930, 5e-4);
    assert_close("red 1 upper", red_1.upper, 2.650, 5e-4);

    let z = Coverage::from_z(2.58).unwrap();
    let from_table =
        Thresholds::derive(TABLE_5_1.iter().map(printed).collect(), z, DEFAULT_OUTER_G).unwrap();
    let expected = [
        ("red", 1.93, 2.65),
        ("yellow", 2.36, 2.96),
        ("blue", 2.89, 3.32),
        ("green", 3.19, 3.86),
    ];
    for (colour, (name, lower, upper)) in from_table.colours.iter().zip(expected) {
        assert_eq!(colour.colour, name);
        assert_close(name, colour.union_g.lower, lower, 0.005);
        assert_close(name, colour.union_g.upper, upper, 0.005);
    }
    assert_eq!(from_table.overlaps().count(), 3);

    let from_weighings = Thresholds::from_samples(&thesis_samples(), &config(0.99, z)).unwrap();
    let red_1 = from_weighings.balls[0].coverage_g;
    assert_close("red 1 lower", red_1.lower, 1.943, 5e-4);
    assert_close("red 1 upper", red_1.upper, 2.637, 5e-4);
    let overlapping: Vec<(&str, &str)> = from_weighings
        .overlaps()
        .map(|limit| (limit.below.as_str(), limit.above.as_str()))
        .collect();
    assert_eq!(
        overlapping,
        [("red", "yellow"), ("yellow", "blue"), ("blue", "green")]
    );
    // red and yellow overlap by about a quarter of a gram
    assert_close(
        "red|yellow gap",
        from_weighings.limits[0].gap_g,
        -0.252,
        0.002,
    );
    // the limits still lie midway (in the middle of each overlap), and in order
    let limits: Vec<f64> = from_weighings
        .limits
        .iter()
        .map(|limit| limit.limit_g)
        .collect();
    assert!(
        limits.windows(2).all(|pair| pair[0] < pair[1]),
        "{limits:?}"
    );
    // the printed table's unions are wider than their own balls' weighings imply in places:
    // its σ column is rounded to two decimals
    assert!(from_table.colours[0].union_g.width() > from_weighings.colours[0].union_g.width());
}

/// (d) Table 5.1 prints σ_upper = 0.07 g for blue 2, but its own interval ⟨3.07, 3.14⟩
/// back-computes (S = half-width·√16 / 2.9467, σ_upper = 1.6936·S) to σ_upper ≈ 0.080 g,
/// as section 12.3's S = 0.048 g does (0.081 g). Every other row back-computes to its
/// printed σ within ±0.01 g; blue 2's misses by 0.0105 g. The test asserts the computed
/// 0.080 g: the formula is not bent to fit the misprint.
#[test]
fn blue_2s_printed_sigma_disagrees_with_its_own_interval() {
    let factors = IntervalFactors::new(16, Confidence::TABLE_5_1).unwrap();
    let back_computed = |row: &Row| {
        let half_width = (row.mu.1 - row.mu.0) / 2.0;
        let sd = half_width * 16.0_f64.sqrt() / factors.t;
        factors.sigma_factor * sd
    };
    for row in &TABLE_5_1 {
        let sigma = back_computed(row);
        if row.ball == "blue 2" {
            assert_close("blue 2 σ upper", sigma, 0.080, 0.001);
            assert!(
                sigma - row.sigma_upper > 0.01,
                "{sigma} vs printed {}",
                row.sigma_upper
            );
        } else {
            assert_close(row.ball, sigma, row.sigma_upper, 0.01);
        }
    }
    let thresholds =
        Thresholds::from_samples(&thesis_samples(), &ThresholdConfig::default()).unwrap();
    let blue_2 = &thresholds.balls[5].statistics;
    assert_eq!(blue_2.ball, "blue 2");
    assert_close("blue 2 σ upper from S", blue_2.sigma_upper_g, 0.0813, 5e-5);
}
