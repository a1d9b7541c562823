//! Checking of statements, expressions and initial values.
//!
//! | file | what |
//! |------|------|
//! | `mod.rs` | every POU's body and initial values in turn, recursion, shared helpers |
//! | `init.rs` | initial values |
//! | `stmt.rs` | statements and l-values |
//! | `expr.rs` | expressions: literals, names, operators |
//! | `call.rs` | calls of functions and FB instances, `REF()` |
//! | `builtin.rs` | built-in functions |

use super::*;
use std::collections::HashSet;

mod builtin;
mod call;
mod expr;
mod init;
mod stmt;

pub(super) fn check_bodies(
    c: &mut Checked,
    type_inits: &[(Init, Ty)],
    diags: &mut Vec<Diagnostic>,
) {
    let mut calls: HashMap<PouId, Vec<(PouId, Span)>> = HashMap::new();
    // initial values of TYPE declarations and STRUCT members, once, before the variables
    // that share them
    let member_inits: Vec<(Init, Ty)> = c
        .types
        .structs
        .iter()
        .flat_map(|s| &s.fields)
        .filter_map(|f| Some((f.init.clone()?, f.ty.clone())))
        .collect();
    for (init, ty) in type_inits.iter().chain(&member_inits) {
        let mut bc = BodyCx {
            c,
            diags,
            pou: None,
            loops: 0,
            calls: Vec::new(),
            used: HashSet::new(),
            stmt_call: None,
        };
        bc.init(init, ty);
    }
    // globals' initial values
    for gi in 0..c.globals.len() {
        let (init, ty) = match c.globals.get(gi) {
            Some(g) => (g.init.clone(), g.ty.clone()),
            None => continue,
        };
        if let Some(init) = init {
            let mut bc = BodyCx {
                c,
                diags,
                pou: None,
                loops: 0,
                calls: Vec::new(),
                used: HashSet::new(),
                stmt_call: None,
            };
            bc.init(&init, &ty);
        }
    }
    for pi in 0..c.pous.len() {
        let id = PouId(pi);
        let Some(item) = c.pous.get(pi).map(|p| p.item) else {
            continue;
        };
        let Some(Item::Pou(pou)) = c.unit.items.get(item).cloned() else {
            continue;
        };
        let vars = c.pous.get(pi).map(|p| p.vars.clone()).unwrap_or_default();
        let mut bc = BodyCx {
            c,
            diags,
            pou: Some(id),
            loops: 0,
            calls: Vec::new(),
            used: HashSet::new(),
            stmt_call: None,
        };
        for v in &vars {
            if let Some(init) = &v.init {
                if v.kind == VarKind::External {
                    continue;
                }
                bc.init(init, &v.ty);
            }
        }
        bc.stmts(&pou.body);
        let used = std::mem::take(&mut bc.used);
        let is_stdlib = bc.c.pou(id).is_some_and(|p| p.stdlib);
        if !is_stdlib {
            for (i, v) in vars.iter().enumerate() {
                let local = matches!(v.kind, VarKind::Local | VarKind::Temp | VarKind::Static);
                let result_var = pou.kind == PouKind::Function && i == 0;
                if local
                    && !result_var
                    && !used.contains(&i)
                    && !v.name.starts_with('_')
                    && v.at.is_none()
                {
                    bc.diags.push(Diagnostic::warning(
                        Code::UnusedVariable,
                        v.span,
                        format!("variable '{}' is declared but never used", v.name),
                    ));
                }
            }
        }
        let found = std::mem::take(&mut bc.calls);
        calls.insert(id, found);
    }
    // recursion: a cycle in the call graph of functions and FB bodies
    let mut state: HashMap<PouId, u8> = HashMap::new();
    // in declaration order, so the same program always reports the same call
    let mut ids: Vec<PouId> = calls.keys().copied().collect();
    ids.sort_by_key(|id| id.0);
    let mut reported = HashSet::new();
    for id in ids {
        detect_cycle(
            id,
            &calls,
            &mut state,
            &mut Vec::new(),
            diags,
            c,
            &mut reported,
        );
    }
}

