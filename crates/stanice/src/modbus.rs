//! `stanice modbus`: Modbus TCP and RTU from the command line — read and write a device's
//! tables, and be a device (a TCP server or an RTU slave) for other tools.
//!
//! ```text
//! read    --tcp | --serial -> modbus::Client (timeout, retries) -> FC 1-4
//!         -> a table of values, or one JSON line
//! write   --coil A=V[,V...] | --register A=V[,V...] -> FC 5/15 or 6/16
//! serve   --listen -> modbus::io::serve_tcp | --serial/--pty -> modbus::io::serve_rtu
//!         on one DataModel (10,000 of each table, zeroed) -> a line per client write
//! ```
//!
//! An exception answered by the device is exit code 1 with its name on standard error
//! (`illegal data address (code 2)`); no answer within the timeout is exit code 2 naming
//! the device and the time, as the serial masters do for a station never reached.

use std::future::Future;
use std::pin::Pin;
use std::process::ExitCode;
use std::time::Duration;

use anyhow::{anyhow, bail, Context as _};
use clap::{Args, Subcommand};
use iec60870::ft12::Parity;
use modbus::io::{serve_rtu, serve_tcp};
use modbus::{
    Client, ClientConfig, ClientError, DataModel, ModelConfig, OpenError, RtuSlave, Setting, Table,
    Transport, Units, Values, WriteEvent,
};

use crate::link_report::NOT_REACHED;
use crate::serial_line::LineArgs;

/// The `stanice modbus` group's examples, its `--help` ends with.
pub(crate) const EXAMPLES: &str = "  stanice modbus serve --listen 127.0.0.1:5020 --json
  stanice modbus read --tcp 127.0.0.1:5020 --unit 1 --holding 100 10
  stanice modbus write --tcp 127.0.0.1:5020 --unit 1 --register 100=1,2,3
  stanice modbus serve --pty --unit 1                      # prints `pty: /dev/pts/N`
  stanice modbus read --serial /dev/pts/4 --parity none --unit 1 --coils 0 16";

/// `stanice modbus read`'s examples.
pub(crate) const READ_EXAMPLES: &str = "  stanice modbus read --tcp 10.0.0.5:502 --unit 1 --holding 100 10
  stanice modbus read --serial /dev/ttyUSB0 --unit 7 --input 0 4 --json    # 19200 Bd 8E1
  stanice modbus read --coils 0 16 --serial /dev/ttyUSB0 --baud 9600 --parity none --stop-bits 2 --unit 3
  stanice modbus read --tcp 127.0.0.1:5020 --unit 1 --discrete 196 22 --timeout 300ms --retries 0
