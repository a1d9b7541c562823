//! Loading from and storing into a place: per lane, through a bit or part, a character
//! of a string, with the subrange check on stores.

use super::place::{Base, Place};
use crate::check::{Lane, Ty};
use crate::compile::{Cx, CE};
use crate::stdlib::string;
use crate::vm::{Fault, Flow, StmtFn, Vm};
use std::rc::Rc;

/// Writes an evaluated value into a place.
pub(crate) type ValWriter = Rc<dyn Fn(&mut Vm, crate::vm::Val) -> Result<(), Fault>>;

impl Cx<'_> {
    /// Loads a scalar from a place.
    pub(crate) fn load(&self, p: &Place) -> CE {
        if let Some(ci) = p.char_ix.clone() {
            let a = p.addr();
            return CE::I(Box::new(move |vm| {
                let at = a(vm)?;
                ci.get(vm, at.s)
            }));
        }
        if let Some(d) = p.direct {
            return CE::I(Box::new(move |vm| {
                Ok(vm.io_read(d.area, d.byte, d.bit, d.bits))
            }));
        }
        if let Some(field) = p.bit.clone() {
            let a = p.addr();
            return CE::I(Box::new(move |vm| {
                let at = a(vm)?;
                Ok(field.get(vm.geti(at.i)?))
            }));
        }
        let off = p.off;
        if let Some(el) = crate::compile::fused::Elem::of(p) {
            return CE::I(Box::new(move |vm| el.get(vm)));
        }
        if let (Some(ix), Some(Lane::Int), Base::Frame | Base::Abs | Base::Callee) =
            (p.index1.clone(), p.ty.lane(), p.base)
        {
            return CE::I(match p.base {
                Base::Frame => Box::new(move |vm| {
                    let k = ix.eval(vm)?;
                    vm.geti(vm.frame.i + off.i + k * ix.stride.i)
                }),
                Base::Abs => Box::new(move |vm| {
                    let k = ix.eval(vm)?;
                    vm.geti(off.i + k * ix.stride.i)
                }),
                _ => Box::new(move |vm| {
                    let k = ix.eval(vm)?;
                    vm.geti(vm.callee.i + off.i + k * ix.stride.i)
                }),
            });
        }
        match (p.ty.lane(), p.base, p.dynamic.is_some()) {
            (Some(Lane::Int), Base::Frame, false) => {
                CE::I(Box::new(move |vm| vm.geti(vm.frame.i + off.i)))
            }
            (Some(Lane::Int), Base::Abs, false) => CE::I(Box::new(move |vm| vm.geti(off.i))),
            (Some(Lane::Int), Base::Callee, false) => {
                CE::I(Box::new(move |vm| vm.geti(vm.callee.i + off.i)))
            }
            (Some(Lane::Real), Base::Frame, false) => {
                CE::R(Box::new(move |vm| vm.getr(vm.frame.r + off.r)))
            }
            (Some(Lane::Real), Base::Abs, false) => CE::R(Box::new(move |vm| vm.getr(off.r))),
            (Some(Lane::Str), _, _) => {
                let a = p.addr();
                CE::S(Box::new(move |vm| {
                    let at = a(vm)?;
                    vm.gets(at.s)
                }))
            }
            (Some(Lane::Real), _, true) => {
                let a = p.addr();
                CE::R(Box::new(move |vm| {
                    let at = a(vm)?;
                    vm.getr(at.r)
                }))
            }
            _ => {
                let a = p.addr();
                CE::I(Box::new(move |vm| {
                    let at = a(vm)?;
                    vm.geti(at.i)
                }))
            }
        }
    }

    /// Stores a scalar value into a place (string truncation, bit insertion, I/O image).
    pub(crate) fn store(&self, p: &Place, v: CE) -> StmtFn {
        let off = p.off;
        let v = match (v, p.range.clone()) {
            (CE::I(f), Some(r)) => CE::I(Box::new(move |vm| r.check(f(vm)?))),
            (v, _) => v,
        };
        if let Some(ci) = p.char_ix.clone() {
            let a = p.addr();
            let CE::I(f) = v else {
                return Box::new(|_| Ok(Flow::Normal));
            };
            return Box::new(move |vm| {
                let x = f(vm)?;
                let at = a(vm)?;
                ci.set(vm, at.s, x)?;
                Ok(Flow::Normal)
            });
        }
        if let Some(d) = p.direct {
            let CE::I(f) = v else {
                return Box::new(|_| Ok(Flow::Normal));
            };
            return Box::new(move |vm| {
                let x = f(vm)?;
                vm.io_write(d.area, d.byte, d.bit, d.bits, x);
                Ok(Flow::Normal)
            });
        }
        if let Some(field) = p.bit.clone() {
            let a = p.addr();
            let CE::I(f) = v else {
                return Box::new(|_| Ok(Flow::Normal));
            };
            return Box::new(move |vm| {
                let x = f(vm)?;
                let at = a(vm)?;
                let old = vm.geti(at.i)?;
                let x = if field.width == 1 {
                    i64::from(x != 0)
                } else {
                    x
                };
                vm.seti(at.i, field.set(old, x))?;
                Ok(Flow::Normal)
            });
        }
        if let (Some(el), CE::I(_)) = (crate::compile::fused::Elem::of(p), &v) {
            let CE::I(f) = v else {
                return Box::new(|_| Ok(Flow::Normal));
            };
            return Box::new(move |vm| {
                let x = f(vm)?;
                el.set(vm, x)?;
                Ok(Flow::Normal)
            });
        }
        if let (Some(ix), CE::I(f), Base::Frame | Base::Abs) = (p.index1.clone(), &v, p.base) {
            let _ = f;
            let CE::I(f) = v else {
                return Box::new(|_| Ok(Flow::Normal));
            };
            let frame = p.base == Base::Frame;
            return Box::new(move |vm| {
                let x = f(vm)?;
                let k = ix.eval(vm)?;
                let b = if frame { vm.frame.i } else { 0 };
                vm.seti(b + off.i + k * ix.stride.i, x)?;
                Ok(Flow::Normal)
            });
        }
        match (v, p.base, p.dynamic.is_some()) {
            (CE::I(f), Base::Frame, false) => Box::new(move |vm| {
                let x = f(vm)?;
                vm.seti(vm.frame.i + off.i, x)?;
                Ok(Flow::Normal)
            }),
            (CE::I(f), Base::Callee, false) => Box::new(move |vm| {
                let x = f(vm)?;
                vm.seti(vm.callee.i + off.i, x)?;
                Ok(Flow::Normal)
            }),
            (CE::I(f), Base::Abs, false) => Box::new(move |vm| {
                let x = f(vm)?;
                vm.seti(off.i, x)?;
                Ok(Flow::Normal)
            }),
            (CE::I(f), _, _) => {
                let a = p.addr();
                Box::new(move |vm| {
                    let x = f(vm)?;
                    let at = a(vm)?;
                    vm.seti(at.i, x)?;
                    Ok(Flow::Normal)
                })
            }
            (CE::R(f), Base::Frame, false) => Box::new(move |vm| {
                let x = f(vm)?;
                vm.setr(vm.frame.r + off.r, x)?;
                Ok(Flow::Normal)
            }),
            (CE::R(f), _, _) => {
                let a = p.addr();
                Box::new(move |vm| {
                    let x = f(vm)?;
                    let at = a(vm)?;
                    vm.setr(at.r, x)?;
                    Ok(Flow::Normal)
                })
            }
            (CE::S(f), _, _) => {
                let a = p.addr();
                let max = match p.ty {
                    Ty::String(n) | Ty::WString(n) => n,
                    _ => u32::MAX,
                };
                Box::new(move |vm| {
                    let x = string::truncate(f(vm)?, max);
                    let at = a(vm)?;
                    vm.sets(at.s, x)?;
                    Ok(Flow::Normal)
                })
            }
        }
    }

    /// A writer for a place that takes an already evaluated value.
    pub(crate) fn store_val(&self, p: &Place) -> ValWriter {
        let a = p.addr();
        let max = match p.ty {
            Ty::String(n) | Ty::WString(n) => n,
            _ => u32::MAX,
        };
        let range = p.range.clone();
        Rc::new(move |vm, v| {
            let at = a(vm)?;
            match v {
                crate::vm::Val::Int(x) => {
                    if let Some(r) = &range {
                        r.check(x)?;
                    }
                    vm.seti(at.i, x)
                }
                crate::vm::Val::Real(x) => vm.setr(at.r, x),
                crate::vm::Val::Str(x) => vm.sets(at.s, string::truncate(x, max)),
            }
        })
    }
}
