//! `stanice s7`: Siemens S7 over ISO-on-TCP from the command line — read and write a
//! PLC's memory by absolute address, and be a PLC for the tools and relays that talk to
//! one (the railway-station thesis, section 3.3: LOGO! relays exchanging transfer areas
//! with an S7-1500).
//!
//! ```text
//! read ITEM...        parse every ITEM (DB1.DBW2:INT) -> connect (TSAPs from --rack/--slot
//!                     or --tsap) -> one read, split by the PDU size -> a line per item
//! write ITEM=VALUE... parse every item and value -> connect -> one write, split likewise
//!                     -> a line per item
//! serve               memory (--db N:SIZE, I, Q, M) -> s7::io::serve on --listen
//!                     -> a line per client write (and per connection without --json)
//! ```
//!
//! A misspelt item or value stops the command before it connects (clap's usage error,
//! exit 2, naming the item and what is wrong). An item the PLC refuses is reported on
//! its own line and on standard error; the others are still printed; the exit code is
//! then 1. No connection, or a connection lost mid-request, is exit code 2.

use std::fmt;
use std::net::{IpAddr, SocketAddr};
use std::process::ExitCode;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use ::s7::io::{Client, ClientError, ServeEvent};
use ::s7::{
    Address, ClientConfig, ConnectionError, Memory, Region, ServerConfig, ServerEvent, Tsap, Tsaps,
    Value, WriteEvent,
};
use clap::{Args, Subcommand};

use crate::link_report::NOT_REACHED;

/// The ISO-on-TCP port, taken when `--connect` names no port.
const DEFAULT_PORT: u16 = ::s7::io::ISO_TCP_PORT;

/// Exit code when the PLC refused an item (the others were read or written).
const ITEM_FAILED: u8 = 1;

/// The `stanice s7` group's examples, its `--help` ends with.
pub(crate) const EXAMPLES: &str = "  stanice s7 serve --listen 127.0.0.1:10102 --db 1:256 --db 2:64
  stanice s7 read --connect 127.0.0.1:10102 DB1.DBW2 DB1.DBD8:REAL MB10 IX0.1
  stanice s7 write --connect 127.0.0.1:10102 DB1.DBW2=1234 DB1.DBX0.3=true";

/// `stanice s7 read`'s examples.
pub(crate) const READ_EXAMPLES: &str = "  stanice s7 read --connect 192.168.0.1 DB1.DBW2 DB1.DBX0.3 MW20      # port 102, rack 0, slot 1
  stanice s7 read --connect 192.168.0.1:102 --rack 0 --slot 2 DB1.DBD8:REAL DB1.DBW12:INT
  stanice s7 read --connect 192.168.0.3 --tsap 0100:2000 --json DB1.DBB0 QX0.2   # a LOGO!
  stanice s7 read DB1.DBW2 I0.1 M10.0 --connect 127.0.0.1:10102 --timeout 2s
