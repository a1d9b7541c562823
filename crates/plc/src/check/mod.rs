//! Semantic analysis: declarations, memory layout, name resolution and types.
//!
//! The AST is never modified. Results are side tables keyed by [`NodeId`]:
//! - [`Checked::expr_ty`]: the natural type of every expression;
//! - [`Checked::coerce`]: the *expected* type where an implicit (widening) conversion applies,
//!   kept apart from the natural type;
//! - [`Checked::res`]: what a name, member access or call refers to.

mod body;
pub mod types;

use crate::diagnostics::{Code, Diagnostic};
use crate::syntax::*;
use std::collections::HashMap;
use std::rc::Rc;
pub use types::*;

/// A VAR_IN_OUT is a reference: the absolute address of the actual variable, one integer
/// cell per lane.
pub const REFERENCE_SIZE: Size = Size { i: 3, r: 0, s: 0 };

/// What a name, member or call node refers to.
#[derive(Debug, Clone, PartialEq)]
pub enum Res {
    /// A variable of the POU being checked (index into its `vars`).
    Local(usize),
    /// A global variable (index into [`Checked::globals`]).
    Global(usize),
    /// An enumeration value.
    EnumValue(i64),
    /// The instance of a PROGRAM (`Main.x` from elsewhere).
    Program(PouId),
    /// A quoted name that is really a WSTRING literal.
    WStringLiteral(String),
    /// Struct field (index).
    Field(usize),
    /// Variable of a FB instance or program (POU, index).
    PouVar(PouId, usize),
    /// A call of a user FUNCTION.
    CallFunction(PouId),
    /// A call of a FB instance (the callee expression is the instance).
    CallFb(PouId),
    /// A call of a built-in function.
    CallBuiltin(crate::stdlib::Builtin),
    /// `NULL`, the reference to nothing.
    Null,
}

/// A declared variable.
#[derive(Debug, Clone)]
pub struct VarInfo {
    /// Name as declared.
    pub name: String,
    /// Upper-case key.
    pub key: String,
    /// Section.
    pub kind: VarKind,
    /// Type.
    pub ty: Ty,
    /// Offset in the instance (or absolute for globals).
    pub offset: Size,
    /// CONSTANT.
    pub constant: bool,
    /// RETAIN.
    pub retain: bool,
    /// PERSISTENT.
    pub persistent: bool,
    /// Direct address.
    pub at: Option<String>,
    /// Initial value.
    pub init: Option<Init>,
    /// Declaration.
    pub span: Span,
    /// Subrange bounds when the variable's type is a subrange (checked on every store).
    pub range: Option<(i64, i64)>,
}

/// A checked POU.
#[derive(Debug, Clone)]
pub struct PouInfo {
    /// Name.
    pub name: String,
    /// Kind.
    pub kind: PouKind,
    /// Variables; for functions, index 0 is the result variable (named like the function).
    pub vars: Vec<VarInfo>,
    /// Upper-case name to index.
    pub var_index: HashMap<String, usize>,
    /// Result type of functions.
    pub ret: Option<Ty>,
    /// Instance size.
    pub size: Size,
    /// Absolute base of the single instance of a PROGRAM and of the static frame of a
    /// FUNCTION (IEC 61131-3 forbids recursion, so one frame per function suffices).
    pub base: Option<Size>,
    /// Index into the unit's items.
    pub item: usize,
    /// Declared in the standard library prelude.
    pub stdlib: bool,
}

impl PouInfo {
    /// Variable by upper-case key.
    pub fn var(&self, key: &str) -> Option<(usize, &VarInfo)> {
        let i = *self.var_index.get(key)?;
        Some((i, self.vars.get(i)?))
    }
}

/// The result of checking: the unit plus side tables. Only produced without errors.
#[derive(Debug)]
pub struct Checked {
    /// The parsed program (immutable).
    pub unit: CompilationUnit,
    /// Structs and enums.
    pub types: TypeTable,
    /// All POUs.
    pub pous: Vec<PouInfo>,
    /// Upper-case name to POU.
    pub pou_index: HashMap<String, PouId>,
    /// Global variables (absolute offsets).
    pub globals: Vec<VarInfo>,
    /// Upper-case name to global.
    pub global_index: HashMap<String, usize>,
    /// Total memory size.
    pub memory_size: Size,
    /// Natural type of every expression, by node id.
    pub expr_ty: Vec<Option<Ty>>,
    /// Expected type where an implicit conversion is applied.
    pub coerce: HashMap<NodeId, Ty>,
    /// Name resolution.
    pub res: HashMap<NodeId, Res>,
    /// Warnings.
    pub warnings: Vec<Diagnostic>,
    /// Tasks declared in CONFIGURATION/RESOURCE blocks.
    pub tasks: Vec<TaskSpec>,
}

/// A task declared in the source.
#[derive(Debug, Clone, PartialEq)]
pub struct TaskSpec {
    /// Name.
    pub name: String,
    /// Interval in ns (0 = every cycle).
    pub interval_ns: i64,
    /// Priority (0 = highest).
    pub priority: u8,
    /// PROGRAM types run by the task, in order.
    pub programs: Vec<String>,
}

