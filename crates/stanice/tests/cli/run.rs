//! `stanice run` starting a project: its errors with file, line and column, a relative
//! project path, a taken port, the HMI's configuration and HTTPS, and the console.

use std::io::Read;
use std::process::Stdio;
use std::time::Duration;

use testkit::ports::{self, free_port};
use testkit::process::{assert_success, run_bounded, start_until, Background};
use testkit::projects::{fresh_dir, vsetin};

use crate::support::*;

#[test]
fn run_reports_project_errors_with_file_line_and_column() {
    let dir = std::env::temp_dir().join(format!("stanice-cli-{}-badproject", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("station.toml"),
        "[station]\nname = \"x\"\ntime_zone = \"Europe/Prague\"\n\n[[node]]\nname = \"A\"\ncommon_address = 0\n",
    )
    .unwrap();
    let mut command = stanice();
    command.arg("run").arg(&dir);
    let output = run_bounded(command, 20);
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("station.toml:7:18: error: node[0].common_address"),
        "{stderr}"
    );
}

/// The project's files are resolved against a relative project folder once: `run` reads
/// `proj/plc/...` and writes `proj/events.sqlite`, not `proj/proj/...` (issue 11).
#[test]
fn a_relative_project_path_is_resolved_once() {
    let dir = fresh_dir("relative");
    copy_vsetin(&dir, "proj");
    let port = ports::free_port_range(23);
    let mut run = stanice();
    run.current_dir(&dir)
        .args(["run", "proj", "--port-base", &port.to_string()])
        .args(["--speed", "60", "--duration", "2"]);
    let banner = assert_success(&run_bounded(run, 60));
    assert!(
        banner.contains("events and command audit: sqlite:proj/events.sqlite"),
        "{banner}"
    );
    assert!(dir.join("proj/events.sqlite").is_file());
    assert!(!dir.join("proj/proj").exists());

    let mut events = stanice();
    events
        .current_dir(&dir)
        .args(["events", "proj", "--since", "1h", "--point", "RH2_*"]);
    let text = assert_success(&run_bounded(events, 30));
    assert!(text.lines().count() > 1, "no events: {text}");

    let mut points = stanice();
    points
        .current_dir(&dir)
        .args(["points", "proj", "--node", "RH2"]);
    let text = assert_success(&run_bounded(points, 30));
    assert!(text.contains("RH2_VypnoutQF1"), "{text}");
}

/// A port held by another program: the error names the project, the node, the holder and
/// a free --port-base, once (it was doubled and without a hint).
#[test]
fn a_taken_port_names_the_node_the_holder_and_a_free_port_base() {
    let dir = fresh_dir("port-taken");
    let project = copy_vsetin(&dir, "proj");
    let port = ports::free_port_range(23);
    let _holder = std::net::TcpListener::bind(("127.0.0.1", port)).unwrap();
    let mut run = stanice();
    run.arg("run").arg(&project).args([
        "--port-base",
        &port.to_string(),
        "--duration",
        "1",
        "--store",
        "none",
    ]);
    let output = run_bounded(run, 60);
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("node `RDRT`"), "{stderr}");
    assert!(stderr.contains("project `Vsetín`"), "{stderr}");
    assert!(
        stderr.contains(&format!("held by process {}", std::process::id())),
        "{stderr}"
    );
    assert!(stderr.contains("--port-base "), "{stderr}");
    assert_eq!(stderr.matches("in use").count(), 1, "said once: {stderr}");
}

/// `run --hmi` with a broken hmi.toml fails at once, naming the file, line and column of
/// the mistake, instead of running the station without its HMI (exit 0).
#[test]
fn run_with_a_broken_hmi_toml_fails_with_file_line_and_column() {
    let dir = fresh_dir("broken-hmi");
    let project = copy_vsetin(&dir, "proj");
    let file = project.join("hmi/hmi.toml");
    let text = std::fs::read_to_string(&file).unwrap();
    // A command that points.csv does not have, and a syntax error, each on its own.
    let line = 1 + text
        .lines()
        .position(|l| l == "command = \"RH2_VypnoutQF1\"")
        .unwrap();
    let cases = [
        (
            text.replacen("\"RH2_VypnoutQF1\"", "\"RH2_NoSuchCommand\"", 1),
            format!("hmi.toml:{line}:11: control `RH2_NoSuchCommand` is no command of points.csv"),
        ),
        (
            text.replacen(
                "command = \"RH2_VypnoutQF1\"",
                "command = RH2_VypnoutQF1",
                1,
            ),
            format!("hmi.toml:{line}:11: "),
        ),
    ];
    let port = ports::free_port_range(23);
    for (broken, expected) in cases {
        std::fs::write(&file, broken).unwrap();
        let mut run = stanice();
        run.arg("run")
            .arg(&project)
            .args(["--port-base", &port.to_string(), "--store", "none"])
            .args(["--hmi", "--hmi-port", "0", "--duration", "1"]);
        let output = run_bounded(run, 30);
        let stdout = String::from_utf8_lossy(&output.stdout);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(!output.status.success(), "{stdout}\n{stderr}");
        assert!(stderr.contains(&expected), "{expected}:\n{stderr}");
        assert!(
            !stdout.contains("Ctrl-C stops"),
            "the station must not run without its HMI: {stdout}"
        );
    }
}

