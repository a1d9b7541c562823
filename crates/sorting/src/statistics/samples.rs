//! The weighings as CSV: a header `ball,weight_g`, one row per weighing.
//!
//! ```text
//! ball,weight_g
//! red 1,2.29105
//! red 1,2.21846
//! yellow 2,2.66317
//! ```
//!
//! A ball is named by its colour and a number (`red 1`, `yellow 2`); its colour is the
//! name's first word (in lower case); names differing only in letter case or spacing
//! are one ball. A ball may be weighed any number of times, at
//! least twice (one weighing has no scatter), its rows in any order. Every error names
//! the line it was found on.

use serde::Deserialize;

/// The header a weighings file starts with.
pub const HEADER: &str = "ball,weight_g";

/// Why weighings could not be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SamplesError {
    /// The first line is not the header.
    #[error("line {line}: the first line must be the header `{HEADER}`, not `{found}`")]
    Header {
        /// The line the header was expected on.
        line: u64,
        /// What is there instead (empty for an empty file).
        found: String,
    },
    /// The CSV itself is broken (a row with another number of fields, bad quoting).
    #[error("line {line}: {message}")]
    Csv {
        /// The line of the broken row.
        line: u64,
        /// The CSV reader's reason.
        message: String,
    },
    /// A row without a ball name.
    #[error("line {line}: the ball has no name (e.g. `red 1`)")]
    NoBall {
        /// The row's line.
        line: u64,
    },
    /// A weight that is not a finite number.
    #[error("line {line}: weight_g `{value}` is not a number of grams{hint}")]
    NotANumber {
        /// The row's line.
        line: u64,
        /// The field as written.
        value: String,
        /// A hint for a decimal comma, else empty.
        hint: &'static str,
    },
    /// A ball weighed once only.
    #[error(
        "line {line}: ball `{ball}` has {count} weighing(s); at least 2 are needed for its scatter"
    )]
    TooFewWeighings {
        /// The ball.
        ball: String,
        /// Its weighings.
        count: usize,
        /// The line of its (first) weighing.
        line: u64,
    },
    /// A header and no weighings.
    #[error("line {line}: no weighings after the header")]
    NoWeighings {
        /// The header's line.
        line: u64,
    },
}

/// One ball's weighings, in file order.
#[derive(Debug, Clone, PartialEq)]
pub struct BallSamples {
    /// The ball's name, words separated by one space (`red 1`).
    pub ball: String,
    /// Its weighings in grams.
    pub weighings_g: Vec<f64>,
    /// The line of its first weighing (0 when not read from a file).
    pub line: u64,
}

impl BallSamples {
    /// A ball's weighings not read from a file; the name's words are joined by one space.
    #[must_use]
    pub fn new(ball: &str, weighings_g: Vec<f64>) -> Self {
        Self {
            ball: normalise(ball),
            weighings_g,
            line: 0,
        }
    }

    /// The ball's colour: its name's first word, in lower case.
    #[must_use]
    pub fn colour(&self) -> String {
        colour_of(&self.ball)
    }
}

/// A ball's colour: the first word of its name, in lower case (`Red 1` -> `red`).
#[must_use]
pub fn colour_of(ball: &str) -> String {
    ball.split_whitespace()
        .next()
        .unwrap_or_default()
        .to_lowercase()
}

fn normalise(ball: &str) -> String {
    ball.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// The weighings of a set of balls, each ball in the order of its first row.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Samples {
    balls: Vec<BallSamples>,
}

#[derive(Deserialize)]
struct Row {
    ball: String,
    weight_g: String,
}

impl Samples {
    /// Samples of balls not read from a file (e.g. synthetic ones). Balls of the same
    /// name are merged.
    #[must_use]
    pub fn new(balls: Vec<BallSamples>) -> Self {
        let mut samples = Self::default();
        for ball in balls {
            samples.add(&ball.ball, ball.line, ball.weighings_g);
        }
        samples
    }

