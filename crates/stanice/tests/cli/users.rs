//! `stanice user`: the password read twice without echo on a terminal, and the users file
//! it edits.

use std::process::{Command, Output, Stdio};

use testkit::process::{assert_success, run_bounded};
use testkit::projects::fresh_dir;

use crate::support::*;

/// Runs `command` with `input` on its standard input.
fn run_with_input(mut command: Command, input: &str) -> Output {
    let mut child = command
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    {
        use std::io::Write as _;
        let mut stdin = child.stdin.take().unwrap();
        stdin.write_all(input.as_bytes()).unwrap();
    }
    child.wait_with_output().unwrap()
}

/// Runs `args` of the stanice binary on a new pseudo-terminal (its controlling terminal
/// and standard input, as a person's shell gives it), typing each of `lines` after the
/// prompt before it appears; returns everything the terminal showed and the exit code.
fn on_a_terminal(args: &[&str], prompts_and_lines: &[(&str, &str)]) -> (String, i32) {
    const SCRIPT: &str = r#"
import os, pty, select, sys, termios, time, json
program, args, steps = sys.argv[1], json.loads(sys.argv[2]), json.loads(sys.argv[3])
pid, fd = pty.fork()
if pid == 0:
    os.execv(program, [program] + args)
shown = b""
def read_until(marker, limit):
    global shown
    end = time.time() + limit
    while (marker is None or marker.encode() not in shown) and time.time() < end:
        ready, _, _ = select.select([fd], [], [], 0.1)
        if ready:
            try:
                chunk = os.read(fd, 4096)
            except OSError:
                return
            if not chunk:
                return
            shown += chunk
def echo_off(limit):
    # A program turns echo off after its prompt: type only once it has, as a person
    # would, so that nothing typed is echoed by the terminal before that.
    end = time.time() + limit
    while time.time() < end:
        if not termios.tcgetattr(fd)[3] & termios.ECHO:
            return
        time.sleep(0.01)
for prompt, line in steps:
    read_until(prompt, 30)
    echo_off(5)
    os.write(fd, (line + "\r").encode())
read_until(None, 30)
_, status = os.waitpid(pid, 0)
sys.stdout.write(shown.decode("utf-8", "replace"))
sys.exit(os.waitstatus_to_exitcode(status))
"#;
    let steps: Vec<[&str; 2]> = prompts_and_lines.iter().map(|(p, l)| [*p, *l]).collect();
    let mut python = Command::new("python3");
    python
        .args(["-c", SCRIPT, env!("CARGO_BIN_EXE_stanice")])
        .arg(serde_json::to_string(args).unwrap())
        .arg(serde_json::to_string(&steps).unwrap())
        .stdin(Stdio::null());
    let output = run_bounded(python, 90);
    (
        String::from_utf8_lossy(&output.stdout).into_owned(),
        output.status.code().unwrap_or(-1),
    )
}

/// On a terminal `stanice user add` asks for the password twice and never echoes it; two
/// passwords that differ change nothing.
#[test]
fn user_add_reads_the_password_twice_without_echo_on_a_terminal() {
    let dir = fresh_dir("users-tty");
    let users = dir.join("users.toml");
    let users_arg = users.to_str().unwrap();
    let (shown, code) = on_a_terminal(
        &["user", "add", "carol", "--level", "2", "--users", users_arg],
        &[
            ("password: ", "carol-typed-secret"),
            ("again: ", "carol-typed-secret"),
        ],
    );
    assert_eq!(code, 0, "{shown}");
    assert!(
        !shown.contains("carol-typed-secret"),
        "the password was echoed:\n{shown}"
    );
    assert!(shown.contains("user carol added"), "{shown}");
    let file = std::fs::read_to_string(&users).unwrap();
    assert!(
        file.contains("carol") && !file.contains("carol-typed-secret"),
        "{file}"
    );

    let (shown, code) = on_a_terminal(
        &["user", "add", "dave", "--level", "2", "--users", users_arg],
        &[
            ("password: ", "one-password"),
            ("again: ", "another-password"),
        ],
    );
    assert_ne!(code, 0, "{shown}");
    assert!(shown.contains("differ"), "{shown}");
    assert!(!std::fs::read_to_string(&users).unwrap().contains("dave"));
}

/// `stanice user` edits the users file it is given, or the project's; without either it
/// refuses instead of writing `./users.toml` that no HMI reads.
#[test]
fn user_commands_need_a_users_file_or_a_project() {
    let dir = fresh_dir("users");
    let mut add = stanice();
    add.current_dir(&dir)
        .args(["user", "add", "alice", "--level", "3"]);
    let output = run_with_input(add, "alice-secret\n");
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("--users") && stderr.contains("--project"),
        "{stderr}"
    );
    assert!(!dir.join("users.toml").exists());

    let mut not_a_project = stanice();
    not_a_project
        .current_dir(&dir)
        .args(["user", "list", "--project", "."]);
    let output = run_bounded(not_a_project, 30);
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("not a project folder"), "{stderr}");

    copy_vsetin(&dir, "proj");
    let mut add = stanice();
    add.current_dir(&dir)
        .args(["user", "add", "alice", "--level", "3", "--project", "proj"]);
    let text = assert_success(&run_with_input(add, "alice-secret\n"));
    assert!(text.contains("proj/hmi/users.toml"), "{text}");
    let mut list = stanice();
    list.current_dir(&dir)
        .args(["user", "list", "--project", "proj"]);
    let text = assert_success(&run_bounded(list, 30));
    assert!(text.lines().any(|l| l == "alice\t3"), "{text}");
    assert!(text.lines().any(|l| l.starts_with("operator\t")), "{text}");
    assert!(!dir.join("users.toml").exists());

    let users = dir.join("elsewhere.toml");
    let mut add = stanice();
    add.current_dir(&dir)
        .args(["user", "add", "bob", "--level", "0", "--users"])
        .arg(&users);
    assert_success(&run_with_input(add, "bob-secret\n"));
    assert!(std::fs::read_to_string(&users).unwrap().contains("bob"));
}
