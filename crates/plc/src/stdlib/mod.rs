//! The standard library.
//!
//! Two kinds of members:
//! - **Function blocks written in ST** ([`PRELUDE`]): timers, edge detection, counters and
//!   bistables, plus the `DTL` struct and its conversions. They are compiled with the user's
//!   program like any other POU, so they are inspectable (`Main.t1.ET`) and the compiler is
//!   exercised by them. Their only hook into the host is the `__NOW()` intrinsic (the
//!   scan's monotonic time from the injected clock).
//! - **Built-in functions** ([`Builtin`]): generic or overloaded functions (`MAX`, `LEN`,
//!   `*_TO_*`, ...) typed by [`signature`] and compiled to native closures by
//!   [`crate::compile`]. One module per family holds the implementations.
//!
//! The counters come in every width the standard lists (`CTU_INT` .. `CTUD_ULINT`); the
//! CODESYS names of block parameters (`RESET`, `LOAD`, `SET1`, ...) name the same inputs
//! ([`parameter_aliases`]). Conversions include the typed truncations (`REAL_TRUNC_INT`)
//! and BCD (`WORD_BCD_TO_UINT`, `UINT_TO_BCD_WORD`; a digit above 9 is a fault).
//!
//! Beyond the standard, the prelude has `HYSTERESIS`, `RAMP`, `PID` (CODESYS Util
//! interface), `WEEKLY_SWITCH`, the astronomical clock `SUN_TIME` (NOAA), the Siemens DTL
//! helpers (`RD_LOC_T`, `RD_SYS_T`, `T_DIFF`, `DT_TO_DTL`, ...) and the Mosaic `System_S`
//! flags. TON, TOF, TP, R_TRIG and F_TRIG get native bodies ([`timers`]) checked against
//! their ST text.
//!
//! The date and time functions of IEC 61131-3 table 36 with outputs, `SPLIT_DATE`,
//! `SPLIT_TOD`, `SPLIT_DT` and their L-forms, and their inverses `CONCAT_DATE`,
//! `CONCAT_TOD`, `CONCAT_DT`, ... are built-ins with named parameters ([`params`],
//! [`bind_args`]): `SPLIT_DT(IN := x, YEAR => y, DAY => d)` or without names in the
//! standard's order (`IN`, then the outputs); the fields are ANY_INT. A field out of range
//! (`MONTH` 13, `HOUR` 24, day 31 in February, a year DATE does not hold) is a run-time
//! fault at the call, or a diagnostic when it is a constant ([`time::concat`]).
//!
//! Extension point: a new FB is added to the prelude (ST) or, if it needs native code, as a
//! builtin plus an ST wrapper, or an ST declaration with a native body in [`timers`].

pub mod bits;
pub mod conv;
pub mod numeric;
pub mod string;
pub mod time;
pub mod timers;

use crate::check::Ty;

/// The ST source of the standard function blocks.
pub const PRELUDE: &str = include_str!("prelude.st");

