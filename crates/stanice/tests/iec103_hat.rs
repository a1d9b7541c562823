//! Interoperability of the relay simulator with an IEC 103 master that is not ours:
//! hat-drivers' (`hat.drivers.iec103` over its FT1.2 link layer and serial driver, from
//! PyPI) opens `stanice iec103 relay --pty` as a serial port, synchronises the relay's
//! clock, runs a general interrogation, reads the cyclic measurands, opens the breaker by a
//! general command and reads the announcement of a disturbance record after an earth fault
//! (issue 22: ASDU 9 with SQ = 1 made an independent master drop the connection; the relay
//! now sends ASDUs 9 and 23 with SQ = 0, VSQ 0x09 for nine measurands).
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
use std::process::{Child, ChildStdin, Command, ExitStatus, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use serde_json::Value;
use testkit::peers;

/// Whether hat-drivers' IEC 103 master and serial driver import; panics when they must
/// (CI) and do not.
fn hat_available() -> bool {
    if peers::python_imports("hat.drivers.iec103, hat.drivers.serial") {
        return true;
    }
    peers::skip_or_fail(
        "interoperability peer missing (hat-drivers for python3); run scripts/install-test-deps.sh",
    );
    false
}

/// A child process, killed when dropped. Its stdout and stderr are drained all the time
/// (a full pipe would block it) into lines kept for the assertions and failure messages;
/// its stdin is a pipe (the relay's console) or null.
struct Process {
    child: Child,
    stdout: Arc<Mutex<Vec<String>>>,
    stderr: Arc<Mutex<Vec<String>>>,
    console: Option<ChildStdin>,
}

impl Process {
    fn spawn(mut command: Command, console: bool) -> Process {
        let mut child = command
            .stdin(if console {
                Stdio::piped()
            } else {
                Stdio::null()
            })
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let drain = |pipe: Box<dyn Read + Send>| {
            let sink = Arc::new(Mutex::new(Vec::new()));
            let lines = Arc::clone(&sink);
            std::thread::spawn(move || {
                for line in BufReader::new(pipe).lines().map_while(Result::ok) {
                    lines.lock().unwrap().push(line);
                }
            });
            sink
        };
        let stdout = drain(Box::new(child.stdout.take().unwrap()));
        let stderr = drain(Box::new(child.stderr.take().unwrap()));
        let console = child.stdin.take();
        Process {
            child,
            stdout,
            stderr,
            console,
        }
    }

    fn stdout(&self) -> Vec<String> {
        self.stdout.lock().unwrap().clone()
    }

    /// Waits up to `seconds` for a line on stdout containing `needle`; false if none
    /// came or the process ended without one.
    fn wait_for_line(&mut self, needle: &str, seconds: u64) -> bool {
        let deadline = Instant::now() + Duration::from_secs(seconds);
        loop {
            if self.stdout().iter().any(|line| line.contains(needle)) {
                return true;
            }
            if Instant::now() >= deadline || self.exited() {
                // Its last lines may still be in the pipe.
                std::thread::sleep(Duration::from_millis(200));
                return self.stdout().iter().any(|line| line.contains(needle));
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    fn exited(&mut self) -> bool {
        self.child.try_wait().unwrap().is_some()
    }

    /// Waits up to `seconds` for the process to end (killing it then); its status, and
    /// whether it ended by itself. Its output is read to the end.
    fn wait_exit(&mut self, seconds: u64) -> (ExitStatus, bool) {
        let deadline = Instant::now() + Duration::from_secs(seconds);
        let mut finished = false;
        while Instant::now() < deadline {
            if self.exited() {
                finished = true;
                break;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        if !finished {
            let _ = self.child.kill();
        }
        let status = self.child.wait().unwrap();
        // The drain threads end at the pipes' EOF, right after the exit.
        let drained = Instant::now() + Duration::from_secs(2);
        while Arc::strong_count(&self.stdout) > 1 || Arc::strong_count(&self.stderr) > 1 {
            if Instant::now() >= drained {
                break;
            }
            std::thread::sleep(Duration::from_millis(10));
        }
        (status, finished)
    }

    /// Types a line on its console.
    fn type_line(&mut self, line: &str) {
        use std::io::Write as _;
        let console = self.console.as_mut().unwrap();
        writeln!(console, "{line}").unwrap();
        console.flush().unwrap();
    }

    /// Its last lines, for failure messages.
    fn tail(&self) -> String {
        let mut lines = self.stdout();
        lines.extend(self.stderr.lock().unwrap().iter().cloned());
        lines[lines.len().saturating_sub(60)..].join("\n")
    }
}

impl Drop for Process {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// `stanice iec103 relay --pty ARGS`, its console on a pipe, and the pty's path.
fn start_relay(args: &[&str]) -> (Process, String) {
    let mut command = Command::new(env!("CARGO_BIN_EXE_stanice"));
    command.args(["iec103", "relay", "--pty"]).args(args);
    let mut relay = Process::spawn(command, true);
    assert!(
        relay.wait_for_line("pty: ", 30),
        "the relay printed no pty:\n{}",
        relay.tail()
    );
    let path = relay
        .stdout()
        .iter()
        .find_map(|line| {
            line.strip_prefix("pty: ")
                .map(|path| path.trim().to_owned())
        })
        .unwrap();
    (relay, path)
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
/// at FUN 1 INF 148 with SQ = 0, the breaker (FUN 1 INF 160) opened by a general command,
/// confirmed positively and followed by its new position, then an earth fault typed on the
/// relay's console: the trip (ASDU 2) and the list of recorded disturbances (ASDU 23,
/// SQ = 0) and one more ASDU 9. The master never drops the connection and the relay logs
/// every step.
#[test]
fn hat_drivers_master_interrogates_and_commands_the_relay() {
    if !hat_available() {
        return;
    }
    // Measurands every second, at rated current and voltage (I = 1/2.4, U = 1/1.2 of the
    // REF630's limits).
    let (mut relay, path) = start_relay(&["--address", "1", "--cycle", "1", "--inject", "1,1"]);
    let mut command = Command::new("python3");
    command
        .arg(peers::peer_script("hat103_master.py"))
        .arg(&path)
        .args(["--address", "1", "--parity", "none", "--timeout", "40"])
        .args(["--measurands", "2", "--time-sync", "--command", "1,160,off"])
        .arg("--wait-disturbance");
    let mut master = Process::spawn(command, false);
    let context = |master: &Process, relay: &Process| {
        format!("master:\n{}\nrelay:\n{}", master.tail(), relay.tail())
    };
    // After the GI, the measurands and the command, the master waits for a disturbance:
    // an earth fault on the relay's console.
    assert!(
        master.wait_for_line(r#""event":"waiting""#, 50),
        "the master never got to wait for the fault\n{}",
        context(&master, &relay)
    );
    relay.type_line("fault");
    let (status, finished) = master.wait_exit(30);
    let context = context(&master, &relay);
    assert!(finished, "the master ran past its own timeout\n{context}");
    assert!(status.success(), "the master failed ({status})\n{context}");
    let stdout = master.stdout();
    let events: Vec<Value> = stdout
        .iter()
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

    // The earth fault: the trip with relative time and fault number 1 (ASDU 2, FUN 160
    // INF 92, ON then OFF), then the list of recorded disturbances (ASDU 23, cause 31)
    // with SQ = 0 and one record; hat read on (one more ASDU 9 after it).
    let trips: Vec<(&str, u64, u64)> = of("data")
        .into_iter()
        .filter(|data| data["asdu"] == 2)
        .map(|data| {
            assert_eq!((&data["fun"], &data["inf"]), (&160.into(), &92.into()));
            assert_eq!(data["cause"], "SPONTANEOUS", "{data}");
            (
                data["value"].as_str().unwrap(),
                data["fault_number"].as_u64().unwrap(),
                data["relative_time"].as_u64().unwrap(),
            )
        })
        .collect();
    assert_eq!(trips, [("ON", 1, 40), ("OFF", 1, 120)], "{context}");
    let lists: Vec<&Value> = of("asdu")
        .into_iter()
        .filter(|asdu| asdu["type"] == 23)
        .collect();
    assert_eq!(lists.len(), 1, "{context}");
    assert_eq!(lists[0]["vsq"], 0x01, "{context}");
    assert_eq!(lists[0]["cause"], 31, "{context}");
    assert_eq!(lists[0]["fun"], 160, "{context}");
    // Six octets of header, one entry of FAN, SOF and CP56Time2a.
    assert_eq!(lists[0]["hex"].as_str().unwrap().len(), 2 * (6 + 10));
    assert_eq!(of("disturbance_seen").len(), 1, "{context}");
    assert_eq!(of("done").len(), 1, "{context}");

    // The relay saw it all the same way and is still running.
    for needle in [
        "master: ResetRemoteLink",
        "clock synchronised to",
        "general interrogation, scan number",
        "general command FUN 1 INF 160 OFF: accepted",
        "FUN 1 INF 160 -> Off (remote operation (12))",
        "earth fault number 1: trip, breaker open",
    ] {
        assert!(
            relay.wait_for_line(needle, 10),
            "the relay never logged {needle:?}\n{context}"
        );
    }
    assert!(!relay.exited(), "the relay stopped\n{context}");
}