    /// Reads CSV text with the header `ball,weight_g`.
    ///
    /// # Errors
    ///
    /// A [`SamplesError`] naming the line: a missing header, a broken row, a row without
    /// a ball, a weight that is not a number, a ball with fewer than 2 weighings, no rows.
    pub fn from_csv(text: &str) -> Result<Self, SamplesError> {
        Self::from_bytes(text.as_bytes())
    }

    /// Reads CSV from bytes (UTF-8); see [`Samples::from_csv`].
    ///
    /// Lines are counted here from the byte offsets the CSV reader reports: its own line
    /// count leaves out blank lines.
    ///
    /// # Errors
    ///
    /// As [`Samples::from_csv`]; text that is not UTF-8 is a [`SamplesError::Csv`].
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, SamplesError> {
        let line_at = |position: Option<&csv::Position>| {
            position.map_or(1, |position| line_of(bytes, position.byte()))
        };
        let csv_error = |error: &csv::Error| SamplesError::Csv {
            line: line_at(error.position()),
            message: match error.kind() {
                csv::ErrorKind::UnequalLengths {
                    expected_len, len, ..
                } => format!("{len} field(s) where the header has {expected_len} (`{HEADER}`)"),
                csv::ErrorKind::Utf8 { .. } => "not UTF-8 text".to_owned(),
                _ => error.to_string(),
            },
        };
        let mut csv = csv::ReaderBuilder::new()
            .has_headers(true)
            .trim(csv::Trim::All)
            .from_reader(bytes);
        let header = csv.headers().map_err(|error| csv_error(&error))?.clone();
        let header_line = line_at(header.position());
        let fields: Vec<&str> = header.iter().collect();
        if fields != ["ball", "weight_g"] {
            return Err(SamplesError::Header {
                line: header_line,
                found: fields.join(","),
            });
        }
        let mut samples = Self::default();
        for record in csv.records() {
            let record = record.map_err(|error| csv_error(&error))?;
            let line = line_at(record.position());
            let row: Row =
                record
                    .deserialize(Some(&header))
                    .map_err(|error| SamplesError::Csv {
                        line,
                        message: error.to_string(),
                    })?;
            if row.ball.trim().is_empty() {
                return Err(SamplesError::NoBall { line });
            }
            let weight = row
                .weight_g
                .parse::<f64>()
                .ok()
                .filter(|weight| weight.is_finite())
                .ok_or_else(|| SamplesError::NotANumber {
                    line,
                    hint: if row.weight_g.contains(',') {
                        " (write a decimal point, not a comma)"
                    } else {
                        ""
                    },
                    value: row.weight_g.clone(),
                })?;
            samples.add(&row.ball, line, [weight]);
        }
        if samples.balls.is_empty() {
            return Err(SamplesError::NoWeighings { line: header_line });
        }
        if let Some(ball) = samples.balls.iter().find(|ball| ball.weighings_g.len() < 2) {
            return Err(SamplesError::TooFewWeighings {
                ball: ball.ball.clone(),
                count: ball.weighings_g.len(),
                line: ball.line,
            });
        }
        Ok(samples)
    }

    /// Adds weighings to the ball named `ball` (letter case aside: `Red 1` is `red 1`),
    /// which is added at the end, as first spelt, when new.
    fn add(&mut self, ball: &str, line: u64, weighings_g: impl IntoIterator<Item = f64>) {
        let name = normalise(ball);
        match self
            .balls
            .iter_mut()
            .find(|known| known.ball.to_lowercase() == name.to_lowercase())
        {
            Some(known) => known.weighings_g.extend(weighings_g),
            None => self.balls.push(BallSamples {
                ball: name,
                weighings_g: weighings_g.into_iter().collect(),
                line,
            }),
        }
    }

    /// The balls, each in the order of its first row.
    #[must_use]
    pub fn balls(&self) -> &[BallSamples] {
        &self.balls
    }

    /// The number of weighings of all balls.
    #[must_use]
    pub fn weighings(&self) -> usize {
        self.balls.iter().map(|ball| ball.weighings_g.len()).sum()
    }

