//! The virtual machine: memory image, values and execution state.
//!
//! # Memory
//! Memory is a flat image split into three *lanes*, each a `Vec` of one cell type:
//! - `ints: Vec<i64>`: BOOL (0/1), every integer and bit-string type, TIME/LTIME
//!   (nanoseconds), DATE/DT (nanoseconds since 1970-01-01), TOD (nanoseconds since
//!   midnight) and enumerations;
//! - `reals: Vec<f64>`: REAL (kept rounded to f32 after every operation) and LREAL;
//! - `strs: Vec<String>`: STRING and WSTRING.
//!
//! Every type has a [`Size`] per lane, so a struct, array or FB instance is a contiguous
//! range in each lane, and `a[i].x` is `base + i * elem_size + offset_of(x)` lane by lane.
//! Integer cells hold the value already wrapped to the declared width (sign- or
//! zero-extended), so loads need no conversion.
//!
//! # Faults
//! Nothing here panics: every access is bounds-checked and returns [`Fault`]. Integer
//! division by zero, array indexes out of range and runaway loops (the per-cycle iteration
//! budget) are faults that stop the task; integer overflow wraps (two's complement at the
//! declared width); REAL division by zero follows IEC 60559 (±inf/NaN).

pub mod format;

use crate::check::Size;
use crate::syntax::Span;
use std::rc::Rc;

/// What went wrong at run time.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FaultKind {
    /// Integer division or MOD by zero.
    #[error("division by zero")]
    DivisionByZero(Span),
    /// Array index outside its declared range.
    #[error("array index {index} out of range {lo}..{hi}")]
    IndexOutOfRange {
        /// Where.
        span: Span,
        /// The index.
        index: i64,
        /// Lower bound.
        lo: i64,
        /// Upper bound.
        hi: i64,
    },
    /// A string index `s[i]` outside `1..LEN(s)`.
    #[error("string index {index} out of range 1..{len}")]
    StringIndex {
        /// Where.
        span: Span,
        /// The index.
        index: i64,
        /// The current length of the string.
        len: i64,
    },
    /// A value stored into a subrange variable is outside its range.
    #[error("value {value} outside the subrange {lo}..{hi} of '{name}'")]
    RangeError {
        /// Where.
        span: Span,
        /// The variable (or element, field) written, e.g. `a[i]`, `s.level`.
        name: String,
        /// The value.
        value: i64,
        /// Lower bound.
        lo: i64,
        /// Upper bound.
        hi: i64,
    },
    /// The loop-iteration budget of one cycle is exhausted (endless loop).
    #[error("loop iteration budget of the cycle exhausted (endless loop?)")]
    LoopBudget(Span),
    /// A conversion whose argument has no result (`WORD_BCD_TO_UINT(16#00A1)`).
    #[error("{what}")]
    Conversion {
        /// Where.
        span: Span,
        /// What could not be converted.
        what: String,
    },
    /// `r^` where `r` is NULL.
    #[error("dereference of a NULL reference")]
    NullReference(Span),
    /// A memory access outside the image (a compiler bug, reported instead of panicking).
    #[error("internal error: memory access out of range")]
    Memory,
}

/// A run-time fault; stops the task that raised it. Boxed so that `Result<i64, Fault>`
/// stays two words and is returned in registers on the hot path.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct Fault(pub Box<FaultKind>);

impl From<FaultKind> for Fault {
    fn from(k: FaultKind) -> Self {
        Fault(Box::new(k))
    }
}

impl Fault {
    /// Internal memory error.
    #[cold]
    pub fn memory() -> Fault {
        FaultKind::Memory.into()
    }

    /// What went wrong.
    pub fn kind(&self) -> &FaultKind {
        &self.0
    }

    /// Source position, if known.
    pub fn span(&self) -> Option<Span> {
        match &*self.0 {
            FaultKind::DivisionByZero(s)
            | FaultKind::LoopBudget(s)
            | FaultKind::NullReference(s) => Some(*s),
            FaultKind::IndexOutOfRange { span, .. }
            | FaultKind::StringIndex { span, .. }
            | FaultKind::Conversion { span, .. }
            | FaultKind::RangeError { span, .. } => Some(*span),
            FaultKind::Memory => None,
        }
    }
}

/// How a statement finished. Word-sized, so that `Result<Flow, Fault>` is a pair of
/// scalars returned in two registers (like `Result<i64, Fault>`), not through memory.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(i64)]
pub enum Flow {
    /// Go on with the next statement.
    Normal,
    /// EXIT the innermost loop.
    Exit,
    /// CONTINUE the innermost loop.
    Continue,
    /// RETURN from the POU.
    Return,
}

