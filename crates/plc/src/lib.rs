//! IEC 61131-3 Structured Text: compiler, scan-cycle runtime and standard library.
//!
//! # Layout and data flow
//!
//! ```text
//! source files ──► syntax::lexer ──► syntax::parser ──► CompilationUnit (AST, immutable)
//!                                                             │
//!                 check: declarations, layout, names, types ◄─┘
//!                 (side tables keyed by NodeId: expr_ty, coerce, res)
//!                                                             │
//!                 compile: closures per expression/statement,  ◄┘ ──► Compiled
//!                          loops as machine code (compile::jit)
//!                                                             │
//!                 task::Plc: memory image (vm), tasks, scan cycle, watchdog,
//!                 retain/persistent, forcing, I/O image, paths ◄┘
//! ```
//!
//! - [`syntax`]: [`syntax::SourceMap`] (files, `file:line:col`), the lexer (case-insensitive
//!   keywords, typed/based/time literals, SCL `#local` and `"global"` names), a
//!   recursive-descent parser with error recovery and the AST. Every node has a span
//!   `(FileId, byte range)`; expressions have a [`syntax::NodeId`].
//! - [`diagnostics`]: [`diagnostics::Diagnostic`] with a [`diagnostics::Code`], severity,
//!   primary and secondary labels and notes; rendered as `file:line:col: error: message`.
//!
//! # Diagnostic pages
//!
//! Every [`Code`] has a page, `docs/diagnostics/CODE.md` in this crate (embedded:
//! [`Code::page`]): what the diagnostic means, an example of the mistake and its fix.
//! `stanice plc explain E0201` prints one, `stanice plc explain --list` lists the codes.
//! A test compiles each page's example and checks it reports that code (a run-time fault
//! when it runs) and that the fix compiles clean; rendered diagnostics are `insta`
//! snapshots (`tests/it/snapshots`).
//!
//! - [`check`]: stages as types — parsed [`syntax::CompilationUnit`] to
//!   [`check::Checked`]: types and their three-lane memory layout, POU signatures, name
//!   resolution and IEC implicit (widening) conversions. The AST is not modified.
//! - [`compile`]: [`check::Checked`] to [`compile::Compiled`], closure-compiled code
//!   (see the module for why closures), loops compiled to machine code by Cranelift where
//!   they are in its subset (the one module with `unsafe`: calling that code).
//! - [`vm`]: memory image, values, run-time faults, value formatting.
//! - [`stdlib`]: standard FBs written in ST (timers, edges, counters, bistables, DTL) and
//!   native built-in functions (numeric, bit, selection, string, conversion, time; the
//!   date and time fields of `CONCAT_DATE/TOD/DT` and `SPLIT_DATE/TOD/DT` with their
//!   L-forms, `DAY_OF_WEEK` numbered as the standard does, 0 = Sunday).
//! - [`task`]: the runtime — [`task::Plc`] with a deterministic `run_cycle(now)`.
//!
//! # Run-time rules
//! - Integer overflow wraps at the declared width (two's complement), as on most PLCs.
//! - Integer division/MOD by zero, array index out of range, a value outside the subrange
//!   of a variable, field, array element or input (checked on every store, with the name
//!   of what was written; a FOR counter is checked for every value the body runs with,
//!   the step past the end is not stored if it leaves the subrange) and an
//!   exhausted per-cycle loop budget are *faults*: the task stops with a diagnostic; the
//!   host never panics. The other tasks keep running; the outputs the stopped task drives
//!   go to their safe values, as on a watchdog trip or a PLC STOP (see [`task::safe`]). Constant values outside a subrange are compile-time errors.
//! - Initial values are stored with the same checks. A variable, STRUCT member or array
//!   element without one starts at the `:=` of its TYPE declaration (the nearest through
//!   derived types; structure initializers merge member by member), else at 0, FALSE,
//!   `''`, the first enumeration value or the lower bound of its subrange. VAR_TEMP
//!   starts there on every call, a function's whole frame too. A fault while setting them puts the PLC in
//!   STOP: [`task::Plc::init_fault`] holds the diagnostic, every task is faulted with it
//!   and the next `run_cycle` returns it; [`task::Plc::try_new`] returns it as an error.
//! - `x.%X3`, `x.%B1`, `x.%W0`, `x.%D1`, `x.%L0` read and write a bit, byte, word or
//!   double/long word of a longer bit string or integer (index 0 the least significant);
//!   what is written into the top of a signed integer makes it negative.
//! - `s[i]` reads or writes one character of a STRING/WSTRING as its CHAR/WCHAR code
//!   (IEC 61131-3 3rd edition; CHAR is BYTE, WCHAR is WORD here), 1-based; an index
//!   outside `1..LEN(s)` is a fault.
//! - `REF_TO T` holds the address of a variable, member or array element taken with
//!   `REF(x)` (not of a constant, a bit or a character), or NULL (where every reference
//!   starts). References compare with `=` and `<>` only; `r^` of NULL is a fault.
//!   Functions have static frames, so a reference to a function's variable stays valid
//!   memory but sees the values of the function's last call.
//! - REAL arithmetic follows IEC 60559 (division by zero gives ±INF/NaN).
//! - Functions have one static frame each (IEC 61131-3 forbids recursion, which the
//!   checker rejects); VAR_IN_OUT is passed by reference (the callee holds the address of
//!   the actual variable).
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]
#![cfg_attr(not(test), deny(clippy::indexing_slicing))]

