//! Every command of README.md's `sh` blocks, run as written from the repository root with
//! the `stanice` binary under test: what a newcomer types first has to work.
//!
//! One-shot commands must exit 0. Long-running ones (a station, the demo, an outstation, a
//! client, the HMI) must show a sign of life (a line of output and, for a server, its
//! listening port), still be running after it, and stop cleanly on Ctrl-C (SIGINT). A client
//! or a command runs against the outstation the README starts just before it.
//!
//! The README's commands use its fixed ports (2404, 8080), so they run one after another,
//! and this is a test binary of its own: cargo runs test binaries one at a time, so no other
//! test of this crate runs beside it.

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

use std::io::{BufRead as _, BufReader, Read};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::mpsc::{channel, Receiver};
use std::time::{Duration, Instant};

use testkit::repository_root;

/// README lines that are not run, each with the reason.
const SKIPPED: &[(&str, &str)] = &[
    (
        "bash scripts/test.sh",
        "the whole test suite, this test included; it also installs packages",
    ),
    (
        "cargo bench -p iec60870 --bench iec104_vs_c104",
        "a benchmark: a release build and minutes of measurement, and it needs c104",
    ),
    (
        "cargo bench -p plc --bench st_vs_native",
        "a benchmark: a release build and minutes of measurement",
    ),
    (
        "cargo bench -p plc --bench scan_jitter",
        "a benchmark: a release build and 100 s of real-time scans",
    ),
    (
        "cargo bench -p iec60870 --bench ft12_polling",
        "a benchmark: a release build and minutes of measurement",
    ),
    (
        "cargo bench -p station --bench latency",
        "a benchmark: a release build and minutes of measurement",
    ),
    (
        "cargo bench -p store --bench store",
        "a benchmark: a release build and minutes of measurement",
    ),
    (
        "cargo bench -p lab --bench hour",
        "a benchmark: a release build and a simulated hour of each lab model",
    ),
    (
        "cargo bench -p sorting --bench mechanism",
        "a benchmark: a release build and 1,000 simulated sortings (`stanice sorting reliability --sortings 100`, run above, is the same measurement, shorter)",
    ),
    (
        "cargo bench -p s7 --bench throughput",
        "a benchmark: a release build and seconds of measurement against python-snap7",
    ),
    (
        "cargo bench -p modbus --bench throughput",
        "a benchmark: a release build and seconds of measurement against pymodbus",
    ),
    (
        "cargo bench -p hmi --bench live",
        "a benchmark: a release build and headless Chromium",
    ),
    (
        "cargo bench -p station --bench lift_fleet",
        "a benchmark: a release build and a minute of 200 lifts polled in real time",
    ),
    (
        "cargo bench -p store --bench historian",
        "a benchmark: a release build, a table of a million events and more, and PostgreSQL",
    ),
    (
        "cargo bench -p sparkplug --bench throughput",
        "a benchmark: a release build and a mosquitto broker",
    ),
    (
        "cargo bench -p stanice --bench master_many",
        "a benchmark: a release build, 1,000 outstations and a master process for half a minute",
    ),
    (
        "cargo bench -p stanice --bench vsetin_soak",
        "a benchmark: a release build and most of an hour of the whole station at speed",
    ),
    (
        "cargo bench -p stanice --bench vsetin_processes",
        "a benchmark: a release build and 23 node processes for half a minute on the project's ports moved",
    ),
    (
        "cargo bench -p hmi --bench lift_fleet",
        "a benchmark: a release build, 200 lifts in real time and headless Chromium",
    ),
];

/// Generous bounds: the machine may be busy building or testing something else.
const START_TIMEOUT: Duration = Duration::from_secs(180);
const ONE_SHOT_TIMEOUT: Duration = Duration::from_secs(120);
const STOP_TIMEOUT: Duration = Duration::from_secs(30);
const PORT_FREE_TIMEOUT: Duration = Duration::from_secs(60);

