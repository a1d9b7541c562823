//! The lexer: source text to tokens. Keywords are case-insensitive and are lexed as
//! identifiers; the parser recognises them by their upper-case spelling.

use super::source::{FileId, Span};
use crate::diagnostics::{Code, Diagnostic};

/// What a token is.
#[derive(Debug, Clone, PartialEq)]
pub enum Tok {
    /// Identifier or keyword (original spelling).
    Ident(String),
    /// `#name`: a Siemens SCL local variable.
    HashIdent(String),
    /// `"name"`: an SCL quoted name, or a WSTRING literal (decided by the checker).
    DqString(String),
    /// `'text'`
    SqString(String),
    /// Integer literal (decimal or based), magnitude only.
    Int(u128),
    /// Real literal.
    Real(f64),
    /// `TYPE#` prefix of a typed literal for an elementary type (upper-case name).
    TypePrefix(String),
    /// `T#...`/`LT#...`: nanoseconds; bool = long (LTIME).
    Time(i128, bool),
    /// `D#...`: nanoseconds since 1970-01-01.
    Date(i64),
    /// `TOD#...`: nanoseconds since midnight.
    Tod(i64),
    /// `DT#...`: nanoseconds since 1970-01-01T00:00.
    Dt(i64),
    /// `%IX0.0` and friends (text after `%`, upper-case).
    Direct(String),
    /// Punctuation or operator.
    Punct(&'static str),
    /// End of input.
    Eof,
}

/// A token with its span.
#[derive(Debug, Clone, PartialEq)]
pub struct Token {
    /// The token.
    pub tok: Tok,
    /// Where.
    pub span: Span,
}

const PUNCTS: [&str; 24] = [
    ":=", "=>", "<=", ">=", "<>", "**", "..", "+", "-", "*", "/", "=", "<", ">", "&", "(", ")",
    "[", "]", ",", ";", ":", ".", "^",
];

const ELEMENTARY: [&str; 31] = [
    "BOOL",
    "SINT",
    "INT",
    "DINT",
    "LINT",
    "USINT",
    "UINT",
    "UDINT",
    "ULINT",
    "BYTE",
    "WORD",
    "DWORD",
    "LWORD",
    "REAL",
    "LREAL",
    "STRING",
    "WSTRING",
    "CHAR",
    "WCHAR",
    "TIME",
    "LTIME",
    "DATE",
    "LDATE",
    "TOD",
    "LTOD",
    "TIME_OF_DAY",
    "LTIME_OF_DAY",
    "DT",
    "LDT",
    "DATE_AND_TIME",
    "LDATE_AND_TIME",
];

/// Splits `text` into tokens. Lexing errors are reported and skipped, so the parser always
/// gets a token stream ending in [`Tok::Eof`].
pub fn lex(file: FileId, text: &str, diags: &mut Vec<Diagnostic>) -> Vec<Token> {
    let mut lx = Lexer {
        file,
        src: text.as_bytes(),
        text,
        pos: 0,
        out: Vec::new(),
        diags,
    };
    lx.run();
    let end = text.len();
    lx.out.push(Token {
        tok: Tok::Eof,
        span: Span::new(file, end..end),
    });
    lx.out
}

struct Lexer<'a, 'd> {
    file: FileId,
    src: &'a [u8],
    text: &'a str,
    pos: usize,
    out: Vec<Token>,
    diags: &'d mut Vec<Diagnostic>,
}

fn is_ident_start(c: u8) -> bool {
    c.is_ascii_alphabetic() || c == b'_' || c >= 0x80
}
fn is_ident_char(c: u8) -> bool {
    c.is_ascii_alphanumeric() || c == b'_' || c >= 0x80
}

impl Lexer<'_, '_> {
    fn peek(&self, k: usize) -> u8 {
        self.src.get(self.pos + k).copied().unwrap_or(0)
    }
    fn span(&self, start: usize) -> Span {
        Span::new(self.file, start..self.pos)
    }
    fn push(&mut self, tok: Tok, start: usize) {
        let span = self.span(start);
        self.out.push(Token { tok, span });
    }
    fn error(&mut self, code: Code, start: usize, msg: impl Into<String>) {
        let span = Span::new(
            self.file,
            start..self.pos.max(start + 1).min(self.src.len()),
        );
        self.diags.push(Diagnostic::error(code, span, msg));
    }
    fn slice(&self, a: usize, b: usize) -> &str {
        self.text.get(a..b).unwrap_or("")
    }

