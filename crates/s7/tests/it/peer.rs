//! Interoperability with an S7 implementation that is not ours, python-snap7 3.3 (pure
//! Python client and server, `tests/peer/snap7_*.py`), in both directions, and Wireshark's
//! TPKT, COTP and S7comm dissectors over a captured exchange of our client and server.
//!
//! The peer convention of the workspace (`testkit::peers`, which this crate does not
//! depend on): a test whose peer is missing prints SKIPPED and passes, unless
//! `STANICE_REQUIRE_PEERS=1` (CI), where it fails. Loopback only; ports from binding
//! 127.0.0.1:0 (the snap7 server binds port 0 itself and prints the one it got).
//!
//! What python-snap7 3.3's server does differently from a PLC (seen here, tested around):
//! it answers a write job's first item only (one return code for the whole job), refuses a
//! write to an unknown area with a job error (0x8404) rather than an item return code, and
//! takes a bit item as its whole byte (a bit read returns the byte, a bit write overwrites
//! it). So our client writes to it one item per call, and bits are not exchanged with it.

use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Output, Stdio};
use std::sync::mpsc;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use tokio::net::TcpListener;
use tokio::runtime::Runtime;
use tokio::sync::mpsc as tokio_mpsc;

use s7::io::{serve, Client, ClientError, ServeEvent, SharedMemory};
use s7::pdu::ReturnCode;
use s7::split::WriteItem;
use s7::{
    Address, Area, ClientConfig, ConnectionError, ItemError, Memory, Region, ServerConfig,
    ServerEvent, Tsap, Tsaps, Value, WriteEvent,
};

const TIMEOUT: Duration = Duration::from_secs(10);

/// A JSON line of the peer scripts.
type Json = serde_json::Value;

/// Whether peers must be there (`STANICE_REQUIRE_PEERS=1`).
fn required() -> bool {
    std::env::var("STANICE_REQUIRE_PEERS").as_deref() == Ok("1")
}

/// A peer is missing: fails when peers are required, else says SKIPPED.
fn skip_or_fail(message: &str) {
    assert!(!required(), "{message}");
    eprintln!("SKIPPED: {message}");
}

fn succeeds(command: &mut Command) -> bool {
    command
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|status| status.success())
}

/// Whether python-snap7 is here; says SKIPPED (or fails, when required) if not.
fn snap7_available() -> bool {
    let available =
        succeeds(Command::new("python3").args(["-c", "import snap7.client, snap7.server"]));
    if !available {
        skip_or_fail(
            "python-snap7 missing (python3 -c 'import snap7'); run scripts/install-test-deps.sh",
        );
    }
    available
}

fn tshark_available() -> bool {
    let available = succeeds(Command::new("tshark").arg("--version"));
    if !available {
        skip_or_fail("tshark missing; run scripts/install-test-deps.sh");
    }
    available
}

/// A script of this crate's `tests/peer/`.
fn script(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/peer")
        .join(name)
}

fn runtime() -> Runtime {
    tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap()
}

/// Reads a child's stdout lines on a thread of their own.
fn lines_of(child: &mut Child) -> mpsc::Receiver<String> {
    let stdout = child.stdout.take().unwrap();
    let (sender, receiver) = mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            if sender.send(line).is_err() {
                break;
            }
        }
    });
    receiver
}

/// The next line whose JSON has `"event": event`; each line may take 30 s.
fn wait_for_event(lines: &mpsc::Receiver<String>, event: &str) -> Json {
    let mut seen = Vec::new();
    loop {
        let Ok(line) = lines.recv_timeout(Duration::from_secs(30)) else {
            panic!("no {event:?} line; saw {seen:?}");
        };
        let json =
            serde_json::from_str::<Json>(&line).unwrap_or_else(|_| panic!("not JSON: {line}"));
        if json.get("event").and_then(serde_json::Value::as_str) == Some(event) {
            return json;
        }
        seen.push(line);
    }
}

