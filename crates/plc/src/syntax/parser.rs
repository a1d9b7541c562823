//! Recursive-descent parser with error recovery. Never panics; nesting deeper than
//! [`MAX_DEPTH`] is a diagnostic, not a stack overflow.

use super::ast::*;
use super::lexer::{lex, Tok, Token};
use super::source::{FileId, Span};
use crate::diagnostics::{Code, Diagnostic};

/// Maximum nesting of expressions and statements.
pub const MAX_DEPTH: u32 = 64;

/// Maximum depth of an expression tree (nesting plus left-associative operator, member
/// and index chains), so that later recursive stages cannot overflow the stack.
pub const MAX_TREE: u32 = 400;

/// Parses one file, appending nodes to `unit` (node ids continue from `unit.node_count`).
pub fn parse_into(
    file: FileId,
    text: &str,
    unit: &mut CompilationUnit,
    diags: &mut Vec<Diagnostic>,
) {
    let tokens = lex(file, text, diags);
    parse_tokens_into(tokens, unit, diags);
}

/// Parses the tokens of one file (from [`lex`]), appending nodes to `unit`.
pub fn parse_tokens_into(
    tokens: Vec<Token>,
    unit: &mut CompilationUnit,
    diags: &mut Vec<Diagnostic>,
) {
    let mut p = Parser {
        tokens,
        pos: 0,
        next_id: unit.node_count,
        diags,
        depth: 0,
        tree: 0,
    };
    while !p.at_eof() {
        let before = p.pos;
        match p.item() {
            Ok(mut items) => unit.items.append(&mut items),
            Err(()) => p.recover_top(),
        }
        if p.pos == before {
            p.bump();
        }
    }
    unit.node_count = p.next_id;
}

const RESERVED: [&str; 60] = [
    "IF",
    "THEN",
    "ELSIF",
    "ELSE",
    "END_IF",
    "CASE",
    "OF",
    "END_CASE",
    "FOR",
    "TO",
    "BY",
    "DO",
    "END_FOR",
    "WHILE",
    "END_WHILE",
    "REPEAT",
    "UNTIL",
    "END_REPEAT",
    "EXIT",
    "CONTINUE",
    "RETURN",
    "VAR",
    "VAR_INPUT",
    "VAR_OUTPUT",
    "VAR_IN_OUT",
    "VAR_TEMP",
    "VAR_GLOBAL",
    "VAR_EXTERNAL",
    "END_VAR",
    "PROGRAM",
    "END_PROGRAM",
    "FUNCTION",
    "END_FUNCTION",
    "FUNCTION_BLOCK",
    "END_FUNCTION_BLOCK",
    "TYPE",
    "END_TYPE",
    "STRUCT",
    "END_STRUCT",
    "ARRAY",
    "AND",
    "OR",
    "XOR",
    "NOT",
    "MOD",
    "AT",
    "CONSTANT",
    "RETAIN",
    "BEGIN",
    "END_REGION",
    "REGION",
    "VAR_STAT",
    "PERSISTENT",
    "NON_RETAIN",
    "CONFIGURATION",
    "END_CONFIGURATION",
    "RESOURCE",
    "END_RESOURCE",
    "TASK",
    "WITH",
];

struct Parser<'d> {
    tokens: Vec<Token>,
    pos: usize,
    next_id: u32,
    diags: &'d mut Vec<Diagnostic>,
    depth: u32,
    /// Extra tree depth of open left-associative chains.
    tree: u32,
}

type PResult<T> = Result<T, ()>;

fn describe(t: &Tok) -> String {
    match t {
        Tok::Ident(s) => format!("'{s}'"),
        Tok::HashIdent(s) => format!("'#{s}'"),
        Tok::DqString(s) => format!("\"{s}\""),
        Tok::SqString(s) => format!("'{s}'"),
        Tok::Int(v) => v.to_string(),
        Tok::Real(v) => v.to_string(),
        Tok::TypePrefix(s) => format!("{s}#"),
        Tok::Time(..) => "time literal".into(),
        Tok::Date(_) | Tok::Tod(_) | Tok::Dt(_) => "date literal".into(),
        Tok::Direct(s) => format!("%{s}"),
        Tok::Punct(p) => format!("'{p}'"),
        Tok::Eof => "end of file".into(),
    }
}