    fn run(&mut self) {
        while self.pos < self.src.len() {
            let c = self.peek(0);
            let start = self.pos;
            if c.is_ascii_whitespace() {
                self.pos += 1;
            } else if c == b'(' && self.peek(1) == b'*' {
                self.block_comment(b'(', b'*', b')');
            } else if c == b'/' && self.peek(1) == b'*' {
                self.block_comment(b'/', b'*', b'/');
            } else if c == b'/' && self.peek(1) == b'/' {
                while self.pos < self.src.len() && self.peek(0) != b'\n' {
                    self.pos += 1;
                }
            } else if c == b'{' {
                // pragma / attribute: skipped
                while self.pos < self.src.len() && self.peek(0) != b'}' {
                    self.pos += 1;
                }
                if self.pos >= self.src.len() {
                    self.error(Code::Unterminated, start, "unterminated pragma");
                }
                self.pos += 1;
            } else if is_ident_start(c) {
                self.ident();
            } else if c.is_ascii_digit() {
                self.number(start);
            } else if c == b'\'' || c == b'"' {
                self.string(c);
            } else if c == b'#' && is_ident_start(self.peek(1)) {
                self.pos += 1;
                let s = self.pos;
                while is_ident_char(self.peek(0)) {
                    self.pos += 1;
                }
                let name = self.slice(s, self.pos).to_string();
                self.push(Tok::HashIdent(name), start);
            } else if c == b'#' && self.peek(1) == b'"' {
                // #"quoted local"
                self.pos += 1;
                self.string(b'"');
                if let Some(Token {
                    tok: Tok::DqString(s),
                    ..
                }) = self.out.pop()
                {
                    self.push(Tok::HashIdent(s), start);
                }
            } else if c == b'%' {
                self.pos += 1;
                // a dot belongs to the address only before a digit (`%IX0.3`); in
                // `w.%D1.%B0` it starts the next access
                while self.peek(0).is_ascii_alphanumeric()
                    || (self.peek(0) == b'.' && self.peek(1).is_ascii_digit())
                    || self.peek(0) == b'*'
                {
                    self.pos += 1;
                }
                let text = self.slice(start + 1, self.pos).to_ascii_uppercase();
                self.push(Tok::Direct(text), start);
            } else if let Some(p) = PUNCTS
                .iter()
                .find(|p| self.src.get(self.pos..self.pos + p.len()) == Some(p.as_bytes()))
            {
                // `1..5`: make sure `..` is not taken as part of a number (handled in number)
                self.pos += p.len();
                self.push(Tok::Punct(p), start);
            } else {
                let ch = self.text.get(self.pos..).and_then(|s| s.chars().next());
                self.pos += ch.map(char::len_utf8).unwrap_or(1);
                self.error(
                    Code::UnexpectedCharacter,
                    start,
                    format!("unexpected character '{}'", ch.unwrap_or('?')),
                );
            }
        }
    }

    fn block_comment(&mut self, open0: u8, open1: u8, close: u8) {
        let start = self.pos;
        self.pos += 2;
        let mut depth = 1;
        while self.pos < self.src.len() {
            if self.peek(0) == open0 && self.peek(1) == open1 {
                depth += 1;
                self.pos += 2;
            } else if self.peek(0) == open1 && self.peek(1) == close {
                depth -= 1;
                self.pos += 2;
                if depth == 0 {
                    return;
                }
            } else {
                self.pos += 1;
            }
        }
        self.error(Code::Unterminated, start, "unterminated comment");
    }

    fn ident(&mut self) {
        let start = self.pos;
        while is_ident_char(self.peek(0)) {
            self.pos += 1;
        }
        let name = self.slice(start, self.pos).to_string();
        if self.peek(0) == b'#' {
            let upper = name.to_ascii_uppercase();
            match upper.as_str() {
                "T" | "TIME" | "LT" | "LTIME" => {
                    self.pos += 1;
                    self.time_literal(start, upper.starts_with('L'));
                    return;
                }
                "D" | "DATE" | "LDATE" | "LD" => {
                    self.pos += 1;
                    self.date_like(start, 0);
                    return;
                }
                "TOD" | "TIME_OF_DAY" | "LTOD" | "LTIME_OF_DAY" => {
                    self.pos += 1;
                    self.date_like(start, 1);
                    return;
                }
                "DT" | "DATE_AND_TIME" | "LDT" | "LDATE_AND_TIME" => {
                    self.pos += 1;
                    self.date_like(start, 2);
                    return;
                }
                _ if ELEMENTARY.contains(&upper.as_str()) => {
                    self.pos += 1;
                    self.push(Tok::TypePrefix(upper), start);
                    return;
                }
                _ => {}
            }
        }
        self.push(Tok::Ident(name), start);
    }

