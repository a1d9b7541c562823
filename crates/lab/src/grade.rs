//! Grading a class: every student program in a folder run against one scenario, one row
//! each, written as CSV (for the teacher's spreadsheet) and HTML (to read or publish).
//!
//! A submission is a `.st` file directly in the folder (the student is the file's stem),
//! or a subfolder holding `.st` files compiled together (the student is the folder's
//! name). A program that does not compile gets its diagnostics in the row; a program that
//! compiles is run for the scenario's duration at full speed.

use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::program::{is_st, st_files, Program};
use crate::run::{RunSettings, Session};
use crate::scenario::Scenario;

/// One student's submission.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Submission {
    /// The student (file stem or folder name).
    pub student: String,
    /// Its ST files.
    pub files: Vec<PathBuf>,
}

/// The submissions in `folder`, sorted by student.
pub fn submissions(folder: &Path) -> std::io::Result<Vec<Submission>> {
    let mut found = Vec::new();
    for entry in std::fs::read_dir(folder)? {
        let path = entry?.path();
        let name = path
            .file_stem()
            .map(|stem| stem.to_string_lossy().into_owned())
            .unwrap_or_default();
        if path.is_file() && is_st(&path) {
            found.push(Submission {
                student: name,
                files: vec![path],
            });
        } else if path.is_dir() {
            let files = st_files(&path)?;
            if !files.is_empty() {
                let student = path
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or(name);
                found.push(Submission { student, files });
            }
        }
    }
    found.sort_by(|a, b| a.student.cmp(&b.student));
    Ok(found)
}

/// A submission's verdict.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Verdict {
    /// Ran the scenario without a violation.
    Passed,
    /// Ran, with violations.
    Failed,
    /// The compiler refused it.
    DoesNotCompile,
    /// It compiled but could not be started (no PROGRAM, several, a start-up fault).
    CannotRun,
}

impl Verdict {
    /// As written in the table.
    pub fn text(self) -> &'static str {
        match self {
            Verdict::Passed => "passed",
            Verdict::Failed => "failed",
            Verdict::DoesNotCompile => "does not compile",
            Verdict::CannotRun => "cannot run",
        }
    }
}

/// A row of the grade table.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Grade {
    /// The student.
    pub student: String,
    /// The verdict.
    pub verdict: Verdict,
    /// Violations in all.
    pub violations: u64,
    /// The first violation, as a line (time, what, outputs).
    pub first_violation: String,
    /// The compiler's or the start's messages.
    pub diagnostics: String,
    /// Simulated seconds run.
    pub simulated_s: f64,
}

/// Runs every submission of `folder` against `scenario` with `settings`.
pub fn grade(
    folder: &Path,
    scenario: &Scenario,
    settings: &RunSettings,
    main: Option<&str>,
) -> std::io::Result<Vec<Grade>> {
    Ok(submissions(folder)?
        .into_iter()
        .map(|submission| grade_one(&submission, scenario, settings, main))
        .collect())
}

fn grade_one(
    submission: &Submission,
    scenario: &Scenario,
    settings: &RunSettings,
    main: Option<&str>,
) -> Grade {
    let refused = |verdict, diagnostics: String| Grade {
        student: submission.student.clone(),
        verdict,
        violations: 0,
        first_violation: String::new(),
        diagnostics,
        simulated_s: 0.0,
    };
    let program = match Program::load(&submission.files, main) {
        Ok(program) => program,
        Err(error @ crate::program::ProgramError::Compile(_)) => {
            return refused(Verdict::DoesNotCompile, error.to_string())
        }
        Err(error) => return refused(Verdict::CannotRun, error.to_string()),
    };
    let report =
        match Session::new(program, settings.clone(), Some(scenario)).and_then(Session::run) {
            Ok(report) => report,
            Err(error) => return refused(Verdict::CannotRun, error.to_string()),
        };
    Grade {
        student: submission.student.clone(),
        verdict: if report.passed {
            Verdict::Passed
        } else {
            Verdict::Failed
        },
        violations: report.violations_total,
        first_violation: report
            .first_violation()
            .map(|v| v.line().trim().to_owned())
            .unwrap_or_default(),
        diagnostics: String::new(),
        simulated_s: report.simulated_s,
    }
}

/// The table as CSV (RFC 4180, a header row).
pub fn csv(grades: &[Grade]) -> Result<String, csv::Error> {
    let mut writer = csv::Writer::from_writer(Vec::new());
    writer.write_record([
        "student",
        "verdict",
        "violations",
        "first violation",
        "diagnostics",
        "simulated s",
    ])?;
    for grade in grades {
        writer.write_record([
            grade.student.as_str(),
            grade.verdict.text(),
            &grade.violations.to_string(),
            &grade.first_violation,
            &grade.diagnostics,
            &format!("{:.1}", grade.simulated_s),
        ])?;
    }
    let bytes = writer.into_inner().map_err(|error| error.into_error())?;
    Ok(String::from_utf8_lossy(&bytes).into_owned())
}

/// The table as a self-contained HTML page titled `title`.
pub fn html(title: &str, grades: &[Grade]) -> String {
    let passed = grades
        .iter()
        .filter(|g| g.verdict == Verdict::Passed)
        .count();
    let mut rows = String::new();
    for grade in grades {
        let class = match grade.verdict {
            Verdict::Passed => "passed",
            Verdict::Failed => "failed",
            Verdict::DoesNotCompile | Verdict::CannotRun => "refused",
        };
        rows.push_str(&format!(
            "<tr class=\"{class}\"><td>{}</td><td>{}</td><td class=\"n\">{}</td><td><code>{}</code></td><td><pre>{}</pre></td></tr>\n",
            escape(&grade.student),
            grade.verdict.text(),
            grade.violations,
            escape(&grade.first_violation),
            escape(&grade.diagnostics),
        ));
    }
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\
<title>{title}</title><style>\
body{{font-family:system-ui,sans-serif;margin:1.5rem}}table{{border-collapse:collapse}}\
td,th{{border:1px solid #bbb;padding:.3rem .5rem;vertical-align:top;text-align:left}}\
td.n{{text-align:right}}tr.passed td:nth-child(2){{color:#176f2c}}\
tr.failed td:nth-child(2),tr.refused td:nth-child(2){{color:#a31515;font-weight:600}}\
pre{{margin:0;white-space:pre-wrap}}</style></head><body>\n\
<h1>{title}</h1>\n<p>{passed} of {} passed.</p>\n<table>\n\
<thead><tr><th>student</th><th>verdict</th><th>violations</th><th>first violation</th><th>diagnostics</th></tr></thead>\n\
<tbody>\n{rows}</tbody></table></body></html>\n",
        grades.len(),
        title = escape(title),
    )
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}
