//! The project's own files stand alone: a user's clone has no `shared/` folder beside
//! it, so no documentation, example, program or source file may send a reader there. The
//! theses are cited by their short names (docs/THESES.md).

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::{Path, PathBuf};

use testkit::repository_root;

/// Every text file under `folder`, skipping build output and hidden folders.
fn text_files(folder: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(folder).unwrap().flatten() {
        let path = entry.path();
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.starts_with('.') || name == "target" || name == "corpus" || name == "artifacts" {
            continue;
        }
        if path.is_dir() {
            text_files(&path, out);
        } else if [
            "rs", "md", "toml", "st", "py", "sh", "js", "csv", "html", "css", "svg",
        ]
        .iter()
        .any(|ext| path.extension().is_some_and(|e| e == *ext))
        {
            out.push(path);
        }
    }
}

#[test]
fn no_project_file_points_into_shared() {
    let root = repository_root();
    let mut files = Vec::new();
    for folder in ["crates", "docs", "examples", "scripts", "tests", "fuzz"] {
        text_files(&root.join(folder), &mut files);
    }
    files.push(root.join("README.md"));
    // Spelled in two pieces so that this file does not match itself.
    let needles = [format!("shared/{}", "spec"), format!("shared/{}", "seeds")];
    let mut offenders = Vec::new();
    for file in &files {
        let Ok(text) = std::fs::read_to_string(file) else {
            continue;
        };
        for (number, line) in text.lines().enumerate() {
            if needles.iter().any(|needle| line.contains(needle.as_str())) {
                offenders.push(format!(
                    "{}:{}: {}",
                    file.strip_prefix(&root).unwrap_or(file).display(),
                    number + 1,
                    line.trim()
                ));
            }
        }
    }
    assert!(
        offenders.is_empty(),
        "cite the theses by name (docs/THESES.md), not shared/:\n{}",
        offenders.join("\n")
    );
}

#[test]
fn the_examples_name_files_that_exist() {
    let root = repository_root();
    let toml = std::fs::read_to_string(root.join("examples/vsetin/station.toml")).unwrap();
    for word in toml.split_whitespace() {
        let word = word.trim_end_matches(['.', ',', ')', ';']);
        if word.starts_with("crates/") && word.ends_with(".rs") {
            assert!(
                root.join(word).is_file(),
                "examples/vsetin/station.toml names {word}"
            );
        }
    }
}
