//! Values as IEC literals (`TRUE`, `T#5s`, `'text'`, `Color#Red`): formatting and parsing
//! by a variable's type.

use super::PlcError;
use crate::check::{Checked, Ty};
use crate::vm::{format, Val};

/// Formats a scalar value of `ty` as an IEC literal.
pub fn format_value(c: &Checked, ty: &Ty, v: &Val) -> String {
    match (ty, v) {
        (Ty::Bool, Val::Int(x)) => if *x != 0 { "TRUE" } else { "FALSE" }.into(),
        (Ty::Time, Val::Int(x)) => format::time(*x, false),
        (Ty::LTime, Val::Int(x)) => format::time(*x, true),
        (Ty::Tod, Val::Int(x)) => format::tod(*x),
        (Ty::Date, Val::Int(x)) => format::date(*x),
        (Ty::Dt, Val::Int(x)) => format::dt(*x),
        (Ty::ULInt | Ty::LWord, Val::Int(x)) => (*x as u64).to_string(),
        (Ty::Ref(_), Val::Int(0)) => "NULL".into(),
        (Ty::Ref(_), Val::Int(x)) => {
            // the cells referred to, per lane (see `compile::expr::reference::pack`)
            let at = crate::compile::unpack(x.wrapping_sub(1));
            format!("REF({}, {}, {})", at.i, at.r, at.s)
        }
        (Ty::Enum(id), Val::Int(x)) => match c.types.enum_def(*id) {
            Some(d) => match d.values.iter().find(|(_, v)| v == x) {
                Some((n, _)) => format!("{}#{n}", d.name),
                None => x.to_string(),
            },
            None => x.to_string(),
        },
        (_, Val::Int(x)) => x.to_string(),
        (t, Val::Real(x)) => format::real(*x, *t == Ty::Real),
        (Ty::WString(_), Val::Str(s)) => format::string(s, true),
        (_, Val::Str(s)) => format::string(s, false),
    }
}

/// Parses an IEC literal (`TRUE`, `42`, `16#FF`, `1.5`, `T#5s`, `'text'`, `Color#Red`) as a
/// value of `ty`.
pub fn parse_value(c: &Checked, ty: &Ty, text: &str) -> Result<Val, PlcError> {
    let bad = || PlcError::BadValue {
        text: text.to_string(),
        ty: c.type_name(ty),
    };
    if let Ty::Ref(_) = ty {
        // an address comes from REF() in the program; from outside only NULL
        return if text.trim().eq_ignore_ascii_case("NULL") {
            Ok(Val::Int(0))
        } else {
            Err(bad())
        };
    }
    let mut diags = Vec::new();
    let toks = crate::syntax::lexer::lex(crate::syntax::FileId(0), text.trim(), &mut diags);
    if !diags.is_empty() {
        return Err(bad());
    }
    use crate::syntax::lexer::Tok;
    let kinds: Vec<&Tok> = toks
        .iter()
        .map(|t| &t.tok)
        .filter(|t| !matches!(t, Tok::Eof))
        .collect();
    let (neg, rest) = match kinds.first() {
        Some(Tok::Punct("-")) => (true, kinds.get(1..).unwrap_or(&[])),
        _ => (false, kinds.as_slice()),
    };
    let rest: Vec<&Tok> = match rest.first() {
        Some(Tok::TypePrefix(_)) => rest.get(1..).unwrap_or(&[]).to_vec(),
        _ => rest.to_vec(),
    };
    let one = match rest.as_slice() {
        [t] => *t,
        [Tok::Ident(_), Tok::HashIdent(v)] => {
            if let Ty::Enum(id) = ty {
                let d = c.types.enum_def(*id).ok_or_else(bad)?;
                let (_, x) = d
                    .values
                    .iter()
                    .find(|(n, _)| n.eq_ignore_ascii_case(v))
                    .ok_or_else(bad)?;
                return Ok(Val::Int(*x));
            }
            return Err(bad());
        }
        [Tok::Punct("-"), t] if !neg => *t,
        _ => return Err(bad()),
    };
    let sign = |x: i128| if neg { -x } else { x };
    let v = match (ty.lane(), one) {
        (Some(crate::check::Lane::Int), Tok::Ident(s)) if *ty == Ty::Bool => {
            match s.to_ascii_uppercase().as_str() {
                "TRUE" => Val::Int(1),
                "FALSE" => Val::Int(0),
                _ => return Err(bad()),
            }
        }
        (Some(crate::check::Lane::Int), Tok::Ident(s)) => {
            let Ty::Enum(id) = ty else { return Err(bad()) };
            let d = c.types.enum_def(*id).ok_or_else(bad)?;
            let (_, x) = d
                .values
                .iter()
                .find(|(n, _)| n.eq_ignore_ascii_case(s))
                .ok_or_else(bad)?;
            Val::Int(*x)
        }
        (Some(crate::check::Lane::Int), Tok::Int(x)) => {
            let x = sign(i128::try_from(*x).map_err(|_| bad())?);
            if let Some((lo, hi)) = ty.int_range() {
                if x < lo || x > hi {
                    return Err(bad());
                }
            }
            Val::Int(x as i64)
        }
        (Some(crate::check::Lane::Int), Tok::Time(ns, _)) if ty.is_duration() => {
            Val::Int(i64::try_from(sign(*ns)).map_err(|_| bad())?)
        }
        (Some(crate::check::Lane::Int), Tok::Tod(x)) if *ty == Ty::Tod => Val::Int(*x),
        (Some(crate::check::Lane::Int), Tok::Date(x)) if *ty == Ty::Date => Val::Int(*x),
        (Some(crate::check::Lane::Int), Tok::Dt(x)) if *ty == Ty::Dt => Val::Int(*x),
        (Some(crate::check::Lane::Real), Tok::Real(x)) => Val::Real(crate::stdlib::conv::fit_real(
            if neg { -*x } else { *x },
            ty,
        )),
        (Some(crate::check::Lane::Real), Tok::Int(x)) => Val::Real(crate::stdlib::conv::fit_real(
            sign(i128::try_from(*x).map_err(|_| bad())?) as f64,
            ty,
        )),
        (Some(crate::check::Lane::Str), Tok::SqString(s) | Tok::DqString(s)) => {
            let n = match ty {
                Ty::String(n) | Ty::WString(n) => *n,
                _ => u32::MAX,
            };
            Val::Str(crate::stdlib::string::truncate(s.clone(), n))
        }
        _ => return Err(bad()),
    };
    Ok(v)
}
