//! `stanice iec104 client`: connect, start data transfer, print every ASDU.

use std::process::ExitCode;
use std::time::Duration;

use clap::Args;
use iec60870::asdu::CommonAddress;
use iec60870::cs104::client::{spawn_client, ClientConfig, ClientEvent};

use super::render;
use super::LinkOptions;

/// Arguments of `stanice iec104 client`.
#[derive(Args, Debug)]
pub(crate) struct ClientArgs {
    /// Server address `HOST:PORT`; alternates may follow, separated by commas.
    address: String,
    /// Common address of the station (for interrogation and clock sync).
    #[arg(long, default_value_t = 1)]
    ca: u16,
    /// Send a general interrogation after the start of data transfer.
    #[arg(long)]
    gi: bool,
    /// Send a clock synchronisation (UTC) after the start of data transfer.
    #[arg(long)]
    clock_sync: bool,
    /// Stop after this long (`30s`, `10m`; a plain number is seconds); runs until Ctrl-C
    /// or SIGTERM otherwise.
    #[arg(long, value_name = "TIME", value_parser = crate::duration_arg::seconds)]
    duration: Option<std::time::Duration>,
    /// One JSON object per information object instead of analyser lines.
    #[arg(long)]
    json: bool,
    /// Stop when the general interrogation has terminated (with --gi).
    #[arg(long, requires = "gi")]
    exit_after_gi: bool,
    /// Do not reconnect after the connection is lost: exit non-zero instead.
    #[arg(long)]
    no_reconnect: bool,
    /// The zone of the station's time tags, which printed times are shown in too (with
    /// their offset): an IANA name (`Europe/Prague`), `UTC` (the test servers' default)
    /// or `local`.
    #[arg(long, value_name = "ZONE", default_value = "UTC")]
    time_zone: iec60870::time::TimeZonePolicy,
    #[command(flatten)]
    link: LinkOptions,
}

pub(crate) async fn run(args: ClientArgs) -> anyhow::Result<ExitCode> {
    crate::printed_time::set_tool_zone(args.time_zone);
    let mut addresses = Vec::new();
    for address in args.address.split(',') {
        addresses.push(super::server_address(address).await?);
    }
    let mut config = ClientConfig::new(
        addresses.first().cloned().unwrap_or_default(),
        CommonAddress::new(args.ca),
    );
    config.addresses = addresses;
    config.apci = args.link.apci()?;
    config.interrogate_on_start = args.gi;
    config.clock_sync_on_start = args.clock_sync;
    config.reconnect = !args.no_reconnect;
    // A connection another controlling station has put on standby (its redundancy group
    // started elsewhere) gets nothing: after 10 quiet seconds the client probes, and says
    // so when the station does not answer, rather than sit silent.
    config.standby_probe = Some(Duration::from_secs(10));
    if let Some(pem) = args.link.tls()? {
        let host = config
            .addresses
            .first()
            .and_then(|address| {
                address
                    .rsplit_once(':')
                    .map(|(host, _)| host.trim_matches(['[', ']']).to_owned())
            })
            .unwrap_or_default();
        let name = iec60870::cs104::tls::server_name(&host)?;
        config.tls = Some((iec60870::cs104::tls::client_config(&pem)?, name));
    }
    // One listener for the whole loop: a Ctrl-C between two events is not lost.
    let mut interrupt = crate::interrupt::Interrupt::listen();
    let (client, mut events) = spawn_client(config);
    let deadline = args
        .duration
        .map(|duration| tokio::time::Instant::now() + duration);
    let mut exit = ExitCode::SUCCESS;
    // Whether the server was ever reached, and the last reason it was not.
    let mut reached = false;
    let mut last_failure = None;
    loop {
        let event = tokio::select! {
            event = events.recv() => event,
            () = sleep_until(deadline) => break,
            () = interrupt.recv() => break,
        };
        let Some(event) = event else { break };
        let gi_terminated = matches!(&event, ClientEvent::Asdu(asdu)
            if asdu.type_id == iec60870::asdu::TypeId::C_IC_NA_1
                && asdu.cot.cause == iec60870::asdu::Cause::ACTIVATION_TERMINATION);
        let lost = matches!(event, ClientEvent::Disconnected { .. });
        match &event {
            ClientEvent::Connected { .. } => reached = true,
            ClientEvent::Disconnected { reason } => last_failure = Some(reason.clone()),
            _ => {}
        }
        // A refused interrogation (unknown common address, cause 46, say) never terminates:
        // say so, and with --exit-after-gi end with an error instead of waiting forever.
        let gi_refused = matches!(&event, ClientEvent::Asdu(asdu)
            if asdu.type_id == iec60870::asdu::TypeId::C_IC_NA_1 && asdu.cot.negative);
        if let (true, ClientEvent::Asdu(asdu)) = (gi_refused, &event) {
            eprintln!(
                "the station refused the general interrogation of CA {} (negative confirmation, cause {})",
                asdu.common_address, asdu.cot.cause
            );
        }
        let lines = if args.json {
            render::json_lines(&event)
        } else {
            vec![render::analyser_text(&event)]
        };
        if !crate::console::print_lines(&lines) {
            // The reader went away (`| head`): stop quietly, as command-line tools do.
            break;
        }
        if args.exit_after_gi && gi_terminated {
            break;
        }
        if args.exit_after_gi && gi_refused {
            exit = ExitCode::from(1);
            break;
        }
        if lost && args.no_reconnect {
            exit = ExitCode::from(1);
            break;
        }
    }
    client.close().await;
    if !reached {
        eprintln!(
            "never reached {}: {}",
            args.address,
            last_failure.as_deref().unwrap_or("no connection was made")
        );
        return Ok(ExitCode::from(2));
    }
    Ok(exit)
}

async fn sleep_until(deadline: Option<tokio::time::Instant>) {
    match deadline {
        Some(deadline) => tokio::time::sleep_until(deadline).await,
        None => std::future::pending().await,
    }
}
