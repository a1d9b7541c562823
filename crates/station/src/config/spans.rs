//! Key paths and their positions in the project file: every error points at a value.

use super::*;

// ---------------------------------------------------------------------------------------
// Key paths and positions

/// One step of a key path.
#[derive(Clone, Copy)]
pub(in crate::config) enum Seg {
    Key(&'static str),
    Index(usize),
}

pub(in crate::config) use Seg::{Index as I, Key as K};

pub(in crate::config) fn key_string(path: &[Seg]) -> String {
    let mut out = String::new();
    for seg in path {
        match seg {
            Seg::Key(key) => {
                if !out.is_empty() {
                    out.push('.');
                }
                out.push_str(key);
            }
            Seg::Index(index) => out.push_str(&format!("[{index}]")),
        }
    }
    out
}

pub(in crate::config) struct Ctx<'a> {
    pub(in crate::config) file: PathBuf,
    pub(in crate::config) text: &'a str,
    /// The kinds `[[node.device]]` may name.
    pub(in crate::config) kinds: &'a crate::device::DeviceKinds,
    pub(in crate::config) tree: Spanned<DeTable<'a>>,
    pub(in crate::config) errors: Vec<ConfigError>,
    /// Problems past [`MAX_ERRORS_PER_FILE`], per file.
    pub(in crate::config) omitted: Vec<(PathBuf, usize)>,
}

/// 1-based line and column (in characters) of a byte offset.
pub(in crate::config) fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let mut offset = offset.min(text.len());
    while offset > 0 && !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = text.get(..offset).unwrap_or("");
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let column = before.get(line_start..).unwrap_or("").chars().count() + 1;
    (line, column)
}

pub(in crate::config) fn table_get<'t, 'i>(
    table: &'t DeTable<'i>,
    key: &str,
) -> Option<&'t Spanned<DeValue<'i>>> {
    table
        .iter()
        .find(|(k, _)| k.get_ref().as_ref() == key)
        .map(|(_, v)| v)
}

impl Ctx<'_> {
    pub(in crate::config) fn push_at(
        &mut self,
        span: Range<usize>,
        key: String,
        problem: ConfigProblem,
    ) {
        let (line, column) = line_col(self.text, span.start);
        self.push(ConfigError {
            file: self.file.clone(),
            line,
            column,
            key,
            problem,
        });
    }

    /// Keeps `error` unless its file has [`MAX_ERRORS_PER_FILE`] already; then counts it.
    pub(in crate::config) fn push(&mut self, error: ConfigError) {
        let kept = self.errors.iter().filter(|e| e.file == error.file).count();
        if kept < MAX_ERRORS_PER_FILE {
            self.errors.push(error);
        } else if let Some((_, count)) = self.omitted.iter_mut().find(|(f, _)| *f == error.file) {
            *count += 1;
        } else {
            self.omitted.push((error.file, 1));
        }
    }

    pub(in crate::config) fn into_errors(self) -> ConfigErrors {
        ConfigErrors {
            errors: self.errors,
            omitted: self.omitted,
        }
    }

    /// The span of the value at `path`, or of its deepest present ancestor.
    pub(in crate::config) fn span(&self, path: &[Seg]) -> Range<usize> {
        let mut span = 0..0;
        let mut table: Option<&DeTable<'_>> = Some(self.tree.get_ref());
        let mut array: Option<&[Spanned<DeValue<'_>>]> = None;
        for seg in path {
            let value = match (seg, table, array) {
                (Seg::Key(key), Some(t), _) => table_get(t, key),
                (Seg::Index(i), _, Some(a)) => a.get(*i),
                _ => None,
            };
            let Some(value) = value else { break };
            span = value.span();
            table = None;
            array = None;
            match value.get_ref() {
                DeValue::Table(t) => table = Some(t),
                DeValue::Array(a) => array = Some(a),
                _ => {}
            }
        }
        span
    }

    pub(in crate::config) fn err(&mut self, path: &[Seg], problem: impl Into<ConfigProblem>) {
        let span = self.span(path);
        self.push_at(span, key_string(path), problem.into());
    }

    /// The key path of the innermost value containing `offset` (for serde errors).
    pub(in crate::config) fn key_at(&self, offset: usize) -> String {
        /// The latest place at or before `offset` where `value` (or, for an array, one of
        /// its elements) starts: headers of arrays of tables are spread over the file.
        fn latest_start(value: &Spanned<DeValue<'_>>, offset: usize) -> Option<usize> {
            match value.get_ref() {
                DeValue::Array(array) => array
                    .iter()
                    .map(|v| v.span().start)
                    .filter(|start| *start <= offset)
                    .max(),
                _ => Some(value.span().start).filter(|start| *start <= offset),
            }
        }
        fn walk(value: &DeValue<'_>, offset: usize, path: &mut Vec<String>) {
            match value {
                DeValue::Table(table) => {
                    let covering = table.iter().find(|(key, value)| {
                        value.span().contains(&offset) || key.span().contains(&offset)
                    });
                    // a value whose span does not cover the offset: a table or an array of
                    // tables declared by a header before it
                    let found = covering.or_else(|| {
                        table
                            .iter()
                            .filter(|(_, v)| {
                                matches!(v.get_ref(), DeValue::Table(_) | DeValue::Array(_))
                            })
                            .filter_map(|(k, v)| latest_start(v, offset).map(|s| (s, (k, v))))
                            .max_by_key(|(start, _)| *start)
                            .map(|(_, entry)| entry)
                    });
                    if let Some((key, value)) = found {
                        path.push(format!(".{}", key.get_ref()));
                        walk(value.get_ref(), offset, path);
                    }
                }
                DeValue::Array(array) => {
                    let found = array
                        .iter()
                        .enumerate()
                        .find(|(_, v)| v.span().contains(&offset))
                        .or_else(|| {
                            array
                                .iter()
                                .enumerate()
                                .rfind(|(_, v)| v.span().start <= offset)
                        });
                    if let Some((index, value)) = found {
                        path.push(format!("[{index}]"));
                        walk(value.get_ref(), offset, path);
                    }
                }
                _ => {}
            }
        }
        let mut path = Vec::new();
        let root = DeValue::Table(self.tree.get_ref().clone());
        walk(&root, offset, &mut path);
        let joined: String = path.concat();
        joined.strip_prefix('.').unwrap_or(&joined).to_owned()
    }
}
