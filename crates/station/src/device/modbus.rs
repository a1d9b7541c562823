//! A Modbus device as a kind of field device (`kind = "modbus"`): the station is the
//! client (TCP) or master (RTU), reading the items the node's PLC takes as inputs and
//! writing the ones it drives (the `modbus` crate), as the lab's and the lifts' field I/O
//! mostly speak it.
//!
//! ```toml
//! [[node.device]]
//! name = "IO1"
//! kind = "modbus"
//! ioa_base = 950                    # IO1.not_answering
//! settings = { tcp = "10.0.0.40:502", unit = 1, cycle_ms = 100 }
//! # or serial = "/dev/ttyUSB0", baud = 19200, parity = "even" (RTU)
//!
//! [[node.io]]
//! device = "IO1"
//! item = "holding:100:INT"          # TABLE:ADDRESS[:TYPE]
//! direction = "input"
//! variable = "Main.Level"
//! ```
//!
//! Items: `coils:N`, `discrete:N` (bits), `holding:N`, `input:N` (registers; `discrete` and
//! `input` are read only), a register's type `:UINT` (the default), `:INT`, or two
//! registers, the high word first, `:UDINT`, `:DINT`, `:REAL`. Settings: exactly one of
//! `tcp` (port 502 unless given) and `serial` (with `baud`, default 19200, and `parity`,
//! default even: the Modbus serial line's defaults), `unit` (1), `cycle_ms` (100),
//! `write_every_ms` (1000), `timeout_ms` (1000), `retries` (2). Inputs are read per table
//! in spans of neighbouring addresses (at most 125 registers or 2000 bits a request).
//!
//! While the device does not answer its inputs in the PLC keep their last value and are
//! invalid, as those of a pulled I/O module are, and its status point is TRUE; the
//! field-source supervisor opens the line again.

use std::time::Duration;

use modbus::Table;
use points::DeviceProfile;

use super::{DeviceDriver, DeviceError, DeviceItem, DeviceKind};
use crate::config::FieldDeviceConfig;

/// The kind's name in a project.
pub const KIND: &str = "modbus";

/// The Modbus device kind.
#[derive(Debug)]
pub struct ModbusKind {
    profile: DeviceProfile,
}

impl ModbusKind {
    /// The kind: its only point is the status (`DEVICE.not_answering` at offset 0); its
    /// values go through the PLC's I/O image.
    pub fn new() -> ModbusKind {
        ModbusKind {
            profile: DeviceProfile {
                kind: KIND.to_owned(),
                description: "a Modbus TCP server or RTU slave read and written by the station"
                    .to_owned(),
                status_offset: 0,
                signals: Vec::new(),
            },
        }
    }
}

impl Default for ModbusKind {
    fn default() -> ModbusKind {
        ModbusKind::new()
    }
}

/// How an item's registers hold its value.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Encoding {
    Bit,
    Uint,
    Int,
    Udint,
    Dint,
    Real,
}

impl Encoding {
    /// Registers (or bits) the item takes.
    fn width(self) -> u16 {
        match self {
            Encoding::Bit | Encoding::Uint | Encoding::Int => 1,
            Encoding::Udint | Encoding::Dint | Encoding::Real => 2,
        }
    }
}

/// An item of a Modbus device.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Item {
    table: Table,
    address: u16,
    encoding: Encoding,
}

