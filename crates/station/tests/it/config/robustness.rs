//! Robustness: nothing panics on arbitrary bytes, text or mangled examples, and every
//! problem is an error with a position.

use std::path::Path;

use proptest::prelude::*;
use station::config::Project;

use super::support::*;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..512)) {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("station.toml"), &bytes).unwrap();
        if let Err(errors) = Project::load(dir.path()) {
            prop_assert!(!errors.errors().is_empty());
            let _ = errors.to_string();
        }
    }

    #[test]
    fn mangled_example_never_panics(
        drop_lines in proptest::collection::vec(0usize..600, 0..8),
        cut in 0usize..20_000,
    ) {
        let original = std::fs::read_to_string(testkit::projects::vsetin().join("station.toml")).unwrap();
        let kept: String = original
            .lines()
            .enumerate()
            .filter(|(i, _)| !drop_lines.contains(i))
            .map(|(_, l)| format!("{l}\n"))
            .collect();
        let mut end = cut.min(kept.len());
        while !kept.is_char_boundary(end) {
            end -= 1;
        }
        let dir = folder(&kept[..end], &[]);
        std::fs::create_dir_all(dir.path().join("plc")).unwrap();
        std::fs::copy(
            testkit::projects::vsetin().join("plc/logo_board.st"),
            dir.path().join("plc/logo_board.st"),
        )
        .unwrap();
        if let Err(errors) = Project::load(dir.path()) {
            for e in errors.errors() {
                prop_assert!(e.line >= 1 && e.column >= 1, "{e}");
            }
        }
    }
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(300))]

    #[test]
    fn arbitrary_text_never_panics(text in "\\PC{0,400}") {
        let folder = Path::new("/nonexistent");
        let _ = Project::parse(folder, &folder.join("station.toml"), &text);
    }

    #[test]
    fn mutated_example_never_panics_and_errors_have_positions(
        cuts in proptest::collection::vec((0usize..6000, 0usize..40, "\\PC{0,12}"), 1..4)
    ) {
        let original = std::fs::read_to_string(testkit::projects::vsetin().join("station.toml")).unwrap();
        let mut text: Vec<char> = original.chars().take(6000).collect();
        for (at, len, insert) in cuts {
            let at = at.min(text.len());
            let end = (at + len).min(text.len());
            text.splice(at..end, insert.chars());
        }
        let text: String = text.into_iter().collect();
        let folder = testkit::projects::vsetin();
        if let Err(errors) = Project::parse(&folder, &folder.join("station.toml"), &text) {
            let lines = text.lines().count().max(1);
            for error in errors.errors() {
                proptest::prop_assert!(error.line <= lines + 1, "{error}");
            }
        }
    }
}
