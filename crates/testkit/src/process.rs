//! Child processes of a test: a command run to its end with a time limit, and long-running
//! children (outstations, stations, simulators) killed when the test lets go of them.
//!
//! Every pipe a helper opens is drained while the child runs: a chatty child never blocks
//! on a full pipe, and a test never hangs on one.

use std::io::{BufRead, BufReader, Read};
use std::process::{Child, Command, Output, Stdio};
use std::sync::mpsc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// How long a started child may take to print its marker.
pub const START_WITHIN: Duration = Duration::from_secs(20);

/// Runs a command to completion with standard input closed, killing it after `seconds`;
/// its output is drained while it runs. Returns the output and whether it finished by
/// itself (`false`: it was killed).
pub fn run_within(mut command: Command, seconds: u64) -> (Output, bool) {
    let mut child = command
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let stdout = drain(Box::new(child.stdout.take().unwrap()));
    let stderr = drain(Box::new(child.stderr.take().unwrap()));
    let deadline = Instant::now() + Duration::from_secs(seconds);
    let mut finished = false;
    while Instant::now() < deadline {
        if child.try_wait().unwrap().is_some() {
            finished = true;
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    if !finished {
        let _ = child.kill();
    }
    let status = child.wait().unwrap();
    let output = Output {
        status,
        stdout: stdout.join().unwrap(),
        stderr: stderr.join().unwrap(),
    };
    (output, finished)
}

/// Runs a command to completion as [`run_within`] does; fails the test (with the command's
/// standard output) when it has not finished within `seconds`.
pub fn run_bounded(command: Command, seconds: u64) -> Output {
    let (output, finished) = run_within(command, seconds);
    assert!(
        finished,
        "command did not finish within {seconds} s; stdout:\n{}",
        String::from_utf8_lossy(&output.stdout)
    );
    output
}

/// Reads a pipe to its end on a thread of its own; the thread's result is what it read.
fn drain(mut pipe: Box<dyn Read + Send>) -> JoinHandle<Vec<u8>> {
    std::thread::spawn(move || {
        let mut bytes = Vec::new();
        let _ = pipe.read_to_end(&mut bytes);
        bytes
    })
}

/// A long-running child (outstation, station, simulator), killed when dropped.
pub struct Background(pub Child);

impl Drop for Background {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Starts a process and waits until a stdout line contains `marker`.
pub fn start_until(command: Command, marker: &str) -> Background {
    start_until_line(command, marker).0
}

/// Starts a process and waits until a stdout line contains `marker`; returns the line.
/// Its standard error is discarded.
pub fn start_until_line(mut command: Command, marker: &str) -> (Background, String) {
    let child = command
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    wait_for_marker(child, marker)
}

/// Starts a process and waits until a stdout line contains `marker`; its standard error
/// is collected until it ends (the thread's result).
pub fn start_until_with_log(
    mut command: Command,
    marker: &str,
) -> (Background, JoinHandle<String>) {
    let mut child = command
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stderr = child.stderr.take().unwrap();
    let log = std::thread::spawn(move || {
        let mut text = String::new();
        let _ = stderr.read_to_string(&mut text);
        text
    });
    (wait_for_marker(child, marker).0, log)
}

/// Waits (at most [`START_WITHIN`]) until a stdout line of `child` contains `marker`;
/// returns the line. The child is killed and the test fails when it never does.
pub fn wait_for_marker(child: Child, marker: &str) -> (Background, String) {
    let (child, line, lines) = wait_for_marker_keeping_output(child, marker);
    // Keep draining so the child never blocks on a full pipe.
    std::thread::spawn(move || for _ in lines {});
    (child, line)
}

/// Starts a process and waits until a stdout line contains `marker`, keeping the lines
/// after it for the test to wait on ([`wait_for_line`]): a simulator's console answers.
pub fn start_until_line_keeping_output(
    mut command: Command,
    marker: &str,
) -> (Background, String, mpsc::Receiver<String>) {
    let child = command
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    wait_for_marker_keeping_output(child, marker)
}

fn wait_for_marker_keeping_output(
    mut child: Child,
    marker: &str,
) -> (Background, String, mpsc::Receiver<String>) {
    let stdout = child.stdout.take().unwrap();
    let (sender, receiver) = mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            if sender.send(line).is_err() {
                break;
            }
        }
    });
    let deadline = Instant::now() + START_WITHIN;
    let mut seen = Vec::new();
    while Instant::now() < deadline {
        if let Ok(line) = receiver.recv_timeout(Duration::from_millis(100)) {
            if line.contains(marker) {
                return (Background(child), line, receiver);
            }
            seen.push(line);
        }
    }
    let _ = child.kill();
    let _ = child.wait();
    panic!("never saw '{marker}'; saw {seen:?}");
}

/// Waits (at most [`START_WITHIN`]) for a line containing `text` among a process's
/// output lines; returns it. The test fails, listing what came, when none does.
pub fn wait_for_line(lines: &mpsc::Receiver<String>, text: &str) -> String {
    let deadline = Instant::now() + START_WITHIN;
    let mut seen = Vec::new();
    while Instant::now() < deadline {
        if let Ok(line) = lines.recv_timeout(Duration::from_millis(100)) {
            if line.contains(text) {
                return line;
            }
            seen.push(line);
        }
    }
    panic!("never saw '{text}'; saw {seen:?}");
}

/// Fails the test, with the command's standard output and error, unless it succeeded;
/// returns its standard output.
pub fn assert_success(output: &Output) -> String {
    assert!(
        output.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
    String::from_utf8_lossy(&output.stdout).into_owned()
}

/// Resident set (KiB, `/proc/PID/status` VmRSS) and CPU time used so far (clock ticks,
/// `/proc/PID/stat` utime + stime; 100 a second on Linux) of a process, for benchmarks
/// that measure another process.
pub fn resident_and_cpu(pid: u32) -> Option<(u64, u64)> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let rss = status
        .lines()
        .find_map(|line| line.strip_prefix("VmRSS:"))?
        .split_whitespace()
        .next()?
        .parse()
        .ok()?;
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // utime and stime: the 12th and 13th fields after the command's closing parenthesis.
    let fields: Vec<&str> = stat.rsplit_once(')')?.1.split_whitespace().collect();
    let utime: u64 = fields.get(11)?.parse().ok()?;
    let stime: u64 = fields.get(12)?.parse().ok()?;
    Some((rss, utime + stime))
}
