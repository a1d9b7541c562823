//! Unary and binary operators: arithmetic, comparison, logic, time and date arithmetic.

use crate::check::Ty;
use crate::compile::{IFn, CE};
use crate::syntax::*;
use crate::vm::{Fault, FaultKind};

fn ty_is_u64(t: &Ty) -> bool {
    matches!(t, Ty::ULInt | Ty::LWord)
}

pub(super) fn unary(op: UnOp, v: CE, ty: &Ty) -> CE {
    let ty = ty.clone();
    match (op, v) {
        (UnOp::Plus, v) => v,
        (UnOp::Neg, CE::I(f)) => CE::I(Box::new(move |vm| Ok(ty.wrap(f(vm)?.wrapping_neg())))),
        (UnOp::Neg, CE::R(f)) => CE::R(Box::new(move |vm| Ok(-f(vm)?))),
        (UnOp::Not, CE::I(f)) => {
            if ty == Ty::Bool {
                CE::I(Box::new(move |vm| Ok(i64::from(f(vm)? == 0))))
            } else {
                CE::I(Box::new(move |vm| Ok(ty.wrap(!f(vm)?))))
            }
        }
        (_, v) => v,
    }
}

const DAY: i64 = 86_400_000_000_000;

#[allow(clippy::too_many_arguments)]
pub(crate) fn binary(op: BinOp, a: CE, b: CE, ta: &Ty, tb: &Ty, ty: &Ty, span: Span) -> CE {
    use BinOp::*;
    let cmp = matches!(op, Lt | Gt | Le | Ge | Eq | Ne);
    match (a, b) {
        (CE::I(a), CE::I(b)) => {
            if cmp {
                let unsigned = ty_is_u64(ta) || ty_is_u64(tb);
                return CE::I(int_cmp(op, a, b, unsigned));
            }
            // time arithmetic
            let timey = |t: &Ty| matches!(t, Ty::Time | Ty::LTime | Ty::Tod | Ty::Dt | Ty::Date);
            if timey(ta) || timey(tb) {
                let tod = *ty == Ty::Tod;
                return CE::I(match op {
                    Add => Box::new(move |vm| {
                        let r = a(vm)?.wrapping_add(b(vm)?);
                        Ok(if tod { r.rem_euclid(DAY) } else { r })
                    }),
                    Sub => Box::new(move |vm| {
                        let r = a(vm)?.wrapping_sub(b(vm)?);
                        Ok(if tod { r.rem_euclid(DAY) } else { r })
                    }),
                    Mul => Box::new(move |vm| Ok(a(vm)?.wrapping_mul(b(vm)?))),
                    Div => Box::new(move |vm| {
                        let x = a(vm)?;
                        let y = b(vm)?;
                        if y == 0 {
                            return Err(Fault::from(FaultKind::DivisionByZero(span)));
                        }
                        Ok(x.wrapping_div(y))
                    }),
                    _ => Box::new(move |vm| a(vm)),
                });
            }
            let t = ty.clone();
            let u64op = ty_is_u64(ty);
            CE::I(match op {
                Add => match t {
                    Ty::LInt | Ty::ULInt | Ty::LWord => {
                        Box::new(move |vm| Ok(a(vm)?.wrapping_add(b(vm)?)))
                    }
                    Ty::DInt => {
                        Box::new(move |vm| Ok(i64::from((a(vm)?.wrapping_add(b(vm)?)) as i32)))
                    }
                    Ty::Int => {
                        Box::new(move |vm| Ok(i64::from((a(vm)?.wrapping_add(b(vm)?)) as i16)))
                    }
                    _ => Box::new(move |vm| Ok(t.wrap(a(vm)?.wrapping_add(b(vm)?)))),
                },
                Sub => match t {
                    Ty::DInt => {
                        Box::new(move |vm| Ok(i64::from((a(vm)?.wrapping_sub(b(vm)?)) as i32)))
                    }
                    _ => Box::new(move |vm| Ok(t.wrap(a(vm)?.wrapping_sub(b(vm)?)))),
                },
                Mul => Box::new(move |vm| Ok(t.wrap(a(vm)?.wrapping_mul(b(vm)?)))),
                Div => Box::new(move |vm| {
                    let x = a(vm)?;
                    let y = b(vm)?;
                    if y == 0 {
                        return Err(Fault::from(FaultKind::DivisionByZero(span)));
                    }
                    if u64op {
                        return Ok(((x as u64) / (y as u64)) as i64);
                    }
                    Ok(t.wrap(x.wrapping_div(y)))
                }),
                Mod => Box::new(move |vm| {
                    let x = a(vm)?;
                    let y = b(vm)?;
                    if y == 0 {
                        return Err(Fault::from(FaultKind::DivisionByZero(span)));
                    }
                    if u64op {
                        return Ok(((x as u64) % (y as u64)) as i64);
                    }
                    Ok(t.wrap(x.wrapping_rem(y)))
                }),
                And => Box::new(move |vm| {
                    let x = a(vm)?;
                    if x == 0 && t == Ty::Bool {
                        return Ok(0);
                    }
                    Ok(x & b(vm)?)
                }),
                Or => Box::new(move |vm| {
                    let x = a(vm)?;
                    if x == 1 && t == Ty::Bool {
                        return Ok(1);
                    }
                    Ok(x | b(vm)?)
                }),
                Xor => Box::new(move |vm| Ok(a(vm)? ^ b(vm)?)),
                Pow => Box::new(move |vm| Ok(t.wrap(crate::stdlib::numeric::ipow(a(vm)?, b(vm)?)))),
                _ => Box::new(move |vm| a(vm)),
            })
        }
        (CE::R(a), CE::R(b)) => {
            if cmp {
                return CE::I(match op {
                    Lt => Box::new(move |vm| Ok(i64::from(a(vm)? < b(vm)?))),
                    Gt => Box::new(move |vm| Ok(i64::from(a(vm)? > b(vm)?))),
                    Le => Box::new(move |vm| Ok(i64::from(a(vm)? <= b(vm)?))),
                    Ge => Box::new(move |vm| Ok(i64::from(a(vm)? >= b(vm)?))),
                    Eq => Box::new(move |vm| Ok(i64::from(a(vm)? == b(vm)?))),
                    _ => Box::new(move |vm| Ok(i64::from(a(vm)? != b(vm)?))),
                });
            }
            let single = *ty == Ty::Real;
            let fit = move |x: f64| if single { f64::from(x as f32) } else { x };
            CE::R(match op {
                Add => Box::new(move |vm| Ok(fit(a(vm)? + b(vm)?))),
                Sub => Box::new(move |vm| Ok(fit(a(vm)? - b(vm)?))),
                Mul => Box::new(move |vm| Ok(fit(a(vm)? * b(vm)?))),
                Div => Box::new(move |vm| Ok(fit(a(vm)? / b(vm)?))),
                Pow => Box::new(move |vm| Ok(fit(a(vm)?.powf(b(vm)?)))),
                _ => Box::new(move |vm| a(vm)),
            })
        }
        (CE::I(a), CE::R(b)) => {
            // TIME * REAL, TIME / REAL
            CE::I(match op {
                Mul => Box::new(move |vm| Ok((a(vm)? as f64 * b(vm)?).round() as i64)),
                Div => Box::new(move |vm| Ok((a(vm)? as f64 / b(vm)?).round() as i64)),
                _ => Box::new(move |vm| a(vm)),
            })
        }
        (CE::R(a), CE::I(b)) => CE::I(Box::new(move |vm| {
            Ok((a(vm)? * b(vm)? as f64).round() as i64)
        })),
        (CE::S(a), CE::S(b)) => CE::I(match op {
            Lt => Box::new(move |vm| Ok(i64::from(a(vm)? < b(vm)?))),
            Gt => Box::new(move |vm| Ok(i64::from(a(vm)? > b(vm)?))),
            Le => Box::new(move |vm| Ok(i64::from(a(vm)? <= b(vm)?))),
            Ge => Box::new(move |vm| Ok(i64::from(a(vm)? >= b(vm)?))),
            Eq => Box::new(move |vm| Ok(i64::from(a(vm)? == b(vm)?))),
            _ => Box::new(move |vm| Ok(i64::from(a(vm)? != b(vm)?))),
        }),
        (a, _) => a,
    }
}

