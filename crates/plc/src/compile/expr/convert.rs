//! Conversions between types: implicit widening and `*_TO_*`.

use crate::check::{Lane, Ty};
use crate::compile::CE;
use crate::stdlib::conv;

/// Converts a value between types (implicit widening and `*_TO_*`).
pub(crate) fn convert(v: CE, from: &Ty, to: &Ty, c: &crate::check::Checked) -> CE {
    if from == to {
        return v;
    }
    let (from, to) = (from.clone(), to.clone());
    match v {
        CE::I(f) => match to.lane() {
            Some(Lane::Int) => {
                let same_repr = (from.is_int() || from.is_bits() || from == Ty::Bool)
                    && (to.is_int() || to.is_bits())
                    && from.converts_to(&to);
                if same_repr || (from.is_duration() && to.is_duration()) {
                    CE::I(f)
                } else {
                    CE::I(Box::new(move |vm| Ok(conv::int_to_int(f(vm)?, &from, &to))))
                }
            }
            Some(Lane::Real) => CE::R(Box::new(move |vm| {
                Ok(conv::fit_real(conv::int_to_f64(f(vm)?, &from), &to))
            })),
            Some(Lane::Str) => {
                let names: Option<Vec<(String, i64)>> = match &from {
                    Ty::Enum(id) => c.types.enum_def(*id).map(|d| d.values.clone()),
                    _ => None,
                };
                CE::S(Box::new(move |vm| {
                    let x = f(vm)?;
                    let n = names
                        .as_ref()
                        .and_then(|n| n.iter().find(|(_, v)| *v == x))
                        .map(|(n, _)| n.as_str());
                    Ok(conv::int_to_string(x, &from, n))
                }))
            }
            None => CE::I(f),
        },
        CE::R(f) => match to.lane() {
            Some(Lane::Int) => CE::I(Box::new(move |vm| Ok(conv::real_to_int(f(vm)?, &to)))),
            Some(Lane::Real) => CE::R(Box::new(move |vm| Ok(conv::fit_real(f(vm)?, &to)))),
            Some(Lane::Str) => {
                let single = from == Ty::Real;
                CE::S(Box::new(move |vm| {
                    Ok(crate::vm::format::real(f(vm)?, single))
                }))
            }
            None => CE::R(f),
        },
        CE::S(f) => match to.lane() {
            Some(Lane::Int) => CE::I(Box::new(move |vm| Ok(conv::string_to_int(&f(vm)?, &to)))),
            Some(Lane::Real) => CE::R(Box::new(move |vm| {
                Ok(conv::fit_real(conv::string_to_real(&f(vm)?), &to))
            })),
            _ => CE::S(f),
        },
    }
}
