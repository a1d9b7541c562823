//! Native bodies of the most used standard FBs (TON, TOF, TP, R_TRIG, F_TRIG).
//!
//! The prelude declares these blocks in ST — their interface and the reference semantics —
//! and the compiler swaps in these bodies, which implement exactly the same ST code over
//! the instance memory. A body takes the instance's integer cells as one fixed-size array
//! (one bounds check per call, the variables at their declared positions), so a program
//! with 1,000 timers costs a few nanoseconds per timer.

use crate::check::PouInfo;
use crate::vm::{Fault, Flow, StmtFn, Vm};

/// A standard FB with a native body.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NativeFb {
    /// On-delay timer.
    Ton,
    /// Off-delay timer.
    Tof,
    /// Pulse timer.
    Tp,
    /// Rising edge.
    RTrig,
    /// Falling edge.
    FTrig,
}

impl NativeFb {
    /// The native body for a standard FB, if it has one and its instance layout is the
    /// one the body assumes (the variables in declaration order from integer cell 0).
    pub fn of(pou: &PouInfo) -> Option<NativeFb> {
        if !pou.stdlib {
            return None;
        }
        const TIMER: &[&str] = &["IN", "PT", "Q", "ET", "RUNNING", "START"];
        let (kind, names): (NativeFb, &[&str]) = match pou.name.as_str() {
            "TON" => (NativeFb::Ton, TIMER),
            "TOF" => (NativeFb::Tof, TIMER),
            "TP" => (NativeFb::Tp, &["IN", "PT", "Q", "ET", "PREV", "START"]),
            "R_TRIG" => (NativeFb::RTrig, &["CLK", "Q", "M"]),
            "F_TRIG" => (NativeFb::FTrig, &["CLK", "Q", "M"]),
            _ => return None,
        };
        for (k, name) in names.iter().enumerate() {
            let (_, v) = pou.var(name)?;
            if v.offset.i != k || v.ty.lane() != Some(crate::check::Lane::Int) {
                return None;
            }
        }
        Some(kind)
    }

    /// A small number naming the block (for generated code).
    pub fn code(self) -> u32 {
        self as u32
    }

    /// The block named by [`NativeFb::code`].
    pub fn from_code(code: u32) -> Option<NativeFb> {
        [
            NativeFb::Ton,
            NativeFb::Tof,
            NativeFb::Tp,
            NativeFb::RTrig,
            NativeFb::FTrig,
        ]
        .into_iter()
        .find(|f| f.code() == code)
    }

    /// How many integer cells of the instance the body uses (from cell 0).
    pub fn cells(self) -> usize {
        match self {
            NativeFb::Ton | NativeFb::Tof | NativeFb::Tp => 6,
            NativeFb::RTrig | NativeFb::FTrig => 3,
        }
    }

    /// Runs the body on the instance's integer cells (at least [`NativeFb::cells`]; a
    /// shorter slice is left alone).
    #[inline]
    pub fn run_cells(self, c: &mut [i64], now: i64) {
        match self {
            NativeFb::Ton => {
                if let Some(c) = c.first_chunk_mut() {
                    ton(c, now);
                }
            }
            NativeFb::Tof => {
                if let Some(c) = c.first_chunk_mut() {
                    tof(c, now);
                }
            }
            NativeFb::Tp => {
                if let Some(c) = c.first_chunk_mut() {
                    tp(c, now);
                }
            }
            NativeFb::RTrig | NativeFb::FTrig => {
                if let Some(c) = c.first_chunk_mut() {
                    trig(c, self == NativeFb::RTrig);
                }
            }
        }
    }

    /// Runs the body on the instance whose integer cells start at `base`.
    #[inline]
    pub fn run(self, vm: &mut Vm, base: usize) -> Result<(), Fault> {
        let now = vm.now;
        match self {
            NativeFb::Ton => ton(cells(vm, base)?, now),
            NativeFb::Tof => tof(cells(vm, base)?, now),
            NativeFb::Tp => tp(cells(vm, base)?, now),
            NativeFb::RTrig => trig(cells(vm, base)?, true),
            NativeFb::FTrig => trig(cells(vm, base)?, false),
        }
        Ok(())
    }
}

/// The `N` integer cells of an instance.
#[inline(always)]
fn cells<const N: usize>(vm: &mut Vm, base: usize) -> Result<&mut [i64; N], Fault> {
    base.checked_add(N)
        .and_then(|end| vm.ints.get_mut(base..end))
        .and_then(|s| <&mut [i64; N]>::try_from(s).ok())
        .ok_or_else(Fault::memory)
}

/// TON: `Q` once `IN` has been TRUE for `PT`.
#[inline(always)]
fn ton(c: &mut [i64; 6], now: i64) {
    let [inp, pt, q, et, running, start] = c;
    if *inp != 0 {
        if *running == 0 {
            *running = 1;
            *start = now;
        }
        if *q == 0 {
            let e = now.wrapping_sub(*start);
            if e >= *pt {
                *et = *pt;
                *q = 1;
            } else {
                *et = e;
            }
        }
    } else {
        *running = 0;
        *q = 0;
        *et = 0;
    }
}

/// TOF: `Q` stays TRUE for `PT` after `IN` falls.
#[inline(always)]
fn tof(c: &mut [i64; 6], now: i64) {
    let [inp, pt, q, et, running, start] = c;
    if *inp != 0 {
        *q = 1;
        *et = 0;
        *running = 0;
    } else if *q != 0 {
        if *running == 0 {
            *running = 1;
            *start = now;
        }
        let e = now.wrapping_sub(*start);
        if e >= *pt {
            *et = *pt;
            *q = 0;
            *running = 0;
        } else {
            *et = e;
        }
    }
}

/// TP: a pulse of `PT` on a rising `IN`, not retriggerable.
#[inline(always)]
fn tp(c: &mut [i64; 6], now: i64) {
    let [inp, pt, q, et, prev, start] = c;
    let i = *inp != 0;
    if *q == 0 && i && *prev == 0 && *et == 0 {
        *q = 1;
        *start = now;
    }
    if *q != 0 {
        let e = now.wrapping_sub(*start);
        if e >= *pt {
            *et = *pt;
            *q = 0;
        } else {
            *et = e;
        }
    }
    if *q == 0 && !i {
        *et = 0;
    }
    *prev = i64::from(i);
}

/// R_TRIG / F_TRIG.
#[inline(always)]
fn trig(c: &mut [i64; 3], rising: bool) {
    let [clk, q, m] = c;
    let (now, before) = (*clk != 0, *m != 0);
    *q = i64::from(if rising {
        now && !before
    } else {
        !now && before
    });
    *m = i64::from(now);
}

/// The native body for a standard FB as a POU body (on the instance at `vm.frame`).
pub fn native_body(pou: &PouInfo) -> Option<StmtFn> {
    let fb = NativeFb::of(pou)?;
    Some(Box::new(move |vm| {
        fb.run(vm, vm.frame.i)?;
        Ok(Flow::Normal)
    }))
}