ADDRESS is the protocol's 0-based address (register 40101 of a manual is --holding 100).
--json prints {\"unit\": 1, \"table\": \"holding\", \"address\": 100, \"values\": [...]}, coils and
discrete inputs as true/false. The exit code is 1 when the device answers an exception (named on
standard error), 2 when it does not answer.";

/// `stanice modbus write`'s examples.
pub(crate) const WRITE_EXAMPLES: &str =
    "  stanice modbus write --tcp 10.0.0.5:502 --unit 1 --coil 10=true        # FC 5
  stanice modbus write --tcp 10.0.0.5:502 --unit 1 --coil 20=1,0,1,1        # FC 15
  stanice modbus write --serial /dev/ttyUSB0 --unit 7 --register 100=-1     # FC 6: 65535
  stanice modbus write --register 100=1,2,0x8000 --tcp 127.0.0.1:5020 --unit 1   # FC 16
One value is FC 5 or 6, several FC 15 or 16. Coils: true/false, on/off or 1/0. Registers:
0..65535, 0x hex, or -32768..-1 for a signed INT (written as its two's complement, -1 = 65535).";

/// `stanice modbus serve`'s examples.
pub(crate) const SERVE_EXAMPLES: &str = "  stanice modbus serve --listen 127.0.0.1:5020
  stanice modbus serve --listen 0.0.0.0:502 --unit 1 --json      # port 502 needs root
  stanice modbus serve --pty --unit 1 --json                     # prints `pty: /dev/pts/N` first
  stanice modbus serve --serial /dev/ttyUSB0 --baud 9600 --parity even --unit 7
10,000 coils, discrete inputs, holding and input registers, zeroed, shared by every client;
runs until Ctrl-C or SIGTERM. Without --unit every unit id is answered; with it, another unit's
request is answered exception 0x0B over TCP and not at all on a serial line. --json prints a line
per write by a client: {\"unit\": 1, \"table\": \"holding\", \"address\": 100, \"count\": 2,
\"values\": [1, 2]}.";

/// `Examples:` and the examples, for an `after_help`.
pub(crate) fn help(examples: &str) -> String {
    format!("Examples:\n{examples}")
}

/// The `stanice modbus` subcommands.
#[derive(Debug, Subcommand)]
pub(crate) enum ModbusCommand {
    /// Read coils, discrete inputs, holding or input registers of a device (FC 1-4).
    #[command(after_help = help(READ_EXAMPLES))]
    Read(ReadArgs),
    /// Write coils (FC 5, 15) or holding registers (FC 6, 16) of a device.
    #[command(after_help = help(WRITE_EXAMPLES))]
    Write(WriteArgs),
    /// A Modbus TCP server or RTU slave with 10,000 of each table, zeroed; a line per
    /// write by a client.
    #[command(after_help = help(SERVE_EXAMPLES))]
    Serve(ServeArgs),
}

/// The serial line's settings (RTU).
#[derive(Args, Clone, Debug)]
pub(crate) struct SerialSettings {
    /// Line speed in baud (1200-115200).
    #[arg(long, default_value_t = 19_200)]
    baud: u32,
    /// Parity: even (the Modbus standard's, the default on a serial port), odd or none
    /// (the default with --pty, which keeps no parity).
    #[arg(long)]
    parity: Option<Parity>,
    /// Stop bits, 1 or 2 (the standard wants 2 without parity; many devices take 1).
    #[arg(long, default_value_t = 1)]
    stop_bits: u8,
}

/// The device a client talks to.
#[derive(Args, Clone, Debug)]
pub(crate) struct DeviceArgs {
    /// A Modbus TCP server at HOST:PORT.
    #[arg(
        long,
        value_name = "HOST:PORT",
        conflicts_with = "serial",
        required_unless_present = "serial"
    )]
    tcp: Option<String>,
    /// Modbus RTU on a serial port (/dev/ttyUSB0, or a pseudo-terminal's path).
    #[arg(long, value_name = "DEV")]
    serial: Option<String>,
    #[command(flatten)]
    settings: SerialSettings,
    /// The unit id (slave address): 1-247 on a serial line, 0-255 over TCP.
    #[arg(long, value_name = "N")]
    unit: u8,
    /// How long to wait for an answer (`300ms`, `2s`; a plain number is milliseconds).
    #[arg(long, value_name = "TIME", default_value = "1s", value_parser = crate::duration_arg::millis)]
    timeout: Duration,
    /// Repeats of a request that got no answer.
    #[arg(long, default_value_t = 2)]
    retries: u8,
}

/// Which table `read` reads: exactly one of the four flags.
#[derive(Args, Clone, Debug)]
#[group(required = true, multiple = false)]
pub(crate) struct TableArgs {
    /// Coils (FC 1).
    #[arg(long)]
    coils: bool,
    /// Discrete inputs (FC 2).
    #[arg(long)]
    discrete: bool,
    /// Holding registers (FC 3).
    #[arg(long)]
    holding: bool,
    /// Input registers (FC 4).
    #[arg(long)]
    input: bool,
}

impl TableArgs {
    fn table(&self) -> Table {
        if self.coils {
            Table::Coils
        } else if self.discrete {
            Table::DiscreteInputs
        } else if self.holding {
            Table::HoldingRegisters
        } else {
            Table::InputRegisters
        }
    }
}

/// `stanice modbus read`
#[derive(Debug, Args)]
pub(crate) struct ReadArgs {
    #[command(flatten)]
    device: DeviceArgs,
    #[command(flatten)]
    table: TableArgs,
    /// The first address, 0-based (0-65535).
    address: u16,
    /// How many: 1-2000 coils or discrete inputs, 1-125 registers.
    count: u16,
    /// One JSON line: {"unit": 1, "table": "holding", "address": 100, "values": [...]}.
    #[arg(long)]
    json: bool,
}

/// `stanice modbus write`
#[derive(Debug, Args)]
pub(crate) struct WriteArgs {
    #[command(flatten)]
    device: DeviceArgs,
    /// Coils from ADDRESS: one value is FC 5, several FC 15 (true/false, on/off, 1/0).
    #[arg(
        long,
        value_name = "ADDRESS=VALUE[,VALUE...]",
        conflicts_with = "register",
        required_unless_present = "register"
    )]
    coil: Option<String>,
    /// Holding registers from ADDRESS: one value is FC 6, several FC 16 (0..65535, 0x
    /// hex, or -32768..-1 as two's complement).
    #[arg(long, value_name = "ADDRESS=VALUE[,VALUE...]")]
    register: Option<String>,
    /// One JSON line of what was written, shaped as `read --json`'s.
    #[arg(long)]
    json: bool,
}

