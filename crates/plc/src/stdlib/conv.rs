//! Type conversions (`*_TO_*`, `TO_*` and the implicit widening conversions).
//!
//! Rules (documented behaviour):
//! - integer to narrower integer: wraps (two's complement), like CODESYS;
//! - REAL to integer: rounds to nearest, ties to even (IEC 60559), then saturates to the
//!   64-bit range and wraps to the target width;
//! - TIME to integer: milliseconds; LTIME: nanoseconds; TOD to integer: milliseconds since
//!   midnight; DATE/DT to integer: seconds since 1970-01-01 (and back);
//! - to STRING: IEC literal text without type prefix for numbers (`INT_TO_STRING(5)` =
//!   `'5'`), with prefix for times (`'T#1s'`); from STRING: parsed, 0 when malformed.

use crate::check::Ty;
use crate::vm::format;

/// Whether `*_TO_*` exists between the two types.
pub fn convertible(from: &Ty, to: &Ty) -> bool {
    (from.is_elementary() && to.is_elementary())
        || (matches!(from, Ty::Enum(_)) && (to.is_int() || to.is_bits() || to.is_string()))
}

/// Integer-lane value of `from` as the integer-lane value of `to`.
pub fn int_to_int(v: i64, from: &Ty, to: &Ty) -> i64 {
    // to a common "scalar" first
    let scalar: i64 = match from {
        Ty::Time => v / 1_000_000,
        Ty::Tod => v / 1_000_000,
        Ty::Date | Ty::Dt => v.div_euclid(1_000_000_000),
        _ => v,
    };
    match to {
        Ty::Bool => i64::from(v != 0),
        Ty::Time | Ty::LTime => match from {
            Ty::Time | Ty::LTime | Ty::Tod | Ty::Date | Ty::Dt => v,
            _ if *to == Ty::Time => scalar.wrapping_mul(1_000_000),
            _ => scalar,
        },
        Ty::Tod => match from {
            Ty::Dt | Ty::Date => v.rem_euclid(86_400_000_000_000),
            Ty::Time | Ty::LTime | Ty::Tod => v.rem_euclid(86_400_000_000_000),
            _ => scalar
                .wrapping_mul(1_000_000)
                .rem_euclid(86_400_000_000_000),
        },
        Ty::Date => match from {
            Ty::Dt | Ty::Date => v - v.rem_euclid(86_400_000_000_000),
            _ => {
                let ns = scalar.wrapping_mul(1_000_000_000);
                ns - ns.rem_euclid(86_400_000_000_000)
            }
        },
        Ty::Dt => match from {
            Ty::Dt | Ty::Date => v,
            _ => scalar.wrapping_mul(1_000_000_000),
        },
        _ => to.wrap(scalar),
    }
}

/// Integer-lane value as f64.
pub fn int_to_f64(v: i64, from: &Ty) -> f64 {
    match from {
        Ty::ULInt | Ty::LWord => v as u64 as f64,
        Ty::Time | Ty::Tod => v as f64 / 1e6,
        Ty::Date | Ty::Dt => v as f64 / 1e9,
        _ => v as f64,
    }
}

/// Rounds to the cell precision of `to` (REAL is kept at f32 precision).
#[inline]
pub fn fit_real(v: f64, to: &Ty) -> f64 {
    if *to == Ty::Real {
        f64::from(v as f32)
    } else {
        v
    }
}

/// Real to integer-lane value of `to`.
pub fn real_to_int(v: f64, to: &Ty) -> i64 {
    match to {
        Ty::Bool => i64::from(v != 0.0),
        Ty::Time | Ty::Tod => (v * 1e6).round() as i64,
        Ty::Date | Ty::Dt => (v * 1e9).round() as i64,
        Ty::ULInt | Ty::LWord => {
            let r = v.round_ties_even();
            if r < 0.0 {
                r as i64
            } else {
                r as u64 as i64
            }
        }
        _ => to.wrap(v.round_ties_even() as i64),
    }
}

/// Real truncated toward zero to the integer `to`: saturates to the 64-bit range and wraps
/// to the target width, as [`real_to_int`] does after rounding.
pub fn real_trunc_to_int(v: f64, to: &Ty) -> i64 {
    let t = v.trunc();
    match to {
        Ty::ULInt if t >= 0.0 => t as u64 as i64,
        _ => to.wrap(t as i64),
    }
}

/// The value of the binary coded decimal `v` (one decimal digit per 4 bits), or the
/// first nibble that is no decimal digit.
pub fn bcd_decode(v: i64, bits: u32) -> Result<i64, i64> {
    let mut value: i64 = 0;
    for k in (0..bits / 4).rev() {
        let digit = v.checked_shr(4 * k).unwrap_or(0) & 0xF;
        if digit > 9 {
            return Err(digit);
        }
        value = value.wrapping_mul(10).wrapping_add(digit);
    }
    Ok(value)
}

/// `v` as binary coded decimal in `bits` bits, if it is not negative and has few enough
/// digits.
pub fn bcd_encode(v: i64, bits: u32) -> Option<i64> {
    let mut rest = u64::try_from(v).ok()?;
    let mut out: u64 = 0;
    for k in 0..bits / 4 {
        out |= (rest % 10).checked_shl(4 * k)?;
        rest /= 10;
    }
    (rest == 0).then_some(out as i64)
}

/// Integer-lane value as text.
pub fn int_to_string(v: i64, from: &Ty, enum_name: Option<&str>) -> String {
    match from {
        Ty::Bool => if v != 0 { "TRUE" } else { "FALSE" }.into(),
        Ty::ULInt | Ty::LWord => (v as u64).to_string(),
        Ty::Time => format::time(v, false),
        Ty::LTime => format::time(v, true),
        Ty::Tod => format::tod(v),
        Ty::Date => format::date(v),
        Ty::Dt => format::dt(v),
        Ty::Enum(_) => enum_name
            .map(str::to_string)
            .unwrap_or_else(|| v.to_string()),
        _ => v.to_string(),
    }
}

/// Parses text as an integer-lane value of `to` (0 when malformed).
pub fn string_to_int(s: &str, to: &Ty) -> i64 {
    let t = s.trim().replace('_', "");
    let up = t.to_ascii_uppercase();
    if *to == Ty::Bool {
        return i64::from(up == "TRUE" || up == "1");
    }
    if to.is_duration() || matches!(to, Ty::Tod | Ty::Date | Ty::Dt) {
        let body = up
            .split_once('#')
            .map(|(_, b)| b.to_string())
            .unwrap_or(up.clone());
        return match to {
            Ty::Time | Ty::LTime => crate::syntax::lexer::parse_duration(&body)
                .and_then(|v| i64::try_from(v).ok())
                .unwrap_or(0),
            _ => 0,
        };
    }
    let (neg, digits) = match up.strip_prefix('-') {
        Some(r) => (true, r.to_string()),
        None => (false, up.trim_start_matches('+').to_string()),
    };
    let v: i128 = if let Some((radix, d)) = digits.split_once('#') {
        radix
            .parse::<u32>()
            .ok()
            .filter(|r| matches!(r, 2 | 8 | 16))
            .and_then(|r| i128::from_str_radix(d, r).ok())
            .unwrap_or(0)
    } else {
        digits.parse::<i128>().unwrap_or(0)
    };
    let v = if neg { -v } else { v };
    to.wrap(v as i64)
}

/// Parses text as a real (0.0 when malformed).
pub fn string_to_real(s: &str) -> f64 {
    s.trim().replace('_', "").parse().unwrap_or(0.0)
}