/// Runs a command to its end with standard input closed; a watchdog kills it after
/// `seconds` (the scripts bound themselves; this is the bound of last resort).
fn run_within(command: &mut Command, seconds: u64) -> Output {
    let child = command
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let pid = child.id().to_string();
    let (done, finished) = mpsc::channel::<()>();
    let watchdog = std::thread::spawn(move || {
        if let Err(mpsc::RecvTimeoutError::Timeout) =
            finished.recv_timeout(Duration::from_secs(seconds))
        {
            let _ = Command::new("kill").args(["-KILL", &pid]).status();
        }
    });
    let output = child.wait_with_output().unwrap();
    let _ = done.send(());
    watchdog.join().unwrap();
    output
}

// ---------------------------------------------------------------- our client, snap7 server

/// `snap7_server.py`, killed when dropped.
struct Snap7Server {
    child: Child,
    stdin: ChildStdin,
    lines: mpsc::Receiver<String>,
    port: u16,
}

impl Snap7Server {
    fn start(args: &[&str]) -> Snap7Server {
        let mut child = Command::new("python3")
            .arg(script("snap7_server.py"))
            .args(args)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .unwrap();
        let stdin = child.stdin.take().unwrap();
        let lines = lines_of(&mut child);
        let ready = wait_for_event(&lines, "ready");
        let port = u16::try_from(
            ready
                .get("port")
                .and_then(serde_json::Value::as_u64)
                .unwrap(),
        )
        .unwrap();
        Snap7Server {
            child,
            stdin,
            lines,
            port,
        }
    }

    /// The bytes of an area (`DB1`, `I`, `Q`, `M`) as the server holds them now.
    fn dump(&mut self, area: &str) -> Vec<u8> {
        writeln!(self.stdin, "dump").unwrap();
        self.stdin.flush().unwrap();
        let dump = wait_for_event(&self.lines, "dump");
        unhex(
            dump.get("areas")
                .and_then(|a| a.get(area))
                .and_then(serde_json::Value::as_str)
                .unwrap(),
        )
    }
}

impl Drop for Snap7Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn unhex(text: &str) -> Vec<u8> {
    (0..text.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&text[i..i + 2], 16).unwrap())
        .collect()
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

fn addresses(texts: &[&str]) -> Vec<Address> {
    texts.iter().map(|text| text.parse().unwrap()).collect()
}

/// DB3's bytes for the large read: a pattern that shows any byte out of place.
fn pattern(len: usize) -> Vec<u8> {
    (0..len).map(|i| (i * 7 + i / 256) as u8).collect()
}