fn parse_item(text: &str) -> Result<Item, String> {
    let mut parts = text.split(':');
    let table = match parts.next() {
        Some("coils") => Table::Coils,
        Some("discrete") => Table::DiscreteInputs,
        Some("holding") => Table::HoldingRegisters,
        Some("input") => Table::InputRegisters,
        _ => {
            return Err(format!(
                "`{text}`: TABLE:ADDRESS[:TYPE], the table one of coils, discrete, holding, input"
            ))
        }
    };
    let address = parts
        .next()
        .and_then(|a| a.parse::<u16>().ok())
        .ok_or_else(|| format!("`{text}`: the address is a number from 0 to 65535"))?;
    let bits = matches!(table, Table::Coils | Table::DiscreteInputs);
    let encoding = match (parts.next().map(str::to_ascii_uppercase).as_deref(), bits) {
        (None, true) => Encoding::Bit,
        (None | Some("UINT" | "WORD"), false) => Encoding::Uint,
        (Some("INT"), false) => Encoding::Int,
        (Some("UDINT" | "DWORD"), false) => Encoding::Udint,
        (Some("DINT"), false) => Encoding::Dint,
        (Some("REAL"), false) => Encoding::Real,
        (Some(other), true) => return Err(format!("`{text}`: a bit has no type (`{other}`)")),
        (Some(other), false) => {
            return Err(format!(
                "`{text}`: type `{other}`: UINT, INT, UDINT, DINT or REAL"
            ))
        }
    };
    if parts.next().is_some() {
        return Err(format!("`{text}`: TABLE:ADDRESS[:TYPE]"));
    }
    if u32::from(address) + u32::from(encoding.width()) > 65_536 {
        return Err(format!("`{text}`: past the table's last address"));
    }
    Ok(Item {
        table,
        address,
        encoding,
    })
}

/// Where the device is.
#[derive(Debug, Clone, PartialEq)]
enum Line {
    Tcp(String),
    Serial {
        path: String,
        settings: serial_line::LineSettings,
    },
}

/// A device's settings, read.
#[derive(Debug, Clone, PartialEq)]
struct Settings {
    line: Line,
    unit: u8,
    cycle: Duration,
    write_every: Duration,
    timeout: Duration,
    retries: u8,
}

fn setting(key: &str, reason: impl Into<String>) -> DeviceError {
    DeviceError::Setting {
        key: key.to_owned(),
        reason: reason.into(),
    }
}

fn settings(table: &toml::Table) -> Result<Settings, DeviceError> {
    const KEYS: [&str; 10] = [
        "tcp",
        "serial",
        "baud",
        "parity",
        "unit",
        "cycle_ms",
        "write_every_ms",
        "timeout_ms",
        "retries",
        "stop_bits",
    ];
    if let Some(key) = table.keys().find(|key| !KEYS.contains(&key.as_str())) {
        return Err(setting(
            key,
            format!("not a modbus setting ({})", KEYS.join(", ")),
        ));
    }
    let number = |key: &str, default: i64, min: i64, max: i64| -> Result<i64, DeviceError> {
        match table.get(key) {
            None => Ok(default),
            Some(toml::Value::Integer(n)) if (min..=max).contains(n) => Ok(*n),
            Some(_) => Err(setting(key, format!("a whole number from {min} to {max}"))),
        }
    };
    let text = |key: &str| match table.get(key) {
        None => Ok(None),
        Some(toml::Value::String(text)) => Ok(Some(text.clone())),
        Some(_) => Err(setting(key, "text is needed")),
    };
    let line = match (text("tcp")?, text("serial")?) {
        (Some(address), None) => Line::Tcp(
            if address
                .rsplit_once(':')
                .is_some_and(|(_, port)| port.parse::<u16>().is_ok())
            {
                address
            } else {
                format!("{address}:502")
            },
        ),
        (None, Some(path)) => {
            let parity = text("parity")?
                .unwrap_or_else(|| "even".to_owned())
                .parse::<serial_line::Parity>()
                .map_err(|error| setting("parity", error.to_string()))?;
            let settings = serial_line::LineSettings {
                baud: u32::try_from(number("baud", 19_200, 300, 921_600)?).unwrap_or(19_200),
                parity,
                stop_bits: u8::try_from(number("stop_bits", 1, 1, 2)?).unwrap_or(1),
            };
            settings
                .validate()
                .map_err(|error| setting("baud", error.to_string()))?;
            Line::Serial { path, settings }
        }
        _ => {
            return Err(setting(
                "tcp",
                "exactly one of tcp (host:port) or serial (a port) says where the device is",
            ))
        }
    };
    let millis = |key: &str, default: i64| -> Result<Duration, DeviceError> {
        Ok(Duration::from_millis(
            number(key, default, 1, 3_600_000)?.unsigned_abs(),
        ))
    };
    Ok(Settings {
        line,
        unit: u8::try_from(number("unit", 1, 0, 255)?).unwrap_or(1),
        cycle: millis("cycle_ms", 100)?,
        write_every: millis("write_every_ms", 1000)?,
        timeout: millis("timeout_ms", 1000)?,
        retries: u8::try_from(number("retries", 2, 0, 10)?).unwrap_or(2),
    })
}

