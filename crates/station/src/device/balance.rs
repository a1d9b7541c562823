//! The remote sorting lab's balance as a kind of field device (`kind = "balance"`): a
//! Sartorius 1612MP8 read on its serial line (`devices::balance`), its weight and
//! stability as points, silent after 2 s without a legal record.
//!
//! ```toml
//! [[node.device]]
//! name = "BAL"
//! kind = "balance"
//! ioa_base = 5000
//! settings = { serial = "/dev/ttyUSB0" }        # or tcp = "host:port", or simulate = "red 1"
//! ```
//!
//! Settings: exactly one of `serial` (a port, 1200 Bd 8N1 unless `baud`/`parity` say
//! otherwise), `tcp` (a terminal server) or `simulate` (a simulated balance in the
//! station's process, with a ball on its pan: a name of table 5.1, a mass in grams, or
//! `empty`); `seed` for the simulation.

use points::{DeviceProfile, PointKind, PointType, SignalProfile, TimeStamp};

use super::{DeviceDriver, DeviceError, DeviceKind};
use crate::config::FieldDeviceConfig;

/// The kind's name in a project.
pub const KIND: &str = "balance";

/// The balance's kind.
#[derive(Debug)]
pub struct BalanceKind {
    profile: DeviceProfile,
}

impl BalanceKind {
    /// The kind with its profile: `BAL.not_answering` at offset 0, `BAL.weight` (grams,
    /// a short float) at 1, `BAL.stable` at 2.
    pub fn new() -> BalanceKind {
        let signal = |name: &str, offset, kind, description: &str| SignalProfile {
            name: name.to_owned(),
            offset,
            point_type: PointType::new(kind, TimeStamp::Full),
            description: description.to_owned(),
            storage: points::StorageRule::default(),
        };
        BalanceKind {
            profile: DeviceProfile {
                kind: KIND.to_owned(),
                description: "Sartorius 1612MP8 balance on RS-232 (the sorting lab's)".to_owned(),
                status_offset: 0,
                signals: vec![
                    signal(
                        "weight",
                        1,
                        PointKind::Float,
                        "the weight on the pan, grams",
                    ),
                    signal(
                        "stable",
                        2,
                        PointKind::Single,
                        "the balance calls the weight stable",
                    ),
                ],
            },
        }
    }
}

impl Default for BalanceKind {
    fn default() -> BalanceKind {
        BalanceKind::new()
    }
}

/// Where a balance's line is, from its settings.
#[derive(Debug, Clone, PartialEq)]
enum Line {
    Serial {
        path: String,
        baud: u32,
        parity: iec60870::ft12::Parity,
    },
    Tcp(String),
    Simulated {
        ball: String,
        seed: u64,
    },
}

fn setting(key: &str, reason: impl Into<String>) -> DeviceError {
    DeviceError::Setting {
        key: key.to_owned(),
        reason: reason.into(),
    }
}

fn line(settings: &toml::Table) -> Result<Line, DeviceError> {
    let text = |key: &str| -> Result<Option<String>, DeviceError> {
        match settings.get(key) {
            None => Ok(None),
            Some(toml::Value::String(text)) => Ok(Some(text.clone())),
            Some(_) => Err(setting(key, "text is needed")),
        }
    };
    let number = |key: &str, default: i64| -> Result<i64, DeviceError> {
        match settings.get(key) {
            None => Ok(default),
            Some(toml::Value::Integer(n)) => Ok(*n),
            Some(_) => Err(setting(key, "a whole number is needed")),
        }
    };
    for key in settings.keys() {
        if !["serial", "tcp", "simulate", "baud", "parity", "seed"].contains(&key.as_str()) {
            return Err(setting(
                key,
                "not a balance setting (serial, tcp, simulate, baud, parity, seed)",
            ));
        }
    }
    match (text("serial")?, text("tcp")?, text("simulate")?) {
        (Some(path), None, None) => Ok(Line::Serial {
            path,
            baud: u32::try_from(number("baud", 1200)?)
                .map_err(|_| setting("baud", "1200 to 115200"))?,
            parity: text("parity")?
                .unwrap_or_else(|| "none".to_owned())
                .parse()
                .map_err(|error| setting("parity", format!("{error}")))?,
        }),
        (None, Some(address), None) => Ok(Line::Tcp(address)),
        (None, None, Some(ball)) => {
            if ball != "empty"
                && devices::balance::simulator::ball(&ball).is_none()
                && !ball
                    .parse::<f64>()
                    .is_ok_and(|g| (0.0..=160.0).contains(&g))
            {
                return Err(setting(
                    "simulate",
                    "a ball of table 5.1 (red 1 .. green 2), a mass in grams or empty",
                ));
            }
            Ok(Line::Simulated {
                ball,
                seed: u64::try_from(number("seed", 0)?).unwrap_or(0),
            })
        }
        _ => Err(setting(
            "serial",
            "exactly one of serial, tcp or simulate says where the balance is",
        )),
    }
}

impl DeviceKind for BalanceKind {
    fn profile(&self) -> &DeviceProfile {
        &self.profile
    }

    fn check(&self, device: &FieldDeviceConfig) -> Result<(), DeviceError> {
        line(&device.settings).map(|_| ())
    }

    fn driver(&self, device: &FieldDeviceConfig) -> Result<Box<dyn DeviceDriver>, DeviceError> {
        let line = line(&device.settings)?;
        driver(line)
    }
}

#[cfg(not(feature = "runtime"))]
fn driver(_line: Line) -> Result<Box<dyn DeviceDriver>, DeviceError> {
    Err(setting(
        "serial",
        "this build of the station has no runtime",
    ))
}