Items: DB1.DBX0.3 (a bit), DB1.DBB1, DB1.DBW2, DB1.DBD4 (byte, word, double word), MB10,
MW20, MD24, M10.0, IB0, IX0.1 or I0.1, QB0, QX0.2 or Q0.2; a type after a colon, :INT, :DINT,
:REAL (also :SINT, :BYTE, :WORD, :DWORD, :BOOL); words and double words are unsigned without
one. --json prints {\"item\": \"DB1.DBW2\", \"value\": 1234} per item, {\"item\": ..., \"error\": ...}
for one the PLC refused. The exit code is 0 when every item was read, 1 when the PLC refused
one, 2 without a connection.";

/// `stanice s7 write`'s examples.
pub(crate) const WRITE_EXAMPLES: &str =
    "  stanice s7 write --connect 192.168.0.1 DB1.DBW2=1234 DB1.DBX0.3=true
  stanice s7 write --connect 192.168.0.1 DB1.DBD8:REAL=21.5 DB1.DBW12:INT=-7 MB10=0x1F
  stanice s7 write QX0.2=1 MW20=65535 --connect 192.168.0.3 --tsap 0100:2000 --json
All items go in one request, split into as many jobs as the PDU size needs; a bit is written
alone, its byte's other bits untouched. The exit code is 0 when every item was written, 1 when
the PLC refused one (named on standard error), 2 without a connection.";

/// `stanice s7 serve`'s examples.
pub(crate) const SERVE_EXAMPLES: &str =
    "  stanice s7 serve --listen 127.0.0.1:10102 --db 1:256 --db 2:64
  stanice s7 serve --listen 0.0.0.0:102 --db 1:1024 --pdu-size 960 --json   # port 102 needs root
  stanice s7 serve --listen 127.0.0.1:0 --db 10:32 --area-size 64      # any free port, printed
Serves inputs (I), outputs (Q) and markers (M) of --area-size bytes and the data blocks given,
all zeroed, to any number of clients with any TSAPs (PG, OP, S7 basic, a LOGO!'s), until
Ctrl-C or SIGTERM. --json prints one line per client write: {\"area\": \"DB\", \"db\": 1,
\"start\": 4, \"size\": 2, \"data\": \"04d2\"} (\"bit\" for a bit write).";

/// `Examples:` and the examples, for an `after_help`.
pub(crate) fn help(examples: &str) -> String {
    format!("Examples:\n{examples}")
}

/// The `stanice s7` subcommands.
#[derive(Debug, Subcommand)]
pub(crate) enum S7Command {
    /// Read items of a PLC's memory by absolute address (DB1.DBW2, MB10, IX0.1, ...).
    #[command(after_help = help(READ_EXAMPLES))]
    Read(ReadArgs),
    /// Write items of a PLC's memory: ITEM=VALUE, several in one request.
    #[command(after_help = help(WRITE_EXAMPLES))]
    Write(WriteArgs),
    /// A simulated PLC: data blocks, inputs, outputs and markers served to S7 clients,
    /// each client write printed.
    #[command(after_help = help(SERVE_EXAMPLES))]
    Serve(ServeArgs),
}

/// Where the PLC is and how to address its CPU.
#[derive(Args, Debug)]
pub(crate) struct ConnectArgs {
    /// The PLC: HOST:PORT, or HOST alone for port 102.
    #[arg(long, value_name = "HOST:PORT", value_parser = parse_target)]
    connect: Target,
    /// The CPU's rack, 0-7 (remote TSAP 03, then rack x 32 + slot). Default 0.
    #[arg(long, value_parser = clap::value_parser!(u8).range(0..=7), conflicts_with = "tsap")]
    rack: Option<u8>,
    /// The CPU's slot, 0-31. Default 1 (an S7-300's CPU; S7-1200/1500 answer to it).
    #[arg(long, value_parser = clap::value_parser!(u8).range(0..=31), conflicts_with = "tsap")]
    slot: Option<u8>,
    /// The TSAPs as LOCAL:REMOTE in four hex digits each (`0100:0301`), as a configured
    /// connection of a LOGO! or an S7-1200/1500 has them; in place of --rack and --slot.
    #[arg(long, value_name = "LOCAL:REMOTE", value_parser = parse_tsaps)]
    tsap: Option<Tsaps>,
    /// How long connecting, and then the request, may take (`500ms`, `5s`; a plain
    /// number is seconds).
    #[arg(long, value_name = "TIME", default_value = "5s", value_parser = crate::duration_arg::seconds)]
    timeout: Duration,
}

impl ConnectArgs {
    fn tsaps(&self) -> Tsaps {
        match &self.tsap {
            Some(tsaps) => tsaps.clone(),
            None => Tsaps::rack_slot(self.rack.unwrap_or(0), self.slot.unwrap_or(1)),
        }
    }
}

/// `stanice s7 read`
#[derive(Args, Debug)]
pub(crate) struct ReadArgs {
    #[command(flatten)]
    connection: ConnectArgs,
    /// One JSON object a line: `{"item": "DB1.DBW2", "value": 1234}`, or
    /// `{"item": ..., "error": "..."}` for an item the PLC refused.
    #[arg(long)]
    json: bool,
    /// Absolute addresses with an optional type: DB1.DBX0.3, DB1.DBW2, DB1.DBD8:REAL,
    /// MB10, MW20:INT, I0.1, QX0.2.
    #[arg(value_name = "ITEM", required = true, value_parser = parse_item)]
    items: Vec<Item>,
}

/// `stanice s7 write`
#[derive(Args, Debug)]
pub(crate) struct WriteArgs {
    #[command(flatten)]
    connection: ConnectArgs,
    /// One JSON object a line: `{"item": "DB1.DBW2", "written": 1234}`, or
    /// `{"item": ..., "error": "..."}` for an item the PLC refused.
    #[arg(long)]
    json: bool,
    /// ITEM=VALUE: numbers (hex as 0x1F for the unsigned types), true/false for bits;
    /// DB1.DBW2=1234, DB1.DBX0.3=true, DB1.DBD8:REAL=21.5.
    #[arg(value_name = "ITEM=VALUE", required = true, value_parser = parse_assignment)]
    items: Vec<Assignment>,
}

/// `stanice s7 serve`
#[derive(Args, Debug)]
pub(crate) struct ServeArgs {
    /// Address to listen on; port 0 takes any free port (printed at the start).
    #[arg(long, value_name = "ADDR:PORT", default_value = "127.0.0.1:102")]
    listen: SocketAddr,
    /// A data block, zeroed: NUMBER:SIZE in bytes (`1:256`). Repeatable.
    #[arg(long = "db", value_name = "N:SIZE", value_parser = parse_data_block)]
    data_blocks: Vec<DataBlock>,
    /// Bytes of each of the inputs (I), outputs (Q) and markers (M), zeroed.
    #[arg(long, value_name = "BYTES", default_value_t = 1024,
          value_parser = clap::value_parser!(u32).range(1..=65_536))]
    area_size: u32,
    /// The largest PDU size granted: 240 as a LOGO! or S7-1200, 480 as an S7-300, 960 as
    /// an S7-1500.
    #[arg(long, value_name = "BYTES", default_value_t = 240,
          value_parser = clap::value_parser!(u16).range(64..=960))]
    pdu_size: u16,
    /// One JSON object a line per client write, `{"area": "DB", "db": 1, "start": 4,
    /// "size": 2, "data": "04d2"}`, and nothing about connections.
    #[arg(long)]
    json: bool,
    /// Stop after this long (`30s`, `10m`; a plain number is seconds); runs until Ctrl-C
    /// or SIGTERM otherwise.
    #[arg(long, value_name = "TIME", value_parser = crate::duration_arg::seconds)]
    duration: Option<Duration>,
}

