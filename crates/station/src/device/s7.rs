//! A Siemens PLC or LOGO! as a kind of field device (`kind = "s7"`): the station is the
//! S7 client, reading the items the node's PLC takes as inputs and writing the ones it
//! drives, over ISO-on-TCP (the `s7` crate), the way an S7-1500 concentrator exchanges
//! transfer areas with its LOGO! boards (the railway-station thesis, section 3.3).
//!
//! ```toml
//! [[node.device]]
//! name = "LOGO_RH2"
//! kind = "s7"
//! ioa_base = 900                    # LOGO_RH2.not_answering
//! settings = { connect = "10.0.0.21:102", rack = 0, slot = 1, cycle_ms = 100 }
//!
//! [[node.io]]
//! device = "LOGO_RH2"
//! item = "I0.1"                     # an S7 absolute address, typed with :INT, :REAL ...
//! direction = "input"               # read every cycle into the PLC variable
//! variable = "LogoBoard.QF1_Zapnut"
//! ```
//!
//! Settings: `connect` (host, port 102 unless given; or `node:NAME`, the S7 server of a
//! node of the same project, `[node.s7_server]`), `rack` and `slot` (0 and 1) or
//! `tsap = "LLLL:RRRR"`, `cycle_ms` (the read cycle, default 100), `write_every_ms`
//! (outputs are written when they change and all of them again at this period, default
//! 1000), `timeout_ms` (a connect, a read or a write, default 3000).
//!
//! While the device does not answer (refused, silent past the timeout, closed), its
//! inputs in the PLC keep their last value and are invalid, as those of a pulled I/O
//! module are, and its status point is TRUE; the field-source supervisor connects again.

use std::time::Duration;

use points::DeviceProfile;

use super::{DeviceDriver, DeviceError, DeviceItem, DeviceKind};
use crate::config::FieldDeviceConfig;

/// The kind's name in a project.
pub const KIND: &str = "s7";

/// `connect = "node:RH1.1"`: the S7 server of a node of the same project (a simulated
/// board reporting to a simulated concentrator), wherever the project's ports put it.
pub const NODE_PREFIX: &str = "node:";

/// The S7 device kind.
#[derive(Debug)]
pub struct S7Kind {
    profile: DeviceProfile,
}

impl S7Kind {
    /// The kind: its only point is the status (`DEVICE.not_answering` at offset 0); its
    /// values go through the PLC's I/O image.
    pub fn new() -> S7Kind {
        S7Kind {
            profile: DeviceProfile {
                kind: KIND.to_owned(),
                description: "a Siemens PLC or LOGO! read and written over S7 (ISO-on-TCP)"
                    .to_owned(),
                status_offset: 0,
                signals: Vec::new(),
            },
        }
    }
}

impl Default for S7Kind {
    fn default() -> S7Kind {
        S7Kind::new()
    }
}

/// A device's settings, read.
#[derive(Debug, Clone, PartialEq)]
struct Settings {
    connect: String,
    tsaps: s7::Tsaps,
    cycle: Duration,
    write_every: Duration,
    timeout: Duration,
}

fn setting(key: &str, reason: impl Into<String>) -> DeviceError {
    DeviceError::Setting {
        key: key.to_owned(),
        reason: reason.into(),
    }
}

fn settings(table: &toml::Table) -> Result<Settings, DeviceError> {
    const KEYS: [&str; 7] = [
        "connect",
        "rack",
        "slot",
        "tsap",
        "cycle_ms",
        "write_every_ms",
        "timeout_ms",
    ];
    if let Some(key) = table.keys().find(|key| !KEYS.contains(&key.as_str())) {
        return Err(setting(
            key,
            format!("not an s7 setting ({})", KEYS.join(", ")),
        ));
    }
    let number = |key: &str, default: i64, max: i64| -> Result<i64, DeviceError> {
        match table.get(key) {
            None => Ok(default),
            Some(toml::Value::Integer(n)) if (0..=max).contains(n) => Ok(*n),
            Some(_) => Err(setting(key, format!("a whole number from 0 to {max}"))),
        }
    };
    let Some(toml::Value::String(connect)) = table.get("connect") else {
        return Err(setting("connect", "the PLC's address, host or host:port"));
    };
    let connect = if connect.starts_with(NODE_PREFIX)
        || connect
            .rsplit_once(':')
            .is_some_and(|(_, port)| port.parse::<u16>().is_ok())
            && !connect.ends_with(']')
    {
        connect.clone()
    } else {
        format!("{connect}:102")
    };
    let tsaps = match table.get("tsap") {
        Some(toml::Value::String(text)) => {
            if table.contains_key("rack") || table.contains_key("slot") {
                return Err(setting("tsap", "give tsap or rack and slot, not both"));
            }
            text.parse::<s7::Tsaps>()
                .map_err(|error| setting("tsap", error.to_string()))?
        }
        Some(_) => return Err(setting("tsap", "text such as \"0100:0301\"")),
        None => s7::Tsaps::rack_slot(
            u8::try_from(number("rack", 0, 7)?).unwrap_or(0),
            u8::try_from(number("slot", 1, 31)?).unwrap_or(1),
        ),
    };
    let millis = |key: &str, default: i64| -> Result<Duration, DeviceError> {
        let ms = number(key, default, 3_600_000)?;
        if ms == 0 {
            return Err(setting(key, "more than 0"));
        }
        Ok(Duration::from_millis(ms.unsigned_abs()))
    };
    Ok(Settings {
        connect,
        tsaps,
        cycle: millis("cycle_ms", 100)?,
        write_every: millis("write_every_ms", 1000)?,
        timeout: millis("timeout_ms", 3000)?,
    })
}