#[cfg(feature = "runtime")]
fn driver(line: Line) -> Result<Box<dyn DeviceDriver>, DeviceError> {
    Ok(Box::new(runtime::BalanceDriver::new(line)))
}

#[cfg(feature = "runtime")]
mod runtime {
    use std::ops::ControlFlow;
    use std::pin::Pin;

    use devices::balance::io::{run_reader, run_simulator, DriveEnd, LineStream, Transport};
    use devices::balance::reader::{BalanceReader, ReaderEvent, BALANCE_LINE};
    use devices::balance::simulator::{self, BalanceConfig, BalanceSimulator};
    use points::{PointValue, Quality};

    use super::{DeviceDriver, DeviceError, Line};
    use crate::device::{DriverFuture, Readings};

    pub(super) struct BalanceDriver {
        line: Line,
        stream: Option<Pin<Box<dyn LineStream>>>,
    }

    impl BalanceDriver {
        pub(super) fn new(line: Line) -> BalanceDriver {
            BalanceDriver { line, stream: None }
        }
    }

    impl DeviceDriver for BalanceDriver {
        fn open(&mut self) -> DriverFuture<'_, Result<(), DeviceError>> {
            Box::pin(async move {
                let stream: Pin<Box<dyn LineStream>> = match &self.line {
                    Line::Serial { path, baud, parity } => {
                        let settings = serial_settings(*baud, *parity);
                        Transport::Serial {
                            path: path.clone(),
                            line: settings,
                        }
                        .open()
                        .await
                        .map_err(|error| DeviceError::Io(std::io::Error::other(error.to_string())))?
                        .stream
                    }
                    Line::Tcp(address) => {
                        Transport::Connect(address.clone())
                            .open()
                            .await
                            .map_err(|error| {
                                DeviceError::Io(std::io::Error::other(error.to_string()))
                            })?
                            .stream
                    }
                    Line::Simulated { ball, seed } => simulated(ball, *seed)?,
                };
                self.stream = Some(stream);
                Ok(())
            })
        }

        fn run<'a>(&'a mut self, readings: &'a dyn Readings) -> DriverFuture<'a, DeviceError> {
            Box::pin(async move {
                let Some(stream) = self.stream.take() else {
                    return DeviceError::Closed;
                };
                let mut reader =
                    BalanceReader::new(BALANCE_LINE, tokio::time::Instant::now().into_std());
                let end = run_reader(stream, &mut reader, |event| {
                    match event {
                        ReaderEvent::Record(reading) => {
                            readings.answering(true);
                            readings.value(
                                "weight",
                                PointValue::Float(reading.weight_g),
                                Quality::GOOD,
                            );
                            readings.value(
                                "stable",
                                PointValue::Bool(reading.stable),
                                Quality::GOOD,
                            );
                        }
                        ReaderEvent::Answering(answering) => readings.answering(answering),
                        ReaderEvent::Illegal(_) => {}
                    }
                    ControlFlow::Continue(())
                })
                .await;
                match end {
                    Ok(DriveEnd::Closed | DriveEnd::Stopped) => DeviceError::Closed,
                    Err(error) => DeviceError::Io(error),
                }
            })
        }
    }

    fn serial_settings(baud: u32, parity: iec60870::ft12::Parity) -> iec60870::ft12::LineSettings {
        iec60870::ft12::LineSettings {
            baud,
            parity,
            stop_bits: BALANCE_LINE.stop_bits,
        }
    }

    /// A simulated balance on an in-memory line, with `ball` on its pan.
    fn simulated(ball: &str, seed: u64) -> Result<Pin<Box<dyn LineStream>>, DeviceError> {
        let (ours, theirs) = tokio::io::duplex(4096);
        let now = tokio::time::Instant::now().into_std();
        let mut balance = BalanceSimulator::new(
            BalanceConfig {
                seed,
                ..BalanceConfig::default()
            },
            now,
        );
        if ball != "empty" {
            simulator::operate(&mut balance, now, &format!("ball {ball}")).map_err(|reason| {
                DeviceError::Setting {
                    key: "simulate".to_owned(),
                    reason,
                }
            })?;
        }
        tokio::spawn(async move {
            let mut no_actions = tokio::sync::mpsc::unbounded_channel().1;
            let _ = run_simulator(Box::pin(theirs), &mut balance, &mut no_actions, |_| {
                ControlFlow::Continue(())
            })
            .await;
        });
        Ok(Box::pin(ours))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(text: &str) -> toml::Table {
        text.parse().unwrap()
    }

    #[test]
    fn settings_name_one_line() {
        assert!(matches!(
            line(&table("serial = \"/dev/ttyUSB0\"")),
            Ok(Line::Serial { baud: 1200, .. })
        ));
        assert!(
            matches!(line(&table("tcp = \"10.0.0.7:4001\"")), Ok(Line::Tcp(a)) if a == "10.0.0.7:4001")
        );
        assert!(matches!(
            line(&table("simulate = \"red 1\"\nseed = 4")),
            Ok(Line::Simulated { seed: 4, .. })
        ));
        let error = line(&table("serial = \"/dev/x\"\ntcp = \"h:1\"")).unwrap_err();
        assert!(error.to_string().contains("exactly one"), "{error}");
        let error = line(&table("simulate = \"purple\"")).unwrap_err();
        assert!(error.to_string().contains("table 5.1"), "{error}");
        let error = line(&table("serial = \"/dev/x\"\nspeed = 9600")).unwrap_err();
        assert!(error.to_string().contains("`speed`"), "{error}");
    }
}
