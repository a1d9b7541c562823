//! Types, their memory layout and the IEC implicit-conversion rules.

use crate::syntax::BinOp;
use std::fmt;
use std::rc::Rc;

/// Index of a POU in [`super::Checked::pous`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct PouId(pub usize);

/// Index of a struct in [`TypeTable::structs`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct StructId(pub usize);

/// Index of an enum in [`TypeTable::enums`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct EnumId(pub usize);

/// Size of a value or offset inside one, counted per memory lane: integer-like cells, real
/// cells and string cells. See [`crate::vm`] for why memory has three lanes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub struct Size {
    /// Integer lane cells (BOOL, integers, bit strings, times, dates, enums).
    pub i: usize,
    /// Real lane cells (REAL, LREAL).
    pub r: usize,
    /// String lane cells (STRING, WSTRING).
    pub s: usize,
}

impl Size {
    /// Lane-wise sum.
    pub fn plus(self, o: Size) -> Size {
        Size {
            i: self.i + o.i,
            r: self.r + o.r,
            s: self.s + o.s,
        }
    }
    /// Lane-wise multiple (saturating).
    pub fn times(self, n: usize) -> Size {
        Size {
            i: self.i.saturating_mul(n),
            r: self.r.saturating_mul(n),
            s: self.s.saturating_mul(n),
        }
    }
}

/// An array type.
#[derive(Debug, Clone)]
pub struct ArrayTy {
    /// `(lower, upper)` per dimension.
    pub dims: Vec<(i64, i64)>,
    /// Element type.
    pub elem: Ty,
    /// Size of one element.
    pub elem_size: Size,
    /// Subrange bounds of the element type (checked on every element store).
    pub elem_range: Option<(i64, i64)>,
    /// Initial value of every element not given one by the array's own initializer: the
    /// `:=` of the TYPE declaration the element type names (`ARRAY[1..3] OF Level`).
    pub elem_init: Option<crate::syntax::Init>,
}

/// Two array types are the same type whatever initial values their element types declare:
/// an initial value is where a variable starts, not what it may hold.
impl PartialEq for ArrayTy {
    fn eq(&self, other: &Self) -> bool {
        self.dims == other.dims
            && self.elem == other.elem
            && self.elem_size == other.elem_size
            && self.elem_range == other.elem_range
    }
}

impl ArrayTy {
    /// Number of elements.
    pub fn len(&self) -> usize {
        self.dims
            .iter()
            .map(|(lo, hi)| usize::try_from(hi - lo + 1).unwrap_or(0))
            .product()
    }
    /// Whether the array has no elements.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// A type.
#[derive(Debug, Clone, PartialEq)]
#[allow(missing_docs)]
pub enum Ty {
    Bool,
    SInt,
    Int,
    DInt,
    LInt,
    USInt,
    UInt,
    UDInt,
    ULInt,
    Byte,
    Word,
    DWord,
    LWord,
    Real,
    LReal,
    Time,
    LTime,
    Date,
    Tod,
    Dt,
    /// `STRING[n]`
    String(u32),
    /// `WSTRING[n]`
    WString(u32),
    /// ARRAY
    Array(Rc<ArrayTy>),
    /// STRUCT
    Struct(StructId),
    /// Enumeration
    Enum(EnumId),
    /// Function block instance
    Fb(PouId),
    /// `REF_TO T`: the address of a variable of type `T`, or NULL. One integer cell (the
    /// address packed, 0 = NULL); `REF_TO VOID` is the type of `NULL` itself.
    Ref(Rc<Ty>),
    /// No value (function without result, statement calls)
    Void,
}

/// Default STRING length.
pub const DEFAULT_STRING_LEN: u32 = 80;

/// Which lane a scalar lives in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Lane {
    /// Integer lane.
    Int,
    /// Real lane.
    Real,
    /// String lane.
    Str,
}