#[test]
fn our_client_reads_and_writes_a_snap7_server() {
    if !snap7_available() {
        return;
    }
    // DB1: bit 3 of byte 0, DBB1 200, DBW2 1234, DBD4 4000000000, DBD8 21.5, DBW12 -1234,
    // DBD14 -100000; M10 0x1f; I0 0x02; Q0 0x05; DB3 a 1000-byte pattern.
    let db1 = "08c804d2ee6b280041ac0000fb2efffe7960";
    let db3 = hex(&pattern(1000));
    let mut peer = Snap7Server::start(&[
        "--db",
        "1:64",
        "--db",
        "2:16",
        "--db",
        "3:1000",
        "--fill",
        &format!("DB1:0:{db1}"),
        "--fill",
        "M:10:1f",
        "--fill",
        "I:0:02",
        "--fill",
        "Q:0:05",
        "--fill",
        &format!("DB3:0:{db3}"),
    ]);
    let runtime = runtime();
    let client = runtime
        .block_on(Client::connect(
            ("127.0.0.1", peer.port),
            ClientConfig::default(),
            TIMEOUT,
        ))
        .unwrap();
    // snap7 grants the PDU size asked up to 480 and one job at a time.
    assert_eq!(client.negotiated().pdu_size, 480);
    assert_eq!(client.negotiated().max_jobs, 1);

    // Every typed item kind in one multi-item read job.
    let items = addresses(&[
        "DB1.DBB1",
        "DB1.DBW2",
        "DB1.DBD4",
        "DB1.DBD8:REAL",
        "DB1.DBW12:INT",
        "DB1.DBD14:DINT",
        "DB1.DBB0:SINT",
        "MB10",
        "MW10",
        "IB0",
        "QB0",
        "DB2.DBW0",
    ]);
    let values = runtime.block_on(client.read_values(&items)).unwrap();
    let values: Vec<Value> = values.into_iter().map(Result::unwrap).collect();
    assert_eq!(
        values,
        [
            Value::Byte(200),
            Value::Word(1234),
            Value::DWord(4_000_000_000),
            Value::Real(21.5),
            Value::Int(-1234),
            Value::DInt(-100_000),
            Value::SInt(8),
            Value::Byte(0x1f),
            Value::Word(0x1f00),
            Value::Byte(2),
            Value::Byte(5),
            Value::Word(0),
        ]
    );

    // A single item (snap7's single-item path) and item errors beside good items.
    let values = runtime
        .block_on(client.read_values(&addresses(&["DB1.DBW2:INT"])))
        .unwrap();
    assert_eq!(values, [Ok(Value::Int(1234))]);
    let values = runtime
        .block_on(client.read_values(&addresses(&["DB1.DBW2", "DB9.DBW0", "DB2.DBW20", "MB10"])))
        .unwrap();
    assert_eq!(
        values,
        [
            Ok(Value::Word(1234)),
            Err(ItemError::Refused(ReturnCode::ObjectDoesNotExist)),
            Err(ItemError::Refused(ReturnCode::AddressOutOfRange)),
            Ok(Value::Byte(0x1f)),
        ]
    );
    let values = runtime
        .block_on(client.read_values(&addresses(&["DB9.DBW0"])))
        .unwrap();
    assert_eq!(
        values,
        [Err(ItemError::Refused(ReturnCode::ObjectDoesNotExist))]
    );

    // A region larger than a PDU: split into consecutive jobs, put back together.
    let large = runtime
        .block_on(client.read(vec![Region::Bytes {
            area: Area::DataBlock(3),
            start: 0,
            len: 1000,
        }]))
        .unwrap();
    assert_eq!(large, [Ok(pattern(1000))]);

    // Writes, one item per call (snap7 answers a job's first item only).
    for (text, value) in [
        ("DB1.DBW20", "4321"),
        ("DB1.DBD24:REAL", "-2.5"),
        ("DB1.DBD28:DINT", "-7"),
        ("DB1.DBB32", "0x5A"),
        ("MW12:INT", "-2"),
        ("QB1", "7"),
        ("IB2", "9"),
    ] {
        let address: Address = text.parse().unwrap();
        let value = address.parse_value(value).unwrap();
        let results = runtime
            .block_on(client.write_values(&[(address, value)]))
            .unwrap();
        assert_eq!(results, [Ok(())], "{text}");
        let read = runtime.block_on(client.read_values(&[address])).unwrap();
        assert_eq!(read, [Ok(value)], "{text}");
    }
    // A write larger than a PDU: cut into consecutive single-item jobs.
    let data: Vec<u8> = pattern(700).into_iter().rev().collect();
    let results = runtime
        .block_on(client.write(vec![WriteItem {
            region: Region::Bytes {
                area: Area::DataBlock(3),
                start: 100,
                len: 700,
            },
            data: data.clone(),
        }]))
        .unwrap();
    assert_eq!(results, [Ok(())]);
    // A write to a data block snap7 does not have: a job error, the connection stays.
    let address: Address = "DB9.DBW0".parse().unwrap();
    let results = runtime
        .block_on(client.write_values(&[(address, Value::Word(1))]))
        .unwrap();
    assert!(
        matches!(results.as_slice(), [Err(ItemError::JobRefused(error))] if error.is_error()),
        "{results:?}"
    );
    let values = runtime
        .block_on(client.read_values(&addresses(&["DB1.DBW20"])))
        .unwrap();
    assert_eq!(values, [Ok(Value::Word(4321))]);

    // What snap7 holds now, byte for byte.
    let memory = peer.dump("DB1");
    assert_eq!(&memory[20..22], &[0x10, 0xe1]);
    assert_eq!(&memory[24..28], &(-2.5f32).to_be_bytes());
    assert_eq!(&memory[28..32], &(-7i32).to_be_bytes());
    assert_eq!(memory[32], 0x5a);
    assert_eq!(&peer.dump("M")[12..14], &[0xff, 0xfe]);
    assert_eq!(peer.dump("Q")[1], 7);
    assert_eq!(peer.dump("I")[2], 9);
    let db3 = peer.dump("DB3");
    assert_eq!(&db3[..100], &pattern(1000)[..100]);
    assert_eq!(&db3[100..800], data.as_slice());

    // Several items in one write job: snap7 writes the first and answers one code; our
    // client takes the answer as not matching its job and closes, without hanging.
    let two = [
        ("DB1.DBW40".parse::<Address>().unwrap(), Value::Word(1)),
        ("DB1.DBW42".parse::<Address>().unwrap(), Value::Word(2)),
    ];
    match runtime.block_on(client.write_values(&two)) {
        Ok(results) => assert_eq!(results, [Ok(()), Ok(())]),
        Err(error @ ClientError::Closed(ConnectionError::MismatchedAnswer { .. })) => {
            eprintln!("snap7 server, two items in one write job: {error}");
        }
        Err(other) => panic!("{other}"),
    }
}