impl DeviceKind for S7Kind {
    fn profile(&self) -> &DeviceProfile {
        &self.profile
    }

    fn check(&self, device: &FieldDeviceConfig) -> Result<(), DeviceError> {
        settings(&device.settings).map(|_| ())
    }

    fn check_item(&self, item: &DeviceItem) -> Result<(), String> {
        item.item
            .parse::<s7::Address>()
            .map(|_| ())
            .map_err(|error| error.to_string())
    }

    fn driver(&self, device: &FieldDeviceConfig) -> Result<Box<dyn DeviceDriver>, DeviceError> {
        let settings = settings(&device.settings)?;
        let mut items = Vec::new();
        for item in &device.io {
            let address = item
                .item
                .parse::<s7::Address>()
                .map_err(|error| setting("item", error.to_string()))?;
            items.push((item.item.clone(), address, item.output));
        }
        driver(settings, items)
    }
}

#[cfg(not(feature = "runtime"))]
fn driver(
    _settings: Settings,
    _items: Vec<(String, s7::Address, bool)>,
) -> Result<Box<dyn DeviceDriver>, DeviceError> {
    Err(setting(
        "connect",
        "this build of the station has no runtime",
    ))
}

#[cfg(feature = "runtime")]
fn driver(
    settings: Settings,
    items: Vec<(String, s7::Address, bool)>,
) -> Result<Box<dyn DeviceDriver>, DeviceError> {
    Ok(Box::new(runtime::S7Driver {
        settings,
        items,
        client: None,
    }))
}

#[cfg(feature = "runtime")]
mod runtime {
    use s7::io::Client;
    use s7::{ClientConfig, Value, ValueType};

    use super::{DeviceDriver, DeviceError, Settings};
    use crate::device::{DriverFuture, ImageValue, OutputSchedule, Readings};

    pub(super) struct S7Driver {
        pub(super) settings: Settings,
        pub(super) items: Vec<(String, s7::Address, bool)>,
        pub(super) client: Option<Client>,
    }

    fn io(error: impl std::fmt::Display) -> DeviceError {
        DeviceError::Io(std::io::Error::other(error.to_string()))
    }

    /// A value read, for the PLC.
    fn to_image(value: Value) -> ImageValue {
        match value {
            Value::Bool(on) => ImageValue::Bool(on),
            Value::Byte(x) => ImageValue::Number(f64::from(x)),
            Value::SInt(x) => ImageValue::Number(f64::from(x)),
            Value::Word(x) => ImageValue::Number(f64::from(x)),
            Value::Int(x) => ImageValue::Number(f64::from(x)),
            Value::DWord(x) => ImageValue::Number(f64::from(x)),
            Value::DInt(x) => ImageValue::Number(f64::from(x)),
            Value::Real(x) => ImageValue::Number(f64::from(x)),
        }
    }

    /// What the PLC drives, as the address's type holds it (numbers saturate at the
    /// type's range, as a PLC's conversion would).
    fn from_image(value: ImageValue, value_type: ValueType) -> Value {
        let number = match value {
            ImageValue::Bool(on) => f64::from(u8::from(on)),
            ImageValue::Number(x) => x,
        };
        let whole = number.round();
        match value_type {
            ValueType::Bool => Value::Bool(number != 0.0),
            ValueType::Byte => Value::Byte(whole.clamp(0.0, 255.0) as u8),
            ValueType::SInt => Value::SInt(whole.clamp(-128.0, 127.0) as i8),
            ValueType::Word => Value::Word(whole.clamp(0.0, 65_535.0) as u16),
            ValueType::Int => Value::Int(whole.clamp(-32_768.0, 32_767.0) as i16),
            ValueType::DWord => Value::DWord(whole.clamp(0.0, 4_294_967_295.0) as u32),
            ValueType::DInt => Value::DInt(whole.clamp(-2_147_483_648.0, 2_147_483_647.0) as i32),
            ValueType::Real => Value::Real(number as f32),
        }
    }