impl Ty {
    /// Elementary type by upper-case name.
    pub fn elementary(name: &str) -> Option<Ty> {
        Some(match name {
            "BOOL" => Ty::Bool,
            "SINT" => Ty::SInt,
            "INT" => Ty::Int,
            "DINT" => Ty::DInt,
            "LINT" => Ty::LInt,
            "USINT" => Ty::USInt,
            "UINT" => Ty::UInt,
            "UDINT" => Ty::UDInt,
            "ULINT" => Ty::ULInt,
            "BYTE" | "CHAR" => Ty::Byte,
            "WORD" | "WCHAR" => Ty::Word,
            "DWORD" => Ty::DWord,
            "LWORD" => Ty::LWord,
            "REAL" => Ty::Real,
            "LREAL" => Ty::LReal,
            "TIME" => Ty::Time,
            "LTIME" => Ty::LTime,
            "DATE" | "LDATE" => Ty::Date,
            "TOD" | "TIME_OF_DAY" | "LTOD" | "LTIME_OF_DAY" => Ty::Tod,
            "DT" | "DATE_AND_TIME" | "LDT" | "LDATE_AND_TIME" => Ty::Dt,
            "STRING" => Ty::String(DEFAULT_STRING_LEN),
            "WSTRING" => Ty::WString(DEFAULT_STRING_LEN),
            _ => return None,
        })
    }

    /// The lane of a scalar type; `None` for aggregates.
    pub fn lane(&self) -> Option<Lane> {
        match self {
            Ty::Real | Ty::LReal => Some(Lane::Real),
            Ty::String(_) | Ty::WString(_) => Some(Lane::Str),
            Ty::Array(_) | Ty::Struct(_) | Ty::Fb(_) | Ty::Void => None,
            _ => Some(Lane::Int),
        }
    }

    /// Signed integers.
    pub fn is_signed_int(&self) -> bool {
        matches!(self, Ty::SInt | Ty::Int | Ty::DInt | Ty::LInt)
    }
    /// Unsigned integers.
    pub fn is_unsigned_int(&self) -> bool {
        matches!(self, Ty::USInt | Ty::UInt | Ty::UDInt | Ty::ULInt)
    }
    /// ANY_INT.
    pub fn is_int(&self) -> bool {
        self.is_signed_int() || self.is_unsigned_int()
    }
    /// ANY_BIT without BOOL.
    pub fn is_bits(&self) -> bool {
        matches!(self, Ty::Byte | Ty::Word | Ty::DWord | Ty::LWord)
    }
    /// ANY_REAL.
    pub fn is_real(&self) -> bool {
        matches!(self, Ty::Real | Ty::LReal)
    }
    /// ANY_NUM.
    pub fn is_num(&self) -> bool {
        self.is_int() || self.is_real()
    }
    /// ANY_STRING.
    pub fn is_string(&self) -> bool {
        matches!(self, Ty::String(_) | Ty::WString(_))
    }
    /// TIME or LTIME.
    pub fn is_duration(&self) -> bool {
        matches!(self, Ty::Time | Ty::LTime)
    }
    /// A duration or a point in time: TIME, LTIME, DATE, TOD, DT.
    pub fn is_time_like(&self) -> bool {
        matches!(self, Ty::Time | Ty::LTime | Ty::Date | Ty::Tod | Ty::Dt)
    }

    /// The result of `a op b` when `a` or `b` is a time (IEC 61131-3 time arithmetic: the
    /// operators and the functions `ADD`, `SUB`, `MUL`, `DIV`); `None` where the standard
    /// defines no such operation.
    pub fn time_arith(op: BinOp, a: &Ty, b: &Ty) -> Option<Ty> {
        use BinOp::{Add, Div, Mul, Sub};
        Some(match (op, a, b) {
            (Add | Sub, Ty::Time, Ty::Time) => Ty::Time,
            (Add | Sub, Ty::LTime | Ty::Time, Ty::LTime | Ty::Time) => Ty::LTime,
            (Add | Sub, Ty::Tod, Ty::Time | Ty::LTime) => Ty::Tod,
            (Add, Ty::Time | Ty::LTime, Ty::Tod) => Ty::Tod,
            (Add | Sub, Ty::Dt, Ty::Time | Ty::LTime) => Ty::Dt,
            (Sub, Ty::Tod, Ty::Tod) | (Sub, Ty::Dt, Ty::Dt) | (Sub, Ty::Date, Ty::Date) => Ty::Time,
            (Mul | Div, Ty::Time | Ty::LTime, n) if n.is_num() => a.clone(),
            (Mul, n, Ty::Time | Ty::LTime) if n.is_num() => b.clone(),
            _ => return None,
        })
    }
    /// Elementary (scalar) type.
    pub fn is_elementary(&self) -> bool {
        !matches!(
            self,
            Ty::Array(_) | Ty::Struct(_) | Ty::Fb(_) | Ty::Void | Ty::Enum(_) | Ty::Ref(_)
        )
    }