// ---------------------------------------------------------------- snap7 client, our server

struct OurServer {
    port: u16,
    memory: SharedMemory,
    events: tokio_mpsc::Receiver<ServeEvent>,
}

/// `s7::io::serve` on a free loopback port of `runtime`, on `memory`.
fn our_server(runtime: &Runtime, memory: Memory, config: ServerConfig) -> OurServer {
    let listener = runtime.block_on(TcpListener::bind("127.0.0.1:0")).unwrap();
    let port = listener.local_addr().unwrap().port();
    let memory = Arc::new(Mutex::new(memory));
    let (sender, events) = tokio_mpsc::channel(4096);
    runtime.spawn(serve(listener, Arc::clone(&memory), config, sender));
    OurServer {
        port,
        memory,
        events,
    }
}

impl OurServer {
    /// Every event until `closed` connections have ended (bounded wait).
    fn events_until_closed(&mut self, runtime: &Runtime, closed: usize) -> Vec<ServerEvent> {
        runtime.block_on(async {
            let mut events = Vec::new();
            let mut ended = 0;
            while ended < closed {
                let event = tokio::time::timeout(Duration::from_secs(30), self.events.recv())
                    .await
                    .expect("the connection ends in time")
                    .expect("the server runs");
                if matches!(event.event, ServerEvent::Closed(_)) {
                    ended += 1;
                }
                events.push(event.event);
            }
            events
        })
    }
}

/// Runs `snap7_client.py` against `port` with `calls`; its lines, parsed.
fn snap7_client(port: u16, extra: &[&str], calls: &str) -> Vec<Json> {
    let output = run_within(
        Command::new("python3")
            .arg(script("snap7_client.py"))
            .args(["--port", &port.to_string()])
            .args(extra)
            .arg(calls),
        60,
    );
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(
        output.status.success(),
        "snap7 client: {}\n{stdout}\n{}",
        output.status,
        String::from_utf8_lossy(&output.stderr)
    );
    stdout
        .lines()
        .map(|line| {
            serde_json::from_str::<Json>(line).unwrap_or_else(|_| panic!("not JSON: {line}"))
        })
        .collect()
}

/// The result of the call line at `index` (after the connected line), which must be ok.
fn ok_result(lines: &[Json], index: usize) -> &Json {
    let line = &lines[index + 1];
    assert_eq!(line.get("ok"), Some(&Json::Bool(true)), "{line:?}");
    line.get("result").unwrap()
}

fn hex_result(lines: &[Json], index: usize) -> Vec<u8> {
    unhex(
        ok_result(lines, index)
            .get("hex")
            .and_then(serde_json::Value::as_str)
            .unwrap(),
    )
}

