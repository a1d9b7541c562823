//! A loopback SMTP server for tests that send mail (the notify crate's, the station's lift
//! notifications): `tests/support/smtp_sink.py` (Python aiosmtpd), writing each message it
//! accepts to a JSON file.

use std::io::{BufRead, BufReader, Write};
use std::path::PathBuf;
use std::process::{Child, ChildStdin, Command, Stdio};
use std::time::{Duration, Instant};

use crate::{peers, repository_root};

/// Whether python3 with aiosmtpd is here; panics when it must be (CI) and is not.
pub fn smtp_peer_available() -> bool {
    if peers::python_imports("aiosmtpd") {
        return true;
    }
    peers::skip_or_fail("python3 with aiosmtpd missing; run scripts/install-test-deps.sh");
    false
}

/// The aiosmtpd server of `tests/support/smtp_sink.py`, writing each message to a JSON file.
pub struct SmtpSink {
    child: Child,
    stdin: Option<ChildStdin>,
    dir: tempfile::TempDir,
    /// The loopback port it accepts mail on.
    pub port: u16,
}

impl SmtpSink {
    /// Starts the sink and waits (bounded) until its port accepts connections.
    pub fn start() -> SmtpSink {
        let dir = tempfile::tempdir().unwrap();
        let script = repository_root().join("tests/support/smtp_sink.py");
        let mut child = Command::new("python3")
            .arg(script)
            .arg(dir.path())
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("start python3");
        let stdin = child.stdin.take();
        let mut line = String::new();
        BufReader::new(child.stdout.take().unwrap())
            .read_line(&mut line)
            .unwrap();
        let port: serde_json::Value =
            serde_json::from_str(&line).unwrap_or_else(|_| panic!("smtp_sink.py said {line:?}"));
        let port = u16::try_from(port["port"].as_u64().unwrap()).unwrap();
        let deadline = Instant::now() + Duration::from_secs(10);
        while std::net::TcpStream::connect(("127.0.0.1", port)).is_err() {
            assert!(Instant::now() < deadline, "SMTP sink never accepted");
            std::thread::sleep(Duration::from_millis(20));
        }
        SmtpSink {
            child,
            stdin,
            dir,
            port,
        }
    }

    /// Waits (bounded) until `count` messages are there; returns them in arrival order.
    pub fn wait_for(&self, count: usize) -> Vec<serde_json::Value> {
        let deadline = Instant::now() + Duration::from_secs(10);
        loop {
            let mut files: Vec<PathBuf> = std::fs::read_dir(self.dir.path())
                .unwrap()
                .map(|entry| entry.unwrap().path())
                .filter(|path| path.extension().is_some_and(|e| e == "json"))
                .collect();
            if files.len() >= count {
                files.sort();
                return files
                    .iter()
                    .map(|file| {
                        serde_json::from_str(&std::fs::read_to_string(file).unwrap()).unwrap()
                    })
                    .collect();
            }
            assert!(
                Instant::now() < deadline,
                "{} of {count} messages arrived",
                files.len()
            );
            std::thread::sleep(Duration::from_millis(20));
        }
    }
}

impl Drop for SmtpSink {
    fn drop(&mut self) {
        if let Some(mut stdin) = self.stdin.take() {
            let _ = stdin.flush();
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}
