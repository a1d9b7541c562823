//! `stanice iec104 command`: send one command, print its confirmation sequence.
//!
//! Exit codes: 0 positive confirmation (and termination), 1 negative confirmation,
//! 2 timeout or no connection.

use std::process::ExitCode;
use std::time::Duration;

use clap::Args;
use iec60870::asdu::text::parse_command;
use iec60870::asdu::{CommonAddress, Ioa, TypeId};
use iec60870::cs104::client::{
    spawn_client, ClientConfig, ClientError, ClientEvent, RequestOutcome,
};

use super::render;
use super::LinkOptions;

/// Arguments of `stanice iec104 command`.
#[derive(Args, Debug)]
pub(crate) struct CommandArgs {
    /// Server address `HOST:PORT`.
    address: String,
    /// Common address of the station (1 unless given, as for `client`).
    #[arg(long, default_value_t = 1)]
    ca: u16,
    /// Address of the command point.
    #[arg(long)]
    ioa: u32,
    /// Command type: C_SC_NA_1, C_DC_NA_1, C_RC_NA_1, C_SE_NA_1, C_SE_NB_1, C_SE_NC_1,
    /// C_BO_NA_1 or a time-tagged form (C_SC_TA_1, ...).
    #[arg(long = "type")]
    type_id: TypeId,
    /// Value: ON/OFF for single and double commands (a single command also takes 1/0; a
    /// double command also takes its DCS number, 2 = ON, 1 = OFF, and refuses 0 and 3,
    /// which the standard does not permit), LOWER/HIGHER for regulating steps, a number
    /// for set-points, a number or 0x... for bit strings.
    #[arg(long, allow_hyphen_values = true)]
    value: String,
    /// Select before operate: send a select, and on its confirmation the execute.
    #[arg(long)]
    select: bool,
    /// Qualifier of command (QU 0..=31: 0 none, 1 short pulse, 2 long pulse, 3 persistent)
    /// or of set-point (QL 0..=127).
    #[arg(long, default_value_t = 0)]
    qualifier: u8,
    /// How long to wait for the connection, the confirmation and the termination (`10s`;
    /// a plain number is seconds).
    #[arg(long, value_name = "TIME", default_value = "10s", value_parser = crate::duration_arg::seconds)]
    timeout: Duration,
    /// One JSON object a line: what was sent (`{"event": "sent", ...}`), each received
    /// object as the client prints it, and each step's result (`{"event":
    /// "command_result", "step", "confirmation", "cause", "terminated"}`).
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    link: LinkOptions,
}

pub(crate) async fn run(args: CommandArgs) -> anyhow::Result<ExitCode> {
    if !args.type_id.is_command() {
        anyhow::bail!("{} is not a command type", args.type_id);
    }
    let ioa = Ioa::try_new(args.ioa).map_err(|error| anyhow::anyhow!("--ioa: {error}"))?;
    let execute = parse_command(args.type_id, &args.value, false, args.qualifier)?;
    let timeout = args
        .timeout
        .clamp(Duration::from_millis(100), Duration::from_secs(3600));
    let address = super::server_address(&args.address).await?;
    let mut config = ClientConfig::new(address, CommonAddress::new(args.ca));
    config.apci = args.link.apci()?;
    config.reconnect = false;
    config.command_timeout = timeout;
    if let Some(pem) = args.link.tls()? {
        let host = args
            .address
            .rsplit_once(':')
            .map(|(host, _)| host.trim_matches(['[', ']']).to_owned())
            .unwrap_or_default();
        config.tls = Some((
            iec60870::cs104::tls::client_config(&pem)?,
            iec60870::cs104::tls::server_name(&host)?,
        ));
    }
    let (client, mut events) = spawn_client(config);
    // Wait for the start of data transfer.
    let started = tokio::time::timeout(timeout, async {
        while let Some(event) = events.recv().await {
            match event {
                ClientEvent::Started => return Ok(()),
                ClientEvent::Disconnected { reason } => return Err(reason),
                _ => {}
            }
        }
        Err("client stopped".to_owned())
    })
    .await;
    match started {
        Ok(Ok(())) => {}
        Ok(Err(reason)) => {
            eprintln!("no connection: {reason}");
            return Ok(ExitCode::from(2));
        }
        Err(_) => {
            eprintln!("no connection within {:.1} s", timeout.as_secs_f64());
            return Ok(ExitCode::from(2));
        }
    }
    let mut steps = Vec::new();
    if args.select {
        steps.push((
            "select",
            parse_command(args.type_id, &args.value, true, args.qualifier)?,
        ));
    }
    steps.push(("execute", execute));
    let mut code = ExitCode::SUCCESS;
    let shown = Shown {
        type_id: args.type_id,
        ioa,
        // `--verbose`: every other ASDU that arrives meanwhile (spontaneous data, the
        // interrogation a server may send at start) too; by default only the command's
        // confirmation, termination and return information are shown.
        verbose: crate::verbosity::is_on(),
        json: args.json,
    };
    for (step, element) in steps {
        if args.json {
            println!(
                "{}",
                serde_json::json!({"event": "sent", "step": step, "type": args.type_id.mnemonic(), "ioa": ioa.get(), "text": element.to_string()})
            );
        } else {
            println!("-> {step} {} ioa={} {}", args.type_id, ioa, element);
        }
        let outcome = exchange(
            &client,
            &mut events,
            shown,
            element,
            command_time(args.type_id),
        )
        .await;
        if !report(step, &outcome, args.json) {
            code = match outcome {
                Ok(_) => ExitCode::from(1),
                Err(_) => ExitCode::from(2),
            };
            break;
        }
    }
    // Return information that follows the termination is still shown.
    let linger = tokio::time::sleep(Duration::from_millis(200));
    tokio::pin!(linger);
    loop {
        tokio::select! {
            () = &mut linger => break,
            event = events.recv() => match event {
                Some(event) => print_received(&event, shown),
                None => break,
            },
        }
    }
    client.close().await;
    Ok(code)
}