#[test]
fn a_snap7_client_reads_and_writes_our_server() {
    if !snap7_available() {
        return;
    }
    let runtime = runtime();
    let mut memory = Memory::default();
    memory.add_data_block(1, 64).unwrap();
    memory.add_data_block(2, 2000).unwrap();
    let db1 = unhex("08c804d2ee6b280041ac0000fb2efffe7960");
    memory.area_mut(Area::DataBlock(1)).unwrap()[..db1.len()].copy_from_slice(&db1);
    memory
        .area_mut(Area::DataBlock(2))
        .unwrap()
        .copy_from_slice(&pattern(2000));
    memory.area_mut(Area::Markers).unwrap()[10..12].copy_from_slice(&[0x1f, 0x20]);
    memory.area_mut(Area::Inputs).unwrap()[..4].copy_from_slice(&[1, 2, 3, 4]);
    let mut server = our_server(&runtime, memory, ServerConfig::default());

    let big_write = hex(&pattern(1000).into_iter().rev().collect::<Vec<_>>());
    let calls = format!(
        r#"[
        {{"call": "db_read", "args": [1, 0, 18]}},
        {{"call": "db_write", "args": [1, 20, {{"hex": "a1b2c3"}}]}},
        {{"call": "read_area", "args": [{{"area": "MK"}}, 0, 10, 2]}},
        {{"call": "write_area", "args": [{{"area": "PA"}}, 0, 2, {{"hex": "0507"}}]}},
        {{"call": "read_area", "args": [{{"area": "PE"}}, 0, 0, 4]}},
        {{"call": "read_area", "args": [{{"area": "DB"}}, 1, 3, 1, {{"word_len": "Bit"}}]}},
        {{"call": "read_area", "args": [{{"area": "DB"}}, 1, 2, 1, {{"word_len": "Bit"}}]}},
        {{"call": "write_area", "args": [{{"area": "DB"}}, 1, 245, {{"hex": "01"}}, {{"word_len": "Bit"}}]}},
        {{"call": "read_multi_vars", "args": [[
            {{"area": {{"area": "DB"}}, "db_number": 1, "start": 1, "size": 1}},
            {{"area": {{"area": "MK"}}, "start": 10, "size": 2}},
            {{"area": {{"area": "DB"}}, "db_number": 1, "start": 8, "size": 4}},
            {{"area": {{"area": "PE"}}, "start": 1, "size": 3}}]]}},
        {{"call": "write_multi_vars", "args": [[
            {{"area": {{"area": "DB"}}, "db_number": 1, "start": 50, "data": {{"hex": "beef"}}}},
            {{"area": {{"area": "MK"}}, "start": 30, "data": {{"hex": "42"}}}}]]}},
        {{"call": "db_read_real", "args": [1, 8]}},
        {{"call": "db_read_int", "args": [1, 12]}},
        {{"call": "db_read_dint", "args": [1, 14]}},
        {{"call": "db_write_real", "args": [1, 40, 3.25]}},
        {{"call": "db_write_bool", "args": [1, 44, 2, true]}},
        {{"call": "db_read", "args": [9, 0, 2]}},
        {{"call": "db_read", "args": [1, 62, 4]}},
        {{"call": "db_read", "args": [2, 0, 2000]}},
        {{"call": "db_write", "args": [2, 500, {{"hex": "{big_write}"}}]}},
        {{"call": "db_read", "args": [1, 20, 3]}}
    ]"#
    );
    let lines = snap7_client(server.port, &[], &calls);
    assert_eq!(lines.len(), 21, "{lines:?}");
    // We grant 240 of the 480 snap7 asks (an S7-1200's size).
    assert_eq!(
        lines[0]
            .get("pdu_length")
            .and_then(serde_json::Value::as_u64),
        Some(240)
    );
    assert_eq!(hex_result(&lines, 0), db1);
    ok_result(&lines, 1);
    assert_eq!(hex_result(&lines, 2), [0x1f, 0x20]);
    ok_result(&lines, 3);
    assert_eq!(hex_result(&lines, 4), [1, 2, 3, 4]);
    // A bit read answers the bit, 0 or 1: bit 3 of 0x08 is set, bit 2 is not.
    assert_eq!(hex_result(&lines, 5), [1]);
    assert_eq!(hex_result(&lines, 6), [0]);
    ok_result(&lines, 7);
    let multi = ok_result(&lines, 8).as_array().unwrap()[1]
        .as_array()
        .unwrap();
    let multi: Vec<Vec<u8>> = multi
        .iter()
        .map(|item| unhex(item.get("hex").and_then(serde_json::Value::as_str).unwrap()))
        .collect();
    assert_eq!(
        multi,
        [
            vec![0xc8],
            vec![0x1f, 0x20],
            vec![0x41, 0xac, 0, 0],
            vec![2, 3, 4]
        ]
    );
    ok_result(&lines, 9);
    assert_eq!(ok_result(&lines, 10).as_f64(), Some(21.5));
    assert_eq!(ok_result(&lines, 11).as_f64(), Some(-1234.0));
    assert_eq!(ok_result(&lines, 12).as_f64(), Some(-100_000.0));
    ok_result(&lines, 13);
    ok_result(&lines, 14);
    for (index, code) in [(15, "0x0a"), (16, "0x05")] {
        let line = &lines[index + 1];
        assert_eq!(line.get("ok"), Some(&Json::Bool(false)), "{line:?}");
        let error = line
            .get("error")
            .and_then(serde_json::Value::as_str)
            .unwrap();
        assert!(error.contains(code), "{error}");
    }
    // 2000 bytes through a PDU of 240: snap7 splits, we serve each piece.
    assert_eq!(hex_result(&lines, 17), pattern(2000));
    ok_result(&lines, 18);
    // The connection survived the refused items.
    assert_eq!(hex_result(&lines, 19), [0xa1, 0xb2, 0xc3]);

    // A client of another connection type, rack and slot: S7 basic, rack 1, slot 2.
    let lines = snap7_client(
        server.port,
        &["--connection-type", "3", "--rack", "1", "--slot", "2"],
        r#"[{"call": "db_read", "args": [1, 20, 3]}]"#,
    );
    assert_eq!(hex_result(&lines, 0), [0xa1, 0xb2, 0xc3]);

    let events = server.events_until_closed(&runtime, 2);
    let called: Vec<Option<Tsap>> = events
        .iter()
        .filter_map(|event| match event {
            ServerEvent::Connected { called_tsap, .. } => Some(called_tsap.clone()),
            _ => None,
        })
        .collect();
    // snap7's default connection type is PG (1); then S7 basic (3), 1 x 32 + 2.
    assert_eq!(called, [Some(Tsap::new(0x0101)), Some(Tsap::new(0x0322))]);
    let writes: Vec<&WriteEvent> = events
        .iter()
        .filter_map(|event| match event {
            ServerEvent::Write(write) => Some(write),
            _ => None,
        })
        .collect();
    assert!(writes.contains(&&WriteEvent {
        area: Area::DataBlock(1),
        start: 20,
        bit: None,
        data: vec![0xa1, 0xb2, 0xc3],
    }));
    assert!(writes.contains(&&WriteEvent {
        area: Area::DataBlock(1),
        start: 30,
        bit: Some(5),
        data: vec![1],
    }));

    let memory = server.memory.lock().unwrap();
    let db1 = memory.area(Area::DataBlock(1)).unwrap();
    assert_eq!(&db1[20..23], &[0xa1, 0xb2, 0xc3]);
    // bit 245 = byte 30, bit 5, alone
    assert_eq!(db1[30], 0x20);
    assert_eq!(&db1[40..44], &3.25f32.to_be_bytes());
    assert_eq!(db1[44], 0x04);
    assert_eq!(&db1[50..52], &[0xbe, 0xef]);
    assert_eq!(memory.area(Area::Markers).unwrap()[30], 0x42);
    assert_eq!(&memory.area(Area::Outputs).unwrap()[2..4], &[5, 7]);
    let db2 = memory.area(Area::DataBlock(2)).unwrap();
    assert_eq!(&db2[500..1500], unhex(&big_write).as_slice());
    assert_eq!(&db2[..500], &pattern(2000)[..500]);
}