/// `stanice modbus serve`
#[derive(Debug, Args)]
pub(crate) struct ServeArgs {
    /// Modbus TCP: listen on ADDR:PORT (port 0: any free one, printed).
    #[arg(long, value_name = "ADDR:PORT", conflicts_with_all = ["serial", "pty"], required_unless_present_any = ["serial", "pty"])]
    listen: Option<String>,
    /// Modbus RTU slave on a serial port.
    #[arg(long, value_name = "DEV", conflicts_with = "pty")]
    serial: Option<String>,
    /// Modbus RTU slave on a new pseudo-terminal pair: prints `pty: /dev/pts/N` first,
    /// the path for the client to open.
    #[arg(long)]
    pty: bool,
    #[command(flatten)]
    settings: SerialSettings,
    /// Answer this unit id only; every unit id without it.
    #[arg(long, value_name = "N")]
    unit: Option<u8>,
    /// One JSON line per write by a client.
    #[arg(long)]
    json: bool,
}

/// Runs a `modbus` subcommand.
pub(crate) async fn run(command: ModbusCommand) -> anyhow::Result<ExitCode> {
    match command {
        ModbusCommand::Read(args) => read(args).await,
        ModbusCommand::Write(args) => write(args).await,
        ModbusCommand::Serve(args) => serve(args).await,
    }
}

/// The serial-line options as the shared `LineArgs`: even parity by default on a port,
/// none on a pseudo-terminal, whose refusal of parity is said before anything opens.
fn line_args(
    serial: Option<String>,
    pty: bool,
    settings: &SerialSettings,
) -> anyhow::Result<LineArgs> {
    let parity = match (pty, settings.parity) {
        (true, None) => Parity::None,
        (true, Some(Parity::None)) => Parity::None,
        (true, Some(parity)) => bail!(
            "a pseudo-terminal keeps no parity: --parity {parity} is refused; use --parity none"
        ),
        (false, parity) => parity.unwrap_or(Parity::Even),
    };
    Ok(LineArgs {
        serial,
        pty,
        tcp: None,
        listen: None,
        baud: settings.baud,
        parity,
        stop_bits: settings.stop_bits,
    })
}

/// An error opening a line, with the way out when the port refused the parity.
fn open_failed(error: anyhow::Error) -> anyhow::Error {
    let refused = |error: &OpenError| matches!(error, OpenError::Refused { refused, .. } if refused.setting == Setting::Parity);
    let parity_refused = error.chain().any(|cause| {
        cause.downcast_ref::<OpenError>().is_some_and(refused)
            || matches!(cause.downcast_ref::<ClientError>(), Some(ClientError::Open(open)) if refused(open))
    });
    if parity_refused {
        anyhow!("{error:#}; a pseudo-terminal or a converter without parity: use --parity none")
    } else {
        error
    }
}

/// A client on the device the options name.
async fn client(device: &DeviceArgs) -> anyhow::Result<Client> {
    let (transport, mut config) = match (&device.tcp, &device.serial) {
        (Some(address), None) => (Transport::Connect(address.clone()), ClientConfig::tcp()),
        (None, Some(_)) => {
            if !(1..=247).contains(&device.unit) {
                bail!(
                    "--unit {} on a serial line: a slave's address is 1-247 (0 is the broadcast, which nothing answers)",
                    device.unit
                );
            }
            let line = line_args(device.serial.clone(), false, &device.settings)?;
            (line.transport()?, ClientConfig::rtu(line.settings()?))
        }
        _ => bail!("name the device: --tcp HOST:PORT or --serial DEV"),
    };
    config.timeout = crate::serial_line::within(
        device.timeout,
        Duration::from_millis(5)..=Duration::from_secs(60),
        "--timeout",
    )?;
    config.retries = device.retries;
    // The error names the transport itself (`tcp 10.0.0.5:502: Connection refused`).
    Client::open(transport, config)
        .await
        .map_err(|error| open_failed(error.into()))
}

