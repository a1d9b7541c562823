//! Code generation for built-in functions.

use super::expr::{convert, konst_i};
use super::{Cx, IFn, RFn, SFn, CE};
use crate::check::Ty;
use crate::stdlib::{self, bits, conv, numeric, string, time, Builtin};
use crate::syntax::{Arg, Expr, ExprKind};
use crate::vm::{Fault, FaultKind, StmtFn};
use std::cell::Cell;
use std::rc::Rc;
use Builtin::*;

fn as_i(v: CE) -> IFn {
    match v {
        CE::I(f) => f,
        CE::R(f) => Box::new(move |vm| Ok(f(vm)? as i64)),
        CE::S(_) => konst_i(0),
    }
}
fn as_r(v: CE) -> RFn {
    match v {
        CE::R(f) => f,
        CE::I(f) => Box::new(move |vm| Ok(f(vm)? as f64)),
        CE::S(_) => Box::new(|_| Ok(0.0)),
    }
}
fn as_s(v: CE) -> SFn {
    match v {
        CE::S(f) => f,
        _ => Box::new(|_| Ok(String::new())),
    }
}

fn real1(v: CE, ty: &Ty, f: fn(f64) -> f64) -> CE {
    let a = as_r(v);
    let single = *ty == Ty::Real;
    CE::R(Box::new(move |vm| {
        let x = f(a(vm)?);
        Ok(if single { f64::from(x as f32) } else { x })
    }))
}