fn int_cmp(op: BinOp, a: IFn, b: IFn, unsigned: bool) -> IFn {
    use BinOp::*;
    if unsigned {
        return match op {
            Lt => Box::new(move |vm| Ok(i64::from((a(vm)? as u64) < (b(vm)? as u64)))),
            Gt => Box::new(move |vm| Ok(i64::from((a(vm)? as u64) > (b(vm)? as u64)))),
            Le => Box::new(move |vm| Ok(i64::from((a(vm)? as u64) <= (b(vm)? as u64)))),
            Ge => Box::new(move |vm| Ok(i64::from((a(vm)? as u64) >= (b(vm)? as u64)))),
            Eq => Box::new(move |vm| Ok(i64::from(a(vm)? == b(vm)?))),
            _ => Box::new(move |vm| Ok(i64::from(a(vm)? != b(vm)?))),
        };
    }
    match op {
        Lt => Box::new(move |vm| Ok(i64::from(a(vm)? < b(vm)?))),
        Gt => Box::new(move |vm| Ok(i64::from(a(vm)? > b(vm)?))),
        Le => Box::new(move |vm| Ok(i64::from(a(vm)? <= b(vm)?))),
        Ge => Box::new(move |vm| Ok(i64::from(a(vm)? >= b(vm)?))),
        Eq => Box::new(move |vm| Ok(i64::from(a(vm)? == b(vm)?))),
        _ => Box::new(move |vm| Ok(i64::from(a(vm)? != b(vm)?))),
    }
}