/// The exit code and message of a request that failed.
fn failed(error: ClientError) -> anyhow::Result<ExitCode> {
    match error {
        ClientError::Exception { .. } => {
            eprintln!("error: {error}");
            Ok(ExitCode::FAILURE)
        }
        ClientError::Timeout { .. } | ClientError::Io { .. } => {
            eprintln!("error: {error}");
            Ok(ExitCode::from(NOT_REACHED))
        }
        error => Err(error.into()),
    }
}

/// `{"unit": 1, "table": "holding", "address": 100, "values": [1, 2]}`, with `count`
/// before the values when asked (a server's write lines).
fn json_line(unit: u8, table: Table, address: u16, values: &Values, count: bool) -> String {
    let listed = match values {
        Values::Bits(bits) => bits.iter().map(bool::to_string).collect::<Vec<_>>(),
        Values::Registers(registers) => registers.iter().map(u16::to_string).collect(),
    };
    let count = if count {
        format!(", \"count\": {}", values.len())
    } else {
        String::new()
    };
    format!(
        "{{\"unit\": {unit}, \"table\": \"{}\", \"address\": {address}{count}, \"values\": [{}]}}",
        table.name(),
        listed.join(", ")
    )
}

/// The values as a table: address, value (and hex and signed for registers).
fn value_table(unit: u8, table: Table, address: u16, values: &Values, peer: &str) -> Vec<String> {
    let last = usize::from(address) + values.len().saturating_sub(1);
    let mut lines = vec![format!(
        "unit {unit} on {peer}, {} {address}..={last}",
        table.long_name()
    )];
    match values {
        Values::Bits(bits) => {
            lines.push(format!("{:>7}  value", "address"));
            for (offset, bit) in bits.iter().enumerate() {
                lines.push(format!(
                    "{:>7}  {}",
                    usize::from(address) + offset,
                    u8::from(*bit)
                ));
            }
        }
        Values::Registers(registers) => {
            lines.push(format!(
                "{:>7}  {:>5}  {:>6}  {:>6}",
                "address", "value", "hex", "signed"
            ));
            for (offset, value) in registers.iter().enumerate() {
                lines.push(format!(
                    "{:>7}  {value:>5}  0x{value:04X}  {:>6}",
                    usize::from(address) + offset,
                    i16::from_ne_bytes(value.to_ne_bytes())
                ));
            }
        }
    }
    lines
}

/// A client, or the exit code of a device not reached (no TCP connection; exit code 2,
/// as a device that does not answer).
async fn client_or_exit(device: &DeviceArgs) -> anyhow::Result<Result<Client, ExitCode>> {
    match client(device).await {
        Ok(client) => Ok(Ok(client)),
        Err(error) => match error.downcast_ref::<ClientError>() {
            Some(ClientError::Open(OpenError::Tcp { .. })) => {
                eprintln!("error: {error:#}");
                Ok(Err(ExitCode::from(NOT_REACHED)))
            }
            _ => Err(error),
        },
    }
}

async fn read(args: ReadArgs) -> anyhow::Result<ExitCode> {
    let table = args.table.table();
    let mut client = match client_or_exit(&args.device).await? {
        Ok(client) => client,
        Err(code) => return Ok(code),
    };
    let unit = args.device.unit;
    let values = match client.read(unit, table, args.address, args.count).await {
        Ok(values) => values,
        Err(error) => return failed(error),
    };
    let lines = if args.json {
        vec![json_line(unit, table, args.address, &values, false)]
    } else {
        value_table(unit, table, args.address, &values, client.peer())
    };
    crate::console::print_lines(&lines);
    Ok(ExitCode::SUCCESS)
}

/// `ADDRESS=VALUE[,VALUE...]`: the address and the values' words.
fn assignment<'a>(text: &'a str, option: &str) -> anyhow::Result<(u16, Vec<&'a str>)> {
    let (address, values) = text
        .split_once('=')
        .ok_or_else(|| anyhow!("{option} {text:?}: expected ADDRESS=VALUE[,VALUE...]"))?;
    let address = parse_number(address)
        .and_then(|number| u16::try_from(number).ok())
        .ok_or_else(|| anyhow!("{option} {text:?}: address {address:?} is not 0-65535"))?;
    let values: Vec<&str> = values.split(',').map(str::trim).collect();
    if values.iter().any(|value| value.is_empty()) {
        bail!("{option} {text:?}: an empty value");
    }
    Ok((address, values))
}

