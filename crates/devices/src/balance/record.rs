//! The Sartorius 1612MP8 balance's 15-character record (the sorting-lab thesis,
//! section 7): its layout, the reference parsing (bit 7 masked, resynchronisation on LF,
//! the sign, the decimal point, the digits, the stability flag), the character-class
//! checks and the agreement of two parses the platform adds, and the record a simulator
//! sends.
//!
//! ```text
//!  pos  1     2   3-4        5-9              10          11  12        13  14  15
//!       sign  ' ' ' '/digit  digit/'.'        ' '/'.'     ' ' ' '/'g'   ' ' CR  LF
//!       +2.345 g unstable:  2B 20 20 20 32 2E 33 34 35 20 20 20 20 0D 0A
//! ```

use std::fmt;

/// A record's length.
pub const RECORD_LEN: usize = 15;

/// What a legal record says.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Reading {
    /// The weight in grams (negative after zeroing with a load that was then removed).
    pub weight_g: f64,
    /// The balance calls the value stable (`g` in position 12).
    pub stable: bool,
}

/// Why a record is not legal.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum RecordError {
    /// No LF among the 15 characters: the window holds no whole record.
    #[error("no LF in the record")]
    NoLineFeed,
    /// A character not allowed at its position (section 7.1), 1-based after
    /// resynchronisation.
    #[error("character 0x{byte:02X} not allowed at position {position}")]
    Illegal {
        /// 1-based position.
        position: usize,
        /// The character (bit 7 masked).
        byte: u8,
    },
    /// More than one decimal point, or none with no digit.
    #[error("the weight has no number")]
    NoNumber,
}

/// Bit 7 of every octet cleared: the balance sends 7-bit characters, the line reads 8
/// with the parity position (unused, undefined) as bit 7.
pub fn mask(window: &[u8; RECORD_LEN]) -> [u8; RECORD_LEN] {
    window.map(|byte| byte & 0x7F)
}

/// The window turned so that it ends with its LF (FC50's step 2): a gateway buffer
/// shifted by a record sent while it was being configured is read in order again.
pub fn resynchronise(window: &[u8; RECORD_LEN]) -> Result<[u8; RECORD_LEN], RecordError> {
    let lf = window
        .iter()
        .position(|&byte| byte == b'\n')
        .ok_or(RecordError::NoLineFeed)?;
    let mut record = *window;
    record.rotate_left((lf + 1) % RECORD_LEN);
    Ok(record)
}

/// Whether `byte` may stand at 1-based `position` of a record (section 7.1; positions 3
/// and 10 also take a point, BS-A4).
fn allowed(position: usize, byte: u8) -> bool {
    let digit = byte.is_ascii_digit();
    match position {
        1 => matches!(byte, b'+' | b'-' | b' '),
        2 | 11 | 13 => byte == b' ',
        3 | 4 | 10 => byte == b' ' || digit || byte == b'.',
        5..=9 => digit || byte == b'.',
        12 => matches!(byte, b' ' | b'g'),
        14 => byte == b'\r',
        15 => byte == b'\n',
        _ => false,
    }
}