/// A built-in function.
#[derive(Debug, Clone, PartialEq)]
#[allow(missing_docs)]
pub enum Builtin {
    Abs,
    Sqrt,
    Ln,
    Log,
    Exp,
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    Atan2,
    Expt,
    Trunc,
    Round,
    Floor,
    Ceil,
    Mod,
    Shl,
    Shr,
    Rol,
    Ror,
    Sel,
    Max,
    Min,
    Limit,
    Mux,
    Move,
    Len,
    Left,
    Right,
    Mid,
    Concat,
    Insert,
    Delete,
    Replace,
    Find,
    /// `X_TO_Y` (source checked) or `TO_Y` (source `None`).
    Convert(Option<Ty>, Ty),
    /// `REAL_TRUNC_INT`, `LREAL_TRUNC_DINT`, ... (IEC 61131-3 typed truncation; source
    /// checked) or CODESYS `TRUNC_INT` (source `None`, any REAL or LREAL): toward zero.
    TruncTo(Option<Ty>, Ty),
    /// `WORD_BCD_TO_UINT` (source checked) or `BCD_TO_INT` (any bit string): a binary
    /// coded decimal to an integer.
    BcdTo(Option<Ty>, Ty),
    /// `UINT_TO_BCD_WORD` or `INT_TO_BCD` (the bit string as wide as the integer): an
    /// unsigned value to binary coded decimal.
    ToBcd(Ty, Ty),
    AddTime,
    SubTime,
    MulTime,
    DivTime,
    AddTodTime,
    SubTodTime,
    SubTodTod,
    AddDtTime,
    SubDtTime,
    SubDtDt,
    SubDateDate,
    ConcatDateTod,
    /// The LTIME forms of the typed time functions (`ADD_LTIME`, `SUB_LDT_LDT`, ...): LDATE,
    /// LTOD and LDT are DATE, TOD and DT here; the durations they take and give are LTIME.
    AddLTime,
    SubLTime,
    MulLTime,
    DivLTime,
    AddLTodLTime,
    SubLTodLTime,
    SubLTodLTod,
    AddLDtLTime,
    SubLDtLTime,
    SubLDtLDt,
    SubLDateLDate,
    DtToTod,
    DtToDate,
    TDiff,
    /// Monotonic scan time (`__NOW()`, also `TIME()`).
    Now,
    /// Local wall-clock time as DT.
    LocalTime,
    /// UTC wall-clock time as DT.
    SystemTime,
    /// Day of week of a DATE/DT, 1 = Monday .. 7 = Sunday (ISO).
    DayOfWeek,
    /// `CONCAT_DATE`, `CONCAT_TOD`, `CONCAT_DT` and the L-forms: a value from its fields
    /// (ANY_INT inputs, named or in order; checked at run time, a wrong one is a fault).
    ConcatParts(time::Parts),
    /// `SPLIT_DATE`, `SPLIT_TOD`, `SPLIT_DT` and the L-forms: the fields of a value as
    /// outputs (`YEAR => y`, or in order after `IN`) into ANY_INT variables; a statement.
    SplitParts(time::Parts),
    /// Extensible comparison chain `GT(a, b, c)` = `a > b AND b > c` (and GE, EQ, LE, LT, NE).
    Compare(crate::syntax::BinOp),
    /// `REF(x)`: the address of a variable (typed by the checker, not by [`signature`]).
    Ref,
    /// Extensible arithmetic/logic in function form: `ADD(a, b, c)`, `MUL`, `AND`, `OR`, `XOR`,
    /// and the binary `SUB`, `DIV`.
    Arith(crate::syntax::BinOp),
}

/// Other names of the parameters of standard function blocks, as `(alias, name)`: the
/// CODESYS spellings (`RESET` for a counter's `R`, `LOAD` for `LD`, `SET1`/`RESET` of SR,
/// `SET`/`RESET1` of RS), so programs written for CODESYS call the blocks unchanged.
pub fn parameter_aliases(block: &str) -> &'static [(&'static str, &'static str)] {
    let counter = block.split_once('_').map_or(block, |(kind, _)| kind);
    match (counter, block) {
        ("CTU", _) => &[("RESET", "R")],
        ("CTD", _) => &[("LOAD", "LD")],
        ("CTUD", _) => &[("RESET", "R"), ("LOAD", "LD")],
        (_, "SR") => &[("SET1", "S1"), ("RESET", "R")],
        (_, "RS") => &[("SET", "S"), ("RESET1", "R1")],
        _ => &[],
    }
}

fn type_by_conv_name(name: &str) -> Option<Ty> {
    Ty::elementary(name)
}