    /// Bit width of integer-lane scalars (64 for times/dates).
    pub fn bits(&self) -> u32 {
        match self {
            Ty::Bool => 1,
            Ty::SInt | Ty::USInt | Ty::Byte => 8,
            Ty::Int | Ty::UInt | Ty::Word => 16,
            Ty::DInt | Ty::UDInt | Ty::DWord | Ty::Enum(_) => 32,
            _ => 64,
        }
    }

    /// Whether values are unsigned when stored in an `i64` cell.
    pub fn is_unsigned_cell(&self) -> bool {
        self.is_unsigned_int() || self.is_bits()
    }

    /// The value range of an integer or bit-string type.
    pub fn int_range(&self) -> Option<(i128, i128)> {
        let b = self.bits();
        if self.is_signed_int() {
            Some((-(1i128 << (b - 1)), (1i128 << (b - 1)) - 1))
        } else if self.is_unsigned_cell() || *self == Ty::Bool {
            Some((0, (1i128 << b) - 1))
        } else {
            None
        }
    }

    /// Wraps `v` to this type's width (two's complement; documented overflow rule).
    #[inline]
    pub fn wrap(&self, v: i64) -> i64 {
        match self {
            Ty::Bool => i64::from(v != 0),
            Ty::SInt => i64::from(v as i8),
            Ty::Int => i64::from(v as i16),
            Ty::DInt => i64::from(v as i32),
            Ty::USInt | Ty::Byte => i64::from(v as u8),
            Ty::UInt | Ty::Word => i64::from(v as u16),
            Ty::UDInt | Ty::DWord => i64::from(v as u32),
            _ => v,
        }
    }

    /// Rank for numeric widening (same rank family = convertible upward).
    fn int_rank(&self) -> u8 {
        match self {
            Ty::SInt | Ty::USInt | Ty::Byte => 1,
            Ty::Int | Ty::UInt | Ty::Word => 2,
            Ty::DInt | Ty::UDInt | Ty::DWord => 3,
            Ty::LInt | Ty::ULInt | Ty::LWord => 4,
            _ => 0,
        }
    }

    /// IEC 61131-3 implicit conversion (widening only): may a value of `self` be used where
    /// `to` is expected without an explicit `*_TO_*`?
    pub fn converts_to(&self, to: &Ty) -> bool {
        if self == to {
            return true;
        }
        match (self, to) {
            (Ty::String(_), Ty::String(_)) | (Ty::WString(_), Ty::WString(_)) => true,
            // NULL is a reference to anything
            (Ty::Ref(from), Ty::Ref(_)) => **from == Ty::Void,
            (Ty::Time, Ty::LTime) => true,
            (Ty::Real, Ty::LReal) => true,
            (a, b) if a.is_signed_int() && b.is_signed_int() => a.int_rank() < b.int_rank(),
            (a, b) if a.is_unsigned_int() && b.is_unsigned_int() => a.int_rank() < b.int_rank(),
            (a, b) if a.is_unsigned_int() && b.is_signed_int() => a.int_rank() < b.int_rank(),
            (a, b) if a.is_bits() && b.is_bits() => a.int_rank() < b.int_rank(),
            (a, Ty::Real) if a.is_int() => a.int_rank() <= 2,
            (a, Ty::LReal) if a.is_int() => a.int_rank() <= 3,
            (Ty::Bool, b) if b.is_bits() => true,
            _ => false,
        }
    }

