//! Numeric functions: ABS, SQRT, LN, LOG, EXP, trigonometry, EXPT, ROUND, TRUNC, MAX/MIN/LIMIT.

/// `ROUND`: to nearest, ties away from zero (as TIA Portal and CODESYS OSCAT do).
pub fn round(v: f64) -> f64 {
    v.round()
}

/// `EXPT(base, exponent)` for a real base and an integer exponent.
pub fn expt_int(base: f64, exp: i64) -> f64 {
    match i32::try_from(exp) {
        Ok(e) => base.powi(e),
        Err(_) => base.powf(exp as f64),
    }
}

/// Integer power with wrapping.
pub fn ipow(mut base: i64, mut exp: i64) -> i64 {
    if exp < 0 {
        return match base {
            1 => 1,
            -1 => {
                if exp % 2 == 0 {
                    1
                } else {
                    -1
                }
            }
            _ => 0,
        };
    }
    let mut acc: i64 = 1;
    while exp > 0 {
        if exp & 1 == 1 {
            acc = acc.wrapping_mul(base);
        }
        base = base.wrapping_mul(base);
        exp >>= 1;
    }
    acc
}
