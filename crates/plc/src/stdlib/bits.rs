//! Bit-string functions: SHL, SHR, ROL, ROR on a value of `bits` width.

fn mask(bits: u32) -> u64 {
    if bits >= 64 {
        u64::MAX
    } else {
        (1u64 << bits) - 1
    }
}

/// Shift left, zeros in; counts of the width or more give 0.
pub fn shl(v: i64, n: i64, bits: u32) -> i64 {
    if n < 0 || n >= i64::from(bits) {
        return 0;
    }
    (((v as u64) << n) & mask(bits)) as i64
}

/// Logical shift right.
pub fn shr(v: i64, n: i64, bits: u32) -> i64 {
    if n < 0 || n >= i64::from(bits) {
        return 0;
    }
    (((v as u64) & mask(bits)) >> n) as i64
}

/// Rotate left within the width.
pub fn rol(v: i64, n: i64, bits: u32) -> i64 {
    let b = i64::from(bits.max(1));
    let n = n.rem_euclid(b) as u32;
    let x = (v as u64) & mask(bits);
    if n == 0 {
        return x as i64;
    }
    (((x << n) | (x >> (bits - n))) & mask(bits)) as i64
}

/// Rotate right within the width.
pub fn ror(v: i64, n: i64, bits: u32) -> i64 {
    let b = i64::from(bits.max(1));
    rol(v, b - n.rem_euclid(b), bits)
}