/// A decimal number (with a sign) or a 0x hex one.
fn parse_number(text: &str) -> Option<i64> {
    let text = text.trim();
    match text.strip_prefix("0x").or_else(|| text.strip_prefix("0X")) {
        Some(hex) => i64::from_str_radix(hex, 16).ok(),
        None => text.parse().ok(),
    }
}

fn parse_coil(text: &str) -> anyhow::Result<bool> {
    match text.to_ascii_lowercase().as_str() {
        "true" | "1" | "on" => Ok(true),
        "false" | "0" | "off" => Ok(false),
        _ => bail!("coil value {text:?}: expected true/false, on/off or 1/0"),
    }
}

/// A register: 0..=65535, or -32768..=-1 as its two's complement.
fn parse_register(text: &str) -> anyhow::Result<u16> {
    let number =
        parse_number(text).ok_or_else(|| anyhow!("register value {text:?} is not a number"))?;
    if let Ok(unsigned) = u16::try_from(number) {
        return Ok(unsigned);
    }
    match i16::try_from(number) {
        Ok(signed) => Ok(u16::from_ne_bytes(signed.to_ne_bytes())),
        Err(_) => bail!("register value {text} outside -32768..=65535"),
    }
}

async fn write(args: WriteArgs) -> anyhow::Result<ExitCode> {
    // The values are checked before anything opens.
    let (table, address, values) = match (&args.coil, &args.register) {
        (Some(text), None) => {
            let (address, words) = assignment(text, "--coil")?;
            let bits = words
                .iter()
                .map(|word| parse_coil(word))
                .collect::<anyhow::Result<Vec<bool>>>()?;
            (Table::Coils, address, Values::Bits(bits))
        }
        (None, Some(text)) => {
            let (address, words) = assignment(text, "--register")?;
            let registers = words
                .iter()
                .map(|word| parse_register(word))
                .collect::<anyhow::Result<Vec<u16>>>()?;
            (
                Table::HoldingRegisters,
                address,
                Values::Registers(registers),
            )
        }
        _ => bail!(
            "name what to write: --coil ADDRESS=VALUE[,...] or --register ADDRESS=VALUE[,...]"
        ),
    };
    let mut client = match client_or_exit(&args.device).await? {
        Ok(client) => client,
        Err(code) => return Ok(code),
    };
    let unit = args.device.unit;
    let result = match &values {
        Values::Bits(bits) => client.write_coils(unit, address, bits).await,
        Values::Registers(registers) => client.write_registers(unit, address, registers).await,
    };
    if let Err(error) = result {
        return failed(error);
    }
    let line = if args.json {
        json_line(unit, table, address, &values, false)
    } else {
        let function = match (&values, values.len()) {
            (Values::Bits(_), 1) => 5,
            (Values::Bits(_), _) => 15,
            (Values::Registers(_), 1) => 6,
            (Values::Registers(_), _) => 16,
        };
        format!(
            "unit {unit} on {}: wrote {} (FC {function})",
            client.peer(),
            written(table, address, &values)
        )
    };
    crate::console::print_lines(&[line]);
    Ok(ExitCode::SUCCESS)
}

/// `holding registers 100..=102 = 1, 2, 3`, `coil 10 = true`.
fn written(table: Table, address: u16, values: &Values) -> String {
    let listed = match values {
        Values::Bits(bits) => bits.iter().map(bool::to_string).collect::<Vec<_>>(),
        Values::Registers(registers) => registers.iter().map(u16::to_string).collect(),
    };
    let name = table.long_name();
    if values.len() == 1 {
        format!(
            "{} {address} = {}",
            name.trim_end_matches('s'),
            listed.join(", ")
        )
    } else {
        let last = usize::from(address) + values.len() - 1;
        format!("{name} {address}..={last} = {}", listed.join(", "))
    }
}

type Serving = Pin<Box<dyn Future<Output = anyhow::Result<()>> + Send>>;