pub mod check;
pub mod compile;
pub mod diagnostics;
pub mod stdlib;
pub mod suggest;
pub mod syntax;
pub mod task;
pub mod vm;

pub use compile::{CompileOptions, Compiled};
pub use diagnostics::{Code, Diagnostic, Severity};
pub use syntax::SourceMap;
pub use task::{Plc, PlcError};

/// Name of the standard-library file in the source map.
pub const PRELUDE_NAME: &str = "<stdlib>";

/// Parses, checks and compiles `files` (name, text) together with the standard library.
/// The returned source map renders the diagnostics; warnings come back with success too.
pub fn build(files: &[(String, String)]) -> (SourceMap, Result<Compiled, Vec<Diagnostic>>) {
    build_with(files, CompileOptions::default())
}

/// Like [`build`] with explicit [`CompileOptions`].
pub fn build_with(
    files: &[(String, String)],
    options: CompileOptions,
) -> (SourceMap, Result<Compiled, Vec<Diagnostic>>) {
    let mut sources = SourceMap::new();
    sources.add(PRELUDE_NAME, stdlib::PRELUDE);
    for (name, text) in files {
        sources.add(name.clone(), text.clone());
    }
    let result = build_sources_with(&sources, options);
    (sources, result)
}

/// Like [`build`] for a prepared source map whose first file is the prelude.
///
/// The prelude is parsed once per process ([`prelude`]); only its types, globals and the
/// POUs that the program names (directly or through other prelude POUs) are checked and
/// compiled, so a small program does not pay for the whole standard library.
pub fn build_sources(sources: &SourceMap) -> Result<Compiled, Vec<Diagnostic>> {
    build_sources_with(sources, CompileOptions::default())
}

/// Like [`build_sources`] with explicit [`CompileOptions`].
pub fn build_sources_with(
    sources: &SourceMap,
    options: CompileOptions,
) -> Result<Compiled, Vec<Diagnostic>> {
    let mut unit = syntax::CompilationUnit::default();
    let mut diags = Vec::new();
    let mut stdlib_items = 0;
    let mut files = sources.files();
    let prepared = prelude::get();
    match files.next() {
        Some((id, file)) if file.text == stdlib::PRELUDE && id == prelude::FILE => {
            let mut user = Vec::new();
            let mut names = std::collections::HashSet::new();
            for (id, file) in files {
                let tokens = syntax::lexer::lex(id, &file.text, &mut diags);
                prelude::collect_names(&tokens, &mut names);
                user.push(tokens);
            }
            unit.items = prepared.items_for(&names);
            unit.node_count = prepared.node_count;
            stdlib_items = unit.items.len();
            for tokens in user {
                syntax::parser::parse_tokens_into(tokens, &mut unit, &mut diags);
            }
        }
        first => {
            for (i, (id, file)) in first.into_iter().chain(files).enumerate() {
                syntax::parser::parse_into(id, &file.text, &mut unit, &mut diags);
                if i == 0 {
                    stdlib_items = unit.items.len();
                }
            }
        }
    }
    if diags.iter().any(Diagnostic::is_error) {
        // still check what the parser recovered, to report more than the first problem;
        // undeclared names are left out (they may come from dropped declarations)
        if let Err(more) = check::check(unit, stdlib_items) {
            diags.extend(more.into_iter().filter(|d| d.code != Code::Undeclared));
        }
        diags.sort_by_key(|d| (d.primary.file, d.primary.start));
        return Err(diags);
    }
    let checked = check::check(unit, stdlib_items)?;
    compile::compile_with(checked, options)
}

