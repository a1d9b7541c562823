//! Interoperability of the relay simulator with an IEC 103 master that is not ours:
//! hat-drivers' (`hat.drivers.iec103` over its FT1.2 link layer and serial driver, from
//! PyPI) opens `stanice iec103 relay --pty` as a serial port, synchronises the relay's
//! clock, runs a general interrogation, reads the cyclic measurands and opens the breaker
//! by a general command (issue 22: ASDU 9 with SQ = 1 made an independent master drop the
//! connection; the relay now sends SQ = 0, VSQ 0x09 for nine measurands).
//!
//! The master runs in `tests/peer/hat103_master.py`. Without hat-drivers the test says so
//! and passes, unless `STANICE_REQUIRE_PEERS=1` (set by `scripts/test.sh`, hence in CI),
//! where a missing peer fails it.

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Output, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use serde_json::Value;

/// The peer script.
fn hat_master_script() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/peer/hat103_master.py")
}

/// Whether hat-drivers' IEC 103 master and serial driver import; panics when they must
/// (CI) and do not.
fn hat_available() -> bool {
    let imported = Command::new("python3")
        .args(["-c", "import hat.drivers.iec103, hat.drivers.serial"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|status| status.success());
    if imported {
        return true;
    }
    let message =
        "interoperability peer missing (hat-drivers for python3); run scripts/install-test-deps.sh";
    if std::env::var("STANICE_REQUIRE_PEERS").as_deref() == Ok("1") {
        panic!("{message}");
    }
    eprintln!("SKIPPED: {message}");
    false
}

/// `stanice iec103 relay --pty`, killed when dropped. Its stdout and stderr are drained
/// all the time (a full pipe would block it) and kept for the assertions and failure
/// messages; its console stays open on a pipe.
struct Relay {
    child: Child,
    output: Arc<Mutex<Vec<String>>>,
    _console: ChildStdin,
    path: String,
}

impl Relay {
    fn start(args: &[&str]) -> Relay {
        let mut child = Command::new(env!("CARGO_BIN_EXE_stanice"))
            .args(["iec103", "relay", "--pty"])
            .args(args)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let output = Arc::new(Mutex::new(Vec::new()));
        for pipe in [
            Box::new(child.stdout.take().unwrap()) as Box<dyn Read + Send>,
            Box::new(child.stderr.take().unwrap()),
        ] {
            let sink = Arc::clone(&output);
            std::thread::spawn(move || {
                for line in BufReader::new(pipe).lines().map_while(Result::ok) {
                    sink.lock().unwrap().push(line);
                }
            });
        }
        let console = child.stdin.take().unwrap();
        let mut relay = Relay {
            child,
            output,
            _console: console,
            path: String::new(),
        };
        let deadline = Instant::now() + Duration::from_secs(30);
        while Instant::now() < deadline {
            if let Some(path) = relay.lines().iter().find_map(|line| {
                line.strip_prefix("pty: ")
                    .map(|path| path.trim().to_owned())
            }) {
                relay.path = path;
                return relay;
            }
            if let Ok(Some(status)) = relay.child.try_wait() {
                // Exited: let the pipes drain its last words.
                std::thread::sleep(Duration::from_millis(200));
                panic!(
                    "the relay exited ({status}) before its pty:\n{}",
                    relay.tail()
                );
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        panic!("the relay printed no pty within 30 s:\n{}", relay.tail());
    }

    fn lines(&self) -> Vec<String> {
        self.output.lock().unwrap().clone()
    }

    /// Waits up to `seconds` for a line of the relay's log containing `needle`.
    fn wait_for_line(&self, needle: &str, seconds: u64) -> bool {
        let deadline = Instant::now() + Duration::from_secs(seconds);
        loop {
            if self.lines().iter().any(|line| line.contains(needle)) {
                return true;
            }
            if Instant::now() >= deadline {
                return false;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// The last lines it printed, for failure messages.
    fn tail(&self) -> String {
        let lines = self.lines();
        lines[lines.len().saturating_sub(40)..].join("\n")
    }
}

impl Drop for Relay {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Runs a command to completion, killing it after `seconds`. Its output is drained while
/// it runs, so a chatty command never blocks on a full pipe. Returns its output and
/// whether it finished by itself.
fn run_bounded(mut command: Command, seconds: u64) -> (Output, bool) {
    let mut child = command
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let drain = |mut pipe: Box<dyn Read + Send>| {
        std::thread::spawn(move || {
            let mut bytes = Vec::new();
            let _ = pipe.read_to_end(&mut bytes);
            bytes
        })
    };
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

/// The REF630's general interrogation (FUN, INF, position) as the relay starts: truck in
/// SERVICE, breaker closed, earth switch open, LOCAL/REMOTE in REMOTE.
const GI_POSITIONS: [(u64, u64, &str); 5] = [
    (5, 9, "OFF"),
    (5, 10, "ON"),
    (1, 160, "ON"),
    (1, 168, "OFF"),
    (1, 190, "OFF"),
];

/// hat-drivers' master on the relay's pseudo-terminal (8N1: a pty keeps no parity):
/// link reset, clock sync, GI to its termination, two cyclic ASDUs 9 of nine measurands
/// at FUN 1 INF 148 with SQ = 0, and the breaker (FUN 1 INF 160) opened by a general
/// command, confirmed positively and followed by its new position; the master never drops
/// the connection and the relay logs every step.
#[test]
fn hat_drivers_master_interrogates_and_commands_the_relay() {
    if !hat_available() {
        return;
    }
    // Measurands every second, at rated current and voltage (I = 1/2.4, U = 1/1.2 of the
    // REF630's limits).
    let mut relay = Relay::start(&["--address", "1", "--cycle", "1", "--inject", "1,1"]);
    let mut master = Command::new("python3");
    master
        .arg(hat_master_script())
        .arg(&relay.path)
        .args(["--address", "1", "--parity", "none", "--timeout", "30"])
        .args(["--measurands", "2", "--time-sync", "--command", "1,160,off"]);
    let (output, finished) = run_bounded(master, 60);
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    let context = format!(
        "master stdout:\n{stdout}\nmaster stderr:\n{stderr}\nrelay:\n{}",
        relay.tail()
    );
    assert!(finished, "the master ran past its own timeout\n{context}");
    assert!(
        output.status.success(),
        "the master failed ({})\n{context}",
        output.status
    );
    let events: Vec<Value> = stdout
        .lines()
        .map(|line| {
            serde_json::from_str(line)
                .unwrap_or_else(|error| panic!("not JSON ({error}): {line}\n{context}"))
        })
        .collect();
    let of = |kind: &str| -> Vec<&Value> {
        events
            .iter()
            .filter(|event| event["event"] == kind)
            .collect()
    };
    assert!(of("error").is_empty(), "{context}");
    assert_eq!(of("ready").len(), 1, "{context}");
    assert_eq!(of("connected").len(), 1, "{context}");

    // The general interrogation: every position with cause 9, after the clock sync with a
    // valid time tag, then the termination.
    assert_eq!(of("time_sync_sent").len(), 1, "{context}");
    assert_eq!(of("gi_done").len(), 1, "{context}");
    let gi: Vec<&Value> = of("data")
        .into_iter()
        .filter(|data| data["cause"] == "GENERAL_INTERROGATION")
        .collect();
    let positions: Vec<(u64, u64, &str)> = gi
        .iter()
        .map(|data| {
            assert_eq!(data["asdu"], 1, "{context}");
            assert_eq!(data["ca"], 1, "{context}");
            assert_eq!(data["invalid_time"], false, "{context}");
            (
                data["fun"].as_u64().unwrap(),
                data["inf"].as_u64().unwrap(),
                data["value"].as_str().unwrap(),
            )
        })
        .collect();
    assert_eq!(positions, GI_POSITIONS, "{context}");

    // The measurands: on the wire, VSQ 0x09 (SQ = 0, nine elements) and 6 + 9 * 2 octets;
    // hat decodes each as one information object at FUN 1 INF 148 with nine values.
    let raw9: Vec<&Value> = of("asdu")
        .into_iter()
        .filter(|asdu| asdu["type"] == 9)
        .collect();
    assert!(raw9.len() >= 2, "{context}");
    for asdu in &raw9 {
        assert_eq!(asdu["vsq"], 0x09, "{context}");
        assert_eq!((&asdu["fun"], &asdu["inf"]), (&1.into(), &148.into()));
        assert_eq!(
            asdu["hex"].as_str().unwrap().len(),
            2 * (6 + 9 * 2),
            "{asdu}"
        );
    }
    let measurands: Vec<&Value> = of("data")
        .into_iter()
        .filter(|data| data["asdu"] == 9)
        .collect();
    assert_eq!(measurands.len(), raw9.len(), "{context}");
    for data in &measurands {
        assert_eq!(data["cause"], "CYCLIC", "{context}");
        assert_eq!((&data["fun"], &data["inf"]), (&1.into(), &148.into()));
        let values: Vec<f64> = data["values"]
            .as_array()
            .unwrap()
            .iter()
            .map(|value| value.as_f64().unwrap())
            .collect();
        assert_eq!(values.len(), 9, "{data}");
        let expected = [
            1.0 / 2.4,
            1.0 / 2.4,
            1.0 / 2.4,
            1.0 / 1.2,
            1.0 / 1.2,
            1.0 / 1.2,
        ];
        for (value, expected) in values.iter().zip(expected) {
            // 13 bits and a sign: one step is 1/4096.
            assert!((value - expected).abs() < 1.0 / 2048.0, "{data}");
        }
        for flags in ["invalid", "overflow"] {
            assert!(
                data[flags]
                    .as_array()
                    .unwrap()
                    .iter()
                    .all(|flag| flag == false),
                "{data}"
            );
        }
    }

    // The breaker command: confirmed positively (ASDU 1, cause 20, SIN = its return
    // identifier), then the breaker's new position with cause 12.
    let command = of("command");
    assert_eq!(command.len(), 1, "{context}");
    assert_eq!(command[0]["success"], true, "{context}");
    assert_eq!(of("feedback").len(), 1, "{context}");
    assert!(
        of("data")
            .iter()
            .any(|data| data["cause"] == "REMOTE_OPERATION"
                && data["fun"] == 1
                && data["inf"] == 160
                && data["value"] == "OFF"),
        "{context}"
    );
    assert_eq!(of("done").len(), 1, "{context}");

    // The relay saw it all the same way and is still running.
    for needle in [
        "master: ResetRemoteLink",
        "clock synchronised to",
        "general interrogation, scan number",
        "general command FUN 1 INF 160 OFF: accepted",
        "FUN 1 INF 160 -> Off (remote operation (12))",
    ] {
        assert!(
            relay.wait_for_line(needle, 10),
            "the relay never logged {needle:?}\n{context}"
        );
    }
    assert!(
        relay.child.try_wait().unwrap().is_none(),
        "the relay stopped\n{context}"
    );
}