impl DeviceKind for ModbusKind {
    fn profile(&self) -> &DeviceProfile {
        &self.profile
    }

    fn check(&self, device: &FieldDeviceConfig) -> Result<(), DeviceError> {
        settings(&device.settings).map(|_| ())
    }

    fn check_item(&self, item: &DeviceItem) -> Result<(), String> {
        let parsed = parse_item(&item.item)?;
        if item.output && matches!(parsed.table, Table::DiscreteInputs | Table::InputRegisters) {
            return Err(format!(
                "`{}`: {} are read only; an output goes to coils or holding registers",
                item.item,
                parsed.table.long_name()
            ));
        }
        Ok(())
    }

    fn driver(&self, device: &FieldDeviceConfig) -> Result<Box<dyn DeviceDriver>, DeviceError> {
        let settings = settings(&device.settings)?;
        let mut items = Vec::new();
        for item in &device.io {
            let parsed = parse_item(&item.item).map_err(|reason| setting("item", reason))?;
            items.push((item.item.clone(), parsed, item.output));
        }
        driver(settings, items)
    }
}

#[cfg(not(feature = "runtime"))]
fn driver(
    _settings: Settings,
    _items: Vec<(String, Item, bool)>,
) -> Result<Box<dyn DeviceDriver>, DeviceError> {
    Err(setting("tcp", "this build of the station has no runtime"))
}

#[cfg(feature = "runtime")]
fn driver(
    settings: Settings,
    items: Vec<(String, Item, bool)>,
) -> Result<Box<dyn DeviceDriver>, DeviceError> {
    Ok(Box::new(runtime::ModbusDriver {
        settings,
        items,
        client: None,
    }))
}

/// Neighbouring inputs of one table read together: (table, first address, count, the
/// items in it). (The driver that polls them is the runtime's: a build without it, such
/// as the fuzz targets', only checks the configuration.)
#[cfg(any(feature = "runtime", test))]
fn spans(inputs: &[(String, Item)]) -> Vec<(Table, u16, u16, Vec<usize>)> {
    /// A gap of up to this many unused entries is read rather than split.
    const GAP: u32 = 8;
    let mut sorted: Vec<usize> = (0..inputs.len()).collect();
    sorted.sort_by_key(|&i| {
        inputs
            .get(i)
            .map(|(_, item)| (item.table.name(), item.address))
    });
    let mut spans: Vec<(Table, u16, u16, Vec<usize>)> = Vec::new();
    for index in sorted {
        let Some((_, item)) = inputs.get(index) else {
            continue;
        };
        let limit: u32 = match item.table {
            Table::Coils | Table::DiscreteInputs => 2000,
            Table::HoldingRegisters | Table::InputRegisters => 125,
        };
        let end = u32::from(item.address) + u32::from(item.encoding.width());
        if let Some((table, start, count, members)) = spans.last_mut() {
            let span_end = u32::from(*start) + u32::from(*count);
            if *table == item.table
                && u32::from(item.address) <= span_end + GAP
                && end.max(span_end) - u32::from(*start) <= limit
            {
                *count = u16::try_from(end.max(span_end) - u32::from(*start)).unwrap_or(*count);
                members.push(index);
                continue;
            }
        }
        spans.push((item.table, item.address, item.encoding.width(), vec![index]));
    }
    spans
}

#[cfg(feature = "runtime")]
mod runtime {
    use modbus::{Client, ClientConfig, Table, Values};
    use serial_line::io::Transport;

    use super::{spans, DeviceDriver, DeviceError, Encoding, Item, Line, Settings};
    use crate::device::{DriverFuture, ImageValue, OutputSchedule, Readings};

    pub(super) struct ModbusDriver {
        pub(super) settings: Settings,
        pub(super) items: Vec<(String, Item, bool)>,
        pub(super) client: Option<Client>,
    }

    fn io(error: impl std::fmt::Display) -> DeviceError {
        DeviceError::Io(std::io::Error::other(error.to_string()))
    }