/// Sends one command and prints every ASDU as it arrives (the confirmation, the return
/// information, the termination), stamped with its arrival time; returns the outcome once
/// the ASDUs of its exchange have been printed.
async fn exchange(
    client: &iec60870::cs104::client::ClientHandle,
    events: &mut tokio::sync::mpsc::Receiver<ClientEvent>,
    shown: Shown,
    element: iec60870::asdu::Element,
    time: Option<iec60870::time::Cp56Time2a>,
) -> Result<RequestOutcome, ClientError> {
    let Shown { type_id, ioa, .. } = shown;
    let mut answers_printed = 0;
    let answers = |event: &ClientEvent| match event {
        ClientEvent::Asdu(asdu) => {
            asdu.type_id == type_id && asdu.objects.first().is_some_and(|o| o.ioa == ioa)
        }
        _ => false,
    };
    let command = client.command(type_id, ioa, element, time);
    tokio::pin!(command);
    let outcome = loop {
        tokio::select! {
            outcome = &mut command => break outcome,
            event = events.recv() => match event {
                Some(event) => {
                    answers_printed += usize::from(answers(&event));
                    print_received(&event, shown);
                }
                None => break (&mut command).await,
            },
        }
    };
    // The client hands the answers to the event stream too; show those not shown yet
    // before the verdict (bounded: the stream may have closed).
    if let Ok(outcome) = &outcome {
        let _ = tokio::time::timeout(Duration::from_secs(1), async {
            while answers_printed < outcome.responses.len() {
                match events.recv().await {
                    Some(event) => {
                        answers_printed += usize::from(answers(&event));
                        print_received(&event, shown);
                    }
                    None => break,
                }
            }
        })
        .await;
    }
    outcome
}

/// What of the received traffic is printed.
#[derive(Debug, Clone, Copy)]
struct Shown {
    /// The command's type and address: its confirmation and termination.
    type_id: TypeId,
    ioa: Ioa,
    /// Everything else too.
    verbose: bool,
    /// As JSON lines.
    json: bool,
}

impl Shown {
    /// The command's own answers and return information (causes 11 and 12); with
    /// `--verbose` every ASDU.
    fn shows(&self, asdu: &iec60870::asdu::Asdu) -> bool {
        use iec60870::asdu::Cause;
        self.verbose
            || (asdu.type_id == self.type_id && asdu.objects.iter().any(|o| o.ioa == self.ioa))
            || matches!(asdu.cot.cause, Cause::RETURN_REMOTE | Cause::RETURN_LOCAL)
    }
}

/// One received event, as the protocol analyser prints it (with its arrival time).
fn print_received(event: &ClientEvent, shown: Shown) {
    if let ClientEvent::Asdu(asdu) = event {
        if !shown.shows(asdu) {
            return;
        }
        if shown.json {
            crate::console::print_lines(&render::json_lines(event));
            return;
        }
        let arrow = if asdu.type_id.is_command() {
            "<-"
        } else {
            "  "
        };
        println!("{arrow} {}", render::analyser_text(event));
    }
}

/// A time tag for the time-tagged command types: now, in UTC.
fn command_time(type_id: TypeId) -> Option<iec60870::time::Cp56Time2a> {
    (type_id.time_tag() == iec60870::asdu::TimeTagKind::Cp56)
        .then(|| iec60870::time::Cp56Time2a::from_naive(chrono::Utc::now().naive_utc()).ok())
        .flatten()
}

/// Prints the confirmation sequence; returns whether it was positive and complete.
fn report(step: &str, outcome: &Result<RequestOutcome, ClientError>, json: bool) -> bool {
    if json {
        let line = match outcome {
            Ok(outcome) => serde_json::json!({
                "event": "command_result", "step": step,
                "confirmation": if outcome.positive { "positive" } else { "negative" },
                "cause": outcome.cause.name(), "terminated": outcome.terminated,
            }),
            Err(error) => serde_json::json!({
                "event": "command_result", "step": step, "error": error.to_string(),
            }),
        };
        println!("{line}");
        let positive = outcome.as_ref().is_ok_and(|outcome| outcome.positive);
        if outcome.as_ref().is_ok_and(|outcome| !outcome.positive) {
            eprintln!(
                "the station refused the command; a Stanice station records why in its \
                 command audit: stanice events PROJECT --commands"
            );
        }
        return positive;
    }
    match outcome {
        Ok(outcome) => {
            if outcome.positive {
                let termination = if outcome.terminated {
                    " and terminated"
                } else {
                    ""
                };
                println!("{step}: positive confirmation{termination}");
                true
            } else {
                println!("{step}: NEGATIVE confirmation (cause {})", outcome.cause);
                eprintln!(
                    "the station refused the command; a Stanice station records why in its \
                     command audit: stanice events PROJECT --commands"
                );
                false
            }
        }
        Err(error) => {
            println!("{step}: {error}");
            false
        }
    }
}