    fn literal_text(&mut self) -> (usize, String) {
        let s = self.pos;
        if self.peek(0) == b'-' || self.peek(0) == b'+' {
            self.pos += 1;
        }
        while self.peek(0).is_ascii_alphanumeric()
            || matches!(self.peek(0), b'_' | b'.' | b':' | b'-')
        {
            self.pos += 1;
        }
        (s, self.slice(s, self.pos).replace('_', ""))
    }

    fn time_literal(&mut self, start: usize, long: bool) {
        let (_, text) = self.literal_text();
        match parse_duration(&text) {
            Some(ns) => self.push(Tok::Time(ns, long), start),
            None => {
                self.error(
                    Code::BadLiteral,
                    start,
                    format!("malformed time literal '{text}'"),
                );
                self.push(Tok::Time(0, long), start);
            }
        }
    }

    fn date_like(&mut self, start: usize, kind: u8) {
        let (_, text) = self.literal_text();
        let parsed = match kind {
            0 => parse_date(&text).map(Tok::Date),
            1 => parse_tod(&text).map(Tok::Tod),
            _ => parse_dt(&text).map(Tok::Dt),
        };
        match parsed {
            Some(t) => self.push(t, start),
            None => {
                self.error(
                    Code::BadLiteral,
                    start,
                    format!("malformed date/time literal '{text}'"),
                );
                self.push(Tok::Int(0), start);
            }
        }
    }

    fn digits(&mut self, radix: u32) -> String {
        let s = self.pos;
        while (self.peek(0) as char).is_digit(radix) || self.peek(0) == b'_' {
            self.pos += 1;
        }
        self.slice(s, self.pos).replace('_', "")
    }

    fn number(&mut self, start: usize) {
        let int_part = self.digits(10);
        if self.peek(0) == b'#' {
            let radix: u32 = int_part.parse().unwrap_or(0);
            if matches!(radix, 2 | 8 | 16) {
                self.pos += 1;
                let digits = self.digits(radix);
                match u128::from_str_radix(&digits, radix) {
                    Ok(v) => self.push(Tok::Int(v), start),
                    Err(_) => {
                        self.error(Code::BadLiteral, start, "malformed based literal");
                        self.push(Tok::Int(0), start);
                    }
                }
            } else {
                self.pos += 1;
                self.error(
                    Code::BadLiteral,
                    start,
                    format!("unsupported base {int_part}"),
                );
                self.push(Tok::Int(0), start);
            }
            return;
        }
        let mut is_real = false;
        let mut text = int_part;
        if self.peek(0) == b'.' && self.peek(1).is_ascii_digit() {
            is_real = true;
            self.pos += 1;
            text.push('.');
            text.push_str(&self.digits(10));
        }
        if matches!(self.peek(0), b'e' | b'E')
            && (self.peek(1).is_ascii_digit()
                || (matches!(self.peek(1), b'+' | b'-') && self.peek(2).is_ascii_digit()))
        {
            is_real = true;
            self.pos += 1;
            text.push('e');
            if matches!(self.peek(0), b'+' | b'-') {
                text.push(self.peek(0) as char);
                self.pos += 1;
            }
            text.push_str(&self.digits(10));
        }
        if is_real {
            let v = text.parse().unwrap_or(0.0);
            self.push(Tok::Real(v), start);
        } else {
            match text.parse::<u128>() {
                Ok(v) => self.push(Tok::Int(v), start),
                Err(_) => {
                    self.error(Code::BadLiteral, start, "integer literal too large");
                    self.push(Tok::Int(0), start);
                }
            }
        }
    }