/// Parses a 15-octet window as FC50 does, with the platform's checks: bit 7 masked,
/// turned to end with its LF, every character checked against its position, the point
/// looked for in positions 3-10 (none: whole grams; in position 10: whole grams too).
pub fn parse(window: &[u8; RECORD_LEN]) -> Result<Reading, RecordError> {
    let record = resynchronise(&mask(window))?;
    for (index, &byte) in record.iter().enumerate() {
        if !allowed(index + 1, byte) {
            return Err(RecordError::Illegal {
                position: index + 1,
                byte,
            });
        }
    }
    // Positions 3-10 (indices 2..10): digits around at most one point.
    let field = record.get(2..10).ok_or(RecordError::NoNumber)?;
    let points = field.iter().filter(|&&b| b == b'.').count();
    if points > 1 || !field.iter().any(u8::is_ascii_digit) {
        return Err(RecordError::NoNumber);
    }
    let point = field.iter().position(|&b| b == b'.');
    let mut value = 0.0;
    for (index, &byte) in field.iter().enumerate() {
        if !byte.is_ascii_digit() {
            continue;
        }
        // A digit's weight by its distance from the point (units just before it).
        let exponent = match point {
            Some(p) if index < p => i32::try_from(p - index - 1).unwrap_or(0),
            Some(p) => -i32::try_from(index - p).unwrap_or(0),
            None => {
                // No point: whole grams, the last digit the units.
                let last = field.iter().rposition(u8::is_ascii_digit).unwrap_or(index);
                i32::try_from(last - index).unwrap_or(0)
            }
        };
        value += f64::from(byte - b'0') * 10f64.powi(exponent);
    }
    let sign = if record.first() == Some(&b'-') {
        -1.0
    } else {
        1.0
    };
    Ok(Reading {
        // Rounded well below the balance's 0.01 mg: sums of powers of ten are not exact.
        weight_g: (sign * value * 1e7).round() / 1e7,
        stable: record.get(11) == Some(&b'g'),
    })
}

/// The record a balance sends for `weight_g` (three decimals, the last digit switched
/// off as the thesis's balance had it) and `stable`; weights beyond the 7 characters of
/// positions 3-9 are clamped to ±999.999 g (the balance weighs up to 160 g).
pub fn format(weight_g: f64, stable: bool) -> [u8; RECORD_LEN] {
    let clamped = if weight_g.is_finite() {
        weight_g.clamp(-999.999, 999.999)
    } else {
        0.0
    };
    let magnitude = format!("{:>7.3}", clamped.abs());
    let sign = if clamped < 0.0 && magnitude.trim() != "0.000" {
        b'-'
    } else {
        b'+'
    };
    let mut record = [b' '; RECORD_LEN];
    record[0] = sign;
    for (slot, byte) in record.iter_mut().skip(2).zip(magnitude.bytes().take(7)) {
        *slot = byte;
    }
    record[11] = if stable { b'g' } else { b' ' };
    record[13] = b'\r';
    record[14] = b'\n';
    record
}

/// Accepts a value only when two consecutive parses agree within `tolerance_g` (BS-A5):
/// a window without time consistency may join the tail of one record to the head of the
/// next, which a single parse cannot tell.
#[derive(Debug, Clone)]
pub struct Agreement {
    tolerance_g: f64,
    last: Option<Reading>,
}

impl Agreement {
    /// Agreement within one digit of the record (1 mg).
    pub fn new() -> Agreement {
        Agreement::within(0.001)
    }

    /// Agreement within `tolerance_g` grams.
    pub fn within(tolerance_g: f64) -> Agreement {
        Agreement {
            tolerance_g,
            last: None,
        }
    }

    /// Takes a parse (an illegal window breaks the chain); the value once two agree.
    pub fn take(&mut self, parsed: Result<Reading, RecordError>) -> Option<Reading> {
        let Ok(reading) = parsed else {
            self.last = None;
            return None;
        };
        let agreed = self.last.filter(|last| {
            (last.weight_g - reading.weight_g).abs() <= self.tolerance_g + 1e-9
                && last.stable == reading.stable
        });
        self.last = Some(reading);
        agreed.map(|_| reading)
    }
}

impl Default for Agreement {
    fn default() -> Agreement {
        Agreement::new()
    }
}

impl fmt::Display for Reading {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{:+.3} g{}",
            self.weight_g,
            if self.stable { " stable" } else { "" }
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn hex(text: &str) -> [u8; RECORD_LEN] {
        let bytes: Vec<u8> = text
            .split_whitespace()
            .map(|h| u8::from_str_radix(h, 16).unwrap())
            .collect();
        bytes.try_into().unwrap()
    }

    fn reading(weight_g: f64, stable: bool) -> Result<Reading, RecordError> {
        Ok(Reading { weight_g, stable })
    }