    impl DeviceDriver for S7Driver {
        fn open(&mut self) -> DriverFuture<'_, Result<(), DeviceError>> {
            Box::pin(async move {
                let client = Client::connect(
                    self.settings.connect.as_str(),
                    ClientConfig::new(self.settings.tsaps.clone()),
                    self.settings.timeout,
                )
                .await
                .map_err(|error| io(format!("{}: {error}", self.settings.connect)))?;
                self.client = Some(client);
                Ok(())
            })
        }

        fn run<'a>(&'a mut self, readings: &'a dyn Readings) -> DriverFuture<'a, DeviceError> {
            Box::pin(async move {
                let Some(client) = self.client.take() else {
                    return DeviceError::Closed;
                };
                let inputs: Vec<(String, s7::Address)> = self
                    .items
                    .iter()
                    .filter(|(_, _, output)| !output)
                    .map(|(item, address, _)| (item.clone(), *address))
                    .collect();
                let addresses: Vec<s7::Address> =
                    inputs.iter().map(|(_, address)| *address).collect();
                let outputs: std::collections::HashMap<&str, s7::Address> = self
                    .items
                    .iter()
                    .filter(|(_, _, output)| *output)
                    .map(|(item, address, _)| (item.as_str(), *address))
                    .collect();
                let mut schedule = OutputSchedule::new(self.settings.write_every);
                let mut ticks = tokio::time::interval(self.settings.cycle);
                ticks.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
                loop {
                    ticks.tick().await;
                    if !addresses.is_empty() {
                        let results = match client.read_values(&addresses).await {
                            Ok(results) => results,
                            Err(error) => return io(error),
                        };
                        if let Some(image) = readings.image() {
                            for ((item, _), result) in inputs.iter().zip(results) {
                                match result {
                                    Ok(value) => image.set_input(item, to_image(value)),
                                    Err(error) => {
                                        tracing::debug!(item, %error, "item refused");
                                        image.clear_input(item);
                                    }
                                }
                            }
                        }
                    }
                    let due = readings.image().and_then(|image| {
                        schedule.due(image, tokio::time::Instant::now().into_std())
                    });
                    if let Some(values) = due.filter(|_| !outputs.is_empty()) {
                        let items: Vec<(s7::Address, Value)> = values
                            .into_iter()
                            .filter_map(|(item, value)| {
                                let address = outputs.get(item.as_str())?;
                                Some((*address, from_image(value, address.value_type())))
                            })
                            .collect();
                        if !items.is_empty() {
                            match client.write_values(&items).await {
                                Ok(results) => {
                                    for result in results.into_iter().filter_map(Result::err) {
                                        tracing::warn!(%result, "an output refused by the device");
                                    }
                                }
                                Err(error) => return io(error),
                            }
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
        let read = settings(&table("connect = \"10.0.0.21\"")).unwrap();
        assert_eq!(read.connect, "10.0.0.21:102");
        assert_eq!(read.tsaps, s7::Tsaps::rack_slot(0, 1));
        assert_eq!(read.cycle, Duration::from_millis(100));
        let read = settings(&table(
            "connect = \"127.0.0.1:10102\"\ntsap = \"0100:0302\"\ncycle_ms = 50",
        ))
        .unwrap();
        assert_eq!(read.connect, "127.0.0.1:10102");
        assert_eq!(read.tsaps, "0100:0302".parse().unwrap());
        for (text, key) in [
            ("rack = 0", "connect"),
            ("connect = \"h\"\nspeed = 3", "speed"),
            ("connect = \"h\"\ntsap = \"0100:0301\"\nrack = 0", "tsap"),
            ("connect = \"h\"\ncycle_ms = 0", "cycle_ms"),
            ("connect = \"h\"\nslot = 99", "slot"),
        ] {
            let error = settings(&table(text)).unwrap_err().to_string();
            assert!(error.contains(&format!("`{key}`")), "{text}: {error}");
        }
    }

    #[test]
    fn items_are_s7_addresses() {
        let kind = S7Kind::new();
        let item = |text: &str| DeviceItem {
            item: text.to_owned(),
            output: false,
        };
        assert!(kind.check_item(&item("DB1.DBX0.3")).is_ok());
        assert!(kind.check_item(&item("MW20:INT")).is_ok());
        let error = kind.check_item(&item("DB1.DBX0.9")).unwrap_err();
        assert!(error.contains("DB1.DBX0.9"), "{error}");
    }
}
