//! What the integration tests share: building a program or failing the test with its
//! diagnostics rendered as `plc check` prints them.

use plc::{CompileOptions, Compiled, Plc, SourceMap};

/// Builds `files` (with `options`); a program that does not compile fails the test with
/// every diagnostic rendered (and the sources after them, for generated programs).
pub(crate) fn build_or_fail(
    files: &[(String, String)],
    options: CompileOptions,
) -> (SourceMap, Compiled) {
    let (sources, result) = plc::build_with(files, options);
    match result {
        Ok(compiled) => (sources, compiled),
        Err(diagnostics) => panic!(
            "{}\n{}",
            diagnostics
                .iter()
                .map(|d| d.render(&sources))
                .collect::<Vec<_>>()
                .join("\n"),
            files
                .iter()
                .map(|(name, text)| format!("--- {name}\n{text}"))
                .collect::<Vec<_>>()
                .join("\n")
        ),
    }
}

/// One source file `name` with the default options.
pub(crate) fn build_one(name: &str, src: &str) -> (SourceMap, Compiled) {
    build_or_fail(
        &[(name.to_owned(), src.to_owned())],
        CompileOptions::default(),
    )
}

/// A PLC running one source file `name`.
pub(crate) fn plc_of(name: &str, src: &str) -> Plc {
    let (sources, compiled) = build_one(name, src);
    Plc::new(compiled, sources)
}
