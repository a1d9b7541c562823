//! The shipped example, examples/sorting-lab/weighings.csv, is the synthetic sample of
//! the other tests written with the balance's resolution (0.01 mg, five decimals).
//! `SORTING_WRITE_EXAMPLE=1 cargo test -p sorting --test it example` rewrites it.

use std::path::PathBuf;

use sorting::statistics::{Samples, ThresholdConfig, Thresholds};

use crate::{assert_close, thesis_samples, TABLE_5_1};

fn path() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/sorting-lab/weighings.csv")
}

#[test]
fn the_shipped_weighings_are_the_synthetic_sample() {
    let expected = thesis_samples().to_csv(5);
    if std::env::var("SORTING_WRITE_EXAMPLE").as_deref() == Ok("1") {
        std::fs::write(path(), &expected).unwrap();
    }
    let shipped = std::fs::read_to_string(path()).unwrap();
    assert_eq!(
        shipped, expected,
        "run with SORTING_WRITE_EXAMPLE=1 to rewrite it"
    );
    // five decimals keep section 12.3's X̄ and S to 10 µg
    let samples = Samples::from_csv(&shipped).unwrap();
    assert_eq!(samples.weighings(), 128);
    let thresholds = Thresholds::from_samples(&samples, &ThresholdConfig::default()).unwrap();
    for (ball, row) in thresholds.balls.iter().zip(&TABLE_5_1) {
        assert_close(row.ball, ball.statistics.mean_g, row.mean, 1e-5);
        assert_close(row.ball, ball.statistics.sd_g, row.sd, 1e-5);
    }
}

/// The JSON `stanice stats thresholds --json` prints: a ball's statistics flattened
/// beside its coverage, intervals as `{lower, upper}`.
#[test]
fn thresholds_serialise_with_flat_ball_statistics() {
    let thresholds =
        Thresholds::from_samples(&thesis_samples(), &ThresholdConfig::default()).unwrap();
    let json = serde_json::to_value(&thresholds).unwrap();
    let red_1 = &json["balls"][0];
    assert_eq!(red_1["ball"], "red 1");
    assert_eq!(red_1["colour"], "red");
    assert_eq!(red_1["n"], 16);
    assert_eq!(red_1["confidence"], 0.99);
    assert_close("t", red_1["factors"]["t"].as_f64().unwrap(), 2.9467, 5e-5);
    assert_close(
        "μ lower",
        red_1["mean_interval_g"]["lower"].as_f64().unwrap(),
        2.2399,
        5e-5,
    );
    assert!(red_1["coverage_g"]["upper"].is_f64());
    assert!(red_1["reliability"]["expected"].is_f64());
    assert_eq!(json["colours"][1]["colour"], "yellow");
    assert_eq!(json["limits"][2]["above"], "green");
    assert_eq!(json["coverage"]["probability"], 0.99);
    assert_eq!(json["outer_g"]["lower"], 2.0);
}
