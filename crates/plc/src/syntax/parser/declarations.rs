//! Declarations: top-level items (POUs, types, global variables, configurations and
//! resources), variable blocks and declarations, initial values and type references.

use super::{PResult, Parser};
use crate::syntax::ast::*;
use crate::syntax::lexer::Tok;

impl Parser<'_> {
    pub(super) fn item(&mut self) -> PResult<Vec<Item>> {
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
}