/// A single scalar value (for the API, arguments held aside and printing).
#[derive(Debug, Clone, PartialEq)]
pub enum Val {
    /// Integer lane.
    Int(i64),
    /// Real lane.
    Real(f64),
    /// String lane.
    Str(String),
}

/// Compiled statement.
pub type StmtFn = Box<dyn Fn(&mut Vm) -> Result<Flow, Fault>>;
/// Compiled initialiser (runs relative to `vm.frame`).
pub type InitFn = Box<dyn Fn(&mut Vm) -> Result<(), Fault>>;

/// The code of one POU.
pub struct CompiledPou {
    /// The body.
    pub body: StmtFn,
    /// Writes initial values into an instance at `vm.frame`.
    pub init: InitFn,
}

/// All compiled code.
#[derive(Default)]
pub struct Code {
    /// By [`crate::check::PouId`].
    pub pous: Vec<CompiledPou>,
}

/// Size of each process-image area in bytes.
pub const IO_AREA_BYTES: usize = 4096;

/// Execution state: memory, current frame, clock and I/O image.
pub struct Vm {
    /// Integer lane.
    pub ints: Vec<i64>,
    /// Real lane.
    pub reals: Vec<f64>,
    /// String lane.
    pub strs: Vec<String>,
    /// Base of the current POU instance.
    pub frame: Size,
    /// Base of the POU being called while its arguments are bound.
    pub callee: Size,
    /// The code.
    pub code: Rc<Code>,
    /// Monotonic time of the current cycle (ns since start).
    pub now: i64,
    /// UTC wall-clock time (ns since 1970).
    pub utc: i64,
    /// Local time offset from UTC (ns).
    pub local_offset: i64,
    /// Loop iterations left in this cycle.
    pub budget: u64,
    /// `%I` bytes.
    pub inputs: Vec<u8>,
    /// `%Q` bytes.
    pub outputs: Vec<u8>,
    /// `%M` bytes.
    pub markers: Vec<u8>,
}

impl Vm {
    /// A zeroed memory image of `size`.
    pub fn new(size: Size, code: Rc<Code>) -> Self {
        Vm {
            ints: vec![0; size.i],
            reals: vec![0.0; size.r],
            strs: vec![String::new(); size.s],
            frame: Size::default(),
            callee: Size::default(),
            code,
            now: 0,
            utc: 0,
            local_offset: 0,
            budget: u64::MAX,
            inputs: vec![0; IO_AREA_BYTES],
            outputs: vec![0; IO_AREA_BYTES],
            markers: vec![0; IO_AREA_BYTES],
        }
    }

    /// Integer cell.
    #[inline]
    pub fn geti(&self, a: usize) -> Result<i64, Fault> {
        self.ints.get(a).copied().ok_or_else(Fault::memory)
    }
    /// Sets an integer cell.
    #[inline]
    pub fn seti(&mut self, a: usize, v: i64) -> Result<(), Fault> {
        *self.ints.get_mut(a).ok_or_else(Fault::memory)? = v;
        Ok(())
    }
    /// Real cell.
    #[inline]
    pub fn getr(&self, a: usize) -> Result<f64, Fault> {
        self.reals.get(a).copied().ok_or_else(Fault::memory)
    }
    /// Sets a real cell.
    #[inline]
    pub fn setr(&mut self, a: usize, v: f64) -> Result<(), Fault> {
        *self.reals.get_mut(a).ok_or_else(Fault::memory)? = v;
        Ok(())
    }
    /// String cell (cloned).
    #[inline]
    pub fn gets(&self, a: usize) -> Result<String, Fault> {
        self.strs.get(a).cloned().ok_or_else(Fault::memory)
    }
    /// String cell by reference.
    #[inline]
    pub fn gets_ref(&self, a: usize) -> Result<&str, Fault> {
        self.strs
            .get(a)
            .map(String::as_str)
            .ok_or_else(Fault::memory)
    }
    /// Sets a string cell.
    #[inline]
    pub fn sets(&mut self, a: usize, v: String) -> Result<(), Fault> {
        *self.strs.get_mut(a).ok_or_else(Fault::memory)? = v;
        Ok(())
    }

    /// Copies a value of `size` from `src` to `dst` (absolute addresses).
    pub fn copy(&mut self, src: Size, dst: Size, size: Size) -> Result<(), Fault> {
        if src == dst {
            return Ok(());
        }
        copy_within(&mut self.ints, src.i, dst.i, size.i)?;
        copy_within(&mut self.reals, src.r, dst.r, size.r)?;
        for k in 0..size.s {
            let v = self.gets(src.s + k)?;
            self.sets(dst.s + k, v)?;
        }
        Ok(())
    }

