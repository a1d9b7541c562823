//! (e) CSV errors name the line.

use sorting::statistics::{Samples, SamplesError};

#[test]
fn a_missing_header_is_named_on_line_1() {
    let error = Samples::from_csv("red 1,2.29\nred 1,2.30\n").unwrap_err();
    assert_eq!(
        error,
        SamplesError::Header {
            line: 1,
            found: "red 1,2.29".to_owned()
        }
    );
    assert!(error.to_string().starts_with("line 1: "), "{error}");
}

#[test]
fn a_ball_weighed_once_is_named_with_its_line() {
    let text = "ball,weight_g\nred 1,2.29\nred 1,2.30\nblue 2,3.10\nred 1,2.28\n";
    let error = Samples::from_csv(text).unwrap_err();
    assert_eq!(
        error.to_string(),
        "line 4: ball `blue 2` has 1 weighing(s); at least 2 are needed for its scatter"
    );
}

#[test]
fn a_weight_that_is_not_a_number_is_named_with_its_line() {
    let text = "ball,weight_g\nred 1,2.29\nred 1,2.30\n\nred 1,2.3g\n";
    let error = Samples::from_csv(text).unwrap_err();
    assert_eq!(
        error,
        SamplesError::NotANumber {
            line: 5,
            value: "2.3g".to_owned(),
            hint: ""
        }
    );
    assert_eq!(
        error.to_string(),
        "line 5: weight_g `2.3g` is not a number of grams"
    );
    let error = Samples::from_csv("ball,weight_g\nred 1,NaN\nred 1,2.3\n").unwrap_err();
    assert!(
        error.to_string().starts_with("line 2: weight_g `NaN`"),
        "{error}"
    );
}

#[test]
fn a_header_with_other_columns_is_refused() {
    let error = Samples::from_csv("ball,weight\nred 1,2.29\n").unwrap_err();
    assert_eq!(
        error.to_string(),
        "line 1: the first line must be the header `ball,weight_g`, not `ball,weight`"
    );
    let error = Samples::from_csv("ball,weight_g\nred 1,2.29,3\n").unwrap_err();
    assert_eq!(
        error.to_string(),
        "line 2: 3 field(s) where the header has 2 (`ball,weight_g`)"
    );
}
