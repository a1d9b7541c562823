//! References: `REF()` of a place, and the packing of an address into one integer cell
//! (references and aggregate arguments).

use super::konst_i;
use crate::check::Size;
use crate::compile::{Cx, CE};
use crate::syntax::*;

impl Cx<'_> {
    /// `REF(x)`: the packed absolute address of `x` plus 1, so that 0 is NULL (and memory
    /// that starts zeroed starts NULL).
    pub(super) fn reference(&mut self, args: &[Arg], span: Span) -> CE {
        let size = self.c.memory_size;
        if size.i > PACK_LIMIT || size.r > PACK_LIMIT || size.s > PACK_LIMIT {
            self.error(
                span,
                "the memory image is too large for references (2 M cells per lane)",
            );
            return CE::I(konst_i(0));
        }
        let Some(place) = args.first().and_then(|a| self.place(&a.value)) else {
            self.error(span, "cannot take the address of this");
            return CE::I(konst_i(0));
        };
        let addr = place.addr();
        CE::I(Box::new(move |vm| Ok(pack(addr(vm)?).wrapping_add(1))))
    }
}

// An aggregate source address travels through `Val::Int` between get and put: lanes packed
// 21 bits each (memory images are far below 2 M cells per lane).
/// Cells per lane that [`pack`] can address.
const PACK_LIMIT: usize = 0x1F_FFFF;

pub(crate) fn pack(s: Size) -> i64 {
    ((s.i as i64) << 42) | ((s.r as i64 & 0x1F_FFFF) << 21) | (s.s as i64 & 0x1F_FFFF)
}
pub(crate) fn unpack(p: i64) -> Size {
    Size {
        i: (p >> 42) as usize,
        r: ((p >> 21) & 0x1F_FFFF) as usize,
        s: (p & 0x1F_FFFF) as usize,
    }
}
