//! Conditions over a model's signals and state, as a scenario writes its properties:
//! `ERR`, `zel_spodek AND (zel_vrch OR zel_chodci)`, `tank1 > 84`,
//! `cerv_spodek + oran_spodek + zel_spodek = 1`.
//!
//! The syntax is Structured Text's expression syntax, which the lab's users write every
//! day: `NOT`, `AND` (`&`), `XOR`, `OR`, comparisons `= <> < <= > >=`, `+ -`, parentheses,
//! `TRUE`/`FALSE` and numbers. Names (a model's signals and state values) are matched
//! without regard to case, as ST matches them. A BOOL counts 1 or 0 in a sum, and a
//! number holds when it is not 0, so that "exactly one colour lit" is a sum.
//!
//! Written here rather than borrowed from the PLC compiler: a condition is evaluated
//! every scan over a flat table of numbers (a few nanoseconds), and it needs none of the
//! compiler's types, POUs or diagnostics.
//!
//! ```text
//!  text --Parser (precedence climbing, ST's order)--> Expr (names as table indices)
//!                                                       --holds(&[f64])--> bool
//! ```

use std::fmt;

/// A parsed condition, its names resolved to indices of the value table it is evaluated
/// over.
#[derive(Debug, Clone, PartialEq)]
pub struct Condition {
    text: String,
    expr: Expr,
}

/// Why a condition's text is not a condition.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("column {column}: {message}")]
pub struct ConditionError {
    /// Where (1-based, in characters).
    pub column: usize,
    /// What is wrong.
    pub message: String,
}

