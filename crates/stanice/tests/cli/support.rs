//! Helpers of the CLI tests: the `stanice` binary as a command, point files and an IEC 104
//! outstation serving them, ST source files, Vsetín copies, and processes watched line by line.

use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

use testkit::ports::free_port;
use testkit::process::{start_until, Background};
use testkit::projects::{copy_project, vsetin};

pub(crate) fn stanice() -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_stanice"));
    command.stdin(Stdio::null());
    command
}

pub(crate) fn write_points(text: &str) -> PathBuf {
    let path = std::env::temp_dir().join(format!(
        "stanice-cli-{}-{}.csv",
        std::process::id(),
        free_port()
    ));
    std::fs::write(&path, text).unwrap();
    path
}

pub(crate) const POINTS: &str = "ioa,type,value,name\n\
281,M_SP_TB_1,1,FA1 closed\n\
282,M_SP_NA_1,0,FA1.1\n\
2000,M_DP_TB_1,2,breaker\n\
1100,M_ME_NA_1,0.335114,U12\n\
5000,M_ME_NC_1,1904673.75,P\n\
800,M_IT_NA_1,42,energy\n\
2021,C_SC_NA_1,,open QF1\n\
2100,C_DC_NA_1,,breaker command\n\
2101,C_DC_NA_1,,breaker command (select first),\n";

pub(crate) fn outstation(port: u16, extra: &[&str]) -> Background {
    let points = write_points(POINTS);
    let mut command = stanice();
    command
        .args([
            "iec104",
            "server",
            "--listen",
            &format!("127.0.0.1:{port}"),
            "--ca",
            "7",
            "--points",
        ])
        .arg(points)
        .args(extra);
    start_until(command, "IEC 104 outstation on")
}

/// Waits for a spawned child (at most `seconds`), draining its output.
pub(crate) fn wait_bounded(mut child: Child, seconds: u64) -> Output {
    let deadline = Instant::now() + Duration::from_secs(seconds);
    while Instant::now() < deadline {
        if child.try_wait().unwrap().is_some() {
            return child.wait_with_output().unwrap();
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let _ = child.kill();
    let output = child.wait_with_output().unwrap();
    panic!(
        "did not finish within {seconds} s; stdout:\n{}",
        String::from_utf8_lossy(&output.stdout)
    );
}

pub(crate) fn write_source(name: &str, text: &str) -> PathBuf {
    let path = std::env::temp_dir().join(format!("stanice-cli-{}-{name}", std::process::id()));
    std::fs::write(&path, text).unwrap();
    path
}

/// A copy of the Vsetín project in `parent/name`, without its event stores, so that a test
/// runs it from a folder of its own with a relative path.
pub(crate) fn copy_vsetin(parent: &std::path::Path, name: &str) -> PathBuf {
    copy_project(&vsetin(), parent, name)
}

/// Starts a process, waits until a stdout line contains `marker`, and keeps every later
/// stdout line for the test to look at.
pub(crate) fn start_watching(
    mut command: Command,
    marker: &str,
) -> (Background, std::sync::Arc<std::sync::Mutex<Vec<String>>>) {
    let mut child = command
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let stdout = child.stdout.take().unwrap();
    let lines = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
    let collected = std::sync::Arc::clone(&lines);
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            collected.lock().unwrap().push(line);
        }
    });
    let background = Background(child);
    let deadline = Instant::now() + Duration::from_secs(20);
    while !lines
        .lock()
        .unwrap()
        .iter()
        .any(|line| line.contains(marker))
    {
        assert!(
            Instant::now() < deadline,
            "never saw '{marker}'; saw {:?}",
            lines.lock().unwrap()
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    (background, lines)
}

/// Waits (bounded) until one of the lines contains `needle`.
pub(crate) fn wait_for_line(lines: &std::sync::Mutex<Vec<String>>, needle: &str) -> String {
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        if let Some(line) = lines.lock().unwrap().iter().find(|l| l.contains(needle)) {
            return line.clone();
        }
        assert!(
            Instant::now() < deadline,
            "no line with '{needle}' in {:?}",
            lines.lock().unwrap()
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}
