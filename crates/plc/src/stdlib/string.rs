//! String functions. Positions are 1-based and count characters, as in IEC 61131-3;
//! out-of-range arguments give the nearest sensible result instead of a fault.

fn clamp(n: i64, max: usize) -> usize {
    usize::try_from(n.max(0)).unwrap_or(usize::MAX).min(max)
}

/// Character count.
pub fn len(s: &str) -> i64 {
    i64::try_from(s.chars().count()).unwrap_or(i64::MAX)
}

/// First `n` characters.
pub fn left(s: &str, n: i64) -> String {
    s.chars().take(clamp(n, usize::MAX)).collect()
}

/// Last `n` characters.
pub fn right(s: &str, n: i64) -> String {
    let total = s.chars().count();
    let n = clamp(n, total);
    s.chars().skip(total - n).collect()
}

/// `n` characters starting at position `p`.
pub fn mid(s: &str, n: i64, p: i64) -> String {
    if p < 1 {
        return String::new();
    }
    s.chars()
        .skip(clamp(p - 1, usize::MAX))
        .take(clamp(n, usize::MAX))
        .collect()
}

/// `b` inserted after position `p` of `a`.
pub fn insert(a: &str, b: &str, p: i64) -> String {
    let total = a.chars().count();
    let p = clamp(p, total);
    let mut out: String = a.chars().take(p).collect();
    out.push_str(b);
    out.extend(a.chars().skip(p));
    out
}

/// `n` characters deleted from position `p`.
pub fn delete(a: &str, n: i64, p: i64) -> String {
    if p < 1 {
        return a.to_string();
    }
    let p = clamp(p - 1, usize::MAX);
    let n = clamp(n, usize::MAX);
    a.chars()
        .enumerate()
        .filter(|(i, _)| *i < p || *i >= p.saturating_add(n))
        .map(|(_, c)| c)
        .collect()
}

/// `n` characters of `a` from position `p` replaced by `b`.
pub fn replace(a: &str, b: &str, n: i64, p: i64) -> String {
    let p1 = clamp(p - 1, a.chars().count());
    let n = clamp(n, usize::MAX);
    let mut out: String = a.chars().take(p1).collect();
    out.push_str(b);
    out.extend(a.chars().skip(p1.saturating_add(n)));
    out
}

/// 1-based character position of the first `b` in `a`, 0 if absent.
pub fn find(a: &str, b: &str) -> i64 {
    if b.is_empty() {
        return 0;
    }
    match a.find(b) {
        Some(byte) => len(a.get(..byte).unwrap_or("")) + 1,
        None => 0,
    }
}

/// Truncates to at most `n` characters (assignment to `STRING[n]`).
pub fn truncate(mut s: String, n: u32) -> String {
    if s.len() > n as usize {
        if let Some((idx, _)) = s.char_indices().nth(n as usize) {
            s.truncate(idx);
        }
    }
    s
}
