//! Embeds every file of `web/` (the browser application) into the binary, so that the
//! HMI is one self-contained program.

use std::fmt::Write as _;
use std::path::Path;

fn mime(name: &str) -> &'static str {
    match name.rsplit('.').next() {
        Some("html") => "text/html; charset=utf-8",
        Some("js") => "text/javascript; charset=utf-8",
        Some("css") => "text/css; charset=utf-8",
        Some("svg") => "image/svg+xml",
        Some("png") => "image/png",
        Some("ico") => "image/x-icon",
        Some("json") => "application/json",
        _ => "application/octet-stream",
    }
}

/// The entity tag of a file: FNV-1a, 64 bits (a change detector, not a digest against
/// an adversary; no crate needed for ten lines).
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |hash, byte| {
        (hash ^ u64::from(*byte)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

fn main() -> Result<(), String> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("web");
    println!("cargo:rerun-if-changed={}", dir.display());
    // A build that cannot read web/ fails: an HMI built without its pages would answer
    // every page with 404 (seen once, from a build in a since-removed worktree).
    let entries = std::fs::read_dir(&dir)
        .map_err(|error| format!("cannot read {}: {error}", dir.display()))?;
    let mut names: Vec<String> = entries
        .filter_map(Result::ok)
        .filter(|e| e.path().is_file())
        .filter_map(|e| e.file_name().into_string().ok())
        .filter(|n| !n.starts_with('.'))
        .collect();
    names.sort();
    for required in ["index.html", "login.html", "app.js"] {
        if !names.iter().any(|name| name == required) {
            return Err(format!("{} has no {required}", dir.display()));
        }
    }
    let mut out = String::from("/// The embedded files of `web/`: (name, content type, bytes, entity tag).\npub(crate) static FILES: &[(&str, &str, &[u8], &str)] = &[\n");
    for name in &names {
        let path = dir.join(name);
        println!("cargo:rerun-if-changed={}", path.display());
        let bytes = std::fs::read(&path)
            .map_err(|error| format!("cannot read {}: {error}", path.display()))?;
        let _ = writeln!(
            out,
            "    ({name:?}, {:?}, include_bytes!({:?}), {:?}),",
            mime(name),
            path.display().to_string(),
            format!("\"{:016x}\"", fnv1a(&bytes))
        );
    }
    out.push_str("];\n");
    let target =
        Path::new(&std::env::var("OUT_DIR").unwrap_or_else(|_| ".".into())).join("web_files.rs");
    std::fs::write(&target, out)
        .map_err(|error| format!("cannot write {}: {error}", target.display()))
}