    fn string(&mut self, quote: u8) {
        let start = self.pos;
        self.pos += 1;
        let mut s = String::new();
        loop {
            let c = self.peek(0);
            if self.pos >= self.src.len() || c == b'\n' {
                self.error(Code::Unterminated, start, "unterminated string literal");
                break;
            }
            if c == quote {
                self.pos += 1;
                break;
            }
            if c == b'$' {
                let n = self.peek(1);
                self.pos += 2;
                match n.to_ascii_uppercase() {
                    b'$' => s.push('$'),
                    b'\'' => s.push('\''),
                    b'"' => s.push('"'),
                    b'L' | b'N' => s.push('\n'),
                    b'P' => s.push('\x0c'),
                    b'R' => s.push('\r'),
                    b'T' => s.push('\t'),
                    h if h.is_ascii_hexdigit() => {
                        let hex = self.slice(self.pos - 1, (self.pos + 1).min(self.src.len()));
                        match u8::from_str_radix(hex, 16) {
                            Ok(v) => {
                                s.push(char::from(v));
                                self.pos += 1;
                            }
                            Err(_) => self.error(Code::BadLiteral, start, "bad $ escape"),
                        }
                    }
                    _ => self.error(Code::BadLiteral, start, "bad $ escape"),
                }
                continue;
            }
            let ch = self
                .text
                .get(self.pos..)
                .and_then(|t| t.chars().next())
                .unwrap_or('?');
            s.push(ch);
            self.pos += ch.len_utf8();
        }
        let tok = if quote == b'\'' {
            Tok::SqString(s)
        } else {
            Tok::DqString(s)
        };
        self.push(tok, start);
    }
}

/// Parses `1h2m3s4ms`, `0.25s`, `-5s` (without the `T#`) to nanoseconds.
pub fn parse_duration(text: &str) -> Option<i128> {
    let (neg, mut rest) = match text.strip_prefix('-') {
        Some(r) => (true, r),
        None => (false, text.strip_prefix('+').unwrap_or(text)),
    };
    if rest.is_empty() {
        return None;
    }
    let lower = rest.to_ascii_lowercase();
    rest = &lower;
    let mut total: f64 = 0.0;
    let mut exact: i128 = 0;
    let mut all_exact = true;
    while !rest.is_empty() {
        let n = rest
            .find(|c: char| !(c.is_ascii_digit() || c == '.'))
            .unwrap_or(rest.len());
        let (num, tail) = rest.split_at(n);
        if num.is_empty() {
            return None;
        }
        let u = tail
            .find(|c: char| c.is_ascii_digit())
            .unwrap_or(tail.len());
        let (unit, tail2) = tail.split_at(u);
        let scale: i128 = match unit {
            "d" => 86_400_000_000_000,
            "h" => 3_600_000_000_000,
            "m" => 60_000_000_000,
            "s" => 1_000_000_000,
            "ms" => 1_000_000,
            "us" => 1_000,
            "ns" => 1,
            _ => return None,
        };
        if num.contains('.') {
            all_exact = false;
            total += num.parse::<f64>().ok()? * scale as f64;
        } else {
            let v: i128 = num.parse().ok()?;
            exact = exact.checked_add(v.checked_mul(scale)?)?;
        }
        rest = tail2;
    }
    let ns = if all_exact {
        exact
    } else {
        exact + total.round() as i128
    };
    Some(if neg { -ns } else { ns })
}

/// Days since 1970-01-01 of a proleptic Gregorian date.
pub fn days_from_civil(y: i64, m: u32, d: u32) -> i64 {
    let y = if m <= 2 { y - 1 } else { y };
    let era = y.div_euclid(400);
    let yoe = y - era * 400;
    let m = i64::from(m);
    let doy = (153 * (if m > 2 { m - 3 } else { m + 9 }) + 2) / 5 + i64::from(d) - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    era * 146_097 + doe - 719_468
}

/// (year, month, day) of days since 1970-01-01.
pub fn civil_from_days(z: i64) -> (i64, u32, u32) {
    let z = z + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36524 - doe / 146_096) / 365;
    let y = yoe + era * 400;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    (if m <= 2 { y + 1 } else { y }, m, d)
}

const DAY_NS: i64 = 86_400_000_000_000;

fn parse_date(text: &str) -> Option<i64> {
    let mut it = text.splitn(3, '-');
    let y: i64 = it.next()?.parse().ok()?;
    let m: u32 = it.next()?.parse().ok()?;
    let d: u32 = it.next()?.parse().ok()?;
    if !(1..=12).contains(&m) || !(1..=31).contains(&d) {
        return None;
    }
    days_from_civil(y, m, d).checked_mul(DAY_NS)
}

fn parse_tod(text: &str) -> Option<i64> {
    let mut it = text.splitn(3, ':');
    let h: i64 = it.next()?.parse().ok()?;
    let m: i64 = it.next()?.parse().ok()?;
    let s: f64 = it.next().unwrap_or("0").parse().ok()?;
    if !(0..24).contains(&h) || !(0..60).contains(&m) || !(0.0..60.0).contains(&s) {
        return None;
    }
    Some(h * 3_600_000_000_000 + m * 60_000_000_000 + (s * 1e9).round() as i64)
}

fn parse_dt(text: &str) -> Option<i64> {
    // YYYY-MM-DD-hh:mm:ss
    let idx = text.match_indices('-').nth(2)?.0;
    let date = parse_date(text.get(..idx)?)?;
    let tod = parse_tod(text.get(idx + 1..)?)?;
    date.checked_add(tod)
}