impl Checked {
    /// Natural type of an expression.
    pub fn ty(&self, id: NodeId) -> Ty {
        self.expr_ty
            .get(id.0 as usize)
            .cloned()
            .flatten()
            .unwrap_or(Ty::Void)
    }
    /// Type after implicit conversion.
    pub fn final_ty(&self, id: NodeId) -> Ty {
        self.coerce.get(&id).cloned().unwrap_or_else(|| self.ty(id))
    }
    /// A POU.
    pub fn pou(&self, id: PouId) -> Option<&PouInfo> {
        self.pous.get(id.0)
    }
    /// The size of a type.
    pub fn size_of(&self, ty: &Ty) -> Size {
        size_of(ty, &self.types, &self.pous)
    }
    /// Human-readable type name.
    pub fn type_name(&self, ty: &Ty) -> String {
        type_name(ty, &self.types, &self.pous)
    }
}

fn size_of(ty: &Ty, types: &TypeTable, pous: &[PouInfo]) -> Size {
    match ty {
        Ty::Real | Ty::LReal => Size { i: 0, r: 1, s: 0 },
        Ty::String(_) | Ty::WString(_) => Size { i: 0, r: 0, s: 1 },
        Ty::Array(a) => a.elem_size.times(a.len()),
        Ty::Struct(id) => types.struct_def(*id).map(|s| s.size).unwrap_or_default(),
        Ty::Fb(id) => pous.get(id.0).map(|p| p.size).unwrap_or_default(),
        Ty::Void => Size::default(),
        _ => Size { i: 1, r: 0, s: 0 },
    }
}

fn type_name(ty: &Ty, types: &TypeTable, pous: &[PouInfo]) -> String {
    match ty {
        Ty::Struct(id) => types
            .struct_def(*id)
            .map(|s| s.name.clone())
            .unwrap_or_default(),
        Ty::Enum(id) => types
            .enum_def(*id)
            .map(|s| s.name.clone())
            .unwrap_or_default(),
        Ty::Fb(id) => pous.get(id.0).map(|p| p.name.clone()).unwrap_or_default(),
        Ty::Ref(t) if **t == Ty::Void => "NULL".to_string(),
        Ty::Ref(t) => format!("REF_TO {}", type_name(t, types, pous)),
        Ty::Array(a) => {
            let dims: Vec<String> = a.dims.iter().map(|(l, h)| format!("{l}..{h}")).collect();
            format!(
                "ARRAY[{}] OF {}",
                dims.join(", "),
                type_name(&a.elem, types, pous)
            )
        }
        other => other.to_string(),
    }
}

#[derive(Clone)]
enum TypeSlot {
    Pending(usize, usize),
    /// Being resolved; a STRUCT already has its type (its members may refer to it by
    /// `REF_TO`, a reference being one cell whatever it refers to).
    InProgress(Option<Ty>),
    Done(Ty),
}

enum PouSlot {
    Pending,
    InProgress,
    Done,
}

/// Checks a parsed unit. `stdlib_items` is the number of leading items that come from the
/// standard-library prelude.
pub fn check(unit: CompilationUnit, stdlib_items: usize) -> Result<Checked, Vec<Diagnostic>> {
    let mut cx = Decls {
        unit: &unit,
        diags: Vec::new(),
        types: TypeTable::default(),
        type_slots: HashMap::new(),
        pous: Vec::new(),
        pou_index: HashMap::new(),
        pou_state: Vec::new(),
        globals: Vec::new(),
        global_index: HashMap::new(),
        consts: HashMap::new(),
        type_decls: HashMap::new(),
        type_inits: Vec::new(),
    };
    cx.register(stdlib_items);
    cx.resolve_all();
    // other spellings of standard block parameters (CODESYS `RESET` for `R`): one more
    // key for the same variable, so calls, member access and paths all accept them
    for p in cx.pous.iter_mut().filter(|p| p.stdlib) {
        for (alias, name) in crate::stdlib::parameter_aliases(&p.name.to_uppercase()) {
            if let Some(&i) = p.var_index.get(*name) {
                p.var_index.entry((*alias).to_string()).or_insert(i);
            }
        }
    }
    // layout: globals, programs, functions
    let mut base = Size::default();
    let mut globals = std::mem::take(&mut cx.globals);
    for g in &mut globals {
        g.offset = base;
        base = base.plus(size_of(&g.ty, &cx.types, &cx.pous));
    }
    for p in &mut cx.pous {
        if matches!(p.kind, PouKind::Program | PouKind::Function) {
            p.base = Some(base);
            base = base.plus(p.size);
        }
    }
    let Decls {
        diags,
        types,
        pous,
        pou_index,
        global_index,
        type_inits,
        ..
    } = cx;
    let mut checked = Checked {
        expr_ty: vec![None; unit.node_count as usize],
        unit,
        types,
        pous,
        pou_index,
        globals,
        global_index,
        memory_size: base,
        coerce: HashMap::new(),
        res: HashMap::new(),
        warnings: Vec::new(),
        tasks: Vec::new(),
    };
    let mut diags = diags;
    checked.tasks = configure(&checked, &mut diags);
    body::check_bodies(&mut checked, &type_inits, &mut diags);
    let (errors, warnings): (Vec<_>, Vec<_>) = diags.into_iter().partition(Diagnostic::is_error);
    if errors.is_empty() {
        checked.warnings = warnings;
        Ok(checked)
    } else {
        let mut all = errors;
        all.extend(warnings);
        all.sort_by_key(|d| (d.primary.file, d.primary.start));
        Err(all)
    }
}