/// Splits a command line into words as a POSIX shell does for the simple lines of the
/// README: blanks separate words, single and double quotes group, a `#` starting a word
/// starts a comment.
fn shell_words(line: &str) -> Vec<String> {
    let mut words = Vec::new();
    let mut word: Option<String> = None;
    let mut chars = line.chars();
    while let Some(c) = chars.next() {
        match c {
            ' ' | '\t' => {
                if let Some(done) = word.take() {
                    words.push(done);
                }
            }
            '#' if word.is_none() => break,
            '\'' => {
                let word = word.get_or_insert_with(String::new);
                for c in chars.by_ref() {
                    if c == '\'' {
                        break;
                    }
                    word.push(c);
                }
            }
            '"' => {
                let word = word.get_or_insert_with(String::new);
                while let Some(c) = chars.next() {
                    match c {
                        '"' => break,
                        '\\' => word.extend(chars.next()),
                        c => word.push(c),
                    }
                }
            }
            '\\' => word.get_or_insert_with(String::new).extend(chars.next()),
            c => word.get_or_insert_with(String::new).push(c),
        }
    }
    words.extend(word);
    words
}

/// The command lines of the README's `sh` blocks, as words, comments dropped.
fn readme_commands(readme: &str) -> Vec<Vec<String>> {
    let mut commands = Vec::new();
    let mut in_sh = false;
    for line in readme.lines() {
        let trimmed = line.trim();
        if in_sh {
            if trimmed.starts_with("```") {
                in_sh = false;
                continue;
            }
            let words = shell_words(trimmed);
            if !words.is_empty() {
                commands.push(words);
            }
        } else if trimmed == "```sh" {
            in_sh = true;
        }
    }
    commands
}