    /// The common type two operands convert to, if any.
    pub fn common(a: &Ty, b: &Ty) -> Option<Ty> {
        if a.converts_to(b) {
            Some(b.clone())
        } else if b.converts_to(a) {
            Some(a.clone())
        } else if a.is_int() && b.is_int() {
            // e.g. UDINT and DINT: next wider signed type
            let r = a.int_rank().max(b.int_rank());
            Some(match r {
                1 => Ty::Int,
                2 => Ty::DInt,
                _ => Ty::LInt,
            })
        } else if a.is_num() && b.is_num() {
            Some(Ty::LReal)
        } else {
            None
        }
    }
}

/// A user or built-in STRUCT.
#[derive(Debug, Clone)]
pub struct StructDef {
    /// Type name.
    pub name: String,
    /// Fields in order.
    pub fields: Vec<Field>,
    /// Total size.
    pub size: Size,
}

/// A field of a struct.
#[derive(Debug, Clone)]
pub struct Field {
    /// Name as declared.
    pub name: String,
    /// Upper-case key.
    pub key: String,
    /// Type.
    pub ty: Ty,
    /// Offset inside the struct.
    pub offset: Size,
    /// Initial value.
    pub init: Option<crate::syntax::Init>,
    /// Subrange bounds when the field's type is a subrange.
    pub range: Option<(i64, i64)>,
}

/// An enumeration.
#[derive(Debug, Clone)]
pub struct EnumDef {
    /// Type name.
    pub name: String,
    /// `(name, value)`.
    pub values: Vec<(String, i64)>,
}

/// All named user types.
#[derive(Debug, Clone, Default)]
pub struct TypeTable {
    /// Structs.
    pub structs: Vec<StructDef>,
    /// Enumerations.
    pub enums: Vec<EnumDef>,
}

impl TypeTable {
    /// The struct definition.
    pub fn struct_def(&self, id: StructId) -> Option<&StructDef> {
        self.structs.get(id.0)
    }
    /// The enum definition.
    pub fn enum_def(&self, id: EnumId) -> Option<&EnumDef> {
        self.enums.get(id.0)
    }
}

impl fmt::Display for Ty {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = match self {
            Ty::Bool => "BOOL",
            Ty::SInt => "SINT",
            Ty::Int => "INT",
            Ty::DInt => "DINT",
            Ty::LInt => "LINT",
            Ty::USInt => "USINT",
            Ty::UInt => "UINT",
            Ty::UDInt => "UDINT",
            Ty::ULInt => "ULINT",
            Ty::Byte => "BYTE",
            Ty::Word => "WORD",
            Ty::DWord => "DWORD",
            Ty::LWord => "LWORD",
            Ty::Real => "REAL",
            Ty::LReal => "LREAL",
            Ty::Time => "TIME",
            Ty::LTime => "LTIME",
            Ty::Date => "DATE",
            Ty::Tod => "TOD",
            Ty::Dt => "DT",
            Ty::String(n) => return write!(f, "STRING[{n}]"),
            Ty::WString(n) => return write!(f, "WSTRING[{n}]"),
            Ty::Array(a) => {
                write!(f, "ARRAY[")?;
                for (i, (lo, hi)) in a.dims.iter().enumerate() {
                    if i > 0 {
                        write!(f, ", ")?;
                    }
                    write!(f, "{lo}..{hi}")?;
                }
                return write!(f, "] OF {}", a.elem);
            }
            Ty::Struct(id) => return write!(f, "struct #{}", id.0),
            Ty::Enum(id) => return write!(f, "enum #{}", id.0),
            Ty::Fb(id) => return write!(f, "function block #{}", id.0),
            Ty::Ref(t) => return write!(f, "REF_TO {t}"),
            Ty::Void => "VOID",
        };
        f.write_str(s)
    }
}