/// Tasks and program bindings of CONFIGURATION/RESOURCE blocks.
fn configure(c: &Checked, diags: &mut Vec<Diagnostic>) -> Vec<TaskSpec> {
    let mut tasks: Vec<TaskSpec> = Vec::new();
    for item in &c.unit.items {
        if let Item::Task(t) = item {
            if tasks
                .iter()
                .any(|x| x.name.eq_ignore_ascii_case(&t.name.name))
            {
                diags.push(Diagnostic::error(
                    Code::Duplicate,
                    t.name.span,
                    format!("task '{}' is declared more than once", t.name.name),
                ));
                continue;
            }
            let interval_ns = match t.interval.as_ref().map(|e| &e.kind) {
                None => 0,
                Some(ExprKind::Literal(Literal::Time(ns, _))) => {
                    i64::try_from(*ns).unwrap_or(i64::MAX)
                }
                Some(_) => {
                    let span = t.interval.as_ref().map(|e| e.span).unwrap_or(t.span);
                    diags.push(Diagnostic::error(
                        Code::NotConstant,
                        span,
                        "INTERVAL must be a TIME literal",
                    ));
                    0
                }
            };
            let priority = match t.priority.as_ref().map(|e| &e.kind) {
                None => 10,
                Some(ExprKind::Literal(Literal::Int(v, _))) if (0..=255).contains(v) => *v as u8,
                Some(_) => {
                    let span = t.priority.as_ref().map(|e| e.span).unwrap_or(t.span);
                    diags.push(Diagnostic::error(
                        Code::NotConstant,
                        span,
                        "PRIORITY must be an integer literal 0..255",
                    ));
                    10
                }
            };
            tasks.push(TaskSpec {
                name: t.name.name.clone(),
                interval_ns,
                priority,
                programs: Vec::new(),
            });
        }
    }
    let mut instantiated: HashMap<String, Span> = HashMap::new();
    for item in &c.unit.items {
        if let Item::ProgramConfig(pc) = item {
            if let Some(first) = instantiated.get(&pc.program.key) {
                diags.push(
                    Diagnostic::error(
                        Code::Unsupported,
                        pc.program.span,
                        format!(
                            "PROGRAM '{}' is instantiated more than once",
                            pc.program.name
                        ),
                    )
                    .with_label(*first, "first instance here")
                    .with_note("each PROGRAM type has exactly one instance in this runtime"),
                );
                continue;
            }
            instantiated.insert(pc.program.key.clone(), pc.program.span);
            let is_program = c
                .pou_index
                .get(&pc.program.key)
                .and_then(|id| c.pou(*id))
                .is_some_and(|p| p.kind == PouKind::Program);
            if !is_program {
                diags.push(Diagnostic::error(
                    Code::Undeclared,
                    pc.program.span,
                    format!("no PROGRAM '{}'", pc.program.name),
                ));
                continue;
            }
            let name = c
                .pou_index
                .get(&pc.program.key)
                .and_then(|id| c.pou(*id))
                .map(|p| p.name.clone())
                .unwrap_or_default();
            match &pc.task {
                Some(t) => match tasks
                    .iter_mut()
                    .find(|x| x.name.eq_ignore_ascii_case(&t.name))
                {
                    Some(task) => task.programs.push(name),
                    None => diags.push(Diagnostic::error(
                        Code::Undeclared,
                        t.span,
                        format!("undeclared task '{}'", t.name),
                    )),
                },
                None => tasks.push(TaskSpec {
                    name: pc.instance.name.clone(),
                    interval_ns: 0,
                    priority: 10,
                    programs: vec![name],
                }),
            }
        }
    }
    tasks
}

struct Decls<'u> {
    unit: &'u CompilationUnit,
    diags: Vec<Diagnostic>,
    types: TypeTable,
    type_slots: HashMap<String, TypeSlot>,
    pous: Vec<PouInfo>,
    pou_index: HashMap<String, PouId>,
    pou_state: Vec<PouSlot>,
    globals: Vec<VarInfo>,
    global_index: HashMap<String, usize>,
    /// Integer constants for array bounds etc.: global and local CONSTANT values.
    consts: HashMap<String, i128>,
    /// TYPE declarations by upper-case name (the first of duplicates).
    type_decls: HashMap<String, &'u TypeDecl>,
    /// Initial values written in TYPE declarations with the type they initialise, checked
    /// once with the bodies (variables of those types share the expressions).
    type_inits: Vec<(Init, Ty)>,
}

