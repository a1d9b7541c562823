//! `stanice plc`: `run` on virtual time with and without the JIT, `check` with file, line
//! and column, and `explain` of the diagnostic codes.

use testkit::process::run_bounded;

use crate::support::*;

#[test]
fn plc_run_prints_the_program_after_n_cycles_on_virtual_time() {
    let source = write_source(
        "lamp.st",
        "PROGRAM Main\nVAR\n  n : INT := 0;\n  t : TON;\n  lamp : BOOL;\n  msg : STRING[20] := 'idle';\n  level : ARRAY[1..2] OF REAL;\nEND_VAR\n\
         n := n + 1;\nt(IN := TRUE, PT := T#50ms);\nlamp := t.Q;\nIF lamp THEN msg := 'lit'; END_IF;\nlevel[2] := INT_TO_REAL(n) / 2.0;\nEND_PROGRAM\n",
    );
    let run = |cycles: &str| {
        let mut command = stanice();
        command.args(["plc", "run"]).arg(&source).args([
            "--program",
            "Main",
            "--cycles",
            cycles,
            "--cycle-ms",
            "10",
        ]);
        let output = run_bounded(command, 20);
        assert!(
            output.status.success(),
            "{}",
            String::from_utf8_lossy(&output.stderr)
        );
        String::from_utf8_lossy(&output.stdout).to_string()
    };
    // Cycle k runs at (k-1) x 10 ms: the 50 ms timer is due exactly on the sixth cycle.
    let five = run("5");
    assert!(
        five.contains("Main.n = 5\n")
            && five.contains("Main.lamp = FALSE\n")
            && five.contains("Main.msg = 'idle'\n"),
        "{five}"
    );
    let six = run("6");
    assert!(
        six.contains("Main.n = 6\n")
            && six.contains("Main.t.Q = TRUE\n")
            && six.contains("Main.t.ET = T#50ms\n"),
        "{six}"
    );
    assert!(
        six.contains("Main.msg = 'lit'\n")
            && six.contains("Main.level[1] = 0.0\n")
            && six.contains("Main.level[2] = 3.0\n"),
        "{six}"
    );

    let mut command = stanice();
    command
        .args(["plc", "run"])
        .arg(&source)
        .args(["--program", "Main", "--set", "Main.n=41"]);
    let output = run_bounded(command, 20);
    assert!(String::from_utf8_lossy(&output.stdout).contains("Main.n = 42\n"));
}

#[test]
fn plc_run_prints_the_same_with_and_without_the_jit() {
    let source = write_source(
        "sort.st",
        "PROGRAM Main\nVAR a : ARRAY[1..6] OF DINT := [5, -3, 9, 0, 9, 1]; i, j, t : DINT; sum : LREAL; END_VAR\n\
         FOR i := 1 TO 5 DO FOR j := 1 TO 6 - i DO\n\
         IF a[j] > a[j + 1] THEN t := a[j]; a[j] := a[j + 1]; a[j + 1] := t; END_IF\n\
         END_FOR END_FOR\nFOR i := 1 TO 6 DO sum := sum + a[i] * 0.5; END_FOR\nEND_PROGRAM\n",
    );
    let run = |extra: &[&str]| {
        let mut command = stanice();
        command
            .args(["plc", "run"])
            .arg(&source)
            .args(["--program", "Main"])
            .args(extra);
        let output = run_bounded(command, 20);
        assert!(
            output.status.success(),
            "{}",
            String::from_utf8_lossy(&output.stderr)
        );
        String::from_utf8_lossy(&output.stdout).to_string()
    };
    let compiled = run(&[]);
    assert!(
        compiled.contains("Main.a[1] = -3\n")
            && compiled.contains("Main.a[6] = 9\n")
            && compiled.contains("Main.sum = 10.5\n"),
        "{compiled}"
    );
    assert_eq!(compiled, run(&["--no-jit"]));
}