    #[test]
    fn the_spec_vectors_b1_to_b9() {
        let vectors = [
            (
                "2B 20 20 20 32 2E 33 34 35 20 20 20 20 0D 0A",
                reading(2.345, false),
            ),
            (
                "2D 20 20 20 30 2E 30 31 32 20 20 20 20 0D 0A",
                reading(-0.012, false),
            ),
            (
                "2B 20 20 20 33 2E 30 39 31 20 20 67 20 0D 0A",
                reading(3.091, true),
            ),
            (
                "33 2E 30 39 31 20 20 67 20 0D 0A 2B 20 20 20",
                reading(3.091, true),
            ),
            (
                "2B 20 20 20 B2 AE 33 34 B5 20 20 20 20 0D 0A",
                reading(2.345, false),
            ),
            (
                "20 20 20 20 30 2E 30 30 30 20 20 67 20 0D 0A",
                reading(0.0, true),
            ),
            (
                "2B 20 31 35 39 2E 39 39 39 20 20 20 20 0D 0A",
                reading(159.999, false),
            ),
            (
                "2B 20 20 20 32 2E 33 34 35 20 20 20 20 0D 20",
                Err(RecordError::NoLineFeed),
            ),
            (
                "2B 20 20 20 32 2C 33 34 35 20 20 20 20 0D 0A",
                Err(RecordError::Illegal {
                    position: 6,
                    byte: 0x2C,
                }),
            ),
        ];
        for (index, (bytes, expected)) in vectors.iter().enumerate() {
            assert_eq!(parse(&hex(bytes)), *expected, "B{}", index + 1);
        }
    }

    #[test]
    fn a_point_in_position_10_or_none_is_whole_grams() {
        // BS-A4: the switchable last digit's position may hold the point.
        assert_eq!(parse(b"+   12345.   \r\n").map(|r| r.weight_g), Ok(12345.0));
        let whole = parse(b"+   12345  g \r\n");
        assert_eq!(
            whole,
            Ok(Reading {
                weight_g: 12345.0,
                stable: true
            })
        );
        assert_eq!(parse(b"+   1.2.3    \r\n"), Err(RecordError::NoNumber));
    }

    #[test]
    fn formatted_records_parse_back() {
        for (weight, stable) in [
            (2.345, false),
            (-0.012, false),
            (159.999, true),
            (0.0, true),
        ] {
            let record = format(weight, stable);
            assert_eq!(
                parse(&record),
                Ok(Reading {
                    weight_g: weight,
                    stable
                }),
                "{record:?}"
            );
        }
        assert_eq!(&format(2.345, false), b"+   2.345    \r\n");
        assert_eq!(&format(159.999, false), b"+ 159.999    \r\n");
    }

    #[test]
    fn two_parses_must_agree() {
        let mut agreement = Agreement::new();
        assert_eq!(agreement.take(reading(2.345, false)), None);
        assert_eq!(
            agreement.take(reading(2.346, false)).map(|r| r.weight_g),
            Some(2.346)
        );
        assert_eq!(agreement.take(reading(2.400, false)), None);
        assert_eq!(agreement.take(Err(RecordError::NoLineFeed)), None);
        assert_eq!(agreement.take(reading(2.400, false)), None);
        assert_eq!(agreement.take(reading(2.400, true)), None);
        assert!(agreement.take(reading(2.400, true)).is_some());
    }

    proptest! {
        #[test]
        fn any_window_parses_or_errs(window in proptest::array::uniform15(any::<u8>())) {
            let _ = parse(&window);
        }

        #[test]
        fn every_rotation_of_a_record_reads_the_same(
            milligrams in -999_999i64..=999_999,
            stable in any::<bool>(),
            turn in 0usize..RECORD_LEN,
            high in any::<u16>(),
        ) {
            let weight = milligrams as f64 / 1000.0;
            let mut window = format(weight, stable);
            window.rotate_left(turn);
            // bit 7 set at random on some characters: masked away
            for (index, byte) in window.iter_mut().enumerate() {
                if high >> (index % 16) & 1 == 1 {
                    *byte |= 0x80;
                }
            }
            let expected = if milligrams == 0 { 0.0 } else { weight };
            prop_assert_eq!(parse(&window), Ok(Reading { weight_g: expected, stable }));
        }
    }
}
