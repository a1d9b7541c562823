//! Opening serial ports: what a real pseudo-terminal keeps of the settings asked, and
//! the errors that name what failed.
//!
//! Found on Linux (6.x): the pty driver clears PARENB and forces CS8 on every
//! `tcsetattr` of its slave end, without an error (`pty_set_termios`), and keeps speed
//! and CSTOPB. So even parity on a pseudo-terminal is the refusal these tests can
//! produce for real; the other settings' refusals are tested on the comparison itself
//! (`settings.rs`).

use serial_line::io::{OpenError, Transport};
use serial_line::{LineSettings, Parity, Setting, SettingsError};

#[tokio::test]
async fn a_pseudo_terminal_refuses_even_parity_by_name() {
    let pty = Transport::Pty.open().await.expect("a pty pair");
    let path = pty.pty_path.clone().expect("its other end");
    let error = Transport::Serial {
        path: path.clone(),
        line: LineSettings::new(9600),
    }
    .open()
    .await
    .expect_err("8E1 on a pseudo-terminal");
    assert_eq!(
        error.to_string(),
        format!("serial {path}: the port refused parity even (it kept none)")
    );
    match &error {
        OpenError::Refused { refused, .. } => {
            assert_eq!(refused.setting, Setting::Parity);
            assert_eq!(
                (refused.asked.as_str(), refused.kept.as_str()),
                ("even", "none")
            );
        }
        other => panic!("{other:?}"),
    }
    // As an io::Error (how the station's reopen loops take it), the message stays.
    let io = std::io::Error::from(error);
    assert_eq!(io.kind(), std::io::ErrorKind::InvalidInput);
    assert!(
        io.to_string()
            .ends_with("refused parity even (it kept none)"),
        "{io}"
    );
}

#[tokio::test]
async fn a_pseudo_terminal_keeps_speed_stop_bits_and_no_parity() {
    let pty = Transport::Pty.open().await.expect("a pty pair");
    let path = pty.pty_path.clone().expect("its other end");
    let line = Transport::Serial {
        path: path.clone(),
        line: LineSettings {
            baud: 19200,
            parity: Parity::None,
            stop_bits: 2,
        },
    }
    .open()
    .await
    .expect("19200 8N2 on a pseudo-terminal");
    assert_eq!(line.peer, path);
    assert_eq!(line.pty_path, None);
}

#[tokio::test]
async fn a_missing_device_gives_the_system_reason() {
    let path = "/dev/serial-line-test-no-such-port";
    let error = Transport::Serial {
        path: path.to_owned(),
        line: LineSettings::new(9600),
    }
    .open()
    .await
    .expect_err("no such device");
    assert!(matches!(error, OpenError::Serial { .. }), "{error:?}");
    assert_eq!(
        error.to_string(),
        format!("serial {path}: No such file or directory")
    );
    assert_eq!(
        std::io::Error::from(error).kind(),
        std::io::ErrorKind::NotFound
    );
}

#[tokio::test]
async fn settings_no_line_takes_are_refused_before_opening() {
    let error = Transport::Serial {
        path: "/dev/serial-line-test-never-opened".to_owned(),
        line: LineSettings::new(300),
    }
    .open()
    .await
    .expect_err("300 Bd");
    assert!(
        matches!(
            error,
            OpenError::Settings {
                reason: SettingsError::Baud(300),
                ..
            }
        ),
        "{error:?}"
    );
    assert_eq!(
        error.to_string(),
        "serial /dev/serial-line-test-never-opened: baud rate 300 outside 1200..=115200"
    );
}

#[tokio::test]
async fn a_refused_connection_names_the_address() {
    // A port just bound and released: nothing listens there.
    let address = {
        let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        listener.local_addr().unwrap().to_string()
    };
    let error = Transport::Connect(address.clone())
        .open()
        .await
        .expect_err("nothing listens");
    assert!(
        error.to_string().starts_with(&format!("tcp {address}: ")),
        "{error}"
    );
}
