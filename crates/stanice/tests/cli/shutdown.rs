//! How `stanice run` ends: Ctrl-C and SIGTERM stop it cleanly with the store flushed, and
//! after kill -9 the audit holds every positively confirmed command.

use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use testkit::ports;
use testkit::process::{
    assert_success, run_bounded, start_until, start_until_with_log, Background,
};
use testkit::projects::fresh_dir;

use crate::support::*;

/// Sends a signal: `INT` as Ctrl-C in a terminal does, `TERM` as systemd, container
/// runtimes and `kill` do (std has no signals; `kill` is everywhere).
fn signal(child: &Child, name: &str) {
    let status = Command::new("kill")
        .args([&format!("-{name}"), &child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
}

/// Stops a running `stanice run` by the signal `name` while its console waits for a line
/// on a terminal-like standard input that stays open, and checks the shutdown: exit 0, the
/// events recorded so far in the store with the PLCs' stops (their outputs driven safe),
/// the SQLite write-ahead log checkpointed away, and nothing logged above info.
fn stop_by_signal_and_check_the_shutdown(name: &str) {
    let dir = fresh_dir(&format!("signal-{name}"));
    let project = copy_vsetin(&dir, "proj");
    let port = ports::free_port_range(23);
    let mut run = stanice();
    run.stdin(Stdio::piped())
        .arg("run")
        .arg(&project)
        .args(["--port-base", &port.to_string(), "--speed", "60"])
        .args(["--hmi", "--hmi-port", "0"]);
    let (mut station, log) = start_until_with_log(run, "Ctrl-C stops");
    assert!(station.0.stdin.is_some(), "standard input must stay open");
    signal(&station.0, name);
    // Within a second on an idle machine; the bound is generous for a busy one.
    let deadline = Instant::now() + Duration::from_secs(20);
    let status = loop {
        if let Some(status) = station.0.try_wait().unwrap() {
            break status;
        }
        assert!(
            Instant::now() < deadline,
            "the station did not stop on SIG{name}"
        );
        std::thread::sleep(Duration::from_millis(20));
    };
    let log = log.join().unwrap();
    assert!(status.success(), "SIG{name}: {status}\n{log}");
    assert!(
        !log.contains("WARN") && !log.contains("ERROR"),
        "a normal stop logs nothing above info:\n{log}"
    );
    for leftover in [
        "events.sqlite-wal",
        "events.sqlite-shm",
        "hmi-events.sqlite-wal",
    ] {
        assert!(
            !project.join(leftover).exists(),
            "{leftover} left behind after SIG{name}"
        );
    }

    let mut events = stanice();
    events
        .arg("events")
        .arg(&project)
        .args(["--since", "1h", "--limit", "10000"]);
    let text = assert_success(&run_bounded(events, 30));
    assert!(
        text.lines().any(|l| l.contains(",RDRT,")),
        "the store has no events after SIG{name}: {text}"
    );
    assert!(
        text.lines().any(|l| l.contains("plc-task:")),
        "the PLCs' stops are not recorded after SIG{name}: {text}"
    );
}

/// Ctrl-C stops `stanice run` cleanly.
#[test]
fn ctrl_c_stops_the_station_and_flushes_the_store() {
    stop_by_signal_and_check_the_shutdown("INT");
}

/// SIGTERM (systemd, containers) stops `stanice run` as Ctrl-C does: outputs safe, store
/// flushed, exit 0 (it ended the process at once with status 143).
#[test]
fn sigterm_stops_the_station_as_ctrl_c_does() {
    stop_by_signal_and_check_the_shutdown("TERM");
}

/// Sends commands through the running Vsetín station and kills it (SIGKILL) the moment
/// the last one's positive confirmation arrives; returns how many were confirmed.
fn command_then_kill(port: u16, station: &mut Background, commands: usize) -> usize {
    use iec60870::asdu::{Cause, CommandQualifier, CommonAddress, Element, Ioa, TypeId};
    use iec60870::cs104::client::{spawn_client, ClientConfig, ClientEvent};
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap();
    runtime.block_on(async {
        let mut config = ClientConfig::new(format!("127.0.0.1:{port}"), CommonAddress::new(1));
        config.reconnect = false;
        let (client, mut events) = spawn_client(config);
        tokio::time::timeout(Duration::from_secs(20), async {
            while let Some(event) = events.recv().await {
                if event == ClientEvent::Started {
                    return;
                }
            }
        })
        .await
        .expect("RDRT starts data transfer");
        let mut confirmed = 0;
        // RDRT refuses what it cannot forward yet: its links below may still be coming
        // up on a busy machine. The first command is asked again (a refused command
        // changes nothing) until one goes through, for a minute at most.
        let warm_up = tokio::time::Instant::now() + Duration::from_secs(60);
        let mut index = 0;
        while index < commands {
            // RH2's QF1, through RDRT and RH1.1: open, close, open, ...
            let ioa = if index % 2 == 0 { 2021 } else { 2022 };
            let request = {
                let client = client.clone();
                tokio::spawn(async move {
                    client
                        .command(
                            TypeId::C_SC_NA_1,
                            Ioa::try_new(ioa).unwrap(),
                            Element::SingleCommand {
                                on: true,
                                qualifier: CommandQualifier::EXECUTE,
                            },
                            None,
                        )
                        .await
                })
            };
            let positive = tokio::time::timeout(Duration::from_secs(20), async {
                while let Some(event) = events.recv().await {
                    if let ClientEvent::Asdu(asdu) = event {
                        if asdu.type_id == TypeId::C_SC_NA_1
                            && asdu.cot.cause == Cause::ACTIVATION_CON
                            && asdu.objects[0].ioa.get() == ioa
                        {
                            return !asdu.cot.negative;
                        }
                    }
                }
                false
            })
            .await
            .expect("a confirmation");
            if !positive && index == 0 && tokio::time::Instant::now() < warm_up {
                request.await.unwrap().unwrap();
                eprintln!("first command refused (links below RDRT not up yet?); asking again");
                tokio::time::sleep(Duration::from_millis(500)).await;
                continue;
            }
            assert!(positive, "command {index} refused");
            confirmed += 1;
            if index + 1 == commands {
                // At once: no time for a lazy writer to catch up.
                station.0.kill().unwrap();
                break;
            }
            request.await.unwrap().unwrap();
            index += 1;
        }
        confirmed
    })
}

#[test]
fn a_positively_confirmed_command_is_in_the_audit_even_after_kill_9() {
    let dir = fresh_dir("kill-9");
    let project = copy_vsetin(&dir, "proj");
    let port = ports::free_port_range(23);
    let mut run = stanice();
    run.stdin(Stdio::piped())
        .arg("run")
        .arg(&project)
        .args(["--port-base", &port.to_string()]);
    let mut station = start_until(run, "Ctrl-C stops");
    let confirmed = command_then_kill(port, &mut station, 4);
    let _ = station.0.wait();

    let mut audit = stanice();
    audit.arg("events").arg(&project).arg("--commands");
    let text = assert_success(&run_bounded(audit, 30));
    // Each level audits before it confirms: RDRT (which dispatch heard), and below it
    // RH1.1 and RH2, which confirmed to the level above first.
    for node in ["RDRT", "RH1.1", "RH2"] {
        let executed = text
            .lines()
            .filter(|line| line.contains(&format!(",{node},")) && line.contains(",Executed,"))
            .count();
        assert_eq!(executed, confirmed, "{node}:\n{text}");
    }
}