/// `run --hmi-tls-cert --hmi-tls-key` serves the HMI over HTTPS with that certificate
/// (the options imply --hmi).
#[test]
fn run_serves_the_hmi_over_https() {
    use std::io::Write as _;
    use tokio_rustls::rustls;

    let dir = fresh_dir("https");
    let project = copy_vsetin(&dir, "proj");
    let key = rcgen::KeyPair::generate().unwrap();
    let certificate = rcgen::CertificateParams::new(vec!["localhost".to_owned()])
        .unwrap()
        .self_signed(&key)
        .unwrap();
    let (cert_path, key_path) = (dir.join("hmi.crt"), dir.join("hmi.key"));
    std::fs::write(&cert_path, certificate.pem()).unwrap();
    std::fs::write(&key_path, key.serialize_pem()).unwrap();
    let port = ports::free_port_range(23);
    let hmi_port = free_port();
    let mut run = stanice();
    run.arg("run")
        .arg(&project)
        .args(["--port-base", &port.to_string(), "--store", "none"])
        .args(["--hmi-port", &hmi_port.to_string()])
        .arg("--hmi-tls-cert")
        .arg(&cert_path)
        .arg("--hmi-tls-key")
        .arg(&key_path);
    let _station = start_until(run, &format!("HMI      https://127.0.0.1:{hmi_port}/"));

    let mut roots = rustls::RootCertStore::empty();
    roots.add(certificate.der().clone()).unwrap();
    let config = rustls::ClientConfig::builder_with_provider(std::sync::Arc::new(
        rustls::crypto::ring::default_provider(),
    ))
    .with_safe_default_protocol_versions()
    .unwrap()
    .with_root_certificates(roots)
    .with_no_client_auth();
    let name = rustls::pki_types::ServerName::try_from("localhost").unwrap();
    let connection = rustls::ClientConnection::new(std::sync::Arc::new(config), name).unwrap();
    let tcp = std::net::TcpStream::connect(("127.0.0.1", hmi_port)).unwrap();
    // A bound on every read: a server that never answers fails the test, not hangs it.
    tcp.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
    let mut tls = rustls::StreamOwned::new(connection, tcp);
    tls.write_all(b"GET /login HTTP/1.1\r\nHost: localhost\r\nConnection: close\r\n\r\n")
        .unwrap();
    let mut reply = Vec::new();
    // The server closes after the reply (Connection: close); some close without a TLS
    // close_notify, which is an error here after the whole reply has arrived.
    let _ = tls.read_to_end(&mut reply);
    let reply = String::from_utf8_lossy(&reply);
    assert!(reply.starts_with("HTTP/1.1 200"), "{reply}");
    assert!(reply.contains("login-form"), "the login page: {reply}");
}

/// Types `line` on the station's console.
fn type_line(station: &mut Background, line: &str) {
    use std::io::Write as _;
    let stdin = station.0.stdin.as_mut().unwrap();
    writeln!(stdin, "{line}").unwrap();
    stdin.flush().unwrap();
}

/// The console of `stanice run` as a newcomer meets it (issue 11): `help` names the devices
/// each fault and operation takes, a unique short name is enough, an ambiguous one lists
/// its candidates, and `status` shows the breakers and the supply transfer.
#[test]
fn the_console_names_the_devices_and_accepts_unique_short_names() {
    let port = ports::free_port_range(23);
    let mut run = stanice();
    run.stdin(Stdio::piped()).arg("run").arg(vsetin()).args([
        "--port-base",
        &port.to_string(),
        "--store",
        "none",
    ]);
    let (mut station, lines) = start_watching(run, "Ctrl-C stops");

    type_line(&mut station, "help");
    wait_for_line(&lines, "stuck-open NAME");
    let breakers = wait_for_line(&lines, "NAME (breaker):");
    assert!(breakers.contains("RH11_QF1"), "{breakers}");
    wait_for_line(&lines, "MODULE (module):");
    wait_for_line(&lines, "NODE/LINK: RDRT/RH");

    type_line(&mut station, "close QF1");
    let refused = wait_for_line(&lines, "error: `QF1` could be");
    assert!(
        refused.contains("RH11_QF1, RH12_QF1, RH2_QF1, RHDT_QF1, RZS2_QF1, RZSDT_QF1, RZZ_QF1"),
        "{refused}"
    );

    type_line(&mut station, "stuck-open rh2_fa1.1");
    wait_for_line(&lines, "ok: stuck-open rh2_fa1.1");
    type_line(&mut station, "module-pulled P9");
    wait_for_line(&lines, "ok: module-pulled P9");
    type_line(&mut station, "emergency-off RZS1");
    wait_for_line(&lines, "error: no board with emergency off named `RZS1`");

    type_line(&mut station, "status");
    let faults = wait_for_line(&lines, "faults:");
    assert!(
        faults.contains("stuck-open RH2_FA1.1") && faults.contains("module-pulled RDRT_P9"),
        "{faults}"
    );
    wait_for_line(&lines, "transfer:  RZS on");
    wait_for_line(&lines, "RH2_FA1.1 open (stuck)");
    wait_for_line(&lines, "contactors:");
}