/// The standard-library prelude, parsed once per process.
pub mod prelude {
    use crate::syntax::lexer::{lex, Tok, Token};
    use crate::syntax::{parser, CompilationUnit, FileId, Item};
    use std::collections::HashSet;
    use std::sync::OnceLock;

    /// The prelude's file id: it is always the first file of a source map.
    pub const FILE: FileId = FileId(0);

    /// A prelude POU's upper-case name and the names its text mentions.
    type PouNames = (String, Vec<String>);

    /// The parsed prelude with, for every POU, the names its text mentions.
    pub struct Prepared {
        /// Items in source order, each with the upper-case names it mentions (empty for
        /// items that are always included).
        items: Vec<(Item, Option<PouNames>)>,
        /// Node ids used by the prelude (the program's continue from here).
        pub node_count: u32,
    }

    impl Prepared {
        /// Types and globals, plus the POUs named in `names` and, transitively, the
        /// prelude POUs those mention; in prelude order.
        pub fn items_for(&self, names: &HashSet<String>) -> Vec<Item> {
            let mut want: HashSet<&str> = names.iter().map(String::as_str).collect();
            let mut take = vec![false; self.items.len()];
            let mut changed = true;
            while changed {
                changed = false;
                for ((_, pou), t) in self.items.iter().zip(take.iter_mut()) {
                    let needed = match pou {
                        None => true,
                        Some((key, _)) => want.contains(key.as_str()),
                    };
                    if needed && !*t {
                        *t = true;
                        changed = true;
                        if let Some((_, deps)) = pou {
                            want.extend(deps.iter().map(String::as_str));
                        }
                    }
                }
            }
            self.items
                .iter()
                .zip(take)
                .filter(|(_, t)| *t)
                .map(|((item, _), _)| item.clone())
                .collect()
        }
    }

    /// Adds the upper-case spelling of every name-like token (identifiers, `#local` and
    /// `"quoted"` names) to `names`.
    pub fn collect_names(tokens: &[Token], names: &mut HashSet<String>) {
        for t in tokens {
            if let Tok::Ident(n) | Tok::HashIdent(n) | Tok::DqString(n) = &t.tok {
                if !names.contains(n.as_str()) {
                    names.insert(n.to_ascii_uppercase());
                }
            }
        }
    }

    /// The prepared prelude (parsed on first use).
    pub fn get() -> &'static Prepared {
        static PRELUDE: OnceLock<Prepared> = OnceLock::new();
        PRELUDE.get_or_init(prepare)
    }

    fn prepare() -> Prepared {
        let mut diags = Vec::new();
        let tokens = lex(FILE, crate::stdlib::PRELUDE, &mut diags);
        let mut unit = CompilationUnit::default();
        parser::parse_tokens_into(tokens.clone(), &mut unit, &mut diags);
        let items = unit
            .items
            .into_iter()
            .map(|item| {
                let pou = match &item {
                    Item::Pou(p) => {
                        let mut deps = HashSet::new();
                        let inside: Vec<Token> = tokens
                            .iter()
                            .filter(|t| t.span.start >= p.span.start && t.span.end <= p.span.end)
                            .cloned()
                            .collect();
                        collect_names(&inside, &mut deps);
                        deps.remove(&p.name.key);
                        Some((p.name.key.clone(), deps.into_iter().collect()))
                    }
                    _ => None,
                };
                (item, pou)
            })
            .collect();
        Prepared {
            items,
            node_count: unit.node_count,
        }
    }
}