/// Looks up a built-in by upper-case name.
pub fn lookup(name: &str) -> Option<Builtin> {
    use Builtin::*;
    Some(match name {
        "ABS" => Abs,
        "SQRT" => Sqrt,
        "LN" => Ln,
        "LOG" => Log,
        "EXP" => Exp,
        "SIN" => Sin,
        "COS" => Cos,
        "TAN" => Tan,
        "ASIN" => Asin,
        "ACOS" => Acos,
        "ATAN" => Atan,
        "ATAN2" => Atan2,
        "EXPT" => Expt,
        "TRUNC" => Trunc,
        "ROUND" => Round,
        "FLOOR" => Floor,
        "CEIL" => Ceil,
        "MOD" => Mod,
        "SHL" => Shl,
        "SHR" => Shr,
        "ROL" => Rol,
        "ROR" => Ror,
        "SEL" => Sel,
        "MAX" => Max,
        "MIN" => Min,
        "LIMIT" => Limit,
        "MUX" => Mux,
        "MOVE" => Move,
        "LEN" => Len,
        "LEFT" => Left,
        "RIGHT" => Right,
        "MID" => Mid,
        "CONCAT" => Concat,
        "INSERT" => Insert,
        "DELETE" => Delete,
        "REPLACE" => Replace,
        "FIND" => Find,
        "ADD_TIME" => AddTime,
        "SUB_TIME" => SubTime,
        "MUL_TIME" | "MULTIME" => MulTime,
        "DIV_TIME" | "DIVTIME" => DivTime,
        "ADD_TOD_TIME" => AddTodTime,
        "SUB_TOD_TIME" => SubTodTime,
        "SUB_TOD_TOD" => SubTodTod,
        "ADD_DT_TIME" => AddDtTime,
        "SUB_DT_TIME" => SubDtTime,
        "SUB_DT_DT" => SubDtDt,
        "SUB_DATE_DATE" => SubDateDate,
        "CONCAT_DATE_TOD" | "CONCAT_DATE_LTOD" | "CONCAT_LDATE_LTOD" => ConcatDateTod,
        "ADD_LTIME" => AddLTime,
        "SUB_LTIME" => SubLTime,
        "MUL_LTIME" => MulLTime,
        "DIV_LTIME" => DivLTime,
        "ADD_LTOD_LTIME" => AddLTodLTime,
        "SUB_LTOD_LTIME" => SubLTodLTime,
        "SUB_LTOD_LTOD" => SubLTodLTod,
        "ADD_LDT_LTIME" => AddLDtLTime,
        "SUB_LDT_LTIME" => SubLDtLTime,
        "SUB_LDT_LDT" => SubLDtLDt,
        "SUB_LDATE_LDATE" => SubLDateLDate,
        "DT_TO_TOD" | "DATE_AND_TIME_TO_TIME_OF_DAY" => DtToTod,
        "DT_TO_DATE" | "DATE_AND_TIME_TO_DATE" => DtToDate,
        "__NOW" | "TIME" => Now,
        "LOCAL_TIME" | "__LOCAL_TIME" => LocalTime,
        "SYSTEM_TIME" | "__SYSTEM_TIME" => SystemTime,
        "DAY_OF_WEEK" => DayOfWeek,
        "CONCAT_DATE" => ConcatParts(time::Parts::Date),
        "CONCAT_LDATE" => ConcatParts(time::Parts::LDate),
        "CONCAT_TOD" => ConcatParts(time::Parts::Tod),
        "CONCAT_LTOD" => ConcatParts(time::Parts::LTod),
        "CONCAT_DT" => ConcatParts(time::Parts::Dt),
        "CONCAT_LDT" => ConcatParts(time::Parts::LDt),
        "SPLIT_DATE" => SplitParts(time::Parts::Date),
        "SPLIT_LDATE" => SplitParts(time::Parts::LDate),
        "SPLIT_TOD" => SplitParts(time::Parts::Tod),
        "SPLIT_LTOD" => SplitParts(time::Parts::LTod),
        "SPLIT_DT" => SplitParts(time::Parts::Dt),
        "SPLIT_LDT" => SplitParts(time::Parts::LDt),
        "GT" => Compare(crate::syntax::BinOp::Gt),
        "GE" => Compare(crate::syntax::BinOp::Ge),
        "EQ" => Compare(crate::syntax::BinOp::Eq),
        "LE" => Compare(crate::syntax::BinOp::Le),
        "LT" => Compare(crate::syntax::BinOp::Lt),
        "NE" => Compare(crate::syntax::BinOp::Ne),
        "ADD" => Arith(crate::syntax::BinOp::Add),
        "MUL" => Arith(crate::syntax::BinOp::Mul),
        "SUB" => Arith(crate::syntax::BinOp::Sub),
        "DIV" => Arith(crate::syntax::BinOp::Div),
        "AND" => Arith(crate::syntax::BinOp::And),
        "OR" => Arith(crate::syntax::BinOp::Or),
        "XOR" => Arith(crate::syntax::BinOp::Xor),
        _ => {
            if let Some(rest) = name.strip_prefix("BCD_TO_") {
                return Some(BcdTo(None, Ty::elementary(rest).filter(Ty::is_int)?));
            }
            if let Some((a, b)) = name.split_once("_BCD_TO_") {
                let from = Ty::elementary(a).filter(Ty::is_bits)?;
                let to = Ty::elementary(b).filter(Ty::is_int)?;
                return Some(BcdTo(Some(from), to));
            }
            if let Some((a, b)) = name.split_once("_TO_BCD") {
                let from = Ty::elementary(a).filter(Ty::is_int)?;
                let to = match b {
                    "" => match from.bits() {
                        8 => Ty::Byte,
                        16 => Ty::Word,
                        32 => Ty::DWord,
                        _ => Ty::LWord,
                    },
                    _ => Ty::elementary(b.strip_prefix('_')?).filter(Ty::is_bits)?,
                };
                return Some(ToBcd(from, to));
            }
            if let Some(rest) = name.strip_prefix("TRUNC_") {
                return Some(TruncTo(None, Ty::elementary(rest).filter(Ty::is_int)?));
            }
            if let Some((a, b)) = name.split_once("_TRUNC_") {
                let from = Ty::elementary(a).filter(Ty::is_real)?;
                let to = Ty::elementary(b).filter(Ty::is_int)?;
                return Some(TruncTo(Some(from), to));
            }
            if let Some(rest) = name.strip_prefix("TO_") {
                return Some(Convert(None, type_by_conv_name(rest)?));
            }
            if let Some((a, b)) = name.split_once("_TO_") {
                let from = type_by_conv_name(a)?;
                let to = type_by_conv_name(b)?;
                return Some(Convert(Some(from), to));
            }
            // TRUNC_INT / TRUNC_DINT style
            return None;
        }
    })
}