/// The arguments of `stanice` in a README line: `stanice ARGS` or
/// `cargo run ... -p stanice ... -- ARGS`; `None` for any other program.
fn stanice_arguments(words: &[String]) -> Option<Vec<String>> {
    match words {
        [first, rest @ ..] if first == "stanice" => Some(rest.to_vec()),
        [cargo, run, rest @ ..] if cargo == "cargo" && run == "run" => {
            let split = rest
                .iter()
                .position(|w| w == "--")
                .unwrap_or_else(|| panic!("`{}`: no `--` before the arguments", words.join(" ")));
            assert!(
                rest[..split]
                    .windows(2)
                    .any(|w| w[0] == "-p" && w[1] == "stanice"),
                "`{}` does not run the stanice package",
                words.join(" ")
            );
            Some(rest[split + 1..].to_vec())
        }
        _ => None,
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    /// Runs until stopped (Ctrl-C).
    LongRunning,
    /// Runs until stopped, and the clients and commands after it talk to it.
    Outstation,
    /// Talks to the outstation started before it, until stopped.
    Client,
    /// Talks to the outstation started before it, then exits.
    PeerOneShot,
    /// Exits by itself.
    OneShot,
}

fn kind(arguments: &[String]) -> Kind {
    let words: Vec<&str> = arguments.iter().map(String::as_str).collect();
    match words.as_slice() {
        ["run" | "demo" | "hmi", ..] | ["lab", "serve", ..] => Kind::LongRunning,
        ["iec104", "server", ..]
        | ["lift", "simulate", ..]
        | ["s7", "serve", ..]
        | ["modbus", "serve", ..] => Kind::Outstation,
        ["iec104", "client", ..] => Kind::Client,
        ["iec104", "command", ..]
        | ["lift", "poll", ..]
        | ["s7", "read" | "write", ..]
        | ["modbus", "read" | "write", ..] => Kind::PeerOneShot,
        _ => Kind::OneShot,
    }
}

/// The address a long-running command listens on, if it serves: `--listen ADDR`, or the
/// top node of the Vsetín project (port_base 2404) for `run` and `demo`.
fn listen_address(arguments: &[String]) -> Option<SocketAddr> {
    if let Some(i) = arguments.iter().position(|a| a == "--listen") {
        return Some(arguments[i + 1].parse().unwrap());
    }
    match arguments.first().map(String::as_str) {
        Some("demo") => Some(SocketAddr::from(([127, 0, 0, 1], 2404))),
        // `stanice lab serve`'s default
        Some("lab") => Some(SocketAddr::from(([127, 0, 0, 1], 8090))),
        Some("run") => Some(SocketAddr::from((
            [127, 0, 0, 1],
            arguments.get(1).map_or(2404, |project| port_base(project)),
        ))),
        _ => None,
    }
}

/// The `port_base` of a project's station.toml (2404 when it sets none): where `stanice
/// run PROJECT` serves its top node.
fn port_base(project: &str) -> u16 {
    let text = std::fs::read_to_string(repository_root().join(project).join("station.toml"))
        .unwrap_or_default();
    text.lines()
        .filter_map(|line| line.trim().strip_prefix("port_base"))
        .filter_map(|rest| rest.trim().strip_prefix('='))
        .find_map(|value| value.split('#').next()?.trim().parse().ok())
        .unwrap_or(2404)
}

/// Waits until `address` can be bound: the previous command's server has let it go and
/// nobody else on the machine holds it.
fn wait_port_free(address: SocketAddr) {
    let deadline = Instant::now() + PORT_FREE_TIMEOUT;
    while TcpListener::bind(address).is_err() {
        assert!(
            Instant::now() < deadline,
            "{address} stays in use: the README's commands need it"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
}

/// A command running in the background, its output collected line by line.
struct Running {
    line: String,
    child: Child,
    lines: Receiver<String>,
    seen: Vec<String>,
}

impl Running {
    fn start(line: &str, arguments: &[String]) -> Running {
        let mut child = Command::new(env!("CARGO_BIN_EXE_stanice"))
            .args(arguments)
            .current_dir(repository_root())
            // Kept open, as a terminal's: the station's console waits on it.
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let (sender, lines) = channel();
        let stdout = child.stdout.take().unwrap();
        let stderr = child.stderr.take().unwrap();
        for pipe in [
            Box::new(stdout) as Box<dyn Read + Send>,
            Box::new(stderr) as Box<dyn Read + Send>,
        ] {
            let sender = sender.clone();
            // Drains the pipe to its end, so the child never blocks on a full one.
            std::thread::spawn(move || {
                for line in BufReader::new(pipe).lines().map_while(Result::ok) {
                    let _ = sender.send(line);
                }
            });
        }
        Running {
            line: line.to_owned(),
            child,
            lines,
            seen: Vec::new(),
        }
    }

    fn collect(&mut self) {
        let lines: Vec<String> = self.lines.try_iter().collect();
        self.seen.extend(lines);
    }

    fn output(&mut self) -> String {
        if self.exited().is_some() {
            // The pipes end with the process: wait for its last lines.
            while let Ok(line) = self.lines.recv_timeout(Duration::from_secs(5)) {
                self.seen.push(line);
            }
        } else {
            self.collect();
        }
        self.seen.join("\n")
    }

    /// Fails the test with what the command printed.
    fn fail(&mut self, what: &str) -> ! {
        let output = self.output();
        panic!("`{}` {what}:\n{output}", self.line)
    }

    fn exited(&mut self) -> Option<ExitStatus> {
        self.child.try_wait().unwrap()
    }

    /// Waits for a line of output and, for a server, a connection to its port.
    fn wait_for_life(&mut self, listen: Option<SocketAddr>) {
        let deadline = Instant::now() + START_TIMEOUT;
        loop {
            if let Some(status) = self.exited() {
                self.fail(&format!("ended while starting ({status})"));
            }
            if let Ok(line) = self.lines.recv_timeout(Duration::from_millis(100)) {
                self.seen.push(line);
            }
            let serving = listen.is_none_or(|address| {
                TcpStream::connect_timeout(&address, Duration::from_millis(200)).is_ok()
            });
            if !self.seen.is_empty() && serving {
                break;
            }
            if Instant::now() > deadline {
                self.fail(&format!("showed no sign of life within {START_TIMEOUT:?}"));
            }
        }
        if let Some(status) = self.exited() {
            self.fail(&format!("ended after starting ({status})"));
        }
    }

    /// Ctrl-C, as in a terminal; the command must stop cleanly.
    fn interrupt(mut self) {
        let status = Command::new("kill")
            .args(["-INT", &self.child.id().to_string()])
            .status()
            .unwrap();
        assert!(status.success());
        let deadline = Instant::now() + STOP_TIMEOUT;
        let status = loop {
            if let Some(status) = self.exited() {
                break status;
            }
            if Instant::now() > deadline {
                let _ = self.child.kill();
                let _ = self.child.wait();
                self.fail(&format!("did not stop within {STOP_TIMEOUT:?} of Ctrl-C"));
            }
            std::thread::sleep(Duration::from_millis(20));
        };
        if !status.success() {
            self.fail(&format!("failed on Ctrl-C ({status})"));
        }
    }
}

impl Drop for Running {
    fn drop(&mut self) {
        // After a failed assertion: never leave a process holding the README's ports.
        if self.exited().is_none() {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}

fn run_one_shot(line: &str, arguments: &[String]) {
    let mut running = Running::start(line, arguments);
    // Nothing for it on standard input: a one-shot command must not wait for it.
    drop(running.child.stdin.take());
    let deadline = Instant::now() + ONE_SHOT_TIMEOUT;
    let status = loop {
        if let Some(status) = running.exited() {
            break status;
        }
        if Instant::now() > deadline {
            running.fail(&format!("did not finish within {ONE_SHOT_TIMEOUT:?}"));
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    if !status.success() {
        running.fail(&format!("failed ({status})"));
    }
}

/// Files a README command leaves in the repository root that are no part of it: the web
/// HMI's default event store is `hmi-events.sqlite` in the current directory.
fn stray_files(root: &Path) -> Vec<PathBuf> {
    [
        "hmi-events.sqlite",
        "hmi-events.sqlite-wal",
        "hmi-events.sqlite-shm",
    ]
    .iter()
    .map(|name| root.join(name))
    .filter(|path| path.exists())
    .collect()
}

#[test]
fn shell_words_split_like_a_shell() {
    assert_eq!(
        shell_words("stanice events examples/vsetin --point 'RH2_*'   # comment"),
        ["stanice", "events", "examples/vsetin", "--point", "RH2_*"]
    );
    assert_eq!(shell_words("a \"b c\" d#e # f"), ["a", "b c", "d#e"]);
    assert_eq!(shell_words("# only a comment"), Vec::<String>::new());
}

/// The README's commands and the examples' use the same fixed ports: one test at a time.
static FIXED_PORTS: std::sync::Mutex<()> = std::sync::Mutex::new(());

#[test]
fn every_readme_command_works_as_written() {
    let _ports = FIXED_PORTS
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    let root = repository_root();
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let commands = readme_commands(&readme);
    assert!(commands.len() >= 10, "{commands:?}");
    let strays_before = stray_files(&root);

    let mut outstation: Option<Running> = None;
    let mut ran = 0;
    for words in &commands {
        let line = words.join(" ");
        let Some(arguments) = stanice_arguments(words) else {
            let Some((_, reason)) = SKIPPED.iter().find(|(skipped, _)| *skipped == line) else {
                panic!(
                    "README command `{line}` is neither run nor listed in SKIPPED with a reason"
                );
            };
            eprintln!("README: {line} skipped: {reason}");
            continue;
        };
        let kind = kind(&arguments);
        eprintln!("README: {line} ({kind:?})");
        if matches!(kind, Kind::Client | Kind::PeerOneShot) {
            let server = outstation.as_mut().unwrap_or_else(|| {
                panic!("`{line}` needs the outstation the README starts before it")
            });
            if server.exited().is_some() {
                server.fail("ended before its clients ran");
            }
        } else if let Some(server) = outstation.take() {
            // The outstation's clients are done: it gives the port back to what follows.
            server.interrupt();
        }
        match kind {
            Kind::OneShot | Kind::PeerOneShot => run_one_shot(&line, &arguments),
            Kind::LongRunning | Kind::Outstation | Kind::Client => {
                let listen = listen_address(&arguments);
                if let Some(address) = listen {
                    wait_port_free(address);
                }
                let mut running = Running::start(&line, &arguments);
                running.wait_for_life(listen);
                if kind == Kind::Outstation {
                    outstation = Some(running);
                } else {
                    running.interrupt();
                }
            }
        }
        ran += 1;
    }
    if let Some(server) = outstation.take() {
        server.interrupt();
    }
    for path in stray_files(&root) {
        if !strays_before.contains(&path) {
            let _ = std::fs::remove_file(path);
        }
    }
    assert!(ran >= 10, "only {ran} README commands ran");
}

/// The commands an example's header suggests: the `#   stanice ...` lines of the comment
/// block that opens its station.toml.
fn header_commands(text: &str) -> Vec<Vec<String>> {
    text.lines()
        .take_while(|line| line.starts_with('#') || line.trim().is_empty())
        .filter_map(|line| line.strip_prefix('#'))
        .map(str::trim)
        .filter(|line| line.starts_with("stanice "))
        .map(shell_words)
        .collect()
}

/// Runs a one-shot command that talks to a station just started, until it succeeds: the
/// station's devices come up a moment after its port (a simulated relay's first poll), so
/// a command may be refused at first. Bounded; the last failure fails the test.
fn run_until_accepted(line: &str, arguments: &[String]) {
    let deadline = Instant::now() + ONE_SHOT_TIMEOUT;
    loop {
        let output = Command::new(env!("CARGO_BIN_EXE_stanice"))
            .args(arguments)
            .current_dir(repository_root())
            .stdin(Stdio::null())
            .output()
            .unwrap();
        if output.status.success() {
            return;
        }
        assert!(
            Instant::now() < deadline,
            "`{line}` failed ({}):\n{}\n{}",
            output.status,
            String::from_utf8_lossy(&output.stdout),
            String::from_utf8_lossy(&output.stderr)
        );
        std::thread::sleep(Duration::from_millis(500));
    }
}

/// Every command the examples' headers suggest works as written, in order: servers and
/// stations stay up for the commands after them; a command gets a positive confirmation.
#[test]
fn every_example_header_command_works_as_written() {
    let _ports = FIXED_PORTS
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    let root = repository_root();
    let strays_before = stray_files(&root);
    let mut examples: Vec<PathBuf> = std::fs::read_dir(root.join("examples"))
        .unwrap()
        .flatten()
        .map(|entry| entry.path().join("station.toml"))
        .filter(|path| path.is_file())
        .collect();
    examples.sort();
    let mut ran = 0;
    for example in &examples {
        let text = std::fs::read_to_string(example).unwrap();
        let mut background: Vec<Running> = Vec::new();
        for words in header_commands(&text) {
            let line = words.join(" ");
            let arguments = stanice_arguments(&words).unwrap();
            eprintln!("{}: {line}", example.display());
            let plain: Vec<&str> = arguments.iter().map(String::as_str).collect();
            match plain.as_slice() {
                ["iec104", "command", ..] | ["iec104", "client", .., "--exit-after-gi"] => {
                    run_until_accepted(&line, &arguments)
                }
                ["iec104", "client", ..] => {
                    let mut client = Running::start(&line, &arguments);
                    client.wait_for_life(None);
                    client.interrupt();
                }
                ["run" | "iec101" | "iec103" | "iec104" | "lift" | "hmi", ..]
                    if kind(&arguments) != Kind::OneShot
                        || matches!(
                            plain.as_slice(),
                            ["iec101" | "iec103", "slave" | "relay", ..]
                        ) =>
                {
                    let listen = listen_address(&arguments);
                    if let Some(address) = listen {
                        wait_port_free(address);
                    }
                    let mut running = Running::start(&line, &arguments);
                    running.wait_for_life(listen);
                    background.push(running);
                }
                _ => run_one_shot(&line, &arguments),
            }
            ran += 1;
        }
        // The station first, then what it was connected to.
        while let Some(running) = background.pop() {
            running.interrupt();
        }
    }
    for path in stray_files(&root) {
        if !strays_before.contains(&path) {
            let _ = std::fs::remove_file(path);
        }
    }
    assert!(ran >= 8, "only {ran} example header commands ran");
}

/// The command the demo's banner suggests to dispatch is accepted (it suggested one that
/// the station refused from dispatch), and the banner names the program that runs.
#[test]
fn the_demo_banner_suggests_a_command_dispatch_may_send() {
    let _ports = FIXED_PORTS
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    let arguments = vec!["demo".to_owned()];
    let listen = listen_address(&arguments);
    if let Some(address) = listen {
        wait_port_free(address);
    }
    let mut demo = Running::start("stanice demo", &arguments);
    demo.wait_for_life(listen);
    let deadline = Instant::now() + START_TIMEOUT;
    let suggestion = loop {
        let output = demo.output();
        if let Some(line) = output
            .lines()
            .find(|line| line.contains(" iec104 command "))
        {
            break line.to_owned();
        }
        if Instant::now() > deadline {
            demo.fail("suggests no command");
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    let words = shell_words(suggestion.trim());
    assert_eq!(
        words[0],
        env!("CARGO_BIN_EXE_stanice"),
        "the banner names the running program: {suggestion}"
    );
    run_until_accepted(&suggestion, &words[1..]);
    demo.interrupt();
}