#[derive(Debug, Clone, PartialEq)]
enum Expr {
    Number(f64),
    Value(usize),
    Not(Box<Expr>),
    Negate(Box<Expr>),
    Binary(Op, Box<Expr>, Box<Expr>),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Op {
    Or,
    Xor,
    And,
    Eq,
    Ne,
    Lt,
    Le,
    Gt,
    Ge,
    Add,
    Sub,
}

impl Op {
    /// Binding strength, ST's order: OR < XOR < AND < comparison < addition.
    fn precedence(self) -> u8 {
        match self {
            Op::Or => 1,
            Op::Xor => 2,
            Op::And => 3,
            Op::Eq | Op::Ne => 4,
            Op::Lt | Op::Le | Op::Gt | Op::Ge => 5,
            Op::Add | Op::Sub => 6,
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
enum Token {
    Number(f64),
    Name(String),
    Op(Op),
    Not,
    Minus,
    Open,
    Close,
}

impl Condition {
    /// Parses `text`, resolving each name with `resolve` (its index in the value table,
    /// or `None` for a name the model does not have; the error then lists `known`).
    pub fn parse(
        text: &str,
        resolve: &dyn Fn(&str) -> Option<usize>,
        known: &dyn Fn() -> Vec<String>,
    ) -> Result<Condition, ConditionError> {
        let tokens = tokens(text)?;
        let mut parser = Parser {
            tokens,
            next: 0,
            resolve,
            known,
            length: text.chars().count(),
        };
        let expr = parser.expression(0, 0)?;
        if let Some((column, token)) = parser.tokens.get(parser.next) {
            return Err(ConditionError {
                column: *column,
                message: format!("unexpected {token:?} after a complete condition"),
            });
        }
        Ok(Condition {
            text: text.trim().to_owned(),
            expr,
        })
    }

    /// Whether the condition holds over `values` (the table its names index).
    pub fn holds(&self, values: &[f64]) -> bool {
        truth(self.expr.value(values))
    }

    /// Its value over `values` (1 or 0 for a logical condition).
    pub fn value(&self, values: &[f64]) -> f64 {
        self.expr.value(values)
    }

    /// The condition as written.
    pub fn text(&self) -> &str {
        &self.text
    }
}

impl fmt::Display for Condition {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.text)
    }
}

fn truth(x: f64) -> bool {
    x != 0.0 && !x.is_nan()
}

fn logical(b: bool) -> f64 {
    if b {
        1.0
    } else {
        0.0
    }
}

impl Expr {
    fn value(&self, values: &[f64]) -> f64 {
        match self {
            Expr::Number(x) => *x,
            // An index is resolved against the same table at parse time; a shorter table
            // (never built so) reads as 0 rather than panicking.
            Expr::Value(i) => values.get(*i).copied().unwrap_or(0.0),
            Expr::Not(e) => logical(!truth(e.value(values))),
            Expr::Negate(e) => -e.value(values),
            Expr::Binary(op, a, b) => {
                let (x, y) = (a.value(values), b.value(values));
                match op {
                    Op::Or => logical(truth(x) || truth(y)),
                    Op::Xor => logical(truth(x) != truth(y)),
                    Op::And => logical(truth(x) && truth(y)),
                    Op::Eq => logical(x == y),
                    Op::Ne => logical(x != y),
                    Op::Lt => logical(x < y),
                    Op::Le => logical(x <= y),
                    Op::Gt => logical(x > y),
                    Op::Ge => logical(x >= y),
                    Op::Add => x + y,
                    Op::Sub => x - y,
                }
            }
        }
    }
}

/// The tokens of `text` with their 1-based columns.
fn tokens(text: &str) -> Result<Vec<(usize, Token)>, ConditionError> {
    let chars: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while let Some(&c) = chars.get(i) {
        let column = i + 1;
        if c.is_whitespace() {
            i += 1;
            continue;
        }
        let next = chars.get(i + 1).copied();
        let (token, width) = match c {
            '(' => (Token::Open, 1),
            ')' => (Token::Close, 1),
            '&' => (Token::Op(Op::And), 1),
            '+' => (Token::Op(Op::Add), 1),
            '-' => (Token::Minus, 1),
            '=' => (Token::Op(Op::Eq), 1),
            '<' if next == Some('>') => (Token::Op(Op::Ne), 2),
            '<' if next == Some('=') => (Token::Op(Op::Le), 2),
            '<' => (Token::Op(Op::Lt), 1),
            '>' if next == Some('=') => (Token::Op(Op::Ge), 2),
            '>' => (Token::Op(Op::Gt), 1),
            c if c.is_ascii_digit() || c == '.' => {
                let end = chars
                    .iter()
                    .skip(i)
                    .position(|c| !(c.is_ascii_digit() || *c == '.' || *c == '_'))
                    .map_or(chars.len(), |n| i + n);
                let digits: String = chars
                    .get(i..end)
                    .unwrap_or_default()
                    .iter()
                    .filter(|c| **c != '_')
                    .collect();
                let number = digits.parse::<f64>().map_err(|_| ConditionError {
                    column,
                    message: format!("`{digits}` is not a number"),
                })?;
                (Token::Number(number), end - i)
            }
            c if c.is_alphabetic() || c == '_' => {
                let end = chars
                    .iter()
                    .skip(i)
                    .position(|c| !(c.is_alphanumeric() || *c == '_' || *c == '.'))
                    .map_or(chars.len(), |n| i + n);
                let word: String = chars.get(i..end).unwrap_or_default().iter().collect();
                let token = match word.to_ascii_uppercase().as_str() {
                    "AND" => Token::Op(Op::And),
                    "OR" => Token::Op(Op::Or),
                    "XOR" => Token::Op(Op::Xor),
                    "NOT" => Token::Not,
                    "TRUE" => Token::Number(1.0),
                    "FALSE" => Token::Number(0.0),
                    _ => Token::Name(word),
                };
                (token, end - i)
            }
            other => {
                return Err(ConditionError {
                    column,
                    message: format!("`{other}` has no meaning in a condition"),
                })
            }
        };
        out.push((column, token));
        i += width;
    }
    Ok(out)
}

/// Deeper nesting than this is refused: a condition is a line of a scenario, and the
/// recursion must stay bounded on any input.
const MAX_DEPTH: usize = 64;

struct Parser<'a> {
    tokens: Vec<(usize, Token)>,
    next: usize,
    resolve: &'a dyn Fn(&str) -> Option<usize>,
    known: &'a dyn Fn() -> Vec<String>,
    length: usize,
}

impl Parser<'_> {
    fn error(&self, message: impl Into<String>) -> ConditionError {
        let column = self
            .tokens
            .get(self.next)
            .map_or(self.length + 1, |(column, _)| *column);
        ConditionError {
            column,
            message: message.into(),
        }
    }

    /// Operands joined by operators binding at least `min` (precedence climbing).
    fn expression(&mut self, min: u8, depth: usize) -> Result<Expr, ConditionError> {
        if depth > MAX_DEPTH {
            return Err(self.error("the condition nests too deeply"));
        }
        let mut left = self.operand(depth)?;
        loop {
            let op = match self.tokens.get(self.next) {
                Some((_, Token::Op(op))) => *op,
                Some((_, Token::Minus)) => Op::Sub,
                _ => return Ok(left),
            };
            if op.precedence() < min.max(1) {
                return Ok(left);
            }
            self.next += 1;
            let right = self.expression(op.precedence() + 1, depth + 1)?;
            left = Expr::Binary(op, Box::new(left), Box::new(right));
        }
    }

