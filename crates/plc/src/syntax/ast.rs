//! The abstract syntax tree. Immutable after parsing; every expression and statement carries
//! a [`NodeId`] so later stages keep their results in side tables.

use super::source::Span;

/// Identity of an expression node, dense from 0 within one parse.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct NodeId(pub u32);

/// A name as written, with its case-folded key.
#[derive(Debug, Clone, PartialEq)]
pub struct Ident {
    /// Original spelling.
    pub name: String,
    /// Upper-case key used for lookup (IEC names are case-insensitive).
    pub key: String,
    /// Where.
    pub span: Span,
}

impl Ident {
    /// Makes an identifier.
    pub fn new(name: impl Into<String>, span: Span) -> Self {
        let name = name.into();
        let key = name.to_uppercase();
        Ident { name, key, span }
    }
}

/// A whole parsed file or set of files.
#[derive(Debug, Clone, Default)]
pub struct CompilationUnit {
    /// Top-level declarations in source order.
    pub items: Vec<Item>,
    /// Number of expression nodes allocated (size for side tables).
    pub node_count: u32,
}

/// A top-level declaration.
#[derive(Debug, Clone)]
#[allow(clippy::large_enum_variant)] // built once per parse; boxing buys nothing
pub enum Item {
    /// PROGRAM, FUNCTION_BLOCK or FUNCTION.
    Pou(Pou),
    /// TYPE ... END_TYPE.
    Types(Vec<TypeDecl>),
    /// VAR_GLOBAL ... END_VAR at top level (possibly inside a resource/configuration).
    Globals(VarBlock),
    /// `TASK name (INTERVAL := ..., PRIORITY := ...);` in a configuration/resource.
    Task(TaskDecl),
    /// `PROGRAM inst WITH task : Type;` in a configuration/resource.
    ProgramConfig(ProgramConfig),
}

/// A task declaration of a resource.
#[derive(Debug, Clone)]
pub struct TaskDecl {
    /// Task name.
    pub name: Ident,
    /// INTERVAL (a TIME constant).
    pub interval: Option<Expr>,
    /// PRIORITY (an integer constant, 0 = highest).
    pub priority: Option<Expr>,
    /// Where.
    pub span: Span,
}

/// A program instance bound to a task.
#[derive(Debug, Clone)]
pub struct ProgramConfig {
    /// Instance name (programs have one instance named like their type in this runtime).
    pub instance: Ident,
    /// Task.
    pub task: Option<Ident>,
    /// PROGRAM type.
    pub program: Ident,
    /// Where.
    pub span: Span,
}

/// Kind of program organisation unit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PouKind {
    /// PROGRAM
    Program,
    /// FUNCTION_BLOCK
    FunctionBlock,
    /// FUNCTION
    Function,
}

/// A program organisation unit.
#[derive(Debug, Clone)]
pub struct Pou {
    /// Kind.
    pub kind: PouKind,
    /// Name.
    pub name: Ident,
    /// Return type of a FUNCTION.
    pub return_type: Option<TypeRef>,
    /// Variable sections in order.
    pub vars: Vec<VarBlock>,
    /// Statements.
    pub body: Vec<Stmt>,
    /// Whole POU.
    pub span: Span,
}

/// Section kind of a variable block.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum VarKind {
    /// VAR
    Local,
    /// VAR_INPUT
    Input,
    /// VAR_OUTPUT
    Output,
    /// VAR_IN_OUT
    InOut,
    /// VAR_TEMP
    Temp,
    /// VAR_GLOBAL
    Global,
    /// VAR_EXTERNAL
    External,
    /// VAR_STAT (SCL static)
    Static,
}

/// A `VAR... END_VAR` block.
#[derive(Debug, Clone)]
pub struct VarBlock {
    /// Section kind.
    pub kind: VarKind,
    /// CONSTANT qualifier.
    pub constant: bool,
    /// RETAIN qualifier.
    pub retain: bool,
    /// PERSISTENT qualifier.
    pub persistent: bool,
    /// Declarations.
    pub decls: Vec<VarDecl>,
    /// Span of the keyword.
    pub span: Span,
}