/// The PLC's address as given, with port 102 added when it had none.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Target(String);

impl fmt::Display for Target {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

/// `HOST:PORT`, `HOST`, `IP`, `[IPv6]:PORT`, `[IPv6]` or a bare IPv6 address.
fn parse_target(text: &str) -> Result<Target, String> {
    let text = text.trim();
    if text.is_empty() {
        return Err("no address: expected HOST:PORT or HOST (port 102)".to_owned());
    }
    if text.parse::<SocketAddr>().is_ok() {
        return Ok(Target(text.to_owned()));
    }
    if let Ok(ip) = text.parse::<IpAddr>() {
        return Ok(Target(SocketAddr::new(ip, DEFAULT_PORT).to_string()));
    }
    if text.starts_with('[') && text.ends_with(']') {
        return Ok(Target(format!("{text}:{DEFAULT_PORT}")));
    }
    match text.rsplit_once(':') {
        None => Ok(Target(format!("{text}:{DEFAULT_PORT}"))),
        Some((host, port)) if !host.is_empty() && !host.contains(':') => port
            .parse::<u16>()
            .map(|_| Target(text.to_owned()))
            .map_err(|_| format!("{port:?} is no port number (0-65535)")),
        Some(_) => Err("expected HOST:PORT, HOST (port 102) or [IPv6]:PORT".to_owned()),
    }
}

fn parse_tsaps(text: &str) -> Result<Tsaps, String> {
    text.parse::<Tsaps>().map_err(|error| error.to_string())
}

/// An item as written on the command line and the address it names.
#[derive(Debug, Clone)]
pub(crate) struct Item {
    text: String,
    address: Address,
}

fn parse_item(text: &str) -> Result<Item, String> {
    match text.parse::<Address>() {
        Ok(address) => Ok(Item {
            text: text.to_owned(),
            address,
        }),
        Err(error) => Err(format!("{text}: {}", error.kind)),
    }
}

/// `ITEM=VALUE`, the value parsed as the item's type.
#[derive(Debug, Clone)]
pub(crate) struct Assignment {
    item: Item,
    value: Value,
}

fn parse_assignment(text: &str) -> Result<Assignment, String> {
    let Some((item, value)) = text.split_once('=') else {
        return Err(format!(
            "{text}: expected ITEM=VALUE, e.g. DB1.DBW2=1234 or DB1.DBX0.3=true"
        ));
    };
    let item = parse_item(item)?;
    let value = item
        .address
        .parse_value(value)
        .map_err(|error| format!("{}: {error}", item.text))?;
    Ok(Assignment { item, value })
}

/// A `--db N:SIZE`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct DataBlock {
    number: u16,
    size: u32,
}