    /// An item's value from the registers or bits read from `start`.
    fn decode(item: &Item, start: u16, values: &Values) -> Option<ImageValue> {
        let offset = usize::from(item.address.checked_sub(start)?);
        match values {
            Values::Bits(bits) => bits.get(offset).map(|b| ImageValue::Bool(*b)),
            Values::Registers(words) => {
                let first = *words.get(offset)?;
                let pair = || -> Option<u32> {
                    Some((u32::from(first) << 16) | u32::from(*words.get(offset + 1)?))
                };
                Some(ImageValue::Number(match item.encoding {
                    Encoding::Bit | Encoding::Uint => f64::from(first),
                    Encoding::Int => f64::from(first as i16),
                    Encoding::Udint => f64::from(pair()?),
                    Encoding::Dint => f64::from(pair()? as i32),
                    Encoding::Real => f64::from(f32::from_bits(pair()?)),
                }))
            }
        }
    }

    /// The registers an output's value takes (saturating at the type's range).
    fn encode(encoding: Encoding, value: ImageValue) -> Vec<u16> {
        let number = match value {
            ImageValue::Bool(on) => f64::from(u8::from(on)),
            ImageValue::Number(x) => x,
        };
        let whole = number.round();
        let split = |x: u32| vec![(x >> 16) as u16, (x & 0xFFFF) as u16];
        match encoding {
            Encoding::Bit | Encoding::Uint => vec![whole.clamp(0.0, 65_535.0) as u16],
            Encoding::Int => vec![whole.clamp(-32_768.0, 32_767.0) as i16 as u16],
            Encoding::Udint => split(whole.clamp(0.0, 4_294_967_295.0) as u32),
            Encoding::Dint => split(whole.clamp(-2_147_483_648.0, 2_147_483_647.0) as i32 as u32),
            Encoding::Real => split((number as f32).to_bits()),
        }
    }

    impl DeviceDriver for ModbusDriver {
        fn open(&mut self) -> DriverFuture<'_, Result<(), DeviceError>> {
            Box::pin(async move {
                let (transport, mut config) = match &self.settings.line {
                    Line::Tcp(address) => {
                        (Transport::Connect(address.clone()), ClientConfig::tcp())
                    }
                    Line::Serial { path, settings } => (
                        Transport::Serial {
                            path: path.clone(),
                            line: *settings,
                        },
                        ClientConfig::rtu(*settings),
                    ),
                };
                config.timeout = self.settings.timeout;
                config.retries = self.settings.retries;
                self.client = Some(Client::open(transport, config).await.map_err(io)?);
                Ok(())
            })
        }