/// `a, b AT %IX0.0 : TYPE := init;`
#[derive(Debug, Clone)]
pub struct VarDecl {
    /// Declared names.
    pub names: Vec<Ident>,
    /// Direct address.
    pub at: Option<(String, Span)>,
    /// Type.
    pub ty: TypeRef,
    /// Initial value.
    pub init: Option<Init>,
    /// Whole declaration.
    pub span: Span,
}

/// A type as written in a declaration.
#[derive(Debug, Clone)]
pub enum TypeRef {
    /// A named type (elementary, user type or FB).
    Named(Ident),
    /// `STRING[n]` / `WSTRING(n)`.
    String {
        /// WSTRING.
        wide: bool,
        /// Length expression.
        len: Option<Expr>,
        /// Where.
        span: Span,
    },
    /// `ARRAY[a..b, c..d] OF T`.
    Array {
        /// Dimension bounds.
        dims: Vec<(Expr, Expr)>,
        /// Element type.
        elem: Box<TypeRef>,
        /// Where.
        span: Span,
    },
    /// `STRUCT ... END_STRUCT`.
    Struct(Vec<VarDecl>, Span),
    /// `(A, B := 5, C)`, optionally with a base type.
    Enum(Vec<(Ident, Option<Expr>)>, Span),
    /// `REF_TO T`.
    Ref(Box<TypeRef>, Span),
    /// `INT (0..100)`.
    Subrange {
        /// Base type.
        base: Ident,
        /// Lower bound.
        lo: Expr,
        /// Upper bound.
        hi: Expr,
    },
}

impl TypeRef {
    /// Where the type is written.
    pub fn span(&self) -> Span {
        match self {
            TypeRef::Named(i) => i.span,
            TypeRef::String { span, .. }
            | TypeRef::Array { span, .. }
            | TypeRef::Struct(_, span)
            | TypeRef::Enum(_, span)
            | TypeRef::Ref(_, span) => *span,
            TypeRef::Subrange { base, hi, .. } => base.span.to(hi.span),
        }
    }
}

/// `TYPE name : ... ; END_TYPE` entry.
#[derive(Debug, Clone)]
pub struct TypeDecl {
    /// Name.
    pub name: Ident,
    /// Definition.
    pub ty: TypeRef,
    /// Default initial value.
    pub init: Option<Init>,
}

/// An initial value.
#[derive(Debug, Clone)]
pub enum Init {
    /// A constant expression.
    Expr(Expr),
    /// `[1, 2, 3(0)]`
    Array(Vec<(Option<Expr>, Init)>, Span),
    /// `(a := 1, b := 2)`
    Struct(Vec<(Ident, Init)>, Span),
    /// The `()` of a repetition `n()`: elements keep the initial value of their type.
    Default(Span),
}

/// An expression.
#[derive(Debug, Clone, PartialEq)]
pub struct Expr {
    /// Side-table key.
    pub id: NodeId,
    /// What.
    pub kind: ExprKind,
    /// Where.
    pub span: Span,
}

/// Literal values.
#[derive(Debug, Clone, PartialEq)]
pub enum Literal {
    /// Integer, optionally typed (`INT#5`), value already negated if written `INT#-5`.
    Int(i128, Option<String>),
    /// Real, optionally typed.
    Real(f64, Option<String>),
    /// TRUE / FALSE.
    Bool(bool),
    /// `'text'` (false) or `"text"` (true, WSTRING).
    String(String, bool),
    /// Duration in ns; true = LTIME.
    Time(i128, bool),
    /// DATE in ns since epoch.
    Date(i64),
    /// TOD in ns since midnight.
    Tod(i64),
    /// DT in ns since epoch.
    Dt(i64),
}

/// Unary operators.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UnOp {
    /// `-x`
    Neg,
    /// `+x`
    Plus,
    /// `NOT x`
    Not,
}

/// Binary operators.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BinOp {
    /// `**`
    Pow,
    /// `*`
    Mul,
    /// `/`
    Div,
    /// `MOD`
    Mod,
    /// `+`
    Add,
    /// `-`
    Sub,
    /// `<`
    Lt,
    /// `>`
    Gt,
    /// `<=`
    Le,
    /// `>=`
    Ge,
    /// `=`
    Eq,
    /// `<>`
    Ne,
    /// `AND`, `&`
    And,
    /// `XOR`
    Xor,
    /// `OR`
    Or,
}

