//! Stanice's mimic screens: an SVG file checked and made safe to put into a web page.
//!
//! A screen is configuration, not a program: whatever a drawing tool (or a hostile hand)
//! put into the file, nothing of it may run in an operator's browser. [`clean`] reads the
//! file as XML (a broken file is an error at its line and column, not a blank screen) and
//! writes it again with only what a mimic needs:
//!
//! ```text
//! file text ──quick-xml──▶ events ──allowlist──▶ kept elements and attributes ──▶ markup
//!                 (well-formed,        (SVG elements only; no script,       (one form the
//!                  namespaces,          foreignObject, on*, foreign links,   HTML and XML
//!                  entities)            javascript:/data: URLs, SMIL         parsers read
//!                                       rewriting links or handlers)         alike)
//! ```
//!
//! The markup written is read the same by an XML parser (`DOMParser`, `image/svg+xml`)
//! and by the browser's HTML parser in SVG foreign content (`innerHTML`), which is three
//! to five times quicker on a screen of 10,000 elements and needs no second sanitising
//! pass in the page: only SVG-namespace elements from an allowlist (none of them breaks
//! out of foreign content), written by their local names (the HTML parser restores the
//! camel case of every one of them); attributes without a prefix, plus `xlink:` and
//! `xml:` ones, the only prefixes the HTML parser knows; every element closed; text and
//! values escaped with the four entities both parsers know; `<title>` and `<desc>` (HTML
//! integration points) keep text only; no comments, processing instructions or DOCTYPE.
//! Entities declared in the file's internal DTD (`<!ENTITY ns_svg "...">`, as some
//! drawing tools write) are expanded as text.
//!
//! What is removed (docs/HMI.md, "SVG bindings"): elements outside the SVG namespace or
//! the allowlist (`<script>`, `<foreignObject>`, `<iframe>`, ...) with everything inside;
//! every `on*` attribute; every link (`href`, `xlink:href`) other than a `#` link; every
//! attribute holding a `javascript:`, `vbscript:` or `data:` URL, also with spaces or
//! control characters inside the scheme; every SMIL animation that targets a link or an
//! `on*` attribute or carries such a URL; a `<style>` sheet that imports or holds such a
//! URL.
#![forbid(unsafe_code)]

use std::collections::HashMap;
use std::fmt::Write as _;

use quick_xml::escape::resolve_predefined_entity;
use quick_xml::events::attributes::Attribute;
use quick_xml::events::{BytesStart, Event};
use quick_xml::name::{Namespace, ResolveResult};
use quick_xml::reader::NsReader;
use quick_xml::XmlVersion;

const SVG_NAMESPACE: &str = "http://www.w3.org/2000/svg";
const XLINK_NAMESPACE: &str = "http://www.w3.org/1999/xlink";
const XML_NAMESPACE: &str = "http://www.w3.org/XML/1998/namespace";

/// Deeper nesting than any drawing needs: a bound on the writer's stack for hostile files.
const MAX_DEPTH: usize = 256;

/// The SVG elements a screen may hold: SVG 1.1 and 2 without `script`, `foreignObject`,
/// fonts and `animateColor`. Each is one the HTML parser's foreign-content rules keep in
/// the SVG namespace under its own (camel-case) name.
const ALLOWED_ELEMENTS: &[&str] = &[
    "a",
    "animate",
    "animateMotion",
    "animateTransform",
    "circle",
    "clipPath",
    "defs",
    "desc",
    "ellipse",
    "feBlend",
    "feColorMatrix",
    "feComponentTransfer",
    "feComposite",
    "feConvolveMatrix",
    "feDiffuseLighting",
    "feDisplacementMap",
    "feDistantLight",
    "feDropShadow",
    "feFlood",
    "feFuncA",
    "feFuncB",
    "feFuncG",
    "feFuncR",
    "feGaussianBlur",
    "feImage",
    "feMerge",
    "feMergeNode",
    "feMorphology",
    "feOffset",
    "fePointLight",
    "feSpecularLighting",
    "feSpotLight",
    "feTile",
    "feTurbulence",
    "filter",
    "g",
    "image",
    "line",
    "linearGradient",
    "marker",
    "mask",
    "metadata",
    "mpath",
    "path",
    "pattern",
    "polygon",
    "polyline",
    "radialGradient",
    "rect",
    "set",
    "stop",
    "style",
    "svg",
    "switch",
    "symbol",
    "text",
    "textPath",
    "title",
    "tspan",
    "use",
    "view",
];

