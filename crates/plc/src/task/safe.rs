//! Safe state: which outputs a task drives, and the safe value each output takes when
//! the task stops.
//!
//! An *output* is a variable declared `AT %Q...` (program variable or global), or a
//! variable the host binds as an output with [`Plc::bind_output`](super::Plc::bind_output)
//! (the station's I/O bindings to plant signals).
//!
//! # Declaring a safe value
//!
//! By default an output goes to FALSE / 0 / 0.0 / `''`. An attribute pragma right before
//! the declaration (as in CODESYS) overrides it; the value is an IEC literal of the
//! variable's type (of its elements for an array or structure bound element-wise):
//!
//! ```text
//! VAR
//!     {attribute 'safe_value' := 'TRUE'}
//!     brake_released_n AT %QX0.2 : BOOL;   (* the brake holds when the task stops *)
//!     {attribute 'safe_value' := '-1'}
//!     speed AT %QW4 : INT;
//! END_VAR
//! ```
//!
//! A value that is not a literal of the type puts the PLC in STOP ([`Plc::init_fault`](
//! super::Plc::init_fault), code E0003) with the position of the pragma.
//!
//! # Which task drives an output
//!
//! Like an I/O channel in CODESYS, an output belongs to the tasks that use it: a program
//! variable to the tasks running that program; a global to the tasks whose programs (or
//! the functions and function blocks they call, transitively) name it. When one of those
//! tasks stops, the output goes to its safe value; a task that is still running and
//! also writes it drives it again in its next cycle.

use super::io::direct_key;
use super::path::split_path;
use super::{format_value, parse_value, Leaf, Plc, PlcError};
use crate::check::{Checked, Size, Ty};
use crate::diagnostics::{Code, Diagnostic};
use crate::syntax::{FileId, Item, PouKind, SourceMap, Span};
use crate::vm::{DirectAddress, Val};
use std::collections::{HashMap, HashSet};

/// The safe value declared by a `{attribute 'safe_value' := '...'}` pragma directly
/// before the name at `name` (skipping earlier names of the same declaration, `a, b`):
/// the literal text and the pragma's span.
pub(super) fn declared(sources: &SourceMap, name: Span) -> Option<(String, Span)> {
    let text = sources.file(name.file)?.text.as_str();
    let bytes = text.as_bytes();
    let mut at = usize::try_from(name.start).ok()?;
    let skip_space = |mut i: usize| {
        while i > 0 && bytes.get(i - 1).is_some_and(u8::is_ascii_whitespace) {
            i -= 1;
        }
        i
    };
    // earlier names of `a, b, c : T`
    loop {
        at = skip_space(at);
        if at > 0 && bytes.get(at - 1) == Some(&b',') {
            at = skip_space(at - 1);
            while at > 0
                && bytes
                    .get(at - 1)
                    .is_some_and(|c| c.is_ascii_alphanumeric() || *c == b'_')
            {
                at -= 1;
            }
        } else {
            break;
        }
    }
    // the pragmas right before it, nearest first
    while at > 0 && bytes.get(at - 1) == Some(&b'}') {
        let end = at;
        let open = text.get(..end)?.rfind('{')?;
        let inner = text.get(open + 1..end - 1)?;
        if let Some(value) = safe_value_attribute(inner) {
            let span = Span {
                file: name.file,
                start: u32::try_from(open).ok()?,
                end: u32::try_from(end).ok()?,
            };
            return Some((value.to_string(), span));
        }
        at = skip_space(open);
    }
    None
}

/// `attribute 'safe_value' := 'TRUE'` (any case, any spacing): `TRUE`.
fn safe_value_attribute(inner: &str) -> Option<&str> {
    let rest = inner.trim();
    let keyword = rest.get(..9)?;
    if !keyword.eq_ignore_ascii_case("attribute") {
        return None;
    }
    let rest = rest.get(9..)?.trim_start();
    let rest = rest.strip_prefix('\'')?;
    let (name, rest) = rest.split_once('\'')?;
    if !name.trim().eq_ignore_ascii_case("safe_value") {
        return None;
    }
    let rest = rest.trim_start().strip_prefix(":=")?.trim_start();
    let rest = rest.strip_prefix('\'')?;
    let (value, tail) = rest.split_once('\'')?;
    tail.trim().is_empty().then_some(value)
}

/// The diagnostic of a safe value that is not a literal of the output's type.
pub(super) fn bad_value(checked: &Checked, ty: &Ty, text: &str, pragma: Span) -> Diagnostic {
    Diagnostic::error(
        Code::BadLiteral,
        pragma,
        format!(
            "safe value '{text}' is not a valid {} value",
            checked.type_name(ty)
        ),
    )
    .with_note("the safe value is an IEC literal of the output's type, e.g. {attribute 'safe_value' := 'TRUE'}")
}