impl BinOp {
    /// The operator as written.
    pub fn symbol(self) -> &'static str {
        match self {
            BinOp::Pow => "**",
            BinOp::Mul => "*",
            BinOp::Div => "/",
            BinOp::Mod => "MOD",
            BinOp::Add => "+",
            BinOp::Sub => "-",
            BinOp::Lt => "<",
            BinOp::Gt => ">",
            BinOp::Le => "<=",
            BinOp::Ge => ">=",
            BinOp::Eq => "=",
            BinOp::Ne => "<>",
            BinOp::And => "AND",
            BinOp::Xor => "XOR",
            BinOp::Or => "OR",
        }
    }
}

/// A call argument.
#[derive(Debug, Clone, PartialEq)]
pub struct Arg {
    /// `name :=` or `name =>`.
    pub name: Option<Ident>,
    /// `=>` (output binding).
    pub output: bool,
    /// `NOT name =>`.
    pub negated: bool,
    /// Value (input) or target (output).
    pub value: Expr,
}

/// Expression kinds.
#[derive(Debug, Clone, PartialEq)]
pub enum ExprKind {
    /// A literal.
    Literal(Literal),
    /// A name; `quoted` for SCL `"name"` (may turn out to be a WSTRING literal).
    Name {
        /// The name.
        ident: Ident,
        /// Written as `"name"`.
        quoted: bool,
    },
    /// `a.b`
    Member(Box<Expr>, Ident),
    /// `a.%X3` bit access.
    Bit(Box<Expr>, u32),
    /// `a.%B1`, `a.%W0`, `a.%D1`, `a.%L0`: partial access to a byte, word, double or long
    /// word of a longer bit string or integer, as (width in bits, index from the least
    /// significant part).
    Part(Box<Expr>, u32, u32),
    /// `a[i, j]`
    Index(Box<Expr>, Vec<Expr>),
    /// `p^`
    Deref(Box<Expr>),
    /// `-a`
    Unary(UnOp, Box<Expr>),
    /// `a + b`
    Binary(BinOp, Box<Expr>, Box<Expr>),
    /// `F(args)` or `inst(args)` (callee is a name or path).
    Call(Box<Expr>, Vec<Arg>),
    /// `Color#Red`
    TypedEnum(Ident, Ident),
    /// `%IX0.0` used directly.
    Direct(String),
}

/// A statement.
#[derive(Debug, Clone)]
pub struct Stmt {
    /// What.
    pub kind: StmtKind,
    /// Where.
    pub span: Span,
}

/// `CASE` label.
#[derive(Debug, Clone)]
pub enum CaseLabel {
    /// One value.
    Value(Expr),
    /// `a..b`
    Range(Expr, Expr),
}

/// Statement kinds.
#[derive(Debug, Clone)]
#[allow(clippy::large_enum_variant)] // built once per parse; boxing buys nothing
pub enum StmtKind {
    /// `a := b`
    Assign(Expr, Expr),
    /// `a ?= b` / `S=` / `R=` are not supported; a call statement `f(...)`.
    Call(Expr),
    /// IF / ELSIF / ELSE.
    If(Vec<(Expr, Vec<Stmt>)>, Option<Vec<Stmt>>),
    /// CASE.
    Case(Expr, Vec<(Vec<CaseLabel>, Vec<Stmt>)>, Option<Vec<Stmt>>),
    /// FOR i := a TO b BY c DO ... END_FOR.
    For {
        /// Control variable.
        var: Expr,
        /// Start.
        from: Expr,
        /// End.
        to: Expr,
        /// Step.
        by: Option<Expr>,
        /// Body.
        body: Vec<Stmt>,
    },
    /// WHILE.
    While(Expr, Vec<Stmt>),
    /// REPEAT ... UNTIL.
    Repeat(Vec<Stmt>, Expr),
    /// EXIT.
    Exit,
    /// CONTINUE.
    Continue,
    /// RETURN.
    Return,
    /// `;`
    Empty,
}

/// The letter of a partial access of `width` bits: `X` (1), `B` (8), `W` (16), `D` (32),
/// `L` (64), as in `w.%B1`.
pub fn part_letter(width: u32) -> char {
    match width {
        1 => 'X',
        8 => 'B',
        16 => 'W',
        32 => 'D',
        _ => 'L',
    }
}