impl<'u> Decls<'u> {
    fn err(&mut self, code: Code, span: Span, msg: impl Into<String>) {
        self.diags.push(Diagnostic::error(code, span, msg));
    }

    fn register(&mut self, stdlib_items: usize) {
        for (idx, item) in self.unit.items.iter().enumerate() {
            match item {
                Item::Pou(p) => {
                    if self.pou_index.contains_key(&p.name.key)
                        || self.type_slots.contains_key(&p.name.key)
                    {
                        let mut d = Diagnostic::error(
                            Code::Duplicate,
                            p.name.span,
                            format!("'{}' is declared more than once", p.name.name),
                        );
                        let first = self
                            .pou_index
                            .get(&p.name.key)
                            .and_then(|id| self.pous.get(id.0))
                            .map(|f| (f.item, f.stdlib));
                        if let Some((item, stdlib)) = first {
                            if let Some(Item::Pou(f)) = self.unit.items.get(item) {
                                d = if stdlib {
                                    d.with_note(format!(
                                        "'{}' is part of the standard library",
                                        f.name.name
                                    ))
                                } else {
                                    d.with_label(f.name.span, "first declared here")
                                };
                            }
                        }
                        self.diags.push(d);
                        continue;
                    }
                    let id = PouId(self.pous.len());
                    self.pou_index.insert(p.name.key.clone(), id);
                    self.pous.push(PouInfo {
                        name: p.name.name.clone(),
                        kind: p.kind,
                        vars: Vec::new(),
                        var_index: HashMap::new(),
                        ret: None,
                        size: Size::default(),
                        base: None,
                        item: idx,
                        stdlib: idx < stdlib_items,
                    });
                    self.pou_state.push(PouSlot::Pending);
                }
                Item::Types(decls) => {
                    for (di, d) in decls.iter().enumerate() {
                        if self.type_slots.contains_key(&d.name.key)
                            || self.pou_index.contains_key(&d.name.key)
                            || Ty::elementary(&d.name.key).is_some()
                        {
                            self.err(
                                Code::Duplicate,
                                d.name.span,
                                format!("type '{}' is declared more than once", d.name.name),
                            );
                            continue;
                        }
                        self.type_slots
                            .insert(d.name.key.clone(), TypeSlot::Pending(idx, di));
                        self.type_decls.insert(d.name.key.clone(), d);
                    }
                }
                Item::Globals(_) | Item::Task(_) | Item::ProgramConfig(_) => {}
            }
        }
    }

    fn resolve_all(&mut self) {
        // global constants first (for array bounds), then types, then globals, then POUs
        let unit = self.unit;
        for item in &unit.items {
            if let Item::Globals(b) = item {
                if b.constant {
                    for d in &b.decls {
                        let init = d.init.clone().or_else(|| self.type_default(&d.ty));
                        if let Some(Init::Expr(e)) = &init {
                            if let Some(v) = self.const_int(e) {
                                for n in &d.names {
                                    self.consts.insert(n.key.clone(), v);
                                }
                            }
                        }
                    }
                }
            }
        }
        let keys: Vec<String> = self.type_slots.keys().cloned().collect();
        for k in keys {
            self.named_type(&k, Span::default());
        }
        for item in &unit.items {
            if let Item::Globals(b) = item {
                for d in &b.decls {
                    let ty = self.resolve_type(&d.ty, &d.names[..]);
                    if b.constant {
                        self.no_constant_instances(&ty, &d.names);
                    }
                    for n in &d.names {
                        if let Some(&first) = self.global_index.get(&n.key) {
                            let mut d = Diagnostic::error(
                                Code::Duplicate,
                                n.span,
                                format!("global variable '{}' is declared more than once", n.name),
                            );
                            if let Some(f) = self.globals.get(first) {
                                d = d.with_label(f.span, "first declared here");
                            }
                            self.diags.push(d);
                            continue;
                        }
                        self.global_index.insert(n.key.clone(), self.globals.len());
                        self.globals.push(VarInfo {
                            name: n.name.clone(),
                            key: n.key.clone(),
                            kind: VarKind::Global,
                            ty: ty.clone(),
                            offset: Size::default(),
                            constant: b.constant,
                            retain: b.retain,
                            persistent: b.persistent,
                            at: d.at.as_ref().map(|a| a.0.clone()),
                            init: merge_init(d.init.clone(), self.type_default(&d.ty)),
                            span: n.span,
                            range: self.subrange_of(&d.ty),
                        });
                    }
                }
            }
        }
        for i in 0..self.pous.len() {
            self.layout_pou(PouId(i));
        }
    }

