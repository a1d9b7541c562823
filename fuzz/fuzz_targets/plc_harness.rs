//! The Structured Text an input stands for, shared by the `plc_*` targets: an input that
//! names no PROGRAM is taken as the body of the program in
//! `crates/plc/tests/fuzz/harness.st`, whose declarations cover the newer syntax (typed
//! counters, REF_TO and NULL, partial access, TYPE initial values, safe-value pragmas, a
//! FUNCTION and a FUNCTION_BLOCK with VAR_IN_OUT); any other input is used as it is.
//! The seeds for that form are `crates/plc/tests/fuzz/fragments/*.st`.

const HARNESS: &str = include_str!("../../crates/plc/tests/fuzz/harness.st");

/// The source text for `data`.
pub fn source(data: &[u8]) -> String {
    let text = String::from_utf8_lossy(data);
    if text.to_ascii_uppercase().contains("PROGRAM") {
        text.into_owned()
    } else {
        HARNESS.replacen("(* BODY *)", &text, 1)
    }
}