fn parse_data_block(text: &str) -> Result<DataBlock, String> {
    let usage = || format!("{text:?}: expected NUMBER:SIZE, e.g. 1:256 for DB1 of 256 bytes");
    let (number, size) = text.trim().split_once(':').ok_or_else(usage)?;
    let number = number
        .trim()
        .trim_start_matches(['D', 'B', 'd', 'b'])
        .parse::<u64>()
        .map_err(|_| usage())?;
    let size = size.trim().parse::<u64>().map_err(|_| usage())?;
    let number = match u16::try_from(number) {
        Ok(0) => return Err("data block 0 does not exist on a PLC: numbers start at 1".into()),
        Ok(number) => number,
        Err(_) => return Err(format!("data block number {number} is above 65535")),
    };
    let max = u64::from(::s7::address::MAX_BYTE) + 1;
    if size == 0 || size > max {
        return Err(format!(
            "DB{number}: a size of {size} bytes; a data block has 1 to {max} bytes"
        ));
    }
    Ok(DataBlock {
        number,
        // At most MAX_BYTE + 1, checked above.
        size: u32::try_from(size).unwrap_or(u32::MAX),
    })
}

/// Runs an `s7` subcommand.
pub(crate) async fn run(command: S7Command) -> anyhow::Result<ExitCode> {
    match command {
        S7Command::Read(args) => read(args).await,
        S7Command::Write(args) => write(args).await,
        S7Command::Serve(args) => serve(args).await,
    }
}

/// A whole call that failed, in words naming the PLC (and the time, for a timeout).
fn describe(error: &ClientError, target: &Target, connecting: bool) -> String {
    match error {
        ClientError::Io(io) if connecting => format!("cannot connect to {target}: {io}"),
        ClientError::Io(io) => format!("{target}: the connection failed: {io}"),
        ClientError::Timeout(time) if connecting => format!(
            "{target}: no S7 connection within {}",
            humantime::format_duration(*time)
        ),
        ClientError::Timeout(time) => format!(
            "{target}: no answer within {}",
            humantime::format_duration(*time)
        ),
        ClientError::Closed(
            reason @ (ConnectionError::Disconnected { .. } | ConnectionError::Rejected { .. }),
        ) if connecting => {
            format!("{target} refused the connection: {reason} (check --rack/--slot or --tsap)")
        }
        ClientError::Closed(reason) if connecting => {
            format!("cannot connect to {target}: {reason}")
        }
        ClientError::Closed(reason) => format!("{target}: the connection ended: {reason}"),
        other => format!("{target}: {other}"),
    }
}