    fn const_int(&self, e: &Expr) -> Option<i128> {
        match &e.kind {
            ExprKind::Literal(Literal::Int(v, _)) => Some(*v),
            ExprKind::Name { ident, .. } => self.consts.get(&ident.key).copied(),
            ExprKind::Unary(UnOp::Neg, a) => self.const_int(a).map(|v| -v),
            ExprKind::Unary(UnOp::Plus, a) => self.const_int(a),
            ExprKind::Binary(op, a, b) => {
                let (a, b) = (self.const_int(a)?, self.const_int(b)?);
                match op {
                    BinOp::Add => a.checked_add(b),
                    BinOp::Sub => a.checked_sub(b),
                    BinOp::Mul => a.checked_mul(b),
                    BinOp::Div => a.checked_div(b),
                    BinOp::Mod => a.checked_rem(b),
                    _ => None,
                }
            }
            _ => None,
        }
    }

    /// Bounds of a subrange type, written directly or through TYPE aliases.
    fn subrange_of(&self, t: &TypeRef) -> Option<(i64, i64)> {
        let mut t = t.clone();
        for _ in 0..32 {
            match &t {
                TypeRef::Subrange { lo, hi, .. } => {
                    let (a, b) = (self.const_int(lo)?, self.const_int(hi)?);
                    return Some((i64::try_from(a).ok()?, i64::try_from(b).ok()?));
                }
                TypeRef::Named(id) => {
                    if !self.type_slots.contains_key(&id.key) {
                        return None;
                    }
                    let decl = self.unit.items.iter().find_map(|it| match it {
                        Item::Types(d) => d.iter().find(|d| d.name.key == id.key),
                        _ => None,
                    })?;
                    t = decl.ty.clone();
                }
                _ => return None,
            }
        }
        None
    }

    /// The initial value a declaration of type `t` starts with when it gives none: the
    /// `:=` of the TYPE declaration `t` names, through derived types (the nearest
    /// declaration wins; structure initializers are merged field by field).
    fn type_default(&self, t: &TypeRef) -> Option<Init> {
        let mut t = t;
        let mut found = None;
        // a bound, not a limit users meet: cycles of TYPE aliases are reported elsewhere
        for _ in 0..32 {
            let TypeRef::Named(id) = t else { break };
            let Some(decl) = self.type_decls.get(&id.key) else {
                break;
            };
            found = merge_init(found, decl.init.clone());
            t = &decl.ty;
        }
        found
    }

    fn named_type(&mut self, key: &str, span: Span) -> Option<Ty> {
        if let Some(t) = Ty::elementary(key) {
            return Some(t);
        }
        if let Some(id) = self.pou_index.get(key).copied() {
            let kind = self.pous.get(id.0).map(|p| p.kind);
            if kind == Some(PouKind::FunctionBlock) {
                self.layout_pou(id);
                return Some(Ty::Fb(id));
            }
            let name = self
                .pous
                .get(id.0)
                .map(|p| p.name.clone())
                .unwrap_or_default();
            self.err(
                Code::UnknownType,
                span,
                format!("'{name}' is a program or function, not a type"),
            );
            return None;
        }
        match self.type_slots.get(key).cloned() {
            None => None,
            Some(TypeSlot::Done(t)) => Some(t),
            Some(TypeSlot::InProgress(_)) => {
                self.err(
                    Code::UnknownType,
                    span,
                    format!("type '{key}' is defined in terms of itself"),
                );
                None
            }
            Some(TypeSlot::Pending(item, di)) => {
                self.type_slots
                    .insert(key.to_string(), TypeSlot::InProgress(None));
                let unit = self.unit;
                let decl = match unit.items.get(item) {
                    Some(Item::Types(d)) => d.get(di),
                    _ => None,
                }?;
                let ty = match &decl.ty {
                    TypeRef::Struct(fields, _) => {
                        let id = self.reserve_struct(&decl.name.name);
                        self.type_slots
                            .insert(key.to_string(), TypeSlot::InProgress(Some(Ty::Struct(id))));
                        self.struct_fields(id, fields)
                    }
                    TypeRef::Enum(values, _) => self.enum_type(&decl.name.name, values),
                    other => self.resolve_type(other, std::slice::from_ref(&decl.name)),
                };
                if let Some(init) = &decl.init {
                    self.type_inits.push((init.clone(), ty.clone()));
                }
                self.type_slots
                    .insert(key.to_string(), TypeSlot::Done(ty.clone()));
                Some(ty)
            }
        }
    }

    fn struct_type(&mut self, name: &str, fields: &[VarDecl]) -> Ty {
        let id = self.reserve_struct(name);
        self.struct_fields(id, fields)
    }

    /// A new struct type, its members still to come ([`Decls::struct_fields`]).
    fn reserve_struct(&mut self, name: &str) -> StructId {
        let id = StructId(self.types.structs.len());
        self.types.structs.push(StructDef {
            name: name.to_string(),
            fields: Vec::new(),
            size: Size::default(),
        });
        id
    }

