//! Native bodies of the most used standard FBs (TON, TOF, TP, R_TRIG, F_TRIG).
//!
//! The prelude declares these blocks in ST — their interface and the reference semantics —
//! and the compiler swaps in these bodies, which implement exactly the same ST code over
//! the instance memory. A program with 1,000 timers then costs a few nanoseconds per timer.

use crate::check::PouInfo;
use crate::vm::{Fault, Flow, StmtFn, Vm};

fn off(pou: &PouInfo, name: &str) -> Option<usize> {
    pou.var(&name.to_uppercase()).map(|(_, v)| v.offset.i)
}

#[inline]
fn get(vm: &Vm, a: usize) -> Result<i64, Fault> {
    vm.geti(vm.frame.i + a)
}

#[inline]
fn set(vm: &mut Vm, a: usize, v: i64) -> Result<(), Fault> {
    vm.seti(vm.frame.i + a, v)
}

/// The native body for a standard FB, if there is one.
pub fn native_body(pou: &PouInfo) -> Option<StmtFn> {
    if !pou.stdlib {
        return None;
    }
    match pou.name.as_str() {
        "TON" => {
            let (i, pt, q, et, run, st) = (
                off(pou, "IN")?,
                off(pou, "PT")?,
                off(pou, "Q")?,
                off(pou, "ET")?,
                off(pou, "running")?,
                off(pou, "start")?,
            );
            Some(Box::new(move |vm| {
                if get(vm, i)? != 0 {
                    if get(vm, run)? == 0 {
                        set(vm, run, 1)?;
                        set(vm, st, vm.now)?;
                    }
                    if get(vm, q)? == 0 {
                        let e = vm.now.wrapping_sub(get(vm, st)?);
                        let p = get(vm, pt)?;
                        if e >= p {
                            set(vm, et, p)?;
                            set(vm, q, 1)?;
                        } else {
                            set(vm, et, e)?;
                        }
                    }
                } else {
                    set(vm, run, 0)?;
                    set(vm, q, 0)?;
                    set(vm, et, 0)?;
                }
                Ok(Flow::Normal)
            }))
        }
        "TOF" => {
            let (i, pt, q, et, run, st) = (
                off(pou, "IN")?,
                off(pou, "PT")?,
                off(pou, "Q")?,
                off(pou, "ET")?,
                off(pou, "running")?,
                off(pou, "start")?,
            );
            Some(Box::new(move |vm| {
                if get(vm, i)? != 0 {
                    set(vm, q, 1)?;
                    set(vm, et, 0)?;
                    set(vm, run, 0)?;
                } else if get(vm, q)? != 0 {
                    if get(vm, run)? == 0 {
                        set(vm, run, 1)?;
                        set(vm, st, vm.now)?;
                    }
                    let e = vm.now.wrapping_sub(get(vm, st)?);
                    let p = get(vm, pt)?;
                    if e >= p {
                        set(vm, et, p)?;
                        set(vm, q, 0)?;
                        set(vm, run, 0)?;
                    } else {
                        set(vm, et, e)?;
                    }
                }
                Ok(Flow::Normal)
            }))
        }
        "TP" => {
            let (i, pt, q, et, prev, st) = (
                off(pou, "IN")?,
                off(pou, "PT")?,
                off(pou, "Q")?,
                off(pou, "ET")?,
                off(pou, "prev")?,
                off(pou, "start")?,
            );
            Some(Box::new(move |vm| {
                let inp = get(vm, i)? != 0;
                if get(vm, q)? == 0 && inp && get(vm, prev)? == 0 && get(vm, et)? == 0 {
                    set(vm, q, 1)?;
                    set(vm, st, vm.now)?;
                }
                if get(vm, q)? != 0 {
                    let e = vm.now.wrapping_sub(get(vm, st)?);
                    let p = get(vm, pt)?;
                    if e >= p {
                        set(vm, et, p)?;
                        set(vm, q, 0)?;
                    } else {
                        set(vm, et, e)?;
                    }
                }
                if get(vm, q)? == 0 && !inp {
                    set(vm, et, 0)?;
                }
                set(vm, prev, i64::from(inp))?;
                Ok(Flow::Normal)
            }))
        }
        "R_TRIG" | "F_TRIG" => {
            let rising = pou.name == "R_TRIG";
            let (clk, q, m) = (off(pou, "CLK")?, off(pou, "Q")?, off(pou, "M")?);
            Some(Box::new(move |vm| {
                let c = get(vm, clk)? != 0;
                let mem = get(vm, m)? != 0;
                let out = if rising { c && !mem } else { !c && mem };
                set(vm, q, i64::from(out))?;
                set(vm, m, i64::from(c))?;
                Ok(Flow::Normal)
            }))
        }
        _ => None,
    }
}