/// Parameter types (for implicit conversion of each argument) and result type of a built-in
/// applied to arguments of the given natural types. `Err` is a message for a
/// `WrongArguments`/`TypeMismatch` diagnostic.
pub fn signature(b: &Builtin, args: &[Ty]) -> Result<(Vec<Ty>, Ty), String> {
    use Builtin::*;
    let n = args.len();
    let need = |k: usize| -> Result<(), String> {
        if n == k {
            Ok(())
        } else {
            Err(format!(
                "expects {k} argument{}, got {n}",
                if k == 1 { "" } else { "s" }
            ))
        }
    };
    let arg = |i: usize| args.get(i).cloned().unwrap_or(Ty::Void);
    let common = |tys: &[Ty]| -> Result<Ty, String> {
        let mut t = tys.first().cloned().unwrap_or(Ty::Void);
        for x in tys.iter().skip(1) {
            t = Ty::common(&t, x)
                .ok_or_else(|| format!("arguments of types {t} and {x} do not match"))?;
        }
        Ok(t)
    };
    let real_of = |t: &Ty| if *t == Ty::LReal { Ty::LReal } else { Ty::Real };
    Ok(match b {
        Abs => {
            need(1)?;
            let t = arg(0);
            if !t.is_num() {
                return Err(format!("expects a number, got {t}"));
            }
            (vec![t.clone()], t)
        }
        Sqrt | Ln | Log | Exp | Sin | Cos | Tan | Asin | Acos | Atan | Round | Floor | Ceil => {
            need(1)?;
            let t = arg(0);
            if !t.is_num() {
                return Err(format!("expects a number, got {t}"));
            }
            let r = if t.is_real() {
                t.clone()
            } else {
                real_of(&if t.converts_to(&Ty::Real) {
                    Ty::Real
                } else {
                    Ty::LReal
                })
            };
            (vec![r.clone()], r)
        }
        Atan2 => {
            need(2)?;
            let t = common(args)?;
            let r = if t == Ty::LReal || !t.converts_to(&Ty::Real) {
                Ty::LReal
            } else {
                Ty::Real
            };
            (vec![r.clone(), r.clone()], r)
        }
        Trunc => {
            need(1)?;
            let t = arg(0);
            if !t.is_real() {
                return Err(format!("expects REAL or LREAL, got {t}"));
            }
            (vec![t.clone()], Ty::DInt)
        }
        Expt => {
            need(2)?;
            let t = arg(0);
            if !t.is_num() || !arg(1).is_num() {
                return Err("expects numbers".into());
            }
            let r = if t.is_real() { t } else { Ty::LReal };
            let e = if arg(1).is_int() { arg(1) } else { r.clone() };
            (vec![r.clone(), e], r)
        }
        Mod => {
            need(2)?;
            let t = common(args)?;
            if !t.is_int() && !t.is_bits() {
                return Err(format!("expects integers, got {t}"));
            }
            (vec![t.clone(), t.clone()], t)
        }
        Shl | Shr | Rol | Ror => {
            need(2)?;
            let t = arg(0);
            if !t.is_bits() && !t.is_int() {
                return Err(format!("expects a bit string, got {t}"));
            }
            if !arg(1).is_int() && !arg(1).is_bits() {
                return Err("shift count must be an integer".into());
            }
            (vec![t.clone(), arg(1)], t)
        }
        Sel => {
            need(3)?;
            let t = common(args.get(1..).unwrap_or(&[]))?;
            (vec![Ty::Bool, t.clone(), t.clone()], t)
        }
        Max | Min => {
            if n < 2 {
                return Err(format!("expects at least 2 arguments, got {n}"));
            }
            let t = common(args)?;
            (vec![t.clone(); n], t)
        }
        Limit => {
            need(3)?;
            let t = common(args)?;
            (vec![t.clone(); 3], t)
        }
        Mux => {
            if n < 2 {
                return Err(format!("expects a selector and at least 1 input, got {n}"));
            }
            if !arg(0).is_int() {
                return Err("MUX selector must be an integer".into());
            }
            let t = common(args.get(1..).unwrap_or(&[]))?;
            let mut v = vec![arg(0)];
            v.extend(std::iter::repeat_n(t.clone(), n - 1));
            (v, t)
        }
        Move => {
            need(1)?;
            (vec![arg(0)], arg(0))
        }
        Len => {
            need(1)?;
            if !arg(0).is_string() {
                return Err(format!("expects a string, got {}", arg(0)));
            }
            (vec![arg(0)], Ty::Int)
        }
        Left | Right => {
            need(2)?;
            if !arg(0).is_string() || !arg(1).is_int() {
                return Err("expects (string, integer)".into());
            }
            (vec![arg(0), Ty::DInt], arg(0))
        }
        Mid => {
            need(3)?;
            if !arg(0).is_string() || !arg(1).is_int() || !arg(2).is_int() {
                return Err("expects (string, length, position)".into());
            }
            (vec![arg(0), Ty::DInt, Ty::DInt], arg(0))
        }
        Concat => {
            if n < 2 || !args.iter().all(Ty::is_string) {
                return Err("expects at least 2 strings".into());
            }
            let t = common(args)?;
            let len = args
                .iter()
                .map(|a| match a {
                    Ty::String(l) | Ty::WString(l) => *l,
                    _ => 0,
                })
                .fold(0u32, u32::saturating_add)
                .min(65535);
            let r = if matches!(t, Ty::WString(_)) {
                Ty::WString(len)
            } else {
                Ty::String(len)
            };
            (args.to_vec(), r)
        }
        Insert => {
            need(3)?;
            if !arg(0).is_string() || !arg(1).is_string() || !arg(2).is_int() {
                return Err("expects (string, string, position)".into());
            }
            (vec![arg(0), arg(1), Ty::DInt], arg(0))
        }
        Delete => {
            need(3)?;
            if !arg(0).is_string() || !arg(1).is_int() || !arg(2).is_int() {
                return Err("expects (string, length, position)".into());
            }
            (vec![arg(0), Ty::DInt, Ty::DInt], arg(0))
        }
        Replace => {
            need(4)?;
            if !arg(0).is_string() || !arg(1).is_string() || !arg(2).is_int() || !arg(3).is_int() {
                return Err("expects (string, string, length, position)".into());
            }
            (vec![arg(0), arg(1), Ty::DInt, Ty::DInt], arg(0))
        }
        Find => {
            need(2)?;
            if !arg(0).is_string() || !arg(1).is_string() {
                return Err("expects two strings".into());
            }
            (vec![arg(0), arg(1)], Ty::Int)
        }
        Convert(from, to) => {
            need(1)?;
            let a = arg(0);
            let src = match from {
                Some(f) => {
                    if !a.converts_to(f) {
                        return Err(format!("expects {f}, got {a}"));
                    }
                    f.clone()
                }
                None => a,
            };
            if !conv::convertible(&src, to) {
                return Err(format!("cannot convert {src} to {to}"));
            }
            (vec![src], to.clone())
        }
        BcdTo(from, to) => {
            need(1)?;
            let a = arg(0);
            let src = match from {
                Some(f) if a.converts_to(f) => f.clone(),
                Some(f) => return Err(format!("expects {f}, got {a}")),
                None if a.is_bits() => a,
                None => return Err(format!("expects a bit string, got {a}")),
            };
            (vec![src], to.clone())
        }
        ToBcd(from, to) => {
            need(1)?;
            if !arg(0).converts_to(from) {
                return Err(format!("expects {from}, got {}", arg(0)));
            }
            (vec![from.clone()], to.clone())
        }
        TruncTo(from, to) => {
            need(1)?;
            let a = arg(0);
            let src = match from {
                Some(f) if a.converts_to(f) => f.clone(),
                Some(f) => return Err(format!("expects {f}, got {a}")),
                None if a.is_real() => a,
                None => return Err(format!("expects REAL or LREAL, got {a}")),
            };
            (vec![src], to.clone())
        }
        AddTime | SubTime => {
            need(2)?;
            (vec![Ty::Time, Ty::Time], Ty::Time)
        }
        MulTime | DivTime => {
            need(2)?;
            let k = if arg(1).is_num() { arg(1) } else { Ty::LReal };
            (vec![Ty::Time, k], Ty::Time)
        }
        AddTodTime | SubTodTime => {
            need(2)?;
            (vec![Ty::Tod, Ty::Time], Ty::Tod)
        }
        SubTodTod => {
            need(2)?;
            (vec![Ty::Tod, Ty::Tod], Ty::Time)
        }
        AddDtTime | SubDtTime => {
            need(2)?;
            (vec![Ty::Dt, Ty::Time], Ty::Dt)
        }
        SubDtDt | TDiff => {
            need(2)?;
            (vec![Ty::Dt, Ty::Dt], Ty::Time)
        }
        SubDateDate => {
            need(2)?;
            (vec![Ty::Date, Ty::Date], Ty::Time)
        }
        AddLTime | SubLTime => {
            need(2)?;
            (vec![Ty::LTime, Ty::LTime], Ty::LTime)
        }
        MulLTime | DivLTime => {
            need(2)?;
            let k = if arg(1).is_num() { arg(1) } else { Ty::LReal };
            (vec![Ty::LTime, k], Ty::LTime)
        }
        AddLTodLTime | SubLTodLTime => {
            need(2)?;
            (vec![Ty::Tod, Ty::LTime], Ty::Tod)
        }
        SubLTodLTod => {
            need(2)?;
            (vec![Ty::Tod, Ty::Tod], Ty::LTime)
        }
        AddLDtLTime | SubLDtLTime => {
            need(2)?;
            (vec![Ty::Dt, Ty::LTime], Ty::Dt)
        }
        SubLDtLDt => {
            need(2)?;
            (vec![Ty::Dt, Ty::Dt], Ty::LTime)
        }
        SubLDateLDate => {
            need(2)?;
            (vec![Ty::Date, Ty::Date], Ty::LTime)
        }
        ConcatDateTod => {
            need(2)?;
            (vec![Ty::Date, Ty::Tod], Ty::Dt)
        }
        DtToTod => {
            need(1)?;
            (vec![Ty::Dt], Ty::Tod)
        }
        DtToDate => {
            need(1)?;
            (vec![Ty::Dt], Ty::Date)
        }
        Now => {
            need(0)?;
            (vec![], Ty::Time)
        }
        LocalTime | SystemTime => {
            need(0)?;
            (vec![], Ty::Dt)
        }
        Compare(op) => {
            if n < 2 || (*op == crate::syntax::BinOp::Ne && n != 2) {
                return Err(format!("expects at least 2 arguments, got {n}"));
            }
            let t = common(args)?;
            if !t.is_elementary() {
                return Err(format!("cannot compare {t}"));
            }
            (vec![t; n], Ty::Bool)
        }
        Arith(op) => {
            use crate::syntax::BinOp as B;
            let binary = matches!(op, B::Sub | B::Div);
            if n < 2 || (binary && n != 2) {
                return Err(format!(
                    "expects {} arguments, got {n}",
                    if binary { "2" } else { "at least 2" }
                ));
            }
            let t = common(args)?;
            let logic = matches!(op, B::And | B::Or | B::Xor);
            let ok = if logic {
                t == Ty::Bool || t.is_bits() || t.is_int()
            } else {
                t.is_num()
            };
            if !ok {
                return Err(format!("cannot apply to {t}"));
            }
            (vec![t.clone(); n], t)
        }
        Ref => return Err("REF takes one variable".into()),
        DayOfWeek => {
            need(1)?;
            let t = if arg(0) == Ty::Date { Ty::Date } else { Ty::Dt };
            (vec![t], Ty::USInt)
        }
        // typed by the checker against their parameters ([`params`])
        ConcatParts(_) | SplitParts(_) => return Err("takes named parameters".into()),
    })
}