// ---------------------------------------------------------------- Wireshark's dissectors

/// A tshark capture of one loopback port by the workspace's `tests/peer/capture.sh` (it
/// returns once tshark captures, and stops it with SIGINT so it flushes); stopped when
/// dropped if the test did not stop it.
struct Capture {
    file: PathBuf,
    stopped: bool,
}

fn capture_script() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/peer/capture.sh")
}

impl Capture {
    fn start(port: u16) -> Capture {
        let file =
            std::env::temp_dir().join(format!("stanice-s7-{port}-{}.pcapng", std::process::id()));
        let status = Command::new("bash")
            .arg(capture_script())
            .args(["start", &port.to_string()])
            .arg(&file)
            .stdout(Stdio::null())
            .status()
            .unwrap();
        assert!(status.success(), "tshark capture did not start");
        Capture {
            file,
            stopped: false,
        }
    }

    fn stop(&mut self) {
        self.stopped = true;
        let status = Command::new("bash")
            .arg(capture_script())
            .arg("stop")
            .arg(&self.file)
            .stdout(Stdio::null())
            .status()
            .unwrap();
        assert!(status.success(), "tshark capture did not stop cleanly");
    }
}

impl Drop for Capture {
    fn drop(&mut self) {
        if !self.stopped {
            let _ = Command::new("bash")
                .arg(capture_script())
                .arg("stop")
                .arg(&self.file)
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .status();
        }
        let _ = std::fs::remove_file(&self.file);
    }
}

