//! Files, spans and the source map that turns byte offsets into `file:line:col`.

use std::ops::Range;

/// The UTF-8 byte-order mark, accepted (and dropped) at the start of a source file.
pub const BYTE_ORDER_MARK: char = '\u{FEFF}';

/// A source file that is not UTF-8 text, with the position of its first invalid byte.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("not UTF-8 text: byte 0x{byte:02X} (save the file as UTF-8)")]
pub struct NotUtf8 {
    /// Byte offset of the first invalid byte in the file.
    pub offset: usize,
    /// Its 1-based line.
    pub line: usize,
    /// Its 1-based column, counting the valid characters before it on its line.
    pub col: usize,
    /// The invalid byte.
    pub byte: u8,
}

/// The text of a source file's bytes, without a leading byte-order mark; or where the
/// bytes stop being UTF-8 (line and column as an editor shows them).
pub fn decode(bytes: &[u8]) -> Result<&str, NotUtf8> {
    let bom = BYTE_ORDER_MARK.len_utf8();
    let (skipped, body) = match bytes.strip_prefix("\u{FEFF}".as_bytes()) {
        Some(rest) => (bom, rest),
        None => (0, bytes),
    };
    std::str::from_utf8(body).map_err(|error| {
        let valid = error.valid_up_to();
        let before = std::str::from_utf8(body.get(..valid).unwrap_or_default()).unwrap_or("");
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        NotUtf8 {
            offset: skipped + valid,
            line: before.matches('\n').count() + 1,
            col: before.get(line_start..).unwrap_or("").chars().count() + 1,
            byte: body.get(valid).copied().unwrap_or(0),
        }
    })
}

/// Index of a file in a [`SourceMap`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct FileId(pub u32);

/// A byte range in one source file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Span {
    /// The file.
    pub file: FileId,
    /// First byte.
    pub start: u32,
    /// One past the last byte.
    pub end: u32,
}

impl Span {
    /// A span over `range` in `file`.
    pub fn new(file: FileId, range: Range<usize>) -> Self {
        Span {
            file,
            start: u32::try_from(range.start).unwrap_or(u32::MAX),
            end: u32::try_from(range.end).unwrap_or(u32::MAX),
        }
    }

    /// The smallest span covering both (same file assumed).
    pub fn to(self, other: Span) -> Span {
        Span {
            file: self.file,
            start: self.start.min(other.start),
            end: self.end.max(other.end),
        }
    }
}

/// One loaded source file.
#[derive(Debug, Clone)]
pub struct SourceFile {
    /// Name used in diagnostics (usually the path).
    pub name: String,
    /// The text.
    pub text: String,
    line_starts: Vec<usize>,
}

/// A line and column, both 1-based; the column counts characters.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LineCol {
    /// 1-based line.
    pub line: usize,
    /// 1-based column in characters.
    pub col: usize,
}

/// All source files of a compilation.
#[derive(Debug, Clone, Default)]
pub struct SourceMap {
    files: Vec<SourceFile>,
}

impl SourceMap {
    /// An empty map.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a file and returns its id. A leading UTF-8 byte-order mark (which Windows
    /// editors write) is dropped, so that it is neither lexed nor counted in columns.
    pub fn add(&mut self, name: impl Into<String>, text: impl Into<String>) -> FileId {
        let mut text = text.into();
        if text.starts_with(BYTE_ORDER_MARK) {
            text.drain(..BYTE_ORDER_MARK.len_utf8());
        }
        let mut line_starts = vec![0];
        line_starts.extend(text.match_indices('\n').map(|(i, _)| i + 1));
        let id = FileId(u32::try_from(self.files.len()).unwrap_or(u32::MAX));
        self.files.push(SourceFile {
            name: name.into(),
            text,
            line_starts,
        });
        id
    }

    /// The file with this id.
    pub fn file(&self, id: FileId) -> Option<&SourceFile> {
        self.files.get(id.0 as usize)
    }

    /// All files with their ids.
    pub fn files(&self) -> impl Iterator<Item = (FileId, &SourceFile)> {
        self.files
            .iter()
            .enumerate()
            .map(|(i, f)| (FileId(u32::try_from(i).unwrap_or(u32::MAX)), f))
    }

    /// Line and column of the start of `span`.
    pub fn line_col(&self, span: Span) -> LineCol {
        let Some(file) = self.file(span.file) else {
            return LineCol { line: 0, col: 0 };
        };
        let offset = (span.start as usize).min(file.text.len());
        let line = file.line_starts.partition_point(|&s| s <= offset).max(1);
        let start = file.line_starts.get(line - 1).copied().unwrap_or(0);
        let col = file
            .text
            .get(start..offset)
            .map(|s| s.chars().count())
            .unwrap_or(0)
            + 1;
        LineCol { line, col }
    }

    /// `file:line:col` of the start of `span`.
    pub fn location(&self, span: Span) -> String {
        let lc = self.line_col(span);
        let name = self.file(span.file).map(|f| f.name.as_str()).unwrap_or("?");
        format!("{name}:{}:{}", lc.line, lc.col)
    }

    /// The source text of a span.
    pub fn snippet(&self, span: Span) -> &str {
        self.file(span.file)
            .and_then(|f| f.text.get(span.start as usize..span.end as usize))
            .unwrap_or("")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decode_finds_the_first_invalid_byte_and_drops_a_byte_order_mark() {
        assert_eq!(decode(b"\xEF\xBB\xBFPROGRAM P"), Ok("PROGRAM P"));
        assert_eq!(decode("x := 'ž';".as_bytes()), Ok("x := 'ž';"));
        let error = decode(b"A\n  ok := '\xC5\xBE\xE9';\n").unwrap_err();
        assert_eq!(
            error,
            NotUtf8 {
                offset: 13,
                line: 2,
                col: 11,
                byte: 0xE9
            }
        );
        assert_eq!(
            error.to_string(),
            "not UTF-8 text: byte 0xE9 (save the file as UTF-8)"
        );
        // after a byte-order mark the column is what an editor shows
        let error = decode(b"\xEF\xBB\xBFab\xFF").unwrap_err();
        assert_eq!((error.offset, error.line, error.col), (5, 1, 3));
    }

    #[test]
    fn a_byte_order_mark_is_not_part_of_the_text() {
        let mut map = SourceMap::new();
        let id = map.add("a.st", "\u{FEFF}PROGRAM P");
        assert_eq!(map.file(id).map(|f| f.text.as_str()), Some("PROGRAM P"));
    }
}