async fn connect(args: &ConnectArgs) -> Result<Client, String> {
    let config = ClientConfig::new(args.tsaps());
    Client::connect(args.connect.0.as_str(), config, args.timeout)
        .await
        .map_err(|error| describe(&error, &args.connect, true))
}

/// A JSON string, quoted and escaped.
fn json_string(text: &str) -> String {
    serde_json::Value::from(text).to_string()
}

/// `{"item": "DB1.DBW2", "KEY": VALUE}` with VALUE already JSON.
fn json_line(item: &str, key: &str, value: &str) -> String {
    format!("{{\"item\": {}, \"{key}\": {value}}}", json_string(item))
}

/// Prints the lines of one item (stdout; errors also on stderr); false once stdout is
/// closed.
fn report(lines: &[String], errors: &[String]) -> bool {
    for error in errors {
        eprintln!("error: {error}");
    }
    crate::console::print_lines(lines)
}

async fn read(args: ReadArgs) -> anyhow::Result<ExitCode> {
    let client = match connect(&args.connection).await {
        Ok(client) => client,
        Err(message) => {
            eprintln!("error: {message}");
            return Ok(ExitCode::from(NOT_REACHED));
        }
    };
    let addresses: Vec<Address> = args.items.iter().map(|item| item.address).collect();
    let results: Vec<Result<Value, String>> = match client.read_values(&addresses).await {
        Ok(results) => results
            .into_iter()
            .map(|result| result.map_err(|error| error.to_string()))
            .collect(),
        Err(error) => {
            let message = describe(&error, &args.connection.connect, false);
            let failed: Vec<Result<Value, String>> =
                args.items.iter().map(|_| Err(message.clone())).collect();
            print_read(&args, &failed);
            return Ok(ExitCode::from(NOT_REACHED));
        }
    };
    Ok(if print_read(&args, &results) {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(ITEM_FAILED)
    })
}

/// Prints a read's results; true when every item was read.
fn print_read(args: &ReadArgs, results: &[Result<Value, String>]) -> bool {
    let mut lines = Vec::new();
    let mut errors = Vec::new();
    for (item, result) in args.items.iter().zip(results) {
        match result {
            Ok(value) if args.json => {
                lines.push(json_line(&item.text, "value", &value.to_string()))
            }
            Ok(value) => lines.push(format!("{} = {}", item.text, show(value))),
            Err(message) => {
                if args.json {
                    lines.push(json_line(&item.text, "error", &json_string(message)));
                }
                errors.push(format!("{}: {message}", item.text));
            }
        }
    }
    report(&lines, &errors);
    errors.is_empty()
}

/// A value for people: as in JSON, except a real that is no number.
fn show(value: &Value) -> String {
    match value {
        Value::Real(real) if !real.is_finite() => real.to_string(),
        other => other.to_string(),
    }
}

async fn write(args: WriteArgs) -> anyhow::Result<ExitCode> {
    let client = match connect(&args.connection).await {
        Ok(client) => client,
        Err(message) => {
            eprintln!("error: {message}");
            return Ok(ExitCode::from(NOT_REACHED));
        }
    };
    let items: Vec<(Address, Value)> = args
        .items
        .iter()
        .map(|assignment| (assignment.item.address, assignment.value))
        .collect();
    let (results, code) = match client.write_values(&items).await {
        Ok(results) => (
            results
                .into_iter()
                .map(|result| result.map_err(|error| error.to_string()))
                .collect::<Vec<_>>(),
            ITEM_FAILED,
        ),
        Err(error) => {
            let message = describe(&error, &args.connection.connect, false);
            (
                args.items.iter().map(|_| Err(message.clone())).collect(),
                NOT_REACHED,
            )
        }
    };
    let mut lines = Vec::new();
    let mut errors = Vec::new();
    for (assignment, result) in args.items.iter().zip(&results) {
        let text = &assignment.item.text;
        match result {
            Ok(()) if args.json => {
                lines.push(json_line(text, "written", &assignment.value.to_string()));
            }
            Ok(()) => lines.push(format!("{text} := {}", show(&assignment.value))),
            Err(message) => {
                if args.json {
                    lines.push(json_line(text, "error", &json_string(message)));
                }
                errors.push(format!("{text}: {message}"));
            }
        }
    }
    report(&lines, &errors);
    Ok(if errors.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(code)
    })
}