#[test]
fn plc_check_reports_file_line_col_and_fails() {
    let good = write_source(
        "good.st",
        "PROGRAM P\nVAR x : INT; END_VAR\nx := x + 1;\nEND_PROGRAM\n",
    );
    let mut command = stanice();
    command.args(["plc", "check"]).arg(&good);
    assert!(run_bounded(command, 20).status.success());

    let bad = write_source(
        "bad.st",
        "PROGRAM P\nVAR x : INT; END_VAR\nx := y + 1;\nx := TRUE;\nEND_PROGRAM\n",
    );
    let mut command = stanice();
    command.args(["plc", "check"]).arg(&bad);
    let output = run_bounded(command, 20);
    assert!(!output.status.success());
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
    assert!(
        text.contains(&format!(
            "{}:3:6: error: undeclared name 'y'",
            bad.display()
        )),
        "{text}"
    );
    assert!(
        text.contains(&format!("{}:4:6: error: type mismatch", bad.display())),
        "{text}"
    );

    let broken = write_source(
        "broken.st",
        "PROGRAM P\nVAR x : INT; END_VAR\nx := (1 + ;\n",
    );
    let mut command = stanice();
    command.args(["plc", "check"]).arg(&broken);
    let output = run_bounded(command, 20);
    assert!(!output.status.success());
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
    assert!(
        text.contains(&format!("{}:3:", broken.display())) && text.contains("error:"),
        "{text}"
    );

    // Windows editors start UTF-8 files with a byte-order mark: accepted. Latin-1 text
    // is refused at its first invalid byte (line 2, after `(* caf`).
    let with_bom = write_source(
        "bom.st",
        "\u{FEFF}PROGRAM P\nVAR x : INT; END_VAR\nx := x + 1;\nEND_PROGRAM\n",
    );
    let mut command = stanice();
    command.args(["plc", "check"]).arg(&with_bom);
    let output = run_bounded(command, 20);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stdout)
    );
    let latin1 = write_source("latin1.st", "");
    std::fs::write(
        &latin1,
        b"PROGRAM P\nVAR x : INT; (* caf\xE9 *) END_VAR\nEND_PROGRAM\n",
    )
    .unwrap();
    let mut command = stanice();
    command.args(["plc", "check"]).arg(&latin1);
    let output = run_bounded(command, 20);
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains(&format!(
            "{}:2:20: error: not UTF-8 text: byte 0xE9",
            latin1.display()
        )),
        "{stderr}"
    );
}

/// `plc check` of one file, its whole output (run in the file's folder so the path is
/// stable), and `plc explain` of the codes it names.
#[test]
fn plc_check_output_and_explain() {
    let file = write_source(
        "explain.st",
        "PROGRAM Main\nVAR small : INT; big : DINT; spare : BOOL; END_VAR\nsmall := big;\nEND_PROGRAM\n",
    );
    let name = file.file_name().unwrap().to_str().unwrap().to_owned();
    let mut command = stanice();
    command
        .current_dir(file.parent().unwrap())
        .args(["plc", "check", &name]);
    let output = run_bounded(command, 20);
    assert_eq!(output.status.code(), Some(1));
    assert_eq!(
        String::from_utf8_lossy(&output.stdout),
        format!(
            "{name}:2:30: warning: variable 'spare' is declared but never used
  |
2 | VAR small : INT; big : DINT; spare : BOOL; END_VAR
  |                              ^^^^^
  = code: W0001
{name}:3:10: error: type mismatch: value of type DINT where INT is expected
  |
3 | small := big;
  |          ^^^
  {name}:2:5: 'small' is declared as INT here
  = note: IEC 61131-3 converts implicitly only to wider types; use an explicit *_TO_* conversion
  = code: E0201
"
        )
    );

    // the page of the code, in any case
    let mut command = stanice();
    command.args(["plc", "explain", "e0201"]);
    let output = run_bounded(command, 20);
    assert!(output.status.success());
    let page = String::from_utf8_lossy(&output.stdout);
    assert!(page.starts_with("# E0201: type mismatch"), "{page}");
    assert!(page.contains("## Example of the mistake") && page.contains("DINT_TO_INT"));

    // every code listed
    let mut command = stanice();
    command.args(["plc", "explain", "--list"]);
    let output = run_bounded(command, 20);
    assert!(output.status.success());
    let list = String::from_utf8_lossy(&output.stdout);
    assert!(
        list.lines().any(|l| l.starts_with("E0401  run-time fault")),
        "{list}"
    );
    assert!(list.lines().any(|l| l.starts_with("W0001  ")), "{list}");

    // an unknown code: exit 2 and the list
    let mut command = stanice();
    command.args(["plc", "explain", "E9999"]);
    let output = run_bounded(command, 20);
    assert_eq!(output.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("no diagnostic code 'E9999'") && stderr.contains("E0201  type mismatch"),
        "{stderr}"
    );
    let _ = std::fs::remove_file(&file);
}