        fn run<'a>(&'a mut self, readings: &'a dyn Readings) -> DriverFuture<'a, DeviceError> {
            Box::pin(async move {
                let Some(mut client) = self.client.take() else {
                    return DeviceError::Closed;
                };
                let unit = self.settings.unit;
                let inputs: Vec<(String, Item)> = self
                    .items
                    .iter()
                    .filter(|(_, _, output)| !output)
                    .map(|(text, item, _)| (text.clone(), *item))
                    .collect();
                let spans = spans(&inputs);
                let outputs: std::collections::HashMap<&str, Item> = self
                    .items
                    .iter()
                    .filter(|(_, _, output)| *output)
                    .map(|(text, item, _)| (text.as_str(), *item))
                    .collect();
                let mut schedule = OutputSchedule::new(self.settings.write_every);
                let mut ticks = tokio::time::interval(self.settings.cycle);
                ticks.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
                loop {
                    ticks.tick().await;
                    for (table, start, count, members) in &spans {
                        let values = match client.read(unit, *table, *start, *count).await {
                            Ok(values) => values,
                            Err(modbus::ClientError::Exception { .. }) => {
                                // the device refused these addresses: their inputs invalid
                                if let Some(image) = readings.image() {
                                    for (text, _) in members.iter().filter_map(|&i| inputs.get(i)) {
                                        image.clear_input(text);
                                    }
                                }
                                continue;
                            }
                            Err(error) => return io(error),
                        };
                        if let Some(image) = readings.image() {
                            for (text, item) in members.iter().filter_map(|&i| inputs.get(i)) {
                                match decode(item, *start, &values) {
                                    Some(value) => image.set_input(text, value),
                                    None => image.clear_input(text),
                                }
                            }
                        }
                    }
                    let due = readings.image().and_then(|image| {
                        schedule.due(image, tokio::time::Instant::now().into_std())
                    });
                    for (text, value) in due.into_iter().flatten() {
                        let Some(item) = outputs.get(text.as_str()) else {
                            continue;
                        };
                        let result = match item.table {
                            Table::Coils => {
                                let on = match value {
                                    ImageValue::Bool(on) => on,
                                    ImageValue::Number(x) => x != 0.0,
                                };
                                client.write_coils(unit, item.address, &[on]).await
                            }
                            _ => {
                                client
                                    .write_registers(
                                        unit,
                                        item.address,
                                        &encode(item.encoding, value),
                                    )
                                    .await
                            }
                        };
                        match result {
                            Ok(()) => {}
                            Err(modbus::ClientError::Exception { .. }) => {
                                tracing::warn!(item = %text, "an output refused by the device");
                            }
                            Err(error) => return io(error),
                        }
                    }
                    readings.answering(true);
                }
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(text: &str) -> toml::Table {
        text.parse().unwrap()
    }

    #[test]
    fn settings_are_read_with_their_defaults_and_mistakes_named() {
        let read = settings(&table("tcp = \"10.0.0.40\"")).unwrap();
        assert_eq!(read.line, Line::Tcp("10.0.0.40:502".to_owned()));
        assert_eq!((read.unit, read.retries), (1, 2));
        let read = settings(&table("serial = \"/dev/ttyUSB0\"\nunit = 7")).unwrap();
        assert!(matches!(
            read.line,
            Line::Serial { settings, .. } if settings.baud == 19_200 && settings.parity == serial_line::Parity::Even
        ));
        for (text, key) in [
            ("unit = 1", "tcp"),
            ("tcp = \"h\"\nserial = \"/dev/x\"", "tcp"),
            ("tcp = \"h\"\nspeed = 1", "speed"),
            ("serial = \"/dev/x\"\nparity = \"mark\"", "parity"),
            ("tcp = \"h\"\nunit = 300", "unit"),
            ("tcp = \"h\"\ncycle_ms = 0", "cycle_ms"),
        ] {
            let error = settings(&table(text)).unwrap_err().to_string();
            assert!(error.contains(&format!("`{key}`")), "{text}: {error}");
        }
    }

    #[test]
    fn items_name_a_table_an_address_and_a_type() {
        assert_eq!(
            parse_item("holding:100:REAL").unwrap(),
            Item {
                table: Table::HoldingRegisters,
                address: 100,
                encoding: Encoding::Real
            }
        );
        assert_eq!(parse_item("coils:3").unwrap().encoding, Encoding::Bit);
        for (text, message) in [
            ("holding", "the address"),
            ("relays:1", "the table one of"),
            ("coils:1:INT", "a bit has no type"),
            ("holding:65535:DINT", "past the table's last address"),
            ("holding:1:LREAL", "type `LREAL`"),
        ] {
            let error = parse_item(text).unwrap_err();
            assert!(error.contains(message), "{text}: {error}");
        }
        let kind = ModbusKind::new();
        let output = |text: &str| DeviceItem {
            item: text.to_owned(),
            output: true,
        };
        assert!(kind.check_item(&output("holding:4")).is_ok());
        let error = kind.check_item(&output("input:4")).unwrap_err();
        assert!(error.contains("read only"), "{error}");
    }

    #[test]
    fn neighbouring_inputs_are_read_together_within_the_limits() {
        let input = |text: &str| (text.to_owned(), parse_item(text).unwrap());
        let inputs = vec![
            input("holding:100"),
            input("holding:102:REAL"),
            input("holding:120"),
            input("coils:0"),
            input("holding:300"),
            input("holding:101"),
        ];
        let spans = spans(&inputs);
        let shape: Vec<(Table, u16, u16)> = spans.iter().map(|(t, s, c, _)| (*t, *s, *c)).collect();
        assert_eq!(
            shape,
            vec![
                (Table::Coils, 0, 1),
                (Table::HoldingRegisters, 100, 4),
                (Table::HoldingRegisters, 120, 1),
                (Table::HoldingRegisters, 300, 1),
            ]
        );
    }
}