async fn serve(args: ServeArgs) -> anyhow::Result<ExitCode> {
    let area_size = args.area_size as usize;
    let mut memory = Memory::new(area_size, area_size, area_size);
    for block in &args.data_blocks {
        memory
            .add_data_block(block.number, block.size as usize)
            .map_err(|error| anyhow::anyhow!("--db {}:{}: {error}", block.number, block.size))?;
    }
    let mut config = ServerConfig::default();
    config.max_pdu_size = args.pdu_size;
    let mut interrupt = crate::interrupt::Interrupt::listen();
    let listener = tokio::net::TcpListener::bind(args.listen)
        .await
        .map_err(|error| {
            let hint = if error.kind() == std::io::ErrorKind::PermissionDenied
                && args.listen.port() < 1024
            {
                " (ports below 1024 need root or CAP_NET_BIND_SERVICE; try another port, e.g. 10102)"
            } else {
                ""
            };
            anyhow::anyhow!("cannot listen on {}: {error}{hint}", args.listen)
        })?;
    let local = listener.local_addr()?;
    let banner = if args.json {
        let blocks: Vec<String> = args
            .data_blocks
            .iter()
            .map(|b| format!("{{\"db\": {}, \"size\": {}}}", b.number, b.size))
            .collect();
        format!(
            "{{\"listening\": {}, \"db\": [{}], \"area_size\": {}, \"pdu_size\": {}}}",
            json_string(&local.to_string()),
            blocks.join(", "),
            args.area_size,
            args.pdu_size
        )
    } else {
        let blocks: Vec<String> = args
            .data_blocks
            .iter()
            .map(|b| format!("DB{} ({} bytes)", b.number, b.size))
            .collect();
        let blocks = if blocks.is_empty() {
            "no data blocks".to_owned()
        } else {
            blocks.join(", ")
        };
        format!(
            "S7 server on {local}: {blocks}; I, Q and M {} bytes each; PDU size up to {}; Ctrl-C stops",
            args.area_size, args.pdu_size
        )
    };
    if !crate::console::print_lines(&[banner]) {
        return Ok(ExitCode::SUCCESS);
    }
    let memory = Arc::new(Mutex::new(memory));
    let (events, mut received) = tokio::sync::mpsc::channel::<ServeEvent>(256);
    let server = ::s7::io::serve(listener, memory, config, events);
    let json = args.json;
    let print = async move {
        while let Some(event) = received.recv().await {
            if let Some(line) = event_line(&event, json) {
                if !crate::console::print_lines(&[line]) {
                    return;
                }
            }
        }
    };
    tokio::select! {
        () = server => {}
        () = print => {}
        () = crate::console::run_for(args.duration) => {}
        () = interrupt.recv() => {}
    }
    Ok(ExitCode::SUCCESS)
}

/// The line a server event prints: with `json`, only writes, as the crate's JSON.
fn event_line(event: &ServeEvent, json: bool) -> Option<String> {
    let peer = event.peer;
    match &event.event {
        ServerEvent::Write(write) if json => Some(write.to_json()),
        _ if json => None,
        ServerEvent::Connected {
            calling_tsap,
            called_tsap,
        } => Some(format!(
            "{peer} connected (TSAPs {}:{})",
            tsap_text(calling_tsap.as_ref()),
            tsap_text(called_tsap.as_ref())
        )),
        ServerEvent::Negotiated { pdu_size, max_jobs } => Some(format!(
            "{peer} set up: PDU size {pdu_size}, {max_jobs} job(s) at once"
        )),
        ServerEvent::Write(write) => Some(format!("{peer} wrote {}", write_text(write))),
        ServerEvent::Closed(reason) => Some(format!("{peer} disconnected: {reason}")),
    }
}