/// A parameter of a built-in with named parameters and outputs (`SPLIT_DT(IN := d,
/// YEAR => y)`): `IN` or a field of a date and time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Param {
    /// The field, or `None` for `IN`.
    pub field: Option<time::Field>,
    /// A VAR_OUTPUT: bound with `=>`, or in a call without names, in order after the inputs.
    pub output: bool,
    /// An input that must be given. The others are 0 when left out of a call with
    /// names, as the standard says; an input whose 0 is always wrong (`MONTH`) must be given.
    pub required: bool,
    /// Given by name only: not in the standard's list (`NANOSECOND` of the L-forms), so
    /// the standard's calls without names mean what they mean elsewhere.
    pub named_only: bool,
}

impl Param {
    /// The parameter's name.
    pub fn name(&self) -> &'static str {
        self.field.map_or("IN", time::Field::name)
    }
}

/// The parameters of a built-in that has named parameters or outputs, in order; `None`
/// for the others (their arguments are positional, typed by [`signature`]).
pub fn params(b: &Builtin) -> Option<Vec<Param>> {
    let field = |f: time::Field, output: bool| Param {
        field: Some(f),
        output,
        required: !output && matches!(f, time::Field::Year | time::Field::Month | time::Field::Day),
        named_only: f == time::Field::Nanosecond,
    };
    match b {
        Builtin::ConcatParts(parts) => {
            Some(parts.fields().iter().map(|&f| field(f, false)).collect())
        }
        Builtin::SplitParts(parts) => {
            let input = Param {
                field: None,
                output: false,
                required: true,
                named_only: false,
            };
            let outputs = parts.fields().iter().map(|&f| field(f, true));
            Some(std::iter::once(input).chain(outputs).collect())
        }
        _ => None,
    }
}