    /// Runs the body of POU `pou` on the instance at `frame`.
    pub fn call(&mut self, pou: usize, frame: Size) -> Result<(), Fault> {
        let code = Rc::clone(&self.code);
        let Some(p) = code.pous.get(pou) else {
            return Err(Fault::memory());
        };
        let saved = std::mem::replace(&mut self.frame, frame);
        let r = (p.body)(self);
        self.frame = saved;
        r.map(|_| ())
    }

    /// Initialises the instance of POU `pou` at `frame`.
    pub fn init(&mut self, pou: usize, frame: Size) -> Result<(), Fault> {
        let code = Rc::clone(&self.code);
        let Some(p) = code.pous.get(pou) else {
            return Err(Fault::memory());
        };
        let saved = std::mem::replace(&mut self.frame, frame);
        let r = (p.init)(self);
        self.frame = saved;
        r
    }

    /// Reads `bits` (1, 8, 16, 32, 64) from a process-image area at byte `byte`, bit `bit`.
    /// Multi-byte values are big-endian (Siemens byte addressing: `%IW4` = bytes 4 and 5).
    pub fn io_read(&self, area: char, byte: usize, bit: u32, bits: u32) -> i64 {
        let mem = match area {
            'I' => &self.inputs,
            'Q' => &self.outputs,
            _ => &self.markers,
        };
        if bits == 1 {
            let b = mem.get(byte).copied().unwrap_or(0);
            return i64::from((b >> (bit & 7)) & 1);
        }
        let n = (bits / 8) as usize;
        let mut v: u64 = 0;
        for k in 0..n {
            v = (v << 8) | u64::from(mem.get(byte + k).copied().unwrap_or(0));
        }
        v as i64
    }

    /// Writes into a process-image area (see [`Vm::io_read`]).
    pub fn io_write(&mut self, area: char, byte: usize, bit: u32, bits: u32, v: i64) {
        let mem = match area {
            'I' => &mut self.inputs,
            'Q' => &mut self.outputs,
            _ => &mut self.markers,
        };
        if bits == 1 {
            if let Some(b) = mem.get_mut(byte) {
                let m = 1u8 << (bit & 7);
                if v != 0 {
                    *b |= m;
                } else {
                    *b &= !m;
                }
            }
            return;
        }
        let n = (bits / 8) as usize;
        for k in 0..n {
            if let Some(b) = mem.get_mut(byte + k) {
                *b = ((v as u64) >> (8 * (n - 1 - k))) as u8;
            }
        }
    }
}

fn copy_within<T: Copy>(v: &mut [T], src: usize, dst: usize, n: usize) -> Result<(), Fault> {
    if n == 0 {
        return Ok(());
    }
    let len = v.len();
    if src.checked_add(n).is_none_or(|e| e > len) || dst.checked_add(n).is_none_or(|e| e > len) {
        return Err(Fault::memory());
    }
    v.copy_within(src..src + n, dst);
    Ok(())
}

/// A parsed direct address: area (`I`, `Q`, `M`), width in bits, byte and bit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DirectAddress {
    /// `I`, `Q` or `M`.
    pub area: char,
    /// 1, 8, 16, 32 or 64.
    pub bits: u32,
    /// Byte offset.
    pub byte: usize,
    /// Bit number for BOOL.
    pub bit: u32,
}

impl DirectAddress {
    /// Parses `IX0.0`, `QW4`, `MD8` (without `%`).
    pub fn parse(text: &str) -> Option<DirectAddress> {
        let mut ch = text.chars();
        let area = ch.next()?;
        if !matches!(area, 'I' | 'Q' | 'M') {
            return None;
        }
        let rest: String = ch.collect();
        let (size, nums) = match rest.chars().next() {
            Some(c) if c.is_ascii_digit() => ('X', rest.as_str()),
            Some(c) => (c, rest.get(1..).unwrap_or("")),
            None => return None,
        };
        let bits = match size {
            'X' => 1,
            'B' => 8,
            'W' => 16,
            'D' => 32,
            'L' => 64,
            _ => return None,
        };
        let mut parts = nums.split('.');
        let byte: usize = parts.next()?.parse().ok()?;
        let bit: u32 = match parts.next() {
            Some(b) => b.parse().ok()?,
            None => 0,
        };
        if byte + (bits as usize / 8).max(1) > IO_AREA_BYTES || bit > 7 {
            return None;
        }
        Some(DirectAddress {
            area,
            bits,
            byte,
            bit,
        })
    }
}