fn tsap_text(tsap: Option<&Tsap>) -> String {
    tsap.map_or_else(|| "none".to_owned(), Tsap::to_string)
}

/// `DB1.DBX0.3 = 1` for a bit, `DB1 bytes 4..6 = 04d2` (hex) for bytes.
fn write_text(write: &WriteEvent) -> String {
    match write.bit {
        Some(bit) => {
            let region = Region::Bit {
                area: write.area,
                byte: write.start,
                bit,
            };
            let set = write.data.first().is_some_and(|byte| *byte != 0);
            format!("{region} = {}", u8::from(set))
        }
        None => {
            let region = Region::Bytes {
                area: write.area,
                start: write.start,
                len: u32::try_from(write.data.len()).unwrap_or(u32::MAX),
            };
            let data: String = write.data.iter().map(|b| format!("{b:02x}")).collect();
            format!("{region} = {data}")
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]

    use super::*;

    #[test]
    fn targets_get_port_102_when_they_have_none() {
        assert_eq!(parse_target("10.0.0.1").unwrap().0, "10.0.0.1:102");
        assert_eq!(parse_target("10.0.0.1:1102").unwrap().0, "10.0.0.1:1102");
        assert_eq!(parse_target("plc.local").unwrap().0, "plc.local:102");
        assert_eq!(
            parse_target("plc.local:10102").unwrap().0,
            "plc.local:10102"
        );
        assert_eq!(parse_target("::1").unwrap().0, "[::1]:102");
        assert_eq!(parse_target("[::1]").unwrap().0, "[::1]:102");
        assert_eq!(parse_target("[::1]:5000").unwrap().0, "[::1]:5000");
        assert!(parse_target("plc:port")
            .unwrap_err()
            .contains("no port number"));
        assert!(parse_target("").is_err());
    }

    #[test]
    fn items_and_values_say_what_is_wrong_with_them() {
        assert_eq!(
            parse_item("DB1.DBX0.9").unwrap_err(),
            "DB1.DBX0.9: bit number 9 is above 7"
        );
        assert_eq!(parse_item("db1.dbw2:int").unwrap().text, "db1.dbw2:int");
        let write = parse_assignment("DB1.DBD8:REAL=21.5").unwrap();
        assert_eq!(write.value, Value::Real(21.5));
        assert!(parse_assignment("DB1.DBW2=70000")
            .unwrap_err()
            .starts_with("DB1.DBW2: 70000 is out of range for WORD"));
        assert!(parse_assignment("DB1.DBW2")
            .unwrap_err()
            .contains("ITEM=VALUE"));
    }

    #[test]
    fn data_blocks_are_number_and_size() {
        let block = parse_data_block("1:256").unwrap();
        assert_eq!((block.number, block.size), (1, 256));
        assert_eq!(parse_data_block("DB7:16").unwrap().number, 7);
        assert!(parse_data_block("0:16")
            .unwrap_err()
            .contains("data block 0"));
        assert!(parse_data_block("1:0").is_err());
        assert!(parse_data_block("1").unwrap_err().contains("NUMBER:SIZE"));
    }

    #[test]
    fn json_lines_keep_the_item_as_written() {
        assert_eq!(
            json_line("DB1.DBW2", "value", "1234"),
            r#"{"item": "DB1.DBW2", "value": 1234}"#
        );
        assert_eq!(
            json_line("a\"b", "error", &json_string("x")),
            r#"{"item": "a\"b", "error": "x"}"#
        );
    }
}