    /// Lays out the members of the reserved struct `id`.
    fn struct_fields(&mut self, id: StructId, fields: &[VarDecl]) -> Ty {
        let mut out = Vec::new();
        let mut off = Size::default();
        let mut seen = HashMap::new();
        for d in fields {
            let ty = self.resolve_type(&d.ty, &d.names);
            for n in &d.names {
                if seen.insert(n.key.clone(), ()).is_some() {
                    self.err(
                        Code::Duplicate,
                        n.span,
                        format!("field '{}' is declared more than once", n.name),
                    );
                }
                out.push(Field {
                    name: n.name.clone(),
                    key: n.key.clone(),
                    ty: ty.clone(),
                    offset: off,
                    init: merge_init(d.init.clone(), self.type_default(&d.ty)),
                    range: self.subrange_of(&d.ty),
                });
                off = off.plus(size_of(&ty, &self.types, &self.pous));
            }
        }
        if let Some(def) = self.types.structs.get_mut(id.0) {
            def.fields = out;
            def.size = off;
        }
        Ty::Struct(id)
    }

    fn enum_type(&mut self, name: &str, values: &[(Ident, Option<Expr>)]) -> Ty {
        let mut out = Vec::new();
        let mut next: i64 = 0;
        let mut seen: HashMap<&str, Span> = HashMap::new();
        let mut numbers: HashMap<i64, (String, Span)> = HashMap::new();
        for (n, v) in values {
            if let Some(first) = seen.insert(n.key.as_str(), n.span) {
                self.diags.push(
                    Diagnostic::error(
                        Code::Duplicate,
                        n.span,
                        format!("enumeration value '{}' is declared more than once", n.name),
                    )
                    .with_label(first, "first declared here"),
                );
                continue;
            }
            if let Some(e) = v {
                match self.const_int(e) {
                    Some(v) => next = i64::try_from(v).unwrap_or(0),
                    None => self.err(
                        Code::NotConstant,
                        e.span,
                        "enumeration value must be a constant integer",
                    ),
                }
            }
            // one value, one name: the value is what is stored, shown and matched by CASE
            if let Some((first, first_span)) = numbers.get(&next) {
                let at = v.as_ref().map_or(n.span, |e| e.span);
                self.diags.push(
                    Diagnostic::error(
                        Code::Duplicate,
                        at,
                        format!(
                            "enumeration values '{first}' and '{}' both have the value {next}",
                            n.name
                        ),
                    )
                    .with_label(*first_span, format!("'{first}' has it here")),
                );
            } else {
                numbers.insert(next, (n.name.clone(), n.span));
            }
            out.push((n.name.clone(), next));
            next = next.wrapping_add(1);
        }
        let id = EnumId(self.types.enums.len());
        self.types.enums.push(EnumDef {
            name: name.to_string(),
            values: out,
        });
        Ty::Enum(id)
    }

    fn resolve_type(&mut self, t: &TypeRef, names: &[Ident]) -> Ty {
        match t {
            TypeRef::Named(id) => match self.named_type(&id.key, id.span) {
                Some(t) => t,
                None => {
                    if !self.diags.iter().any(|d| d.primary == id.span) {
                        self.err(
                            Code::UnknownType,
                            id.span,
                            format!("unknown type '{}'", id.name),
                        );
                    }
                    Ty::Void
                }
            },
            TypeRef::String { wide, len, .. } => {
                let n = match len {
                    Some(e) => match self.const_int(e) {
                        Some(v) if (1..=65535).contains(&v) => v as u32,
                        _ => {
                            self.err(
                                Code::NotConstant,
                                e.span,
                                "string length must be a constant between 1 and 65535",
                            );
                            DEFAULT_STRING_LEN
                        }
                    },
                    None => DEFAULT_STRING_LEN,
                };
                if *wide {
                    Ty::WString(n)
                } else {
                    Ty::String(n)
                }
            }
            TypeRef::Array { dims, elem, .. } => {
                let mut d = Vec::new();
                for (lo, hi) in dims {
                    match (self.const_int(lo), self.const_int(hi)) {
                        (Some(a), Some(b)) if a <= b && b - a < 10_000_000 => {
                            d.push((a as i64, b as i64));
                        }
                        (Some(_), Some(_)) => {
                            self.err(
                                Code::TypeMismatch,
                                lo.span.to(hi.span),
                                "array range is empty or too large",
                            );
                            d.push((0, 0));
                        }
                        _ => {
                            self.err(
                                Code::NotConstant,
                                lo.span.to(hi.span),
                                "array bounds must be constant integers",
                            );
                            d.push((0, 0));
                        }
                    }
                }
                let elem_range = self.subrange_of(elem);
                let elem_init = self.type_default(elem);
                let elem = self.resolve_type(elem, names);
                let elem_size = size_of(&elem, &self.types, &self.pous);
                let a = ArrayTy {
                    dims: d,
                    elem,
                    elem_size,
                    elem_range,
                    elem_init,
                };
                if a.len()
                    .saturating_mul(elem_size.i + elem_size.r + elem_size.s)
                    > 50_000_000
                {
                    self.err(Code::TypeMismatch, t.span(), "array too large");
                    return Ty::Void;
                }
                Ty::Array(Rc::new(a))
            }
            TypeRef::Struct(fields, _) => {
                let name = names.first().map(|n| n.name.clone()).unwrap_or_default();
                self.struct_type(&name, fields)
            }
            TypeRef::Ref(target, _) => {
                // `next : REF_TO Node` inside the STRUCT Node being laid out
                if let TypeRef::Named(n) = &**target {
                    if let Some(TypeSlot::InProgress(Some(t))) = self.type_slots.get(&n.key) {
                        return Ty::Ref(Rc::new(t.clone()));
                    }
                }
                let t = self.resolve_type(target, &[]);
                if t == Ty::Void {
                    return Ty::Void;
                }
                Ty::Ref(Rc::new(t))
            }
            TypeRef::Enum(values, _) => {
                let name = names.first().map(|n| n.name.clone()).unwrap_or_default();
                self.enum_type(&name, values)
            }
            TypeRef::Subrange { base, lo, hi } => {
                // Subranges are checked like their base type (range checks come later).
                let base_ty = self.named_type(&base.key, base.span).unwrap_or(Ty::Void);
                let bounds = lo.span.to(hi.span);
                match (self.const_int(lo), self.const_int(hi)) {
                    (Some(l), Some(h)) if l > h => self.err(
                        Code::TypeMismatch,
                        bounds,
                        format!("empty subrange {l}..{h}: the lower bound is above the upper"),
                    ),
                    (Some(l), Some(h)) => match base_ty.int_range() {
                        Some((min, max)) if base_ty != Ty::Bool && (l < min || h > max) => {
                            self.err(
                                Code::TypeMismatch,
                                bounds,
                                format!(
                                    "subrange {l}..{h} does not fit its base type {base_ty} ({min}..{max})"
                                ),
                            );
                        }
                        Some(_) if base_ty != Ty::Bool => {}
                        _ if base_ty != Ty::Void => self.err(
                            Code::TypeMismatch,
                            base.span,
                            format!("a subrange needs an integer base type, not {base_ty}"),
                        ),
                        _ => {}
                    },
                    _ => self.err(
                        Code::NotConstant,
                        bounds,
                        "subrange bounds must be constant",
                    ),
                }
                base_ty
            }
        }
    }