    fn operand(&mut self, depth: usize) -> Result<Expr, ConditionError> {
        if depth > MAX_DEPTH {
            return Err(self.error("the condition nests too deeply"));
        }
        let Some((_, token)) = self.tokens.get(self.next).cloned() else {
            return Err(self.error("a value or a name is missing at the end"));
        };
        match token {
            Token::Number(x) => {
                self.next += 1;
                Ok(Expr::Number(x))
            }
            Token::Name(name) => match (self.resolve)(&name) {
                Some(index) => {
                    self.next += 1;
                    Ok(Expr::Value(index))
                }
                None => Err(self.error(format!(
                    "the model has no signal or value `{name}` (it has: {})",
                    (self.known)().join(", ")
                ))),
            },
            Token::Not => {
                self.next += 1;
                // NOT binds tighter than AND but looser than a comparison, as in ST:
                // `NOT a = b` is `NOT (a = b)`.
                let operand = self.expression(Op::Eq.precedence(), depth + 1)?;
                Ok(Expr::Not(Box::new(operand)))
            }
            Token::Minus => {
                self.next += 1;
                let operand = self.operand(depth + 1)?;
                Ok(Expr::Negate(Box::new(operand)))
            }
            Token::Open => {
                self.next += 1;
                let inner = self.expression(0, depth + 1)?;
                match self.tokens.get(self.next) {
                    Some((_, Token::Close)) => {
                        self.next += 1;
                        Ok(inner)
                    }
                    _ => Err(self.error("`)` expected")),
                }
            }
            Token::Close | Token::Op(_) => Err(self.error("a value or a name expected")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const NAMES: &[&str] = &["ERR", "zel_spodek", "zel_vrch", "zel_chodci", "tank1"];

    fn parse(text: &str) -> Result<Condition, ConditionError> {
        Condition::parse(
            text,
            &|name| NAMES.iter().position(|n| n.eq_ignore_ascii_case(name)),
            &|| NAMES.iter().map(|n| (*n).to_owned()).collect(),
        )
    }

    #[test]
    fn names_numbers_and_logic() {
        let values = [0.0, 1.0, 0.0, 1.0, 90.0];
        assert!(!parse("ERR").unwrap().holds(&values));
        assert!(parse("NOT err").unwrap().holds(&values));
        let conflict = parse("zel_spodek AND (zel_vrch OR zel_chodci)").unwrap();
        assert!(conflict.holds(&values));
        assert!(parse("tank1 > 84").unwrap().holds(&values));
        assert!(!parse("tank1 <= 84").unwrap().holds(&values));
        assert!(parse("zel_spodek + zel_vrch + zel_chodci = 2")
            .unwrap()
            .holds(&values));
        assert!(parse("zel_spodek XOR zel_vrch").unwrap().holds(&values));
        assert!(parse("zel_spodek & TRUE").unwrap().holds(&values));
        assert_eq!(parse("-tank1 + 100").unwrap().value(&values), 10.0);
    }

    #[test]
    fn st_precedence() {
        let values = [1.0, 0.0, 0.0, 0.0, 0.0];
        // AND before OR
        assert!(parse("ERR OR zel_vrch AND zel_chodci")
            .unwrap()
            .holds(&values));
        // NOT of a comparison
        assert!(parse("NOT tank1 = 5").unwrap().holds(&values));
        // comparison before AND
        assert!(parse("tank1 < 1 AND ERR").unwrap().holds(&values));
    }

    #[test]
    fn errors_say_where_and_what() {
        let error = parse("ERR AND nothing").unwrap_err();
        assert_eq!(error.column, 9);
        assert!(
            error.message.contains("no signal or value `nothing`"),
            "{error}"
        );
        assert!(error.message.contains("zel_vrch"), "{error}");
        assert_eq!(parse("(ERR").unwrap_err().message, "`)` expected");
        assert_eq!(parse("ERR AND").unwrap_err().column, 8);
        assert!(parse("ERR ERR").is_err());
        assert!(parse("ERR ? 1").is_err());
        assert!(parse("").is_err());
        let deep = format!("{}ERR{}", "(".repeat(200), ")".repeat(200));
        assert!(parse(&deep).unwrap_err().message.contains("too deeply"));
    }

    proptest! {
        #[test]
        fn any_text_parses_or_errs_without_panicking(text in "\\PC{0,60}") {
            let _ = parse(&text);
        }

        #[test]
        fn any_operator_soup_parses_or_errs(text in "[()a-zA-Z0-9_ <>=&+.-]{0,80}") {
            if let Ok(condition) = parse(&text) {
                let _ = condition.holds(&[1.0, 0.0, 2.0, -1.0, 84.0]);
            }
        }
    }
}
