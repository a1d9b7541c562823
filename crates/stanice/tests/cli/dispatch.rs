//! The running station as dispatch meets it: the demo serves the whole station, and idle
//! clients never lock dispatch out.

use std::io::{BufRead, BufReader, Read};
use std::process::Stdio;
use std::time::{Duration, Instant};

use serde_json::Value;
use testkit::ports;
use testkit::process::{run_bounded, start_until};
use testkit::projects::vsetin;

use crate::support::*;

#[test]
fn demo_serves_the_station_to_dispatch() {
    let port = ports::free_port_range(23);
    let mut demo = stanice();
    demo.args(["demo", "--port-base", &port.to_string(), "--store", "none"]);
    let _demo = start_until(demo, "Ctrl-C stops");
    // The demo is ready when its top node serves; the links below it (TLS) may still be
    // coming up on a busy machine, and their points are rightly invalid until then: ask
    // again until every value is valid, for at most a minute.
    let invalid_of = |stdout: &[u8]| -> Vec<String> {
        String::from_utf8_lossy(stdout)
            .lines()
            .filter_map(|line| serde_json::from_str::<Value>(line).ok())
            .filter(|line| line["cot"] == "inrogen")
            .filter(|line| {
                line["quality"]
                    .as_array()
                    .is_some_and(|flags| flags.iter().any(|flag| flag == "IV"))
            })
            .map(|line| line.to_string())
            .collect()
    };
    let deadline = Instant::now() + Duration::from_secs(60);
    let output = loop {
        let mut client = stanice();
        client.args([
            "iec104",
            "client",
            &format!("127.0.0.1:{port}"),
            "--gi",
            "--json",
            "--exit-after-gi",
        ]);
        let output = run_bounded(client, 20);
        if invalid_of(&output.stdout).is_empty() || Instant::now() >= deadline {
            break output;
        }
        std::thread::sleep(Duration::from_millis(500));
    };
    let interrogated: Vec<u64> = String::from_utf8_lossy(&output.stdout)
        .lines()
        .filter_map(|line| serde_json::from_str::<Value>(line).ok())
        .filter(|line| line["cot"] == "inrogen")
        .filter_map(|line| line["ioa"].as_u64())
        .collect();
    // The whole station: the TC700's own points, the concentrators' own I/O and the boards
    // behind them (RH2 at the thesis' addresses), the boards in DT and the thirteen
    // lighting boards.
    for ioa in [
        1, 10, 21, 32, 33, 34, 35, 50, 62, 201, 208, 216, 280, 281, 298, 320, 338, 341, 348, 381,
        398, 401, 415, 440, 458, 501, 514, 601, 614, 10_101, 10_111, 11_332,
    ] {
        assert!(
            interrogated.contains(&ioa),
            "IOA {ioa} missing: {interrogated:?}"
        );
    }
    assert_eq!(interrogated.len(), 508);
    // Every value is valid: the links below RDRT, on TLS, are all up.
    let invalid = invalid_of(&output.stdout);
    assert!(invalid.is_empty(), "{invalid:?}");

    // RH1.1's server (below RDRT) speaks TLS with mutual authentication only.
    let mut plain = stanice();
    plain.args([
        "iec104",
        "client",
        &format!("127.0.0.1:{}", port + 1),
        "--json",
        "--no-reconnect",
    ]);
    let output = run_bounded(plain, 20);
    let text = String::from_utf8_lossy(&output.stdout);
    assert_eq!(output.status.code(), Some(1), "{text}");
    assert!(text.contains("the peer speaks TLS"), "{text}");

    // A reader that goes away (`| head -1`) ends the client quietly, without a panic.
    let mut client = stanice()
        .args([
            "iec104",
            "client",
            &format!("127.0.0.1:{port}"),
            "--gi",
            "--json",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = String::new();
    BufReader::new(client.stdout.take().unwrap())
        .read_line(&mut first)
        .unwrap();
    assert!(first.contains("connected"), "{first}");
    let deadline = Instant::now() + Duration::from_secs(20);
    let status = loop {
        if let Some(status) = client.try_wait().unwrap() {
            break status;
        }
        assert!(
            Instant::now() < deadline,
            "the client goes on writing to a closed pipe"
        );
        std::thread::sleep(Duration::from_millis(20));
    };
    let mut stderr = String::new();
    client
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut stderr)
        .unwrap();
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(status.success(), "{status}");
}

#[test]
fn idle_clients_do_not_lock_dispatch_out_of_the_station() {
    use iec60870::asdu::CommonAddress;
    use iec60870::cs104::client::{spawn_client, ClientConfig};
    let port = ports::free_port_range(23);
    let mut run = stanice();
    run.stdin(Stdio::piped()).arg("run").arg(vsetin()).args([
        "--port-base",
        &port.to_string(),
        "--store",
        "none",
    ]);
    let _station = start_until(run, "Ctrl-C stops");
    // 70 clients that connect and never start data transfer (they held all 64 slots).
    let idle: Vec<std::net::TcpStream> = (0..70)
        .filter_map(|_| std::net::TcpStream::connect(("127.0.0.1", port)).ok())
        .collect();
    assert!(!idle.is_empty());
    // The ED dispatch centre (127.0.0.3, a named redundancy group of RDRT) still gets in
    // and is served a general interrogation.
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap();
    let answers = runtime.block_on(async {
        let mut config = ClientConfig::new(format!("127.0.0.1:{port}"), CommonAddress::new(1));
        config.local_address = Some("127.0.0.3".parse().unwrap());
        config.interrogate_on_start = true;
        config.reconnect = false;
        let (_client, events) = spawn_client(config);
        tokio::time::timeout(Duration::from_secs(20), interrogated_objects(events, "ED"))
            .await
            .expect("the interrogation ends")
    });
    assert!(answers > 400, "{answers} objects interrogated");
    drop(idle);
}

/// The objects a client's general interrogation brings, counted until its termination;
/// a lost connection fails the test naming `who`.
async fn interrogated_objects(
    mut events: tokio::sync::mpsc::Receiver<iec60870::cs104::client::ClientEvent>,
    who: &str,
) -> usize {
    use iec60870::cs104::client::ClientEvent;
    let mut objects = 0;
    while let Some(event) = events.recv().await {
        match event {
            ClientEvent::Asdu(asdu) if asdu.cot.cause.value() == 20 => {
                objects += asdu.objects.len();
            }
            ClientEvent::Asdu(asdu) if asdu.cot.cause.value() == 10 => return objects,
            ClientEvent::Disconnected { reason } => panic!("{who} lost: {reason}"),
            _ => {}
        }
    }
    objects
}

/// Idle clients from other addresses fill the demo's catch-all `dispatch` group (70
/// connections that never start data transfer); a fresh dispatch client still gets its
/// general interrogation at once: a newcomer evicts the longest-idle connection that never
/// started (it got no GI within 20 s, as the idle ones held the group's slots until their
/// start timeout).
#[test]
fn idle_clients_from_other_addresses_do_not_lock_out_a_fresh_dispatch_client() {
    use iec60870::asdu::CommonAddress;
    use iec60870::cs104::client::{spawn_client, ClientConfig};
    let port = ports::free_port_range(23);
    let mut run = stanice();
    run.stdin(Stdio::piped()).arg("run").arg(vsetin()).args([
        "--port-base",
        &port.to_string(),
        "--store",
        "none",
    ]);
    let _station = start_until(run, "Ctrl-C stops");
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap();
    let elapsed = runtime.block_on(async {
        let server: std::net::SocketAddr = format!("127.0.0.1:{port}").parse().unwrap();
        let mut idle = Vec::new();
        for last in 1..=70u8 {
            let socket = tokio::net::TcpSocket::new_v4().unwrap();
            socket
                .bind(std::net::SocketAddr::from(([127, 0, 1, last], 0)))
                .unwrap();
            if let Ok(stream) = socket.connect(server).await {
                idle.push(stream);
            }
        }
        assert!(idle.len() >= 32, "{} idle connections", idle.len());
        // Let the station take them all in (or refuse them) before dispatch comes.
        tokio::time::sleep(Duration::from_millis(300)).await;
        let started = Instant::now();
        let mut config = ClientConfig::new(server.to_string(), CommonAddress::new(1));
        config.interrogate_on_start = true;
        config.reconnect = false;
        let (_client, events) = spawn_client(config);
        let objects = tokio::time::timeout(
            Duration::from_secs(10),
            interrogated_objects(events, "dispatch"),
        )
        .await
        .expect("dispatch's interrogation ends while the idle clients hold on");
        assert!(objects > 400, "{objects} objects interrogated");
        drop(idle);
        started.elapsed()
    });
    eprintln!("dispatch's GI through 70 idle clients took {elapsed:?}");
}