/// For each user POU (upper-case name), the upper-case names its text mentions.
pub(super) fn mentions(checked: &Checked, sources: &SourceMap) -> HashMap<String, HashSet<String>> {
    let mut tokens: HashMap<FileId, Vec<crate::syntax::lexer::Token>> = HashMap::new();
    let mut out = HashMap::new();
    for p in checked.pous.iter().filter(|p| !p.stdlib) {
        let Some(Item::Pou(pou)) = checked.unit.items.get(p.item) else {
            continue;
        };
        let span = pou.span;
        let toks = tokens.entry(span.file).or_insert_with(|| {
            let mut diags = Vec::new();
            sources
                .file(span.file)
                .map(|f| crate::syntax::lexer::lex(span.file, &f.text, &mut diags))
                .unwrap_or_default()
        });
        let inside: Vec<crate::syntax::lexer::Token> = toks
            .iter()
            .filter(|t| t.span.start >= span.start && t.span.end <= span.end)
            .cloned()
            .collect();
        let mut names = HashSet::new();
        crate::prelude::collect_names(&inside, &mut names);
        out.insert(p.name.to_ascii_uppercase(), names);
    }
    out
}

/// The names mentioned by `programs` and, transitively, by the user POUs they name.
pub(super) fn reachable(
    mentions: &HashMap<String, HashSet<String>>,
    programs: &[String],
) -> HashSet<String> {
    let mut seen: HashSet<String> = HashSet::new();
    let mut names: HashSet<String> = HashSet::new();
    let mut todo: Vec<String> = programs.iter().map(|p| p.to_ascii_uppercase()).collect();
    while let Some(pou) = todo.pop() {
        if !seen.insert(pou.clone()) {
            continue;
        }
        if let Some(m) = mentions.get(&pou) {
            for n in m {
                names.insert(n.clone());
                if mentions.contains_key(n) {
                    todo.push(n.clone());
                }
            }
        }
    }
    names
}

/// Who drives an output.
#[derive(Debug, Clone, PartialEq)]
pub(super) enum Owner {
    /// A variable of this PROGRAM (index of the POU).
    Program(usize),
    /// A global (upper-case name): the tasks whose code names it.
    Global(String),
}

/// An output with its safe value.
#[derive(Debug, Clone)]
pub(super) struct SafeOutput {
    /// `%QX0.1` or the variable path.
    pub(super) name: String,
    pub(super) leaf: Leaf,
    pub(super) at: Option<DirectAddress>,
    pub(super) owner: Owner,
    pub(super) safe: Val,
}

impl Plc {
    /// Writes the safe value of every output driven by task `ti` (every output for
    /// `None`) into its variable and the output image; forced addresses stay forced.
    /// Returns what was set.
    pub(super) fn safe_state(&mut self, ti: Option<usize>) -> Vec<(String, String)> {
        let task = ti.and_then(|i| self.tasks.get(i));
        let chosen: Vec<SafeOutput> = self
            .outputs
            .iter()
            .filter(|o| match (task, &o.owner) {
                (None, _) => true,
                (Some(t), Owner::Program(p)) => t.pous.contains(p),
                (Some(t), Owner::Global(key)) => t.names.contains(key),
            })
            .cloned()
            .collect();
        let mut set = Vec::new();
        for o in chosen {
            self.write_leaf(&o.leaf, o.safe.clone());
            if let (Some(d), Ok(v)) = (o.at, self.vm.geti(o.leaf.addr.i)) {
                self.vm.io_write(d.area, d.byte, d.bit, d.bits, v);
            }
            set.push((
                o.name.clone(),
                format_value(&self.compiled.checked, &o.leaf.ty, &o.safe),
            ));
        }
        self.apply_io_forces();
        set
    }