    fn layout_pou(&mut self, id: PouId) {
        match self.pou_state.get(id.0) {
            Some(PouSlot::Pending) => {}
            Some(PouSlot::InProgress) => {
                let (name, span) = self.pou_name_span(id);
                self.err(
                    Code::Recursion,
                    span,
                    format!("function block '{name}' contains an instance of itself"),
                );
                return;
            }
            _ => return,
        }
        if let Some(s) = self.pou_state.get_mut(id.0) {
            *s = PouSlot::InProgress;
        }
        let unit = self.unit;
        let Some(Item::Pou(pou)) = self.pous.get(id.0).and_then(|p| unit.items.get(p.item)) else {
            return;
        };
        let mut vars: Vec<VarInfo> = Vec::new();
        let mut index = HashMap::new();
        let mut off = Size::default();
        let mut ret = None;
        if pou.kind == PouKind::Function {
            let rt = match &pou.return_type {
                Some(t) => self.resolve_type(t, std::slice::from_ref(&pou.name)),
                None => Ty::Void,
            };
            let result_init = pou.return_type.as_ref().and_then(|t| self.type_default(t));
            ret = Some(rt.clone());
            index.insert(pou.name.key.clone(), 0);
            let sz = size_of(&rt, &self.types, &self.pous);
            vars.push(VarInfo {
                name: pou.name.name.clone(),
                key: pou.name.key.clone(),
                kind: VarKind::Output,
                ty: rt,
                offset: off,
                constant: false,
                retain: false,
                persistent: false,
                at: None,
                init: result_init,
                span: pou.name.span,
                range: None,
            });
            off = off.plus(sz);
        }
        // local constants usable in bounds
        for b in &pou.vars {
            if b.constant {
                for d in &b.decls {
                    let init = d.init.clone().or_else(|| self.type_default(&d.ty));
                    if let Some(Init::Expr(e)) = &init {
                        if let Some(v) = self.const_int(e) {
                            for n in &d.names {
                                self.consts.insert(n.key.clone(), v);
                            }
                        }
                    }
                }
            }
        }
        for b in &pou.vars {
            if b.kind == VarKind::Global {
                self.err(
                    Code::Unsupported,
                    b.span,
                    "VAR_GLOBAL inside a POU is not supported; declare globals at top level",
                );
                continue;
            }
            for d in &b.decls {
                let mut ty = if b.kind == VarKind::External {
                    // type comes from the global
                    let g = d
                        .names
                        .first()
                        .and_then(|n| self.global_index.get(&n.key))
                        .and_then(|&g| self.globals.get(g))
                        .map(|g| g.ty.clone());
                    match g {
                        Some(t) => t,
                        None => {
                            if let Some(n) = d.names.first() {
                                self.err(
                                    Code::Undeclared,
                                    n.span,
                                    format!("no global variable '{}' for VAR_EXTERNAL", n.name),
                                );
                            }
                            Ty::Void
                        }
                    }
                } else {
                    self.resolve_type(&d.ty, &d.names)
                };
                if b.constant && b.kind != VarKind::External {
                    self.no_constant_instances(&ty, &d.names);
                }
                // IEC 61131-3: a function has no state from one call to the next, so it
                // holds no instances; it may work on one passed as VAR_IN_OUT
                if pou.kind == PouKind::Function
                    && b.kind != VarKind::InOut
                    && b.kind != VarKind::External
                    && self.holds_instance(&ty)
                {
                    for n in &d.names {
                        self.diags.push(
                            Diagnostic::error(
                                Code::Unsupported,
                                n.span,
                                format!(
                                    "function '{}' cannot declare the function block instance '{}'",
                                    pou.name.name, n.name
                                ),
                            )
                            .with_note("a FUNCTION keeps no state between calls; declare the instance in the caller and pass it as VAR_IN_OUT, or make this a FUNCTION_BLOCK"),
                        );
                    }
                }
                if ty == Ty::Void && b.kind != VarKind::External {
                    ty = Ty::Void;
                }
                for n in &d.names {
                    if let Some(&first) = index.get(&n.key) {
                        let mut d = Diagnostic::error(
                            Code::Duplicate,
                            n.span,
                            format!("variable '{}' is declared more than once", n.name),
                        );
                        if let Some(f) = vars.get(first) {
                            let f: &VarInfo = f;
                            d = d.with_label(f.span, "first declared here");
                        }
                        self.diags.push(d);
                        continue;
                    }
                    index.insert(n.key.clone(), vars.len());
                    let sz = if b.kind == VarKind::External {
                        Size::default()
                    } else if b.kind == VarKind::InOut {
                        REFERENCE_SIZE
                    } else {
                        size_of(&ty, &self.types, &self.pous)
                    };
                    vars.push(VarInfo {
                        name: n.name.clone(),
                        key: n.key.clone(),
                        kind: b.kind,
                        ty: ty.clone(),
                        offset: off,
                        constant: b.constant,
                        retain: b.retain,
                        persistent: b.persistent,
                        at: d.at.as_ref().map(|a| a.0.clone()),
                        init: match b.kind {
                            // a reference and a global's alias start as what they refer to
                            VarKind::InOut | VarKind::External => d.init.clone(),
                            _ => merge_init(d.init.clone(), self.type_default(&d.ty)),
                        },
                        span: n.span,
                        range: if b.kind == VarKind::InOut {
                            None
                        } else {
                            self.subrange_of(&d.ty)
                        },
                    });
                    off = off.plus(sz);
                }
            }
        }
        if let Some(p) = self.pous.get_mut(id.0) {
            p.vars = vars;
            p.var_index = index;
            p.size = off;
            p.ret = ret;
        }
        if let Some(s) = self.pou_state.get_mut(id.0) {
            *s = PouSlot::Done;
        }
    }