/// SMIL elements: they can set an attribute after the page has looked at it.
const ANIMATIONS: &[&str] = &["animate", "animateMotion", "animateTransform", "set"];

/// A screen file that is not well-formed SVG: where and why.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("line {line}, column {column}: {message}")]
pub struct SvgError {
    /// 1-based line of the file.
    pub line: usize,
    /// 1-based column (in characters) of that line.
    pub column: usize,
    /// What is wrong there.
    pub message: String,
}

/// Checks a screen file and writes it again with only what is safe and needed (see the
/// crate's documentation): markup that the browser's HTML and XML parsers read alike.
pub fn clean(text: &str) -> Result<String, SvgError> {
    Cleaner::new(text).run()
}

/// Whether a value is (or, after the browser drops spaces and control characters inside
/// a scheme, becomes) a URL that runs code or carries a document.
pub fn is_dangerous_url(value: &str) -> bool {
    let compact: String = value
        .chars()
        .filter(|c| !(c.is_control() || *c == ' ' || ('\u{7f}'..='\u{9f}').contains(c)))
        .flat_map(char::to_lowercase)
        .collect();
    ["javascript:", "vbscript:", "data:"]
        .iter()
        .any(|scheme| compact.starts_with(scheme))
        || compact.contains("javascript:")
        || compact.contains("vbscript:")
}

/// The tags of markup [`clean`] wrote (the text between each `<` and the next `>`): in
/// that markup every `<` and `>` of text or values is escaped, so this split is exact.
/// For checks of the output (tests, fuzzing).
pub fn tags(markup: &str) -> impl Iterator<Item = &str> {
    markup
        .split('<')
        .skip(1)
        .map(|rest| rest.split('>').next().unwrap_or(rest))
}