    /// Binds the variable at `path` as an output the host drives from (a plant signal,
    /// a field device): when a task that drives it stops, it goes to its safe value
    /// (see [`safe`](self)). Variables declared `AT %Q...` are outputs without this.
    pub fn bind_output(&mut self, path: &str) -> Result<(), PlcError> {
        let leaf = self.leaf(path)?;
        if self
            .outputs
            .iter()
            .any(|o| o.at.is_none() && o.leaf.addr == leaf.addr && o.leaf.ty == leaf.ty)
        {
            return Ok(());
        }
        let c = &self.compiled.checked;
        let first = split_path(path)
            .and_then(|s| s.into_iter().next())
            .map(|(n, _)| n.to_uppercase())
            .unwrap_or_default();
        let (owner, name_span) =
            if let Some(g) = c.global_index.get(&first).and_then(|g| c.globals.get(*g)) {
                (Owner::Global(first), g.span)
            } else {
                let pid = c
                    .pou_index
                    .get(&first)
                    .copied()
                    .ok_or_else(|| PlcError::UnknownPath(path.to_string()))?;
                let var = split_path(path)
                    .and_then(|s| s.into_iter().nth(1))
                    .map(|(n, _)| n.to_uppercase())
                    .unwrap_or_default();
                let span = c
                    .pou(pid)
                    .and_then(|p| p.var(&var))
                    .map(|(_, v)| v.span)
                    .unwrap_or_default();
                (Owner::Program(pid.0), span)
            };
        let safe = self.safe_value(&leaf.ty, name_span)?;
        self.outputs.push(SafeOutput {
            name: path.to_string(),
            leaf,
            at: None,
            owner,
            safe,
        });
        Ok(())
    }

    /// The safe value declared before the variable named at `name` (0 / FALSE / '' when
    /// none is declared).
    fn safe_value(&self, ty: &Ty, name: crate::syntax::Span) -> Result<Val, PlcError> {
        let default = match ty.lane() {
            Some(crate::check::Lane::Real) => Val::Real(0.0),
            Some(crate::check::Lane::Str) => Val::Str(String::new()),
            _ => Val::Int(0),
        };
        let Some((text, pragma)) = declared(&self.sources, name) else {
            return Ok(default);
        };
        parse_value(&self.compiled.checked, ty, &text).map_err(|_| {
            PlcError::Init(Box::new(bad_value(
                &self.compiled.checked,
                ty,
                &text,
                pragma,
            )))
        })
    }

    /// The `AT %Q` outputs with their safe values; a bad safe value is kept in
    /// `safe_error` (the PLC stays in STOP).
    pub(super) fn collect_outputs(&mut self) {
        let c = &self.compiled.checked;
        let mut found: Vec<(Size, Ty, DirectAddress, Owner, String, crate::syntax::Span)> =
            Vec::new();
        for g in &c.globals {
            if let Some(d) = g.at.as_deref().and_then(DirectAddress::parse) {
                found.push((
                    g.offset,
                    g.ty.clone(),
                    d,
                    Owner::Global(g.key.clone()),
                    g.name.clone(),
                    g.span,
                ));
            }
        }
        for (i, p) in c.pous.iter().enumerate() {
            if p.kind != PouKind::Program {
                continue;
            }
            let Some(base) = p.base else { continue };
            for v in &p.vars {
                if let Some(d) = v.at.as_deref().and_then(DirectAddress::parse) {
                    found.push((
                        base.plus(v.offset),
                        v.ty.clone(),
                        d,
                        Owner::Program(i),
                        format!("{}.{}", p.name, v.name),
                        v.span,
                    ));
                }
            }
        }
        for (addr, ty, d, owner, path, span) in found {
            if d.area != 'Q' {
                continue;
            }
            match self.safe_value(&ty, span) {
                Ok(safe) => self.outputs.push(SafeOutput {
                    name: direct_key(&d),
                    leaf: Leaf {
                        path,
                        ty,
                        addr,
                        retain: false,
                        persistent: false,
                    },
                    at: Some(d),
                    owner,
                    safe,
                }),
                Err(PlcError::Init(diag)) => {
                    if self.safe_error.is_none() {
                        self.safe_error = Some(*diag);
                    }
                }
                Err(_) => {}
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn attribute_spellings() {
        assert_eq!(
            safe_value_attribute(" attribute 'safe_value' := 'TRUE' "),
            Some("TRUE")
        );
        assert_eq!(
            safe_value_attribute("ATTRIBUTE 'Safe_Value':='-1'"),
            Some("-1")
        );
        assert_eq!(safe_value_attribute("attribute 'hide'"), None);
        assert_eq!(
            safe_value_attribute("attribute 'safe_value' := 'x' y"),
            None
        );
    }

    #[test]
    fn the_pragma_before_the_first_name_of_a_declaration() {
        let mut sources = SourceMap::new();
        let text = "VAR\n  {attribute 'safe_value' := '5'}\n  {attribute 'other'}\n  a, b : INT;\n  c : INT;\nEND_VAR";
        let f = sources.add("t.st", text);
        let at = |name: &str| {
            let start = text.find(name).unwrap() as u32;
            Span {
                file: f,
                start,
                end: start + 1,
            }
        };
        assert_eq!(declared(&sources, at("a,")).unwrap().0, "5");
        assert_eq!(declared(&sources, at("b :")).unwrap().0, "5");
        assert_eq!(declared(&sources, at("c :")), None);
    }
}