    /// Whether a value of `ty` is or contains a function block instance.
    fn holds_instance(&self, ty: &Ty) -> bool {
        match ty {
            Ty::Fb(_) => true,
            Ty::Array(a) => self.holds_instance(&a.elem),
            Ty::Struct(id) => self
                .types
                .struct_def(*id)
                .is_some_and(|s| s.fields.iter().any(|f| self.holds_instance(&f.ty))),
            _ => false,
        }
    }

    /// Reports instances declared CONSTANT: an instance's state changes when it is called.
    fn no_constant_instances(&mut self, ty: &Ty, names: &[Ident]) {
        if !self.holds_instance(ty) {
            return;
        }
        for n in names {
            self.err(
                Code::NotAssignable,
                n.span,
                format!(
                    "'{}' holds a function block instance and cannot be CONSTANT",
                    n.name
                ),
            );
        }
    }

    fn pou_name_span(&self, id: PouId) -> (String, Span) {
        match self
            .pous
            .get(id.0)
            .and_then(|p| self.unit.items.get(p.item))
        {
            Some(Item::Pou(p)) => (p.name.name.clone(), p.name.span),
            _ => (String::new(), Span::default()),
        }
    }
}

/// `near` over `far`: the initial value written nearer to the variable wins; of two
/// structure initializers every field not given by `near` comes from `far`.
pub(crate) fn merge_init(near: Option<Init>, far: Option<Init>) -> Option<Init> {
    match (near, far) {
        (Some(Init::Struct(mut fields, span)), Some(Init::Struct(defaults, _))) => {
            for (name, default) in defaults {
                match fields.iter_mut().find(|(n, _)| n.key == name.key) {
                    Some((_, given)) => {
                        let merged = merge_init(Some(given.clone()), Some(default));
                        if let Some(m) = merged {
                            *given = m;
                        }
                    }
                    None => fields.push((name, default)),
                }
            }
            Some(Init::Struct(fields, span))
        }
        (Some(Init::Default(_)) | None, far) => far,
        (Some(near), _) => Some(near),
    }
}