/// Whether a tag of [`clean`]'s output would run code: a script or foreign object, an
/// `on*` attribute, or a `javascript:`/`vbscript:` URL anywhere in it.
pub fn tag_is_unsafe(tag: &str) -> bool {
    let lower = tag.to_ascii_lowercase();
    let name = lower.trim_start_matches('/');
    if name.starts_with("script") || name.starts_with("foreignobject") {
        return true;
    }
    // An attribute is ` name="`: values hold no `"` (escaped), so ` on...="` inside a
    // tag is always an attribute.
    let handler = lower.match_indices(" on").any(|(at, _)| {
        let rest = &lower[at + 3..];
        let name_end = rest
            .find(|c: char| !(c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.' | ':')))
            .unwrap_or(rest.len());
        rest[name_end..].starts_with("=\"")
    });
    // As a browser reads a URL: without the spaces and control characters inside it.
    let compact: String = lower
        .chars()
        .filter(|c| !(c.is_control() || *c == ' '))
        .collect();
    handler || compact.contains("javascript:") || compact.contains("vbscript:")
}

/// An element being written.
struct Open {
    /// Its name as written.
    name: &'static str,
    /// `<title>`, `<desc>`: text only (they are HTML integration points).
    text_only: bool,
    /// `<style>`: its text is collected and checked as a whole.
    style: bool,
}

struct Cleaner<'a> {
    text: &'a str,
    reader: NsReader<&'a [u8]>,
    out: String,
    open: Vec<Open>,
    /// Inside a dropped element: how deep (its own start counts 1).
    skipping: usize,
    /// The text of the `<style>` being written.
    style_text: String,
    entities: HashMap<String, String>,
    root_done: bool,
}

impl<'a> Cleaner<'a> {
    fn new(text: &'a str) -> Self {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let mut reader = NsReader::from_str(text);
        let config = reader.config_mut();
        config.check_end_names = true;
        config.expand_empty_elements = false;
        Cleaner {
            text,
            reader,
            out: String::with_capacity(text.len()),
            open: Vec::new(),
            skipping: 0,
            style_text: String::new(),
            entities: HashMap::new(),
            root_done: false,
        }
    }

    fn error_at(&self, offset: u64, message: impl Into<String>) -> SvgError {
        let offset = usize::try_from(offset)
            .unwrap_or(usize::MAX)
            .min(self.text.len());
        // The offset is a byte offset: step back to a character boundary.
        let mut end = offset;
        while !self.text.is_char_boundary(end) {
            end -= 1;
        }
        let before = self.text.get(..end).unwrap_or_default();
        let line = before.matches('\n').count() + 1;
        let column = before
            .rsplit('\n')
            .next()
            .map_or(0, |last| last.chars().count())
            + 1;
        SvgError {
            line,
            column,
            message: message.into(),
        }
    }

    fn run(mut self) -> Result<String, SvgError> {
        loop {
            let at = self.reader.buffer_position();
            let (namespace, event) = match self.reader.read_resolved_event() {
                Ok((namespace, event)) => (owned_namespace(namespace, &self.entities), event),
                Err(error) => {
                    let at = self.reader.error_position();
                    return Err(self.error_at(at, error.to_string()));
                }
            };
            match event {
                Event::Start(element) => self.start(at, namespace, &element, false)?,
                Event::Empty(element) => self.start(at, namespace, &element, true)?,
                Event::End(_) => self.end(),
                Event::Text(text) => {
                    let content = text.xml10_content();
                    self.text_content(at, &content)?;
                }
                Event::CData(data) => {
                    let content = data.xml10_content().into_owned();
                    self.text_content(at, &content)?;
                }
                Event::GeneralRef(reference) => {
                    let resolved = match reference.resolve_char_ref() {
                        Ok(Some(c)) => c.to_string(),
                        Ok(None) => self.entity(at, &reference)?,
                        Err(error) => return Err(self.error_at(at, error.to_string())),
                    };
                    self.text_content(at, &resolved)?;
                }
                Event::DocType(doctype) => {
                    let content = doctype.xml10_content();
                    self.declare_entities(&content);
                }
                Event::Comment(_) | Event::Decl(_) | Event::PI(_) => {}
                Event::Eof => break,
            }
        }
        if let Some(open) = self.open.last() {
            let at = self.text.len() as u64;
            return Err(self.error_at(at, format!("the file ends inside <{}>", open.name)));
        }
        if !self.root_done {
            return Err(self.error_at(0, "no <svg> element"));
        }
        Ok(self.out)
    }

    fn entity(&self, at: u64, name: &str) -> Result<String, SvgError> {
        if let Some(text) = resolve_predefined_entity(name) {
            return Ok(text.to_owned());
        }
        self.entities
            .get(name)
            .cloned()
            .ok_or_else(|| self.error_at(at, format!("unknown entity &{name};")))
    }

    /// `<!ENTITY name "value">` of the internal DTD; parameter and external entities are
    /// not read (a reference to one is an unknown entity).
    fn declare_entities(&mut self, doctype: &str) {
        let mut rest = doctype;
        while let Some(start) = rest.find("<!ENTITY") {
            rest = &rest[start + "<!ENTITY".len()..];
            let trimmed = rest.trim_start();
            if trimmed.starts_with('%') {
                continue;
            }
            let name_end = trimmed
                .find(|c: char| c.is_whitespace())
                .unwrap_or(trimmed.len());
            let name = &trimmed[..name_end];
            let after = trimmed[name_end..].trim_start();
            let Some(quote) = after.chars().next().filter(|c| *c == '"' || *c == '\'') else {
                continue;
            };
            let body = &after[1..];
            if let Some(end) = body.find(quote) {
                let value = &body[..end];
                // Character references inside the value; anything else stays as written.
                let value = quick_xml::escape::unescape(value)
                    .map_or_else(|_| value.to_owned(), |v| v.into_owned());
                self.entities.insert(name.to_owned(), value);
            }
        }
    }

    fn start(
        &mut self,
        at: u64,
        namespace: Owned,
        element: &BytesStart<'_>,
        empty: bool,
    ) -> Result<(), SvgError> {
        if self.skipping > 0 {
            if !empty {
                self.skipping += 1;
            }
            return Ok(());
        }
        if self.root_done {
            return Err(self.error_at(at, "a second root element after </svg>"));
        }
        let local = element.local_name();
        let local: &str = local.as_ref();
        let is_root = self.open.is_empty();
        if let Owned::Unknown(prefix) = &namespace {
            return Err(self.error_at(
                at,
                format!("the prefix `{prefix}` of <{}> is not declared", local),
            ));
        }
        let svg = matches!(&namespace, Owned::Unbound)
            || matches!(&namespace, Owned::Bound(ns) if ns == SVG_NAMESPACE);
        if is_root && !(svg && local == "svg") {
            return Err(self.error_at(
                at,
                format!("the root element is <{local}>, not <svg xmlns=\"{SVG_NAMESPACE}\">"),
            ));
        }
        if self.open.len() >= MAX_DEPTH {
            return Err(self.error_at(at, format!("elements nested deeper than {MAX_DEPTH}")));
        }
        let allowed = ALLOWED_ELEMENTS
            .iter()
            .find(|name| **name == local)
            .copied();
        let inside_text_only = self.open.last().is_some_and(|open| open.text_only);
        let Some(name) = allowed.filter(|_| svg && !inside_text_only) else {
            self.skip(empty);
            return Ok(());
        };
        let attributes = self.attributes(at, element)?;
        if ANIMATIONS.contains(&name) && animation_is_dangerous(&attributes) {
            self.skip(empty);
            return Ok(());
        }
        self.out.push('<');
        self.out.push_str(name);
        if is_root {
            let _ = write!(
                self.out,
                " xmlns=\"{SVG_NAMESPACE}\" xmlns:xlink=\"{XLINK_NAMESPACE}\""
            );
        }
        for (key, value) in &attributes {
            if keep_attribute(key, value) {
                self.out.push(' ');
                self.out.push_str(key);
                self.out.push_str("=\"");
                escape_into(&mut self.out, value, true);
                self.out.push('"');
            }
        }
        if empty {
            self.out.push_str("/>");
            if is_root {
                self.root_done = true;
            }
        } else {
            self.out.push('>');
            self.open.push(Open {
                name,
                text_only: name == "title" || name == "desc",
                style: name == "style",
            });
        }
        Ok(())
    }

    fn skip(&mut self, empty: bool) {
        if !empty {
            self.skipping = 1;
        }
    }

    /// The element's attributes as (name as written, value), namespace declarations and
    /// attributes of other vocabularies (inkscape:, sodipodi:, ...) left out.
    fn attributes(
        &self,
        at: u64,
        element: &BytesStart<'_>,
    ) -> Result<Vec<(String, String)>, SvgError> {
        let mut kept = Vec::new();
        for attribute in element.attributes().with_checks(true) {
            let attribute: Attribute<'_> =
                attribute.map_err(|error| self.error_at(at, error.to_string()))?;
            if attribute.key.as_namespace_binding().is_some() {
                continue;
            }
            let (namespace, local) = self.reader.resolver().resolve_attribute(attribute.key);
            let local: &str = local.as_ref();
            let name = match namespace {
                ResolveResult::Unbound => local.to_owned(),
                ResolveResult::Bound(Namespace(ns))
                    if expand(ns, &self.entities) == XLINK_NAMESPACE =>
                {
                    format!("xlink:{local}")
                }
                // xml:base would move where links point; xml:lang and xml:space are the two
                // the HTML parser knows.
                ResolveResult::Bound(Namespace(ns))
                    if expand(ns, &self.entities) == XML_NAMESPACE
                        && matches!(local, "lang" | "space") =>
                {
                    format!("xml:{local}")
                }
                ResolveResult::Bound(_) => continue,
                ResolveResult::Unknown(prefix) => {
                    return Err(self.error_at(
                        at,
                        format!("the prefix `{prefix}` of attribute {local} is not declared"),
                    ))
                }
            };
            let value = attribute
                .normalized_value_with(XmlVersion::Implicit1_0, 4, |entity| {
                    resolve_predefined_entity(entity)
                        .or_else(|| self.entities.get(entity).map(String::as_str))
                })
                .map_err(|error| self.error_at(at, error.to_string()))?;
            kept.push((name, value.into_owned()));
        }
        Ok(kept)
    }

    fn end(&mut self) {
        if self.skipping > 0 {
            self.skipping -= 1;
            return;
        }
        let Some(open) = self.open.pop() else {
            return;
        };
        if open.style {
            let sheet = std::mem::take(&mut self.style_text);
            let lower = sheet.to_lowercase();
            if !(lower.contains("@import")
                || is_dangerous_url(&sheet)
                || lower.contains("url(data:"))
            {
                escape_into(&mut self.out, &sheet, false);
            }
        }
        self.out.push_str("</");
        self.out.push_str(open.name);
        self.out.push('>');
        if self.open.is_empty() {
            self.root_done = true;
        }
    }

    fn text_content(&mut self, at: u64, text: &str) -> Result<(), SvgError> {
        if self.skipping > 0 {
            return Ok(());
        }
        match self.open.last() {
            None => {
                if text.trim().is_empty() {
                    Ok(())
                } else {
                    Err(self.error_at(at, "text outside the <svg> element"))
                }
            }
            Some(open) if open.style => {
                self.style_text.push_str(text);
                Ok(())
            }
            Some(_) => {
                escape_into(&mut self.out, text, false);
                Ok(())
            }
        }
    }
}

/// A resolved namespace, owned (the reader's borrow ends with the next event).
enum Owned {
    Unbound,
    Bound(String),
    Unknown(String),
}

fn owned_namespace(namespace: ResolveResult<'_>, entities: &HashMap<String, String>) -> Owned {
    match namespace {
        ResolveResult::Unbound => Owned::Unbound,
        ResolveResult::Bound(Namespace(ns)) => Owned::Bound(expand(ns, entities)),
        ResolveResult::Unknown(prefix) => Owned::Unknown(prefix),
    }
}

/// A namespace name with its entity references expanded (`xmlns="&ns_svg;"`, as
/// Illustrator writes): the reader resolves a prefix to the raw attribute value.
fn expand(raw: &str, entities: &HashMap<String, String>) -> String {
    if !raw.contains('&') {
        return raw.to_owned();
    }
    quick_xml::escape::unescape_with(raw, |entity| {
        resolve_predefined_entity(entity).or_else(|| entities.get(entity).map(String::as_str))
    })
    .map_or_else(|_| raw.to_owned(), |expanded| expanded.into_owned())
}

/// Whether an attribute is kept: no event handler, no link other than a `#` link, no URL
/// that runs code.
fn keep_attribute(name: &str, value: &str) -> bool {
    let lower = name.to_ascii_lowercase();
    if lower.starts_with("on") {
        return false;
    }
    if lower == "href" || lower.ends_with(":href") {
        return value.trim().starts_with('#') && !is_dangerous_url(value);
    }
    // Only names the HTML parser reads as the XML parser does.
    let valid = lower
        .chars()
        .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.' | ':'))
        && lower.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_');
    valid && !is_dangerous_url(value)
}

/// SMIL that would set a link or an event handler, or put a dangerous URL anywhere.
fn animation_is_dangerous(attributes: &[(String, String)]) -> bool {
    attributes.iter().any(|(name, value)| match name.as_str() {
        "attributeName" => {
            let target = value.trim().to_ascii_lowercase();
            target == "href" || target.ends_with(":href") || target.starts_with("on")
        }
        "to" | "from" | "values" | "by" => is_dangerous_url(value),
        _ => false,
    })
}

/// Escapes text (and, in attribute values, the quote) with the entities both the XML and
/// the HTML parser decode.
fn escape_into(out: &mut String, text: &str, attribute: bool) {
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' if attribute => out.push_str("&quot;"),
            // A NUL is not XML; the HTML parser would make it U+FFFD.
            '\0' => out.push('\u{fffd}'),
            c => out.push(c),
        }
    }
}