    /// The samples as CSV with the header `ball,weight_g`, ball after ball, the weights
    /// with `decimals` decimals (5 = the balance's 0.01 mg).
    #[must_use]
    pub fn to_csv(&self, decimals: usize) -> String {
        let mut text = format!("{HEADER}\n");
        for ball in &self.balls {
            for weight in &ball.weighings_g {
                text.push_str(&format!("{},{weight:.decimals$}\n", ball.ball));
            }
        }
        text
    }
}

/// The 1-based line of the record starting at a byte offset. The reader reports a
/// record from where it began reading it, before the blank lines it skipped: those are
/// skipped here too.
fn line_of(bytes: &[u8], offset: u64) -> u64 {
    let mut offset = usize::try_from(offset)
        .unwrap_or(usize::MAX)
        .min(bytes.len());
    while matches!(bytes.get(offset), Some(b'\n' | b'\r')) {
        offset += 1;
    }
    let newlines = bytes.get(..offset).map_or(0, |before| {
        before.iter().filter(|&&byte| byte == b'\n').count()
    });
    u64::try_from(newlines).map_or(u64::MAX, |newlines| newlines + 1)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn balls_keep_their_first_row_order_and_collect_their_weighings() {
        let samples = Samples::from_csv(
            "ball,weight_g\nred 1,2.29\nYellow  2, 2.66\nred 1,2.30\nyellow 2,2.65\n",
        )
        .unwrap();
        let balls = samples.balls();
        assert_eq!(balls.len(), 2);
        assert_eq!(balls[0].ball, "red 1");
        assert_eq!(balls[0].weighings_g, vec![2.29, 2.30]);
        assert_eq!(balls[0].line, 2);
        assert_eq!(balls[1].ball, "Yellow 2");
        assert_eq!(balls[1].colour(), "yellow");
        assert_eq!(balls[1].weighings_g, vec![2.66, 2.65]);
        assert_eq!(samples.weighings(), 4);
    }

    #[test]
    fn lines_count_blank_lines_and_crlf() {
        let text = "\r\nball,weight_g\r\nred 1,2.29\r\n\r\n\r\nred 1,x\r\n";
        assert_eq!(
            Samples::from_csv(text).unwrap_err(),
            SamplesError::NotANumber {
                line: 6,
                value: "x".to_owned(),
                hint: ""
            }
        );
    }

    #[test]
    fn written_csv_reads_back() {
        let samples = Samples::new(vec![
            BallSamples::new("blue 1", vec![3.1, 3.08]),
            BallSamples::new("green 2", vec![3.6, 3.63, 3.61]),
        ]);
        let text = samples.to_csv(5);
        assert!(
            text.starts_with("ball,weight_g\nblue 1,3.10000\n"),
            "{text}"
        );
        let back = Samples::from_csv(&text).unwrap();
        assert_eq!(back.balls()[1].weighings_g, vec![3.6, 3.63, 3.61]);
    }

    #[test]
    fn a_decimal_comma_gets_a_hint_and_a_short_row_its_line() {
        let error = Samples::from_csv("ball,weight_g\nred 1,2.29\nred 1,\"2,30\"\n").unwrap_err();
        assert_eq!(
            error.to_string(),
            "line 3: weight_g `2,30` is not a number of grams (write a decimal point, not a comma)"
        );
        let error = Samples::from_csv("ball,weight_g\nred 1,2.29\nred 1\n").unwrap_err();
        assert_eq!(
            error.to_string(),
            "line 3: 1 field(s) where the header has 2 (`ball,weight_g`)"
        );
        let error = Samples::from_csv("ball,weight_g\n,2.29\n").unwrap_err();
        assert_eq!(error, SamplesError::NoBall { line: 2 });
        let error = Samples::from_csv("ball,weight_g\n").unwrap_err();
        assert_eq!(error, SamplesError::NoWeighings { line: 1 });
        let error = Samples::from_csv("").unwrap_err();
        assert_eq!(
            error.to_string(),
            "line 1: the first line must be the header `ball,weight_g`, not ``"
        );
    }
}
