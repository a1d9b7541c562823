//! Values in IEC 61131-3 literal syntax (`TRUE`, `T#1h2m`, `TOD#10:00:00`, `'text'`).

use crate::syntax::lexer::civil_from_days;

const NS_PER_DAY: i64 = 86_400_000_000_000;

/// `T#1h2m3s4ms`, `T#0s`, `T#-5s`; `LT#` when `long`.
pub fn time(ns: i64, long: bool) -> String {
    let prefix = if long { "LT#" } else { "T#" };
    if ns == 0 {
        return format!("{prefix}0s");
    }
    let mut out = String::from(prefix);
    if ns < 0 {
        out.push('-');
    }
    let mut rest = ns.unsigned_abs();
    for (unit, scale) in [
        ("d", 86_400_000_000_000u64),
        ("h", 3_600_000_000_000),
        ("m", 60_000_000_000),
        ("s", 1_000_000_000),
        ("ms", 1_000_000),
        ("us", 1_000),
        ("ns", 1),
    ] {
        let q = rest / scale;
        if q > 0 {
            out.push_str(&format!("{q}{unit}"));
            rest -= q * scale;
        }
    }
    out
}

fn hms(ns: i64) -> String {
    let ns = ns.rem_euclid(NS_PER_DAY);
    let h = ns / 3_600_000_000_000;
    let m = ns / 60_000_000_000 % 60;
    let s = ns / 1_000_000_000 % 60;
    let frac = ns % 1_000_000_000;
    if frac == 0 {
        format!("{h:02}:{m:02}:{s:02}")
    } else {
        let f = format!("{frac:09}");
        format!("{h:02}:{m:02}:{s:02}.{}", f.trim_end_matches('0'))
    }
}

fn ymd(ns: i64) -> String {
    let (y, m, d) = civil_from_days(ns.div_euclid(NS_PER_DAY));
    format!("{y:04}-{m:02}-{d:02}")
}

/// `TOD#10:00:00`
pub fn tod(ns: i64) -> String {
    format!("TOD#{}", hms(ns))
}

/// `D#2024-05-01`
pub fn date(ns: i64) -> String {
    format!("D#{}", ymd(ns))
}

/// `DT#2024-05-01-10:00:00`
pub fn dt(ns: i64) -> String {
    format!("DT#{}-{}", ymd(ns), hms(ns))
}

/// A real: shortest round-trip form with at least one decimal (`1.0`, `0.1`, `1.5E+20`).
pub fn real(v: f64, single: bool) -> String {
    if v.is_nan() {
        return "NaN".into();
    }
    if v.is_infinite() {
        return if v > 0.0 { "INF".into() } else { "-INF".into() };
    }
    let a = v.abs();
    if a != 0.0 && !(1e-5..1e15).contains(&a) {
        let e = if single {
            format!("{:e}", v as f32)
        } else {
            format!("{v:e}")
        };
        let (m, x) = e.split_once('e').unwrap_or((e.as_str(), "0"));
        let m = if m.contains('.') {
            m.to_string()
        } else {
            format!("{m}.0")
        };
        let x = if x.starts_with('-') {
            x.to_string()
        } else {
            format!("+{x}")
        };
        return format!("{m}E{x}");
    }
    let s = if single {
        format!("{}", v as f32)
    } else {
        format!("{v}")
    };
    if s.contains('.') {
        s
    } else {
        format!("{s}.0")
    }
}

/// `'it$'s'` (or `"..."` when wide), with `$` escapes.
pub fn string(s: &str, wide: bool) -> String {
    let q = if wide { '"' } else { '\'' };
    let mut out = String::new();
    out.push(q);
    for c in s.chars() {
        match c {
            '$' => out.push_str("$$"),
            '\n' => out.push_str("$N"),
            '\r' => out.push_str("$R"),
            '\t' => out.push_str("$T"),
            '\x0c' => out.push_str("$P"),
            c if c == q => {
                out.push('$');
                out.push(c);
            }
            c if (c as u32) < 0x20 => out.push_str(&format!("${:02X}", c as u32)),
            c => out.push(c),
        }
    }
    out.push(q);
    out
}