fn detect_cycle(
    id: PouId,
    calls: &HashMap<PouId, Vec<(PouId, Span)>>,
    state: &mut HashMap<PouId, u8>,
    stack: &mut Vec<PouId>,
    diags: &mut Vec<Diagnostic>,
    c: &Checked,
    reported: &mut HashSet<PouId>,
) {
    match state.get(&id) {
        Some(2) => return,
        Some(1) => return,
        _ => {}
    }
    if stack.len() > 1000 {
        return;
    }
    state.insert(id, 1);
    stack.push(id);
    for (callee, span) in calls.get(&id).map(Vec::as_slice).unwrap_or(&[]) {
        if state.get(callee) == Some(&1) {
            if reported.insert(*callee) {
                let name = c.pou(*callee).map(|p| p.name.clone()).unwrap_or_default();
                diags.push(Diagnostic::error(
                    Code::Recursion,
                    *span,
                    format!("recursive call of '{name}' (IEC 61131-3 forbids recursion)"),
                ));
            }
        } else {
            detect_cycle(*callee, calls, state, stack, diags, c, reported);
        }
    }
    stack.pop();
    state.insert(id, 2);
}

struct BodyCx<'a> {
    c: &'a mut Checked,
    diags: &'a mut Vec<Diagnostic>,
    pou: Option<PouId>,
    loops: u32,
    calls: Vec<(PouId, Span)>,
    /// Variables of the POU that are referenced.
    used: HashSet<usize>,
    /// The call being checked as a statement (a function without a result may be one).
    stmt_call: Option<crate::syntax::NodeId>,
}

/// The value of an integer literal, also negated (`-5`).
fn int_literal(e: &Expr) -> Option<i128> {
    match &e.kind {
        ExprKind::Literal(Literal::Int(v, _)) => Some(*v),
        ExprKind::Unary(UnOp::Neg, a) => int_literal(a).map(|v| -v),
        ExprKind::Unary(UnOp::Plus, a) => int_literal(a),
        _ => None,
    }
}

fn is_untyped_literal(e: &Expr) -> bool {
    matches!(
        e.kind,
        ExprKind::Literal(Literal::Int(_, None)) | ExprKind::Literal(Literal::Real(_, None))
    )
}

impl BodyCx<'_> {
    fn err(&mut self, code: Code, span: Span, msg: impl Into<String>) {
        self.diags.push(Diagnostic::error(code, span, msg));
    }

    fn set(&mut self, e: &Expr, t: Ty) -> Ty {
        if let Some(slot) = self.c.expr_ty.get_mut(e.id.0 as usize) {
            *slot = Some(t.clone());
        }
        t
    }

    fn name(&self, t: &Ty) -> String {
        self.c.type_name(t)
    }

    /// Records an implicit conversion of `e` (natural type `from`) to `to`, or reports.
    fn coerce_to(&mut self, e: &Expr, from: &Ty, to: &Ty, what: &str) -> bool {
        if *from == Ty::Void || *to == Ty::Void {
            return true;
        }
        if from == to {
            return true;
        }
        let ok = match (from, to) {
            // enumerations read as integers (as CODESYS allows)
            (Ty::Enum(_), t) if t.is_int() => true,
            (Ty::Array(a), Ty::Array(b)) => {
                a.dims
                    .iter()
                    .map(|(l, h)| h - l)
                    .eq(b.dims.iter().map(|(l, h)| h - l))
                    && (a.elem == b.elem
                        || matches!((&a.elem, &b.elem), (Ty::String(_), Ty::String(_))))
            }
            _ => from.converts_to(to),
        };
        if ok {
            if from.is_elementary() && from != to {
                self.c.coerce.insert(e.id, to.clone());
            }
            true
        } else {
            let msg = format!(
                "type mismatch: {what} of type {} where {} is expected",
                self.name(from),
                self.name(to)
            );
            self.diags.push(
                Diagnostic::error(Code::TypeMismatch, e.span, msg)
                    .with_note("IEC 61131-3 converts implicitly only to wider types; use an explicit *_TO_* conversion"),
            );
            false
        }
    }
}