#[test]
fn wireshark_dissects_our_client_and_server_cleanly() {
    if !tshark_available() {
        return;
    }
    let runtime = runtime();
    let mut memory = Memory::default();
    memory.add_data_block(1, 1200).unwrap();
    let mut server = our_server(&runtime, memory, ServerConfig::default());
    let mut capture = Capture::start(server.port);

    runtime.block_on(async {
        let config = ClientConfig::new(Tsaps {
            local: Tsap::new(0x1000),
            remote: Tsap::new(0x2001),
        });
        let client = Client::connect(("127.0.0.1", server.port), config, TIMEOUT)
            .await
            .unwrap();
        let items: Vec<(Address, Value)> = [
            ("DB1.DBX0.3", "true"),
            ("DB1.DBB1", "200"),
            ("DB1.DBW2:INT", "-1234"),
            ("DB1.DBD4:REAL", "21.5"),
            ("MB10", "7"),
            ("QX0.2", "true"),
            ("IW2", "65535"),
        ]
        .iter()
        .map(|(text, value)| {
            let address: Address = text.parse().unwrap();
            (address, address.parse_value(value).unwrap())
        })
        .collect();
        let written = client.write_values(&items).await.unwrap();
        assert!(written.iter().all(Result::is_ok), "{written:?}");
        let mut read: Vec<Address> = items.iter().map(|(address, _)| *address).collect();
        read.push("DB9.DBW0".parse().unwrap());
        let values = client.read_values(&read).await.unwrap();
        assert_eq!(
            values.last(),
            Some(&Err(ItemError::Refused(ReturnCode::ObjectDoesNotExist)))
        );
        // Larger than a PDU both ways: several jobs, several answers.
        let data = pattern(1000);
        let region = Region::Bytes {
            area: Area::DataBlock(1),
            start: 100,
            len: 1000,
        };
        let results = client
            .write(vec![WriteItem {
                region,
                data: data.clone(),
            }])
            .await
            .unwrap();
        assert_eq!(results, [Ok(())]);
        assert_eq!(client.read(vec![region]).await.unwrap(), [Ok(data)]);
    });
    // The client is gone; once the server saw the end, everything is on the wire.
    server.events_until_closed(&runtime, 1);
    capture.stop();

    let output = run_within(
        Command::new("python3")
            .arg(script("check_s7_capture.py"))
            .arg(&capture.file)
            .arg(server.port.to_string())
            .arg("--json"),
        120,
    );
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(
        output.status.success(),
        "tshark found problems in the frames on port {}:\n{stdout}\n{}",
        server.port,
        String::from_utf8_lossy(&output.stderr)
    );
    eprintln!("tshark: {stdout}");
    let report = serde_json::from_str::<Json>(stdout.lines().last().unwrap()).unwrap();
    let count = |key: &str, field: &str| {
        report
            .get(key)
            .and_then(|map| map.get(field))
            .and_then(serde_json::Value::as_u64)
            .unwrap_or(0)
    };
    // Setup communication, read var and write var, as jobs and as ack_data.
    for function in ["0xf0", "0x04", "0x05"] {
        assert!(count("functions", function) >= 2, "{function}: {stdout}");
    }
    assert!(
        count("rosctr", "1") >= 4 && count("rosctr", "3") >= 4,
        "{stdout}"
    );
    assert!(count("return_codes", "0xff") >= 8, "{stdout}");
    assert!(count("return_codes", "0x0a") >= 1, "{stdout}");
    assert!(
        report
            .get("s7comm")
            .and_then(serde_json::Value::as_u64)
            .unwrap()
            >= 8,
        "{stdout}"
    );
}