impl Parser<'_> {
    fn tok(&self) -> &Tok {
        self.tokens
            .get(self.pos)
            .map(|t| &t.tok)
            .unwrap_or(&Tok::Eof)
    }
    fn tok_at(&self, k: usize) -> &Tok {
        self.tokens
            .get(self.pos + k)
            .map(|t| &t.tok)
            .unwrap_or(&Tok::Eof)
    }
    fn span(&self) -> Span {
        self.tokens
            .get(self.pos)
            .or_else(|| self.tokens.last())
            .map(|t| t.span)
            .unwrap_or_default()
    }
    fn prev_span(&self) -> Span {
        self.tokens
            .get(self.pos.saturating_sub(1))
            .map(|t| t.span)
            .unwrap_or_default()
    }
    fn at_eof(&self) -> bool {
        matches!(self.tok(), Tok::Eof)
    }
    fn bump(&mut self) {
        if self.pos < self.tokens.len() {
            self.pos += 1;
        }
    }
    fn id(&mut self) -> NodeId {
        let id = NodeId(self.next_id);
        self.next_id = self.next_id.saturating_add(1);
        id
    }
    fn is_kw(&self, kw: &str) -> bool {
        matches!(self.tok(), Tok::Ident(s) if s.eq_ignore_ascii_case(kw))
    }
    fn eat_kw(&mut self, kw: &str) -> bool {
        if self.is_kw(kw) {
            self.bump();
            true
        } else {
            false
        }
    }
    fn is_p(&self, p: &str) -> bool {
        matches!(self.tok(), Tok::Punct(q) if *q == p)
    }
    fn eat_p(&mut self, p: &str) -> bool {
        if self.is_p(p) {
            self.bump();
            true
        } else {
            false
        }
    }
    fn error<T>(&mut self, msg: impl Into<String>) -> PResult<T> {
        let span = self.span();
        self.diags.push(Diagnostic::error(Code::Syntax, span, msg));
        Err(())
    }
    fn expected<T>(&mut self, what: &str) -> PResult<T> {
        let found = describe(self.tok());
        self.error(format!("expected {what}, found {found}"))
    }
    fn expect_p(&mut self, p: &str) -> PResult<()> {
        if self.eat_p(p) {
            Ok(())
        } else {
            self.expected(&format!("'{p}'"))
        }
    }
    /// A `;` that ends a statement or declaration. When it is missing the error points
    /// at the end of what lacks it, not at the next token (often on the next line):
    /// that is where the `;` goes.
    fn expect_semicolon(&mut self, what: &str) -> PResult<()> {
        if self.eat_p(";") {
            return Ok(());
        }
        let found = describe(self.tok());
        let previous = self.prev_span();
        let next = self.span();
        // A character the lexer refused between the two is the real mistake, and is
        // reported already.
        let explained = self.diags.iter().any(|d| {
            d.primary.file == previous.file
                && (previous.end..=next.start).contains(&d.primary.start)
        });
        if explained {
            return Err(());
        }
        let at = Span {
            start: previous.end,
            ..previous
        };
        self.diags.push(Diagnostic::error(
            Code::Syntax,
            at,
            format!("expected ';' at the end of this {what}, found {found} after it"),
        ));
        Err(())
    }
    fn expect_kw(&mut self, kw: &str) -> PResult<()> {
        if self.eat_kw(kw) {
            Ok(())
        } else {
            self.expected(kw)
        }
    }
    fn ident(&mut self) -> PResult<Ident> {
        let span = self.span();
        match self.tok().clone() {
            Tok::Ident(s) if !RESERVED.contains(&s.to_ascii_uppercase().as_str()) => {
                self.bump();
                Ok(Ident::new(s, span))
            }
            Tok::DqString(s) | Tok::HashIdent(s) => {
                self.bump();
                Ok(Ident::new(s, span))
            }
            _ => self.expected("a name"),
        }
    }

    fn recover_top(&mut self) {
        while !self.at_eof() {
            if [
                "PROGRAM",
                "FUNCTION",
                "FUNCTION_BLOCK",
                "TYPE",
                "VAR_GLOBAL",
            ]
            .iter()
            .any(|k| self.is_kw(k))
            {
                return;
            }
            self.bump();
        }
    }

    // ---------------------------------------------------------------- items

    fn item(&mut self) -> PResult<Vec<Item>> {
        if self.eat_kw("PROGRAM") {
            Ok(vec![Item::Pou(self.pou(PouKind::Program, "END_PROGRAM")?)])
        } else if self.eat_kw("FUNCTION_BLOCK") {
            Ok(vec![Item::Pou(
                self.pou(PouKind::FunctionBlock, "END_FUNCTION_BLOCK")?,
            )])
        } else if self.eat_kw("FUNCTION") {
            Ok(vec![Item::Pou(
                self.pou(PouKind::Function, "END_FUNCTION")?,
            )])
        } else if self.eat_kw("TYPE") {
            let mut decls = Vec::new();
            while !self.is_kw("END_TYPE") && !self.at_eof() {
                let name = self.ident()?;
                self.expect_p(":")?;
                let ty = self.type_ref(true)?;
                let init = if self.eat_p(":=") {
                    Some(self.init()?)
                } else {
                    None
                };
                self.eat_p(";");
                decls.push(TypeDecl { name, ty, init });
            }
            self.expect_kw("END_TYPE")?;
            Ok(vec![Item::Types(decls)])
        } else if self.is_kw("VAR_GLOBAL") {
            let block = self.var_block()?;
            Ok(vec![Item::Globals(block)])
        } else if self.eat_kw("CONFIGURATION") {
            let _ = self.ident()?;
            let mut items = Vec::new();
            while !self.at_eof() && !self.is_kw("END_CONFIGURATION") {
                if self.is_kw("VAR_GLOBAL") {
                    items.push(Item::Globals(self.var_block()?));
                } else if self.eat_kw("RESOURCE") {
                    items.extend(self.resource()?);
                } else {
                    let before = self.pos;
                    items.extend(self.config_entry()?);
                    if self.pos == before {
                        return self.expected("VAR_GLOBAL, RESOURCE, TASK or PROGRAM");
                    }
                }
            }
            self.expect_kw("END_CONFIGURATION")?;
            Ok(items)
        } else if self.eat_kw("RESOURCE") {
            self.resource()
        } else {
            self.expected("PROGRAM, FUNCTION_BLOCK, FUNCTION, TYPE or VAR_GLOBAL")
        }
    }

    /// After RESOURCE: `name ON processor ... END_RESOURCE`.
    fn resource(&mut self) -> PResult<Vec<Item>> {
        let _ = self.ident()?;
        if self.eat_kw("ON") {
            let _ = self.ident()?;
        }
        let mut items = Vec::new();
        while !self.at_eof() && !self.is_kw("END_RESOURCE") {
            if self.is_kw("VAR_GLOBAL") {
                items.push(Item::Globals(self.var_block()?));
            } else {
                let before = self.pos;
                items.extend(self.config_entry()?);
                if self.pos == before {
                    return self.expected("VAR_GLOBAL, TASK or PROGRAM");
                }
            }
        }
        self.expect_kw("END_RESOURCE")?;
        Ok(items)
    }

    /// `TASK name (INTERVAL := T#10ms, PRIORITY := 1);` or
    /// `PROGRAM inst WITH task : Type;`
    fn config_entry(&mut self) -> PResult<Vec<Item>> {
        let start = self.span();
        if self.eat_kw("TASK") {
            let name = self.ident()?;
            let mut interval = None;
            let mut priority = None;
            if self.eat_p("(") {
                loop {
                    let key = self.ident()?;
                    self.expect_p(":=")?;
                    let v = self.expr()?;
                    match key.key.as_str() {
                        "INTERVAL" => interval = Some(v),
                        "PRIORITY" => priority = Some(v),
                        _ => {}
                    }
                    if !self.eat_p(",") {
                        break;
                    }
                }
                self.expect_p(")")?;
            }
            self.expect_semicolon("declaration")?;
            return Ok(vec![Item::Task(TaskDecl {
                name,
                interval,
                priority,
                span: start.to(self.prev_span()),
            })]);
        }
        if self.eat_kw("PROGRAM") {
            let instance = self.ident()?;
            let task = if self.eat_kw("WITH") {
                Some(self.ident()?)
            } else {
                None
            };
            self.expect_p(":")?;
            let program = self.ident()?;
            if self.eat_p("(") {
                // parameter connections are not supported; skip them
                let mut depth = 1;
                while depth > 0 && !self.at_eof() {
                    if self.is_p("(") {
                        depth += 1;
                    } else if self.is_p(")") {
                        depth -= 1;
                    }
                    self.bump();
                }
            }
            self.expect_semicolon("declaration")?;
            return Ok(vec![Item::ProgramConfig(ProgramConfig {
                instance,
                task,
                program,
                span: start.to(self.prev_span()),
            })]);
        }
        Ok(Vec::new())
    }

    fn pou(&mut self, kind: PouKind, end: &str) -> PResult<Pou> {
        let start = self.prev_span();
        let name = self.ident()?;
        let return_type = if kind == PouKind::Function && self.eat_p(":") {
            Some(self.type_ref(false)?)
        } else {
            None
        };
        // SCL: TITLE = ..., VERSION : 0.1, AUTHOR : ...
        loop {
            if self.is_kw("VERSION")
                || self.is_kw("AUTHOR")
                || self.is_kw("FAMILY")
                || self.is_kw("NAME")
            {
                self.bump();
                self.eat_p(":");
                self.bump();
            } else if self.is_kw("TITLE") {
                self.bump();
                self.eat_p("=");
                while !self.at_eof() && !self.is_var_kw() && !self.is_kw("BEGIN") {
                    let line = self.span();
                    self.bump();
                    if self.span().start > line.end + 1 {
                        break;
                    }
                }
            } else {
                break;
            }
        }
        let mut vars = Vec::new();
        while self.is_var_kw() {
            match self.var_block() {
                Ok(b) => vars.push(b),
                Err(()) => {
                    while !self.at_eof() && !self.is_kw("END_VAR") {
                        self.bump();
                    }
                    self.eat_kw("END_VAR");
                }
            }
        }
        self.eat_kw("BEGIN");
        let body = self.stmts(&[end])?;
        self.expect_kw(end)?;
        Ok(Pou {
            kind,
            name,
            return_type,
            vars,
            body,
            span: start.to(self.prev_span()),
        })
    }

    fn is_var_kw(&self) -> bool {
        [
            "VAR",
            "VAR_INPUT",
            "VAR_OUTPUT",
            "VAR_IN_OUT",
            "VAR_TEMP",
            "VAR_GLOBAL",
            "VAR_EXTERNAL",
            "VAR_STAT",
        ]
        .iter()
        .any(|k| self.is_kw(k))
    }

    fn var_block(&mut self) -> PResult<VarBlock> {
        let span = self.span();
        let kind = match self.tok() {
            Tok::Ident(s) => match s.to_ascii_uppercase().as_str() {
                "VAR" => VarKind::Local,
                "VAR_INPUT" => VarKind::Input,
                "VAR_OUTPUT" => VarKind::Output,
                "VAR_IN_OUT" => VarKind::InOut,
                "VAR_TEMP" => VarKind::Temp,
                "VAR_GLOBAL" => VarKind::Global,
                "VAR_EXTERNAL" => VarKind::External,
                "VAR_STAT" => VarKind::Static,
                _ => return self.expected("VAR"),
            },
            _ => return self.expected("VAR"),
        };
        self.bump();
        let (mut constant, mut retain, mut persistent) = (false, false, false);
        loop {
            if self.eat_kw("CONSTANT") {
                constant = true;
            } else if self.eat_kw("RETAIN") {
                retain = true;
            } else if self.eat_kw("PERSISTENT") {
                persistent = true;
            } else if self.eat_kw("NON_RETAIN") {
            } else {
                break;
            }
        }
        let mut decls = Vec::new();
        while !self.is_kw("END_VAR") && !self.at_eof() {
            match self.var_decl() {
                Ok(d) => decls.push(d),
                Err(()) => {
                    while !self.at_eof() && !self.is_p(";") && !self.is_kw("END_VAR") {
                        self.bump();
                    }
                    self.eat_p(";");
                }
            }
        }
        self.expect_kw("END_VAR")?;
        Ok(VarBlock {
            kind,
            constant,
            retain,
            persistent,
            decls,
            span,
        })
    }

    fn var_decl(&mut self) -> PResult<VarDecl> {
        let start = self.span();
        let mut names = vec![self.ident()?];
        while self.eat_p(",") {
            names.push(self.ident()?);
        }
        let at = if self.eat_kw("AT") {
            let span = self.span();
            match self.tok().clone() {
                Tok::Direct(d) => {
                    self.bump();
                    Some((d, span))
                }
                _ => return self.expected("a direct address like %IX0.0"),
            }
        } else {
            None
        };
        self.expect_p(":")?;
        let ty = self.type_ref(false)?;
        let init = if self.eat_p(":=") {
            Some(self.init()?)
        } else {
            None
        };
        let span = start.to(self.prev_span());
        self.expect_semicolon("declaration")?;
        Ok(VarDecl {
            names,
            at,
            ty,
            init,
            span,
        })
    }

    fn init(&mut self) -> PResult<Init> {
        let start = self.span();
        if self.eat_p("[") {
            let mut items = Vec::new();
            if !self.is_p("]") {
                loop {
                    // n(value) repetition
                    if matches!(self.tok(), Tok::Int(_))
                        && matches!(self.tok_at(1), Tok::Punct("("))
                    {
                        let count = self.expr()?;
                        self.expect_p("(")?;
                        let v = if self.is_p(")") {
                            None
                        } else {
                            Some(self.init()?)
                        };
                        self.expect_p(")")?;
                        let v = v.unwrap_or_else(|| Init::Default(self.prev_span()));
                        items.push((Some(count), v));
                    } else {
                        items.push((None, self.init()?));
                    }
                    if !self.eat_p(",") {
                        break;
                    }
                }
            }
            self.expect_p("]")?;
            return Ok(Init::Array(items, start.to(self.prev_span())));
        }
        if self.is_p("(")
            && matches!(self.tok_at(1), Tok::Ident(_))
            && matches!(self.tok_at(2), Tok::Punct(":="))
        {
            self.bump();
            let mut fields = Vec::new();
            loop {
                let name = self.ident()?;
                self.expect_p(":=")?;
                fields.push((name, self.init()?));
                if !self.eat_p(",") {
                    break;
                }
            }
            self.expect_p(")")?;
            return Ok(Init::Struct(fields, start.to(self.prev_span())));
        }
        Ok(Init::Expr(self.expr()?))
    }

    fn type_ref(&mut self, in_type_decl: bool) -> PResult<TypeRef> {
        let start = self.span();
        if self.eat_kw("REF_TO") {
            let target = self.type_ref(false)?;
            return Ok(TypeRef::Ref(Box::new(target), start.to(self.prev_span())));
        }
        if self.eat_kw("ARRAY") {
            self.expect_p("[")?;
            let mut dims = Vec::new();
            loop {
                let lo = self.expr()?;
                self.expect_p("..")?;
                let hi = self.expr()?;
                dims.push((lo, hi));
                if !self.eat_p(",") {
                    break;
                }
            }
            self.expect_p("]")?;
            self.expect_kw("OF")?;
            let elem = self.type_ref(false)?;
            return Ok(TypeRef::Array {
                dims,
                elem: Box::new(elem),
                span: start.to(self.prev_span()),
            });
        }
        if self.eat_kw("STRUCT") {
            let mut fields = Vec::new();
            while !self.is_kw("END_STRUCT") && !self.at_eof() {
                fields.push(self.var_decl()?);
            }
            self.expect_kw("END_STRUCT")?;
            return Ok(TypeRef::Struct(fields, start.to(self.prev_span())));
        }
        if self.is_p("(") {
            self.bump();
            let mut values = Vec::new();
            loop {
                let name = self.ident()?;
                let v = if self.eat_p(":=") {
                    Some(self.expr()?)
                } else {
                    None
                };
                values.push((name, v));
                if !self.eat_p(",") {
                    break;
                }
            }
            self.expect_p(")")?;
            let _ = in_type_decl;
            return Ok(TypeRef::Enum(values, start.to(self.prev_span())));
        }
        if self.is_kw("STRING") || self.is_kw("WSTRING") {
            let wide = self.is_kw("WSTRING");
            self.bump();
            let len = if self.eat_p("[") {
                let e = self.expr()?;
                self.expect_p("]")?;
                Some(e)
            } else if self.eat_p("(") {
                let e = self.expr()?;
                self.expect_p(")")?;
                Some(e)
            } else {
                None
            };
            return Ok(TypeRef::String {
                wide,
                len,
                span: start.to(self.prev_span()),
            });
        }
        let name = self.ident()?;
        if self.is_p("(") {
            // subrange INT (0..100)  or  enum with base type  INT (A := 1, B := 2)
            if matches!(self.tok_at(1), Tok::Ident(_)) {
                if let TypeRef::Enum(values, span) = self.type_ref(in_type_decl)? {
                    return Ok(TypeRef::Enum(values, span));
                }
            }
            self.bump();
            let lo = self.expr()?;
            self.expect_p("..")?;
            let hi = self.expr()?;
            self.expect_p(")")?;
            return Ok(TypeRef::Subrange { base: name, lo, hi });
        }
        Ok(TypeRef::Named(name))
    }

    // ---------------------------------------------------------------- statements

    fn at_any_kw(&self, ends: &[&str]) -> bool {
        ends.iter().any(|k| self.is_kw(k))
    }

    fn stmts(&mut self, ends: &[&str]) -> PResult<Vec<Stmt>> {
        let mut out = Vec::new();
        while !self.at_eof() && !self.at_any_kw(ends) && !self.at_block_end() {
            let before = self.pos;
            match self.stmt() {
                Ok(s) => out.push(s),
                Err(()) => {
                    // recover: skip to the next ';' or block keyword
                    while !self.at_eof() && !self.is_p(";") && !self.at_any_kw(ends) {
                        if self.pos != before
                            && ["IF", "FOR", "WHILE", "REPEAT", "CASE"]
                                .iter()
                                .any(|k| self.is_kw(k))
                        {
                            break;
                        }
                        self.bump();
                    }
                    self.eat_p(";");
                }
            }
            if self.pos == before {
                self.bump();
            }
        }
        Ok(out)
    }

    /// A keyword that closes some block and can never start a statement.
    fn at_block_end(&self) -> bool {
        matches!(self.tok(), Tok::Ident(s) if {
            let u = s.to_ascii_uppercase();
            u.starts_with("END_") || u == "ELSE" || u == "ELSIF" || u == "UNTIL"
        })
    }

    fn enter(&mut self) -> PResult<()> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            self.depth -= 1;
            return self.error("nesting too deep");
        }
        Ok(())
    }

    fn stmt(&mut self) -> PResult<Stmt> {
        self.enter()?;
        let r = self.stmt_inner();
        self.depth -= 1;
        r
    }

    fn stmt_inner(&mut self) -> PResult<Stmt> {
        let start = self.span();
        let kind = if self.eat_p(";") {
            return Ok(Stmt {
                kind: StmtKind::Empty,
                span: start,
            });
        } else if self.eat_kw("REGION") {
            // SCL REGION name ... END_REGION: transparent
            while !self.at_eof() && self.span().start <= start.end + 200 && !self.is_stmt_start() {
                self.bump();
            }
            let body = self.stmts(&["END_REGION"])?;
            self.expect_kw("END_REGION")?;
            StmtKind::If(
                vec![(
                    Expr {
                        id: self.id(),
                        kind: ExprKind::Literal(Literal::Bool(true)),
                        span: start,
                    },
                    body,
                )],
                None,
            )
        } else if self.eat_kw("IF") {
            let mut arms = Vec::new();
            let c = self.expr()?;
            self.expect_kw("THEN")?;
            let b = self.stmts(&["ELSIF", "ELSE", "END_IF"])?;
            arms.push((c, b));
            let mut els = None;
            loop {
                if self.eat_kw("ELSIF") {
                    let c = self.expr()?;
                    self.expect_kw("THEN")?;
                    let b = self.stmts(&["ELSIF", "ELSE", "END_IF"])?;
                    arms.push((c, b));
                } else if self.eat_kw("ELSE") {
                    els = Some(self.stmts(&["END_IF"])?);
                } else {
                    break;
                }
            }
            self.expect_kw("END_IF")?;
            StmtKind::If(arms, els)
        } else if self.eat_kw("CASE") {
            let sel = self.expr()?;
            self.expect_kw("OF")?;
            let mut arms = Vec::new();
            let mut els = None;
            while !self.at_eof() && !self.is_kw("END_CASE") {
                if self.eat_kw("ELSE") {
                    els = Some(self.stmts(&["END_CASE"])?);
                    break;
                }
                let mut labels = Vec::new();
                loop {
                    let a = self.expr()?;
                    if self.eat_p("..") {
                        let b = self.expr()?;
                        labels.push(CaseLabel::Range(a, b));
                    } else {
                        labels.push(CaseLabel::Value(a));
                    }
                    if !self.eat_p(",") {
                        break;
                    }
                }
                self.expect_p(":")?;
                let body = self.case_body()?;
                arms.push((labels, body));
            }
            self.expect_kw("END_CASE")?;
            StmtKind::Case(sel, arms, els)
        } else if self.eat_kw("FOR") {
            let var = self.primary_path()?;
            self.expect_p(":=")?;
            let from = self.expr()?;
            self.expect_kw("TO")?;
            let to = self.expr()?;
            let by = if self.eat_kw("BY") {
                Some(self.expr()?)
            } else {
                None
            };
            self.expect_kw("DO")?;
            let body = self.stmts(&["END_FOR"])?;
            self.expect_kw("END_FOR")?;
            StmtKind::For {
                var,
                from,
                to,
                by,
                body,
            }
        } else if self.eat_kw("WHILE") {
            let c = self.expr()?;
            self.expect_kw("DO")?;
            let body = self.stmts(&["END_WHILE"])?;
            self.expect_kw("END_WHILE")?;
            StmtKind::While(c, body)
        } else if self.eat_kw("REPEAT") {
            let body = self.stmts(&["UNTIL"])?;
            self.expect_kw("UNTIL")?;
            let c = self.expr()?;
            self.expect_kw("END_REPEAT")?;
            StmtKind::Repeat(body, c)
        } else if self.eat_kw("EXIT") {
            StmtKind::Exit
        } else if self.eat_kw("CONTINUE") {
            StmtKind::Continue
        } else if self.eat_kw("RETURN") {
            StmtKind::Return
        } else {
            let target = self.expr()?;
            if self.eat_p(":=") {
                let value = self.expr()?;
                StmtKind::Assign(target, value)
            } else if matches!(target.kind, ExprKind::Call(..)) {
                StmtKind::Call(target)
            } else {
                return self.expected("':=' or a call");
            }
        };
        let span = start.to(self.prev_span());
        if !matches!(
            kind,
            StmtKind::Assign(..)
                | StmtKind::Call(_)
                | StmtKind::Exit
                | StmtKind::Continue
                | StmtKind::Return
        ) {
            self.eat_p(";");
        } else {
            self.expect_semicolon("statement")?;
        }
        Ok(Stmt { kind, span })
    }

    fn is_stmt_start(&self) -> bool {
        [
            "IF", "CASE", "FOR", "WHILE", "REPEAT", "EXIT", "RETURN", "CONTINUE",
        ]
        .iter()
        .any(|k| self.is_kw(k))
            || matches!(self.tok(), Tok::HashIdent(_) | Tok::DqString(_))
            || (matches!(self.tok(), Tok::Ident(_))
                && matches!(self.tok_at(1), Tok::Punct(":=" | "." | "[" | "(")))
    }

    /// Statements of a CASE arm: up to the next label (`expr :` / `expr ,` / `a..b :`), ELSE
    /// or END_CASE.
    fn case_body(&mut self) -> PResult<Vec<Stmt>> {
        let mut out = Vec::new();
        while !self.at_eof() && !self.is_kw("END_CASE") && !self.is_kw("ELSE") {
            if self.looks_like_case_label() {
                break;
            }
            let before = self.pos;
            match self.stmt() {
                Ok(s) => out.push(s),
                Err(()) => {
                    while !self.at_eof() && !self.is_p(";") && !self.is_kw("END_CASE") {
                        self.bump();
                    }
                    self.eat_p(";");
                }
            }
            if self.pos == before {
                self.bump();
            }
        }
        Ok(out)
    }

    fn looks_like_case_label(&self) -> bool {
        // scan a simple label: [-] literal/name/Type#Value (, ...)* (.. ...)? ':' but not ':='
        let mut k = 0;
        loop {
            if matches!(self.tok_at(k), Tok::Punct("-" | "+")) {
                k += 1;
            }
            match self.tok_at(k) {
                Tok::Int(_) | Tok::SqString(_) => k += 1,
                Tok::TypePrefix(_) => {
                    k += 1;
                    if matches!(self.tok_at(k), Tok::Punct("-")) {
                        k += 1;
                    }
                    k += 1;
                }
                Tok::Ident(s) if !RESERVED.contains(&s.to_ascii_uppercase().as_str()) => {
                    k += 1;
                    if matches!(self.tok_at(k), Tok::Punct("#")) {
                        k += 2;
                    }
                    // Type#Value lexes as Ident, then '#'? No: '#' is not a punct; the
                    // lexer produces HashIdent for `#Value`.
                    if matches!(self.tok_at(k), Tok::HashIdent(_)) {
                        k += 1;
                    }
                }
                Tok::HashIdent(_) | Tok::DqString(_) => k += 1,
                _ => return false,
            }
            match self.tok_at(k) {
                Tok::Punct(",") | Tok::Punct("..") => k += 1,
                Tok::Punct(":") => return true,
                _ => return false,
            }
        }
    }

    // ---------------------------------------------------------------- expressions

    fn expr(&mut self) -> PResult<Expr> {
        self.enter()?;
        let r = self.binary(0);
        self.depth -= 1;
        r
    }

    fn binop(&self) -> Option<(BinOp, u8)> {
        // precedence: OR 1, XOR 2, AND 3, = <> 4, < > <= >= 5, + - 6, * / MOD 7, ** 8
        Some(match self.tok() {
            Tok::Ident(s) => match s.to_ascii_uppercase().as_str() {
                "OR" => (BinOp::Or, 1),
                "XOR" => (BinOp::Xor, 2),
                "AND" => (BinOp::And, 3),
                "MOD" => (BinOp::Mod, 7),
                _ => return None,
            },
            Tok::Punct(p) => match *p {
                "&" => (BinOp::And, 3),
                "=" => (BinOp::Eq, 4),
                "<>" => (BinOp::Ne, 4),
                "<" => (BinOp::Lt, 5),
                ">" => (BinOp::Gt, 5),
                "<=" => (BinOp::Le, 5),
                ">=" => (BinOp::Ge, 5),
                "+" => (BinOp::Add, 6),
                "-" => (BinOp::Sub, 6),
                "*" => (BinOp::Mul, 7),
                "/" => (BinOp::Div, 7),
                "**" => (BinOp::Pow, 8),
                _ => return None,
            },
            _ => return None,
        })
    }

    fn binary(&mut self, min: u8) -> PResult<Expr> {
        let mut lhs = self.unary()?;
        let mut chain = 0u32;
        let r = self.binary_chain(&mut lhs, min, &mut chain);
        self.tree -= chain;
        r.map(|()| lhs)
    }

    /// One more level of a left-deep tree.
    fn grow(&mut self, chain: &mut u32) -> PResult<()> {
        *chain += 1;
        self.tree += 1;
        if self.tree + self.depth > MAX_TREE {
            return self.error(
                "expression too long or too deeply nested; split it with intermediate variables",
            );
        }
        Ok(())
    }

    fn binary_chain(&mut self, lhs: &mut Expr, min: u8, chain: &mut u32) -> PResult<()> {
        while let Some((op, prec)) = self.binop() {
            if prec < min {
                break;
            }
            self.grow(chain)?;
            self.bump();
            // all binary operators are left-associative in IEC 61131-3 (** included)
            self.enter()?;
            let rhs = self.binary(prec + 1);
            self.depth -= 1;
            let rhs = rhs?;
            let span = lhs.span.to(rhs.span);
            let left = std::mem::replace(
                lhs,
                Expr {
                    id: NodeId(0),
                    kind: ExprKind::Literal(Literal::Bool(false)),
                    span,
                },
            );
            *lhs = Expr {
                id: self.id(),
                kind: ExprKind::Binary(op, Box::new(left), Box::new(rhs)),
                span,
            };
        }
        Ok(())
    }

    fn unary(&mut self) -> PResult<Expr> {
        let start = self.span();
        let op = if self.eat_p("-") {
            Some(UnOp::Neg)
        } else if self.eat_p("+") {
            Some(UnOp::Plus)
        } else if self.eat_kw("NOT") {
            Some(UnOp::Not)
        } else {
            None
        };
        match op {
            Some(op) => {
                self.enter()?;
                // NOT binds tighter than comparisons but looser than **: parse a power operand
                let inner = self.unary_operand();
                self.depth -= 1;
                let inner = inner?;
                // fold -literal into the literal
                if op == UnOp::Neg {
                    if let ExprKind::Literal(Literal::Int(v, None)) = &inner.kind {
                        return Ok(Expr {
                            id: inner.id,
                            kind: ExprKind::Literal(Literal::Int(-*v, None)),
                            span: start.to(inner.span),
                        });
                    }
                    if let ExprKind::Literal(Literal::Real(v, None)) = &inner.kind {
                        return Ok(Expr {
                            id: inner.id,
                            kind: ExprKind::Literal(Literal::Real(-*v, None)),
                            span: start.to(inner.span),
                        });
                    }
                }
                let span = start.to(inner.span);
                Ok(Expr {
                    id: self.id(),
                    kind: ExprKind::Unary(op, Box::new(inner)),
                    span,
                })
            }
            None => self.unary_operand(),
        }
    }

    /// Operand of a unary operator: a postfix expression followed by any `**` chain.
    fn unary_operand(&mut self) -> PResult<Expr> {
        if self.is_p("-") || self.is_p("+") || self.is_kw("NOT") {
            return self.unary();
        }
        let mut lhs = self.postfix()?;
        let mut chain = 0u32;
        while self.is_p("**") {
            if let Err(()) = self.grow(&mut chain) {
                self.tree -= chain;
                return Err(());
            }
            self.bump();
            let rhs = self.postfix_or_unary()?;
            let span = lhs.span.to(rhs.span);
            lhs = Expr {
                id: self.id(),
                kind: ExprKind::Binary(BinOp::Pow, Box::new(lhs), Box::new(rhs)),
                span,
            };
        }
        self.tree -= chain;
        Ok(lhs)
    }

    fn postfix_or_unary(&mut self) -> PResult<Expr> {
        if self.is_p("-") || self.is_p("+") || self.is_kw("NOT") {
            self.enter()?;
            let r = self.unary();
            self.depth -= 1;
            r
        } else {
            self.postfix()
        }
    }

    /// A variable path (for FOR control variables).
    fn primary_path(&mut self) -> PResult<Expr> {
        self.postfix()
    }

    fn postfix(&mut self) -> PResult<Expr> {
        let e = self.primary()?;
        let mut chain = 0u32;
        let r = self.postfix_chain(e, &mut chain);
        self.tree -= chain;
        r
    }

    fn postfix_chain(&mut self, mut e: Expr, chain: &mut u32) -> PResult<Expr> {
        loop {
            if self.is_p(".") || self.is_p("[") || self.is_p("^") || self.is_p("(") {
                self.grow(chain)?;
            }
            if self.is_p(".") {
                self.bump();
                let span = self.span();
                match self.tok().clone() {
                    Tok::Direct(d)
                        if d.starts_with('X') || d.chars().all(|c| c.is_ascii_digit()) =>
                    {
                        self.bump();
                        let bit: u32 = d.trim_start_matches('X').parse().unwrap_or(0);
                        let s = e.span.to(span);
                        e = Expr {
                            id: self.id(),
                            kind: ExprKind::Bit(Box::new(e), bit),
                            span: s,
                        };
                    }
                    Tok::Int(v) => {
                        self.bump();
                        let s = e.span.to(span);
                        e = Expr {
                            id: self.id(),
                            kind: ExprKind::Bit(Box::new(e), u32::try_from(v).unwrap_or(u32::MAX)),
                            span: s,
                        };
                    }
                    Tok::Direct(d) if partial_access(&d).is_some() => {
                        self.bump();
                        let ((width, index), bit) = partial_access(&d).unwrap_or(((8, 0), None));
                        let s = e.span.to(span);
                        e = Expr {
                            id: self.id(),
                            kind: ExprKind::Part(Box::new(e), width, index),
                            span: s,
                        };
                        // `%B1.1`: the lexer keeps a dot before a digit in the address
                        // (`%IX0.3`), so a bare bit index after a part comes in the same
                        // token (RuSTy's `d.%D1.%W1.%B1.1`).
                        if let Some(bit) = bit {
                            e = Expr {
                                id: self.id(),
                                kind: ExprKind::Bit(Box::new(e), bit),
                                span: s,
                            };
                        }
                    }
                    _ => {
                        let name = self.ident()?;
                        let s = e.span.to(name.span);
                        e = Expr {
                            id: self.id(),
                            kind: ExprKind::Member(Box::new(e), name),
                            span: s,
                        };
                    }
                }
            } else if self.is_p("[") {
                self.bump();
                let mut idx = vec![self.expr()?];
                while self.eat_p(",") {
                    idx.push(self.expr()?);
                }
                self.expect_p("]")?;
                let s = e.span.to(self.prev_span());
                e = Expr {
                    id: self.id(),
                    kind: ExprKind::Index(Box::new(e), idx),
                    span: s,
                };
            } else if self.is_p("^") {
                self.bump();
                let s = e.span.to(self.prev_span());
                e = Expr {
                    id: self.id(),
                    kind: ExprKind::Deref(Box::new(e)),
                    span: s,
                };
            } else if self.is_p("(")
                && matches!(
                    e.kind,
                    ExprKind::Name { .. }
                        | ExprKind::Member(..)
                        | ExprKind::Index(..)
                        | ExprKind::Deref(_)
                )
            {
                self.bump();
                let args = self.args()?;
                let s = e.span.to(self.prev_span());
                e = Expr {
                    id: self.id(),
                    kind: ExprKind::Call(Box::new(e), args),
                    span: s,
                };
            } else {
                return Ok(e);
            }
        }
    }

    fn args(&mut self) -> PResult<Vec<Arg>> {
        let mut args = Vec::new();
        if self.eat_p(")") {
            return Ok(args);
        }
        loop {
            let negated = self.is_kw("NOT")
                && matches!(self.tok_at(1), Tok::Ident(_) | Tok::HashIdent(_))
                && matches!(self.tok_at(2), Tok::Punct("=>"));
            if negated {
                self.bump();
            }
            let named = matches!(
                self.tok(),
                Tok::Ident(_) | Tok::HashIdent(_) | Tok::DqString(_)
            ) && matches!(self.tok_at(1), Tok::Punct(":=" | "=>"));
            if named {
                let name = self.ident()?;
                let output = self.is_p("=>");
                self.bump();
                if output && (self.is_p(",") || self.is_p(")")) {
                    // `Q =>` with nothing bound: nothing to do
                } else {
                    let value = self.expr()?;
                    args.push(Arg {
                        name: Some(name),
                        output,
                        negated,
                        value,
                    });
                }
            } else {
                let value = self.expr()?;
                args.push(Arg {
                    name: None,
                    output: false,
                    negated: false,
                    value,
                });
            }
            if !self.eat_p(",") {
                break;
            }
        }
        self.expect_p(")")?;
        Ok(args)
    }

    fn primary(&mut self) -> PResult<Expr> {
        let span = self.span();
        let lit = |p: &mut Self, l: Literal| {
            p.bump();
            Ok(Expr {
                id: p.id(),
                kind: ExprKind::Literal(l),
                span,
            })
        };
        match self.tok().clone() {
            Tok::Int(v) => lit(
                self,
                Literal::Int(i128::try_from(v).unwrap_or(i128::MAX), None),
            ),
            Tok::Real(v) => lit(self, Literal::Real(v, None)),
            Tok::SqString(s) => lit(self, Literal::String(s, false)),
            Tok::Time(ns, long) => lit(self, Literal::Time(ns, long)),
            Tok::Date(v) => lit(self, Literal::Date(v)),
            Tok::Tod(v) => lit(self, Literal::Tod(v)),
            Tok::Dt(v) => lit(self, Literal::Dt(v)),
            Tok::Direct(d) => {
                self.bump();
                Ok(Expr {
                    id: self.id(),
                    kind: ExprKind::Direct(d),
                    span,
                })
            }
            Tok::TypePrefix(ty) => {
                self.bump();
                let neg = self.eat_p("-");
                let vspan = self.span();
                let kind = match self.tok().clone() {
                    Tok::Int(v) => {
                        let v = i128::try_from(v).unwrap_or(i128::MAX);
                        if ty == "REAL" || ty == "LREAL" {
                            Literal::Real(if neg { -(v as f64) } else { v as f64 }, Some(ty))
                        } else {
                            Literal::Int(if neg { -v } else { v }, Some(ty))
                        }
                    }
                    Tok::Real(v) => Literal::Real(if neg { -v } else { v }, Some(ty)),
                    Tok::Ident(s) if ty == "BOOL" && s.eq_ignore_ascii_case("TRUE") => {
                        Literal::Bool(true)
                    }
                    Tok::Ident(s) if ty == "BOOL" && s.eq_ignore_ascii_case("FALSE") => {
                        Literal::Bool(false)
                    }
                    Tok::SqString(s) => Literal::String(s, ty.starts_with('W')),
                    Tok::DqString(s) => Literal::String(s, true),
                    _ => return self.expected("a literal value after the type prefix"),
                };
                self.bump();
                let _ = vspan;
                Ok(Expr {
                    id: self.id(),
                    kind: ExprKind::Literal(kind),
                    span: span.to(self.prev_span()),
                })
            }
            Tok::DqString(s) => {
                self.bump();
                Ok(Expr {
                    id: self.id(),
                    kind: ExprKind::Name {
                        ident: Ident::new(s, span),
                        quoted: true,
                    },
                    span,
                })
            }
            Tok::HashIdent(s) => {
                self.bump();
                Ok(Expr {
                    id: self.id(),
                    kind: ExprKind::Name {
                        ident: Ident::new(s, span),
                        quoted: false,
                    },
                    span,
                })
            }
            Tok::Ident(s) => {
                let up = s.to_ascii_uppercase();
                if up == "TRUE" {
                    return lit(self, Literal::Bool(true));
                }
                if up == "FALSE" {
                    return lit(self, Literal::Bool(false));
                }
                // MOD(a, b) in function form
                let fn_form = matches!(up.as_str(), "MOD" | "AND" | "OR" | "XOR")
                    && matches!(self.tok_at(1), Tok::Punct("("));
                if RESERVED.contains(&up.as_str()) && !fn_form {
                    return self.expected("an expression");
                }
                self.bump();
                // Enum typed value: Color#Red lexes as Ident("Color") HashIdent("Red")
                if let Tok::HashIdent(v) = self.tok().clone() {
                    let vspan = self.span();
                    if vspan.start == span.end {
                        self.bump();
                        return Ok(Expr {
                            id: self.id(),
                            kind: ExprKind::TypedEnum(
                                Ident::new(s, span),
                                Ident::new(
                                    v,
                                    Span {
                                        start: vspan.start + 1,
                                        ..vspan
                                    },
                                ),
                            ),
                            span: span.to(vspan),
                        });
                    }
                }
                Ok(Expr {
                    id: self.id(),
                    kind: ExprKind::Name {
                        ident: Ident::new(s, span),
                        quoted: false,
                    },
                    span,
                })
            }
            Tok::Punct("(") => {
                self.bump();
                let e = self.expr()?;
                self.expect_p(")")?;
                Ok(e)
            }
            _ => self.expected("an expression"),
        }
    }
}

/// `B1`, `W0`, `D1`, `L0` after `.%`, optionally followed by a bit index (`B1.1`): the
/// width in bits of the part and its index, and the bit.
fn partial_access(d: &str) -> Option<((u32, u32), Option<u32>)> {
    match d.split_once('.') {
        None => Some((partial_width(d)?, None)),
        Some((part, bit)) => {
            if bit.is_empty() || !bit.chars().all(|c| c.is_ascii_digit()) {
                return None;
            }
            Some((partial_width(part)?, Some(bit.parse().unwrap_or(u32::MAX))))
        }
    }
}

/// `B1`, `W0`, `D1`, `L0` after `.%`: the width in bits of the part and its index.
fn partial_width(d: &str) -> Option<(u32, u32)> {
    let mut chars = d.chars();
    let width = match chars.next()? {
        'B' | 'b' => 8,
        'W' | 'w' => 16,
        'D' | 'd' => 32,
        'L' | 'l' => 64,
        _ => return None,
    };
    let digits = chars.as_str();
    if digits.is_empty() || !digits.chars().all(|c| c.is_ascii_digit()) {
        return None;
    }
    Some((width, digits.parse().unwrap_or(u32::MAX)))
}
