//! `stanice iec104`: the IEC 104 test tool.
//!
//! - `server`: an outstation serving a CSV point list ([`points_file`]), optionally
//!   simulating changes ([`simulate`]), confirming and logging commands.
//! - `client`: connects, starts data transfer and prints every ASDU like a protocol
//!   analyser, or one JSON object per information object ([`render`]).
//! - `command`: sends one command and reports its confirmation sequence.
//! - `decode`: decodes APDUs given as hex.

mod client;
mod command;
mod decode;
pub(crate) mod points_file;
pub(crate) mod render;
pub(crate) mod server;
pub(crate) mod simulate;

use std::process::ExitCode;

use clap::{Args, Subcommand};

/// Options shared by the tool's network commands.
#[derive(Args, Clone, Debug)]
pub(crate) struct LinkOptions {
    /// t1: how long to wait for an acknowledgement or a confirmation (`15s`; a plain
    /// number is seconds).
    #[arg(long, value_name = "TIME", default_value = "15s", value_parser = crate::duration_arg::seconds)]
    pub(crate) t1: std::time::Duration,
    /// t2: how long before acknowledging received frames when there is nothing to send
    /// (`10s`; a plain number is seconds).
    #[arg(long, value_name = "TIME", default_value = "10s", value_parser = crate::duration_arg::seconds)]
    pub(crate) t2: std::time::Duration,
    /// t3: how long a silence lasts before a test frame (`20s`; a plain number is
    /// seconds).
    #[arg(long, value_name = "TIME", default_value = "20s", value_parser = crate::duration_arg::seconds)]
    pub(crate) t3: std::time::Duration,
    /// k: unacknowledged frames sent at most.
    #[arg(long, default_value_t = 12)]
    pub(crate) k: u16,
    /// w: received frames acknowledged at the latest.
    #[arg(long, default_value_t = 8)]
    pub(crate) w: u16,
    /// TLS: this station's certificate (PEM). With --tls-key and --tls-ca.
    #[arg(long, requires_all = ["tls_key", "tls_ca"])]
    pub(crate) tls_cert: Option<std::path::PathBuf>,
    /// TLS: this station's private key (PEM).
    #[arg(long)]
    pub(crate) tls_key: Option<std::path::PathBuf>,
    /// TLS: the certificate authority that signs the peers' certificates (PEM).
    #[arg(long)]
    pub(crate) tls_ca: Option<std::path::PathBuf>,
}

impl LinkOptions {
    pub(crate) fn apci(&self) -> anyhow::Result<iec60870::cs104::config::ApciConfig> {
        let seconds = |value: std::time::Duration, name: &str| {
            if !value.is_zero() && value < std::time::Duration::from_secs(86_400) {
                Ok(value)
            } else {
                Err(anyhow::anyhow!(
                    "{name} must be longer than 0 and shorter than a day"
                ))
            }
        };
        let mut config = iec60870::cs104::config::ApciConfig::default();
        config.k = self.k;
        config.w = self.w;
        config.t1 = seconds(self.t1, "--t1")?;
        config.t2 = seconds(self.t2, "--t2")?;
        config.t3 = seconds(self.t3, "--t3")?;
        config
            .validate()
            .map_err(|error| anyhow::anyhow!("invalid link parameters: {error}"))?;
        Ok(config)
    }

    pub(crate) fn tls(&self) -> anyhow::Result<Option<iec60870::cs104::tls::TlsPem>> {
        match (&self.tls_cert, &self.tls_key, &self.tls_ca) {
            (Some(certificate), Some(private_key), Some(trust_anchors)) => {
                let files = iec60870::cs104::tls::TlsFiles {
                    certificate: certificate.clone(),
                    private_key: private_key.clone(),
                    trust_anchors: trust_anchors.clone(),
                };
                Ok(Some(files.load()?))
            }
            _ => Ok(None),
        }
    }
}

/// The IEC 104 port that a server address without one gets (IEC 60870-5-104, 5.1).
const IEC104_PORT: u16 = 2404;

/// A server address as the command line gives it, checked before any connection is tried:
/// `HOST:PORT`, or `HOST` alone for the standard port 2404 (`localhost`, `[::1]`). A host
/// name that does not resolve is an error naming it, not a client that retries forever.
pub(crate) async fn server_address(text: &str) -> anyhow::Result<String> {
    let text = text.trim();
    let with_port = if text.parse::<std::net::SocketAddr>().is_ok() {
        text.to_owned()
    } else if let Ok(ip) = text.trim_matches(['[', ']']).parse::<std::net::IpAddr>() {
        std::net::SocketAddr::new(ip, IEC104_PORT).to_string()
    } else {
        match text.rsplit_once(':') {
            Some((host, port)) => {
                if host.is_empty() {
                    anyhow::bail!(
                        "{text:?}: no host before the port (HOST:PORT, e.g. 127.0.0.1:2404)"
                    );
                }
                port.parse::<u16>().map_err(|_| {
                    anyhow::anyhow!(
                        "{text:?}: {port:?} is no port number (HOST:PORT, e.g. 127.0.0.1:2404)"
                    )
                })?;
                text.to_owned()
            }
            None if text.is_empty() => {
                anyhow::bail!("no server address given (HOST:PORT, e.g. 127.0.0.1:2404)")
            }
            None => format!("{text}:{IEC104_PORT}"),
        }
    };
    let found = match tokio::net::lookup_host(with_port.clone()).await {
        Ok(found) => found.count(),
        Err(error) => anyhow::bail!("{text:?}: cannot resolve the host: {error}"),
    };
    if found == 0 {
        anyhow::bail!("{text:?}: the host name has no address");
    }
    Ok(with_port)
}

/// The `stanice iec104` subcommands.
#[derive(Subcommand)]
pub(crate) enum Iec104Command {
    /// Run an outstation (controlled station) serving the points of a CSV file.
    Server(server::ServerArgs),
    /// Connect to an outstation and print what it sends.
    Client(client::ClientArgs),
    /// Send one command and print its confirmation sequence.
    Command(command::CommandArgs),
    /// Decode APDUs (or bare ASDUs) given as hex.
    Decode(decode::DecodeArgs),
}

pub(crate) async fn run(command: Iec104Command) -> anyhow::Result<ExitCode> {
    match command {
        Iec104Command::Server(args) => server::run(args).await,
        Iec104Command::Client(args) => client::run(args).await,
        Iec104Command::Command(args) => command::run(args).await,
        Iec104Command::Decode(args) => decode::run(&args),
    }
}