async fn serve(args: ServeArgs) -> anyhow::Result<ExitCode> {
    let units = match args.unit {
        Some(unit) => Units::Single(unit),
        None => Units::Any,
    };
    let answering = match args.unit {
        Some(unit) => format!("unit {unit}"),
        None => "every unit id".to_owned(),
    };
    let model = DataModel::new(ModelConfig::new(units));
    let mut events = model.subscribe();
    let json = args.json;
    // Without --json the banner is for people; with it, standard output is the writes'
    // lines (and a pseudo-terminal's path first).
    let say = move |text: String| {
        if json {
            eprintln!("{text}");
        } else {
            crate::console::print_lines(&[text]);
        }
    };
    let mut interrupt = crate::interrupt::Interrupt::listen();
    let serving: Serving = match &args.listen {
        Some(address) => {
            let listener = tokio::net::TcpListener::bind(address)
                .await
                .with_context(|| format!("cannot listen on tcp {address}"))?;
            say(format!(
                "Modbus TCP server on {} ({answering}), 10,000 of each table; Ctrl-C stops",
                listener.local_addr()?
            ));
            let model = model.clone();
            Box::pin(async move {
                serve_tcp(listener, model).await?;
                Ok(())
            })
        }
        None => {
            let line_args = line_args(args.serial.clone(), args.pty, &args.settings)?;
            let settings = line_args.settings()?;
            let transport = line_args.transport()?;
            let line = line_args.open(&transport).await.map_err(open_failed)?;
            say(format!(
                "Modbus RTU slave on {} ({settings}, {answering}), 10,000 of each table; Ctrl-C stops",
                line.peer
            ));
            let model = model.clone();
            Box::pin(async move {
                // The whole line is kept: a pseudo-terminal's other end stays open.
                let mut line = line;
                let stream = std::mem::replace(&mut line.stream, Box::pin(tokio::io::empty()));
                let peer = line.peer.clone();
                let mut slave = RtuSlave::new(model, settings);
                let end = serve_rtu(stream, &mut slave).await;
                drop(line);
                match end {
                    Ok(_) => bail!("the line {peer} closed"),
                    Err(error) => Err(anyhow!("the line {peer} failed: {error}")),
                }
            })
        }
    };
    let mut serving = serving;
    let print = |event: &WriteEvent| {
        let line = if json {
            json_line(event.unit, event.table, event.address, &event.values, true)
        } else {
            format!(
                "unit {} wrote {}",
                event.unit,
                written(event.table, event.address, &event.values)
            )
        };
        crate::console::print_lines(&[line])
    };
    let result = loop {
        tokio::select! {
            result = &mut serving => break result,
            () = interrupt.recv() => break Ok(()),
            Some(event) = events.recv() => {
                if !print(&event) {
                    break Ok(());
                }
            }
        }
    };
    while let Ok(event) = events.try_recv() {
        print(&event);
    }
    result.map(|()| ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]

    use super::*;

    #[test]
    fn registers_take_unsigned_hex_and_signed_values() {
        assert_eq!(parse_register("0").unwrap(), 0);
        assert_eq!(parse_register("65535").unwrap(), 65535);
        assert_eq!(parse_register("0x8000").unwrap(), 0x8000);
        assert_eq!(parse_register("-1").unwrap(), 0xFFFF);
        assert_eq!(parse_register("-32768").unwrap(), 0x8000);
        assert!(parse_register("65536").is_err());
        assert!(parse_register("-32769").is_err());
        assert!(parse_register("1.5").is_err());
        assert!(parse_coil("ON").unwrap());
        assert!(!parse_coil("0").unwrap());
        assert!(parse_coil("2").is_err());
        assert_eq!(
            assignment("100=1, 2,3", "--register").unwrap(),
            (100, vec!["1", "2", "3"])
        );
        assert!(assignment("100", "--register").is_err());
        assert!(assignment("70000=1", "--register").is_err());
        assert!(assignment("1=1,,2", "--register").is_err());
    }

    #[test]
    fn json_lines_have_the_documented_shape() {
        assert_eq!(
            json_line(
                1,
                Table::HoldingRegisters,
                100,
                &Values::Registers(vec![1, 2]),
                false
            ),
            r#"{"unit": 1, "table": "holding", "address": 100, "values": [1, 2]}"#
        );
        assert_eq!(
            json_line(3, Table::Coils, 7, &Values::Bits(vec![true, false]), true),
            r#"{"unit": 3, "table": "coils", "address": 7, "count": 2, "values": [true, false]}"#
        );
        assert_eq!(
            written(Table::Coils, 10, &Values::Bits(vec![true])),
            "coil 10 = true"
        );
        assert_eq!(
            written(Table::HoldingRegisters, 100, &Values::Registers(vec![1, 2])),
            "holding registers 100..=101 = 1, 2"
        );
    }
}