/// Why an argument binds to no parameter ([`bind_args`]).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ArgError {
    /// A name that is no parameter.
    #[error("has no parameter '{0}'")]
    Unknown(String),
    /// `X =>` of an input.
    #[error("'{0}' is an input, not an output")]
    NotOutput(&'static str),
    /// `X :=` of an output.
    #[error("'{0}' is an output: bind it with `{0} =>`")]
    NotInput(&'static str),
    /// An argument without a name after one with a name.
    #[error("positional argument after named arguments")]
    AfterNamed,
    /// More arguments without names than the parameter list has.
    #[error("too many arguments: it has {0} parameters")]
    TooMany(usize),
    /// A parameter given twice.
    #[error("'{0}' given more than once")]
    Twice(&'static str),
}

/// The parameter (an index into `params`) each argument binds to: by name, or in order
/// (the parameters that are not [`Param::named_only`], outputs included, as a call
/// without names lists them).
pub fn bind_args(params: &[Param], args: &[crate::syntax::Arg]) -> Vec<Result<usize, ArgError>> {
    let positional: Vec<usize> = params
        .iter()
        .enumerate()
        .filter(|(_, p)| !p.named_only)
        .map(|(i, _)| i)
        .collect();
    let mut next = 0usize;
    let mut named = false;
    let mut given: Vec<usize> = Vec::new();
    args.iter()
        .map(|a| {
            let i = match &a.name {
                Some(n) => {
                    named = true;
                    let (i, p) = params
                        .iter()
                        .enumerate()
                        .find(|(_, p)| p.name() == n.key)
                        .ok_or_else(|| ArgError::Unknown(n.name.clone()))?;
                    match (a.output, p.output) {
                        (true, false) => return Err(ArgError::NotOutput(p.name())),
                        (false, true) => return Err(ArgError::NotInput(p.name())),
                        _ => i,
                    }
                }
                None if named => return Err(ArgError::AfterNamed),
                None => {
                    let i = *positional
                        .get(next)
                        .ok_or(ArgError::TooMany(positional.len()))?;
                    next += 1;
                    i
                }
            };
            if given.contains(&i) {
                return Err(ArgError::Twice(params.get(i).map_or("", Param::name)));
            }
            given.push(i);
            Ok(i)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use crate::task::{ClockReading, TaskConfig};

    /// Calls of the date and time functions with named parameters and outputs, as
    /// `plc check` prints what it refuses.
    #[test]
    fn rendered_date_and_time_call_diagnostics() {
        let src = "PROGRAM Main\nVAR y : INT; b : SINT; r : REAL; d : DATE; END_VAR\n\
                   SPLIT_DATE(IN := d, YEAR => y, HOURS => y);\n\
                   SPLIT_DATE(IN := d, YEAR => b, DAY => r);\n\
                   d := CONCAT_DATE(YEAR := 2023, MONTH := 2, DAY := 29);\n\
                   d := CONCAT_DATE(MONTH := 1, DAY := 1);\n\
                   y := SPLIT_TOD(TOD#12:00:00, y);\n\
                   END_PROGRAM\n";
        let (sources, r) = crate::build(&[("dates.st".to_string(), src.to_string())]);
        let Err(diags) = r else {
            panic!("compiled");
        };
        let text = diags
            .iter()
            .map(|d| d.render(&sources))
            .collect::<Vec<_>>()
            .join("\n");
        insta::assert_snapshot!("date_and_time_calls", text);
    }

    /// A wrong field is a run-time fault at the call.
    #[test]
    fn rendered_date_and_time_fault() {
        let src = "PROGRAM Main\nVAR m : INT := 2; d : DATE; x : DT; END_VAR\n\
                   d := CONCAT_DATE(2024, m, 29);\n\
                   x := CONCAT_DT(YEAR := 2023, MONTH := m, DAY := 29, HOUR := 1);\n\
                   END_PROGRAM\n";
        let (sources, r) = crate::build(&[("fault.st".to_string(), src.to_string())]);
        let mut p = crate::Plc::new(r.unwrap(), sources);
        p.add_task(TaskConfig::cyclic("main", 10_000_000, &["Main"]))
            .unwrap();
        let faults = p.run_cycle(ClockReading::default());
        let text = faults
            .iter()
            .map(|d| p.render(d))
            .collect::<Vec<_>>()
            .join("\n");
        insta::assert_snapshot!("date_and_time_fault", text);
    }
}