impl Cx<'_> {
    pub(crate) fn builtin(&mut self, b: &Builtin, args: &[Arg], e: &Expr) -> CE {
        match b {
            ConcatParts(parts) => return self.concat_parts(*parts, args, e),
            SplitParts(parts) => return self.split_parts(*parts, args),
            _ => {}
        }
        let ret = self.c.ty(e.id);
        let tys: Vec<Ty> = args.iter().map(|a| self.c.final_ty(a.value.id)).collect();
        let mut vals: Vec<CE> = args.iter().map(|a| self.expr(&a.value)).collect();
        let t0 = tys.first().cloned().unwrap_or(Ty::Void);
        let nvals = vals.len();
        let mut take = |i: usize| -> CE {
            if i < vals.len() {
                vals.get_mut(i)
                    .map(|v| std::mem::replace(v, CE::I(konst_i(0))))
                    .unwrap_or(CE::I(konst_i(0)))
            } else {
                CE::I(konst_i(0))
            }
        };
        let span = e.span;
        match b {
            Abs => match take(0) {
                CE::I(f) => {
                    let t = ret.clone();
                    CE::I(Box::new(move |vm| Ok(t.wrap(f(vm)?.wrapping_abs()))))
                }
                CE::R(f) => CE::R(Box::new(move |vm| Ok(f(vm)?.abs()))),
                s => s,
            },
            Sqrt => real1(take(0), &ret, f64::sqrt),
            Ln => real1(take(0), &ret, f64::ln),
            Log => real1(take(0), &ret, f64::log10),
            Exp => real1(take(0), &ret, f64::exp),
            Sin => real1(take(0), &ret, f64::sin),
            Cos => real1(take(0), &ret, f64::cos),
            Tan => real1(take(0), &ret, f64::tan),
            Asin => real1(take(0), &ret, f64::asin),
            Acos => real1(take(0), &ret, f64::acos),
            Atan => real1(take(0), &ret, f64::atan),
            Round => real1(take(0), &ret, numeric::round),
            Floor => real1(take(0), &ret, f64::floor),
            Ceil => real1(take(0), &ret, f64::ceil),
            Atan2 => {
                let (a, b2) = (as_r(take(0)), as_r(take(1)));
                CE::R(Box::new(move |vm| Ok(a(vm)?.atan2(b2(vm)?))))
            }
            Trunc => {
                let a = as_r(take(0));
                CE::I(Box::new(move |vm| Ok(i64::from(a(vm)?.trunc() as i32))))
            }
            Expt => {
                let a = as_r(take(0));
                let single = ret == Ty::Real;
                let fit = move |x: f64| if single { f64::from(x as f32) } else { x };
                match take(1) {
                    CE::I(n) => CE::R(Box::new(move |vm| {
                        Ok(fit(numeric::expt_int(a(vm)?, n(vm)?)))
                    })),
                    other => {
                        let n = as_r(other);
                        CE::R(Box::new(move |vm| Ok(fit(a(vm)?.powf(n(vm)?)))))
                    }
                }
            }
            Mod => {
                let (a, b2) = (as_i(take(0)), as_i(take(1)));
                let t = ret.clone();
                let u = matches!(t, Ty::ULInt | Ty::LWord);
                CE::I(Box::new(move |vm| {
                    let x = a(vm)?;
                    let y = b2(vm)?;
                    if y == 0 {
                        return Err(Fault::from(FaultKind::DivisionByZero(span)));
                    }
                    Ok(if u {
                        ((x as u64) % (y as u64)) as i64
                    } else {
                        t.wrap(x.wrapping_rem(y))
                    })
                }))
            }
            Shl | Shr | Rol | Ror => {
                let (a, n) = (as_i(take(0)), as_i(take(1)));
                let w = ret.bits();
                let t = ret.clone();
                let f: fn(i64, i64, u32) -> i64 = match b {
                    Shl => bits::shl,
                    Shr => bits::shr,
                    Rol => bits::rol,
                    _ => bits::ror,
                };
                CE::I(Box::new(move |vm| Ok(t.wrap(f(a(vm)?, n(vm)?, w)))))
            }
            Sel => {
                let g = as_i(take(0));
                match (take(1), take(2)) {
                    (CE::I(a), CE::I(b2)) => {
                        CE::I(Box::new(move |vm| if g(vm)? != 0 { b2(vm) } else { a(vm) }))
                    }
                    (CE::R(a), CE::R(b2)) => {
                        CE::R(Box::new(move |vm| if g(vm)? != 0 { b2(vm) } else { a(vm) }))
                    }
                    (a, b2) => {
                        let (a, b2) = (as_s(a), as_s(b2));
                        CE::S(Box::new(move |vm| if g(vm)? != 0 { b2(vm) } else { a(vm) }))
                    }
                }
            }
            Max | Min => {
                let n = nvals;
                let all: Vec<CE> = (0..n).map(&mut take).collect();
                let is_max = *b == Max;
                let u = matches!(ret, Ty::ULInt | Ty::LWord);
                match ret.lane() {
                    Some(crate::check::Lane::Real) => {
                        let fs: Vec<RFn> = all.into_iter().map(as_r).collect();
                        CE::R(Box::new(move |vm| {
                            let mut best = f64::NAN;
                            for (k, f) in fs.iter().enumerate() {
                                let x = f(vm)?;
                                if k == 0 || (is_max && x > best) || (!is_max && x < best) {
                                    best = x;
                                }
                            }
                            Ok(best)
                        }))
                    }
                    Some(crate::check::Lane::Str) => {
                        let fs: Vec<SFn> = all.into_iter().map(as_s).collect();
                        CE::S(Box::new(move |vm| {
                            let mut best: Option<String> = None;
                            for f in &fs {
                                let x = f(vm)?;
                                best = Some(match best {
                                    Some(b) if (is_max && b >= x) || (!is_max && b <= x) => b,
                                    _ => x,
                                });
                            }
                            Ok(best.unwrap_or_default())
                        }))
                    }
                    _ => {
                        let fs: Vec<IFn> = all.into_iter().map(as_i).collect();
                        CE::I(Box::new(move |vm| {
                            let mut best = 0i64;
                            for (k, f) in fs.iter().enumerate() {
                                let x = f(vm)?;
                                let better = if u {
                                    if is_max {
                                        (x as u64) > (best as u64)
                                    } else {
                                        (x as u64) < (best as u64)
                                    }
                                } else if is_max {
                                    x > best
                                } else {
                                    x < best
                                };
                                if k == 0 || better {
                                    best = x;
                                }
                            }
                            Ok(best)
                        }))
                    }
                }
            }
            Limit => match ret.lane() {
                Some(crate::check::Lane::Real) => {
                    let (mn, x, mx) = (as_r(take(0)), as_r(take(1)), as_r(take(2)));
                    CE::R(Box::new(move |vm| {
                        let (lo, v, hi) = (mn(vm)?, x(vm)?, mx(vm)?);
                        Ok(if v < lo {
                            lo
                        } else if v > hi {
                            hi
                        } else {
                            v
                        })
                    }))
                }
                _ => {
                    let (mn, x, mx) = (as_i(take(0)), as_i(take(1)), as_i(take(2)));
                    CE::I(Box::new(move |vm| {
                        let (lo, v, hi) = (mn(vm)?, x(vm)?, mx(vm)?);
                        Ok(if v < lo {
                            lo
                        } else if v > hi {
                            hi
                        } else {
                            v
                        })
                    }))
                }
            },
            Mux => {
                let k = as_i(take(0));
                let n = nvals;
                let rest: Vec<CE> = (1..n).map(&mut take).collect();
                match ret.lane() {
                    Some(crate::check::Lane::Real) => {
                        let fs: Vec<RFn> = rest.into_iter().map(as_r).collect();
                        CE::R(Box::new(move |vm| {
                            let i = usize::try_from(k(vm)?)
                                .unwrap_or(usize::MAX)
                                .min(fs.len().saturating_sub(1));
                            match fs.get(i) {
                                Some(f) => f(vm),
                                None => Ok(0.0),
                            }
                        }))
                    }
                    Some(crate::check::Lane::Str) => {
                        let fs: Vec<SFn> = rest.into_iter().map(as_s).collect();
                        CE::S(Box::new(move |vm| {
                            let i = usize::try_from(k(vm)?)
                                .unwrap_or(usize::MAX)
                                .min(fs.len().saturating_sub(1));
                            match fs.get(i) {
                                Some(f) => f(vm),
                                None => Ok(String::new()),
                            }
                        }))
                    }
                    _ => {
                        let fs: Vec<IFn> = rest.into_iter().map(as_i).collect();
                        CE::I(Box::new(move |vm| {
                            let i = usize::try_from(k(vm)?)
                                .unwrap_or(usize::MAX)
                                .min(fs.len().saturating_sub(1));
                            match fs.get(i) {
                                Some(f) => f(vm),
                                None => Ok(0),
                            }
                        }))
                    }
                }
            }
            Move => take(0),
            Len => {
                let s = as_s(take(0));
                CE::I(Box::new(move |vm| Ok(string::len(&s(vm)?))))
            }
            Left | Right => {
                let (s, n) = (as_s(take(0)), as_i(take(1)));
                let f: fn(&str, i64) -> String = if *b == Left {
                    string::left
                } else {
                    string::right
                };
                CE::S(Box::new(move |vm| Ok(f(&s(vm)?, n(vm)?))))
            }
            Mid => {
                let (s, n, p) = (as_s(take(0)), as_i(take(1)), as_i(take(2)));
                CE::S(Box::new(move |vm| Ok(string::mid(&s(vm)?, n(vm)?, p(vm)?))))
            }
            Concat => {
                let n = nvals;
                let fs: Vec<SFn> = (0..n).map(&mut take).map(as_s).collect();
                CE::S(Box::new(move |vm| {
                    let mut out = String::new();
                    for f in &fs {
                        out.push_str(&f(vm)?);
                    }
                    Ok(out)
                }))
            }
            Insert => {
                let (a, s2, p) = (as_s(take(0)), as_s(take(1)), as_i(take(2)));
                CE::S(Box::new(move |vm| {
                    Ok(string::insert(&a(vm)?, &s2(vm)?, p(vm)?))
                }))
            }
            Delete => {
                let (a, n, p) = (as_s(take(0)), as_i(take(1)), as_i(take(2)));
                CE::S(Box::new(move |vm| {
                    Ok(string::delete(&a(vm)?, n(vm)?, p(vm)?))
                }))
            }
            Replace => {
                let (a, s2, n, p) = (as_s(take(0)), as_s(take(1)), as_i(take(2)), as_i(take(3)));
                CE::S(Box::new(move |vm| {
                    Ok(string::replace(&a(vm)?, &s2(vm)?, n(vm)?, p(vm)?))
                }))
            }
            Find => {
                let (a, s2) = (as_s(take(0)), as_s(take(1)));
                CE::I(Box::new(move |vm| Ok(string::find(&a(vm)?, &s2(vm)?))))
            }
            BcdTo(_, to) => {
                let a = as_i(take(0));
                let (from, to) = (t0.clone(), to.clone());
                CE::I(Box::new(move |vm| {
                    let v = a(vm)?;
                    match conv::bcd_decode(v, from.bits()) {
                        Ok(x) => Ok(to.wrap(x)),
                        Err(digit) => Err(FaultKind::Conversion {
                            span,
                            what: format!(
                                "16#{v:X} is no BCD value: its digit {digit:X} is above 9"
                            ),
                        }
                        .into()),
                    }
                }))
            }
            ToBcd(_, to) => {
                let a = as_i(take(0));
                let to = to.clone();
                CE::I(Box::new(move |vm| {
                    let v = a(vm)?;
                    conv::bcd_encode(v, to.bits()).ok_or_else(|| {
                        FaultKind::Conversion {
                            span,
                            what: format!("{v} does not fit BCD in {to}"),
                        }
                        .into()
                    })
                }))
            }
            TruncTo(_, to) => {
                let a = as_r(take(0));
                let to = to.clone();
                CE::I(Box::new(move |vm| Ok(conv::real_trunc_to_int(a(vm)?, &to))))
            }
            Convert(_, to) => {
                let v = take(0);
                convert(v, &t0, to, self.c)
            }
            AddTime | AddDtTime | AddLTime | AddLDtLTime => {
                let (a, b2) = (as_i(take(0)), as_i(take(1)));
                CE::I(Box::new(move |vm| Ok(a(vm)?.wrapping_add(b2(vm)?))))
            }
            SubTime | SubDtTime | SubDtDt | SubDateDate | SubTodTod | SubLTime | SubLDtLTime
            | SubLDtLDt | SubLDateLDate | SubLTodLTod => {
                let (a, b2) = (as_i(take(0)), as_i(take(1)));
                CE::I(Box::new(move |vm| Ok(a(vm)?.wrapping_sub(b2(vm)?))))
            }
            AddTodTime | AddLTodLTime => {
                let (a, b2) = (as_i(take(0)), as_i(take(1)));
                CE::I(Box::new(move |vm| Ok(time::add_tod_time(a(vm)?, b2(vm)?))))
            }
            SubTodTime | SubLTodLTime => {
                let (a, b2) = (as_i(take(0)), as_i(take(1)));
                CE::I(Box::new(move |vm| {
                    Ok(time::add_tod_time(a(vm)?, b2(vm)?.wrapping_neg()))
                }))
            }
            MulTime | DivTime | MulLTime | DivLTime => {
                let a = as_i(take(0));
                let is_mul = matches!(b, MulTime | MulLTime);
                match take(1) {
                    CE::I(k) => CE::I(Box::new(move |vm| {
                        let x = a(vm)?;
                        let y = k(vm)?;
                        if is_mul {
                            Ok(x.wrapping_mul(y))
                        } else if y == 0 {
                            Err(Fault::from(FaultKind::DivisionByZero(span)))
                        } else {
                            Ok(x.wrapping_div(y))
                        }
                    })),
                    other => {
                        let k = as_r(other);
                        CE::I(Box::new(move |vm| {
                            let x = a(vm)? as f64;
                            let y = k(vm)?;
                            Ok((if is_mul { x * y } else { x / y }).round() as i64)
                        }))
                    }
                }
            }
            ConcatDateTod => {
                let (a, b2) = (as_i(take(0)), as_i(take(1)));
                CE::I(Box::new(move |vm| {
                    Ok(time::dt_to_date(a(vm)?).wrapping_add(b2(vm)?))
                }))
            }
            DtToTod => {
                let a = as_i(take(0));
                CE::I(Box::new(move |vm| Ok(time::dt_to_tod(a(vm)?))))
            }
            DtToDate => {
                let a = as_i(take(0));
                CE::I(Box::new(move |vm| Ok(time::dt_to_date(a(vm)?))))
            }
            TDiff => {
                let (a, b2) = (as_i(take(0)), as_i(take(1)));
                CE::I(Box::new(move |vm| Ok(a(vm)?.wrapping_sub(b2(vm)?))))
            }
            Now => CE::I(Box::new(|vm| Ok(vm.now))),
            LocalTime => CE::I(Box::new(|vm| Ok(vm.utc.wrapping_add(vm.local_offset)))),
            SystemTime => CE::I(Box::new(|vm| Ok(vm.utc))),
            Compare(op) => {
                let n = nvals;
                let all: Vec<CE> = (0..n).map(&mut take).collect();
                let t = tys.first().cloned().unwrap_or(Ty::Void);
                // a chain of pairwise comparisons, each operand evaluated once
                let op = *op;
                match t.lane() {
                    Some(crate::check::Lane::Real) => {
                        let fs: Vec<RFn> = all.into_iter().map(as_r).collect();
                        CE::I(Box::new(move |vm| {
                            let mut prev: Option<f64> = None;
                            let mut ok = true;
                            for f in &fs {
                                let x = f(vm)?;
                                if let Some(p) = prev {
                                    ok &= cmp_f(op, p, x);
                                }
                                prev = Some(x);
                            }
                            Ok(i64::from(ok))
                        }))
                    }
                    Some(crate::check::Lane::Str) => {
                        let fs: Vec<SFn> = all.into_iter().map(as_s).collect();
                        CE::I(Box::new(move |vm| {
                            let mut prev: Option<String> = None;
                            let mut ok = true;
                            for f in &fs {
                                let x = f(vm)?;
                                if let Some(p) = &prev {
                                    ok &= cmp_ord(op, p.as_str().cmp(x.as_str()));
                                }
                                prev = Some(x);
                            }
                            Ok(i64::from(ok))
                        }))
                    }
                    _ => {
                        let u = matches!(t, Ty::ULInt | Ty::LWord);
                        let fs: Vec<IFn> = all.into_iter().map(as_i).collect();
                        CE::I(Box::new(move |vm| {
                            let mut prev: Option<i64> = None;
                            let mut ok = true;
                            for f in &fs {
                                let x = f(vm)?;
                                if let Some(p) = prev {
                                    let ord = if u {
                                        (p as u64).cmp(&(x as u64))
                                    } else {
                                        p.cmp(&x)
                                    };
                                    ok &= cmp_ord(op, ord);
                                }
                                prev = Some(x);
                            }
                            Ok(i64::from(ok))
                        }))
                    }
                }
            }
            Arith(op) if tys.iter().any(Ty::is_time_like) => {
                // exactly the operator, pair by pair (TOD wraps at midnight, TIME * REAL
                // rounds), with the checker's rule for each intermediate type
                let mut all = (0..nvals).map(&mut take);
                let mut acc = all.next().unwrap_or(CE::I(konst_i(0)));
                let mut acc_ty = t0.clone();
                for (v, t) in all.zip(tys.iter().skip(1)) {
                    let r = Ty::time_arith(*op, &acc_ty, t).unwrap_or_else(|| ret.clone());
                    acc = super::expr::binary(*op, acc, v, &acc_ty, t, &r, span);
                    acc_ty = r;
                }
                acc
            }
            Arith(op) => {
                use crate::syntax::BinOp as B;
                let n = nvals;
                let all: Vec<CE> = (0..n).map(&mut take).collect();
                let t = ret.clone();
                let op = *op;
                match t.lane() {
                    Some(crate::check::Lane::Real) => {
                        let fs: Vec<RFn> = all.into_iter().map(as_r).collect();
                        let single = t == Ty::Real;
                        CE::R(Box::new(move |vm| {
                            let mut acc = 0.0;
                            for (k, f) in fs.iter().enumerate() {
                                let x = f(vm)?;
                                acc = if k == 0 {
                                    x
                                } else {
                                    match op {
                                        B::Add => acc + x,
                                        B::Mul => acc * x,
                                        B::Sub => acc - x,
                                        _ => acc / x,
                                    }
                                };
                            }
                            Ok(if single { f64::from(acc as f32) } else { acc })
                        }))
                    }
                    _ => {
                        let fs: Vec<IFn> = all.into_iter().map(as_i).collect();
                        CE::I(Box::new(move |vm| {
                            let mut acc = 0i64;
                            for (k, f) in fs.iter().enumerate() {
                                let x = f(vm)?;
                                acc = if k == 0 {
                                    x
                                } else {
                                    match op {
                                        B::Add => acc.wrapping_add(x),
                                        B::Mul => acc.wrapping_mul(x),
                                        B::Sub => acc.wrapping_sub(x),
                                        B::And => acc & x,
                                        B::Or => acc | x,
                                        B::Xor => acc ^ x,
                                        _ => {
                                            if x == 0 {
                                                return Err(FaultKind::DivisionByZero(span).into());
                                            }
                                            acc.wrapping_div(x)
                                        }
                                    }
                                };
                                acc = t.wrap(acc);
                            }
                            Ok(acc)
                        }))
                    }
                }
            }
            // compiled by `Cx::reference` (it needs the place, not the value)
            Ref => CE::I(konst_i(0)),
            DayOfWeek => {
                let a = as_i(take(0));
                CE::I(Box::new(move |vm| Ok(time::day_of_week(a(vm)?))))
            }
            // compiled above (named parameters and outputs)
            ConcatParts(_) | SplitParts(_) => CE::I(konst_i(0)),
        }
    }

    /// `CONCAT_DATE(YEAR := y, MONTH := m, DAY := d)` and the other `CONCAT_*`: the
    /// inputs in the order written (those left out are 0); a field out of range is a
    /// fault at the call.
    fn concat_parts(&mut self, parts: time::Parts, args: &[Arg], e: &Expr) -> CE {
        let params = stdlib::params(&ConcatParts(parts)).unwrap_or_default();
        let mut inputs: Vec<(time::Field, bool, IFn)> = Vec::new();
        for (a, bound) in args.iter().zip(stdlib::bind_args(&params, args)) {
            let field = bound.ok().and_then(|i| params.get(i)).and_then(|p| p.field);
            if let Some(field) = field {
                // ULINT keeps its bit pattern in the cell
                let unsigned = self.c.final_ty(a.value.id) == Ty::ULInt;
                inputs.push((field, unsigned, as_i(self.expr(&a.value))));
            }
        }
        let (span, name) = (e.span, callee_name(e));
        CE::I(Box::new(move |vm| {
            let mut fields = time::Fields::default();
            for (field, unsigned, f) in &inputs {
                let v = f(vm)?;
                let v = if *unsigned {
                    i128::from(v as u64)
                } else {
                    i128::from(v)
                };
                fields.set(*field, v);
            }
            time::concat(parts, &fields).map_err(|err| {
                FaultKind::Conversion {
                    span,
                    what: format!("{name}: {err}"),
                }
                .into()
            })
        }))
    }

    /// `SPLIT_DATE(IN := d, YEAR => y, ...)` and the other `SPLIT_*`: `IN` first, then the
    /// outputs stored in the order written (with the subrange checks of any store).
    fn split_parts(&mut self, parts: time::Parts, args: &[Arg]) -> CE {
        let params = stdlib::params(&SplitParts(parts)).unwrap_or_default();
        let fields = Rc::new(Cell::new(time::Fields::default()));
        let mut value: Option<IFn> = None;
        let mut stores: Vec<StmtFn> = Vec::new();
        for (a, bound) in args.iter().zip(stdlib::bind_args(&params, args)) {
            let Some(p) = bound.ok().and_then(|i| params.get(i)) else {
                continue;
            };
            match p.field {
                None => value = Some(as_i(self.expr(&a.value))),
                Some(field) => {
                    let Some(dst) = self.place(&a.value) else {
                        self.error(a.value.span, "cannot compile this output");
                        continue;
                    };
                    let read = Rc::clone(&fields);
                    let v: IFn =
                        Box::new(move |_| Ok(i64::try_from(read.get().get(field)).unwrap_or(0)));
                    stores.push(self.store(&dst, CE::I(v)));
                }
            }
        }
        let value = value.unwrap_or_else(|| konst_i(0));
        CE::I(Box::new(move |vm| {
            fields.set(time::split(parts, value(vm)?));
            for store in &stores {
                store(vm)?;
            }
            Ok(0)
        }))
    }
}

/// The upper-case name of the function a call calls.
fn callee_name(e: &Expr) -> String {
    match &e.kind {
        ExprKind::Call(callee, _) => match &callee.kind {
            ExprKind::Name { ident, .. } => ident.key.clone(),
            _ => String::new(),
        },
        _ => String::new(),
    }
}

fn cmp_ord(op: crate::syntax::BinOp, o: std::cmp::Ordering) -> bool {
    use crate::syntax::BinOp as B;
    use std::cmp::Ordering::*;
    match op {
        B::Gt => o == Greater,
        B::Ge => o != Less,
        B::Eq => o == Equal,
        B::Le => o != Greater,
        B::Lt => o == Less,
        _ => o != Equal,
    }
}

fn cmp_f(op: crate::syntax::BinOp, a: f64, b: f64) -> bool {
    use crate::syntax::BinOp as B;
    match op {
        B::Gt => a > b,
        B::Ge => a >= b,
        B::Eq => a == b,
        B::Le => a <= b,
        B::Lt => a < b,
        _ => a != b,
    }
}
