//! The checks of a node's serial lines (`[[node.line]]`) and of the `line:` references
//! of its points and commands.

use super::*;
use simulators::registry::Speaks;

/// A signal named by `line:LINE/DEVICE/FUN/INF[/INDEX]` (IEC 103) or
/// `line:LINE/DEVICE/IOA` (IEC 101).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(in crate::config) struct LineRef {
    pub(in crate::config) line: String,
    pub(in crate::config) device: String,
    pub(in crate::config) signal: LineSignal,
}

impl LineRef {
    /// The index of an IEC 103 measurand; `None` for an indication or an IEC 101 object.
    pub(in crate::config) fn index(&self) -> Option<u8> {
        match self.signal {
            LineSignal::Iec103 { index, .. } => index,
            LineSignal::Iec101 { .. } => None,
        }
    }
}

/// The protocol names a line's `protocol` key takes.
const IEC103: &str = "iec103";
const IEC101: &str = "iec101";

/// Reads a `line:` reference; `Ok(None)` when the text is no line reference.
pub(in crate::config) fn parse_line_ref(text: &str) -> Result<Option<LineRef>, ConfigProblem> {
    let Some(rest) = text.strip_prefix("line:") else {
        return Ok(None);
    };
    let malformed = || ConfigProblem::Malformed {
        text: text.to_owned(),
        form: Form::LineRef,
    };
    let parts: Vec<&str> = rest.split('/').collect();
    let number = |given: &str, part: &'static str| -> Result<u8, ConfigProblem> {
        given
            .trim()
            .parse::<u8>()
            .map_err(|_| ConfigProblem::Malformed {
                text: text.to_owned(),
                form: Form::LineNumber {
                    part,
                    given: given.to_owned(),
                },
            })
    };
    let (line, device, signal) = match parts[..] {
        [line, device, ioa] => {
            let ioa = ioa
                .trim()
                .parse::<u32>()
                .ok()
                .and_then(|ioa| Ioa::try_new(ioa).ok())
                .ok_or_else(|| ConfigProblem::Malformed {
                    text: text.to_owned(),
                    form: Form::LineIoa {
                        given: ioa.to_owned(),
                    },
                })?;
            (line, device, LineSignal::Iec101 { ioa: ioa.get() })
        }
        [line, device, fun, inf] => (
            line,
            device,
            LineSignal::Iec103 {
                fun: number(fun, "FUN")?,
                inf: number(inf, "INF")?,
                index: None,
            },
        ),
        [line, device, fun, inf, index] => (
            line,
            device,
            LineSignal::Iec103 {
                fun: number(fun, "FUN")?,
                inf: number(inf, "INF")?,
                index: Some(number(index, "INDEX")?),
            },
        ),
        _ => return Err(malformed()),
    };
    if line.is_empty() || device.is_empty() {
        return Err(malformed());
    }
    Ok(Some(LineRef {
        line: line.to_owned(),
        device: device.to_owned(),
        signal,
    }))
}

impl Ctx<'_> {
    /// Checks a `line:` reference against the node's lines; an error at `path` when it
    /// names no line or device.
    pub(in crate::config) fn line_ref_exists(
        &mut self,
        node: &str,
        lines: &[RawLine],
        reference: &LineRef,
        path: &[Seg],
    ) {
        match lines.iter().find(|line| line.name == reference.line) {
            None => self.err(
                path,
                ConfigProblem::Unknown {
                    what: Reference::Line,
                    name: reference.line.clone(),
                    within: node.to_owned(),
                },
            ),
            Some(line)
                if !line
                    .device
                    .iter()
                    .any(|device| device.name == reference.device) =>
            {
                self.err(
                    path,
                    ConfigProblem::Unknown {
                        what: Reference::Device,
                        name: reference.device.clone(),
                        within: reference.line.clone(),
                    },
                )
            }
            Some(line) => {
                let (protocol, form) = match (&reference.signal, line.protocol.as_str()) {
                    (LineSignal::Iec101 { .. }, IEC103) => {
                        (IEC103, "line:LINE/DEVICE/FUN/INF[/INDEX]")
                    }
                    (LineSignal::Iec103 { .. }, IEC101) => (IEC101, "line:LINE/DEVICE/IOA"),
                    _ => return,
                };
                self.err(
                    path,
                    Conflict::LineRefProtocol {
                        line: line.name.clone(),
                        protocol,
                        form,
                    },
                );
            }
        }
    }

    /// A line's or device's status point: a single point of the node without a source.
    fn status_point_of_line(&mut self, raw: &RawNode, point: &str, path: &[Seg]) {
        match raw.point.iter().find(|p| p.name == point) {
            None => self.err(
                path,
                ConfigProblem::Unknown {
                    what: Reference::Point,
                    name: point.to_owned(),
                    within: raw.name.clone(),
                },
            ),
            Some(p) if !matches!(p.type_id.as_str(), "M_SP_NA_1" | "M_SP_TB_1") => self.err(
                path,
                ConfigProblem::WrongType {
                    type_id: p.type_id.clone(),
                    usage: TypeUse::LineStatus {
                        point: point.to_owned(),
                    },
                },
            ),
            Some(p) if p.source.is_some() => self.err(
                path,
                Conflict::StatusPointWithSource {
                    point: point.to_owned(),
                },
            ),
            Some(_) => {}
        }
    }

    pub(in crate::config) fn check_lines(&mut self, n: usize, raw: &RawNode) -> Vec<LineConfig> {
        let mut lines = Vec::new();
        let mut names = HashSet::new();
        for (l, line) in raw.line.iter().enumerate() {
            let at =
                |key: &'static str| -> Vec<Seg> { vec![K("node"), I(n), K("line"), I(l), K(key)] };
            if !names.insert(line.name.clone()) {
                self.err(
                    &at("name"),
                    ConfigProblem::Duplicate {
                        what: Unique::LineName,
                        value: line.name.clone(),
                        other: raw.name.clone(),
                    },
                );
            }
            let protocol = match line.protocol.as_str() {
                IEC103 => {
                    self.no_iec101_keys(line, &at);
                    LineProtocol::Iec103
                }
                IEC101 => LineProtocol::Iec101(self.iec101_settings(line, &at)),
                _ => {
                    self.err(
                        &at("protocol"),
                        ConfigProblem::UnknownValue {
                            what: Vocabulary::Protocol,
                            value: line.protocol.clone(),
                        },
                    );
                    LineProtocol::Iec103
                }
            };
            let transport = match (&line.port, &line.tcp, &line.simulate) {
                (Some(port), None, None) => LineTransport::Serial(port.clone()),
                (None, Some(tcp), None) => LineTransport::Tcp(tcp.clone()),
                (None, None, Some(profile)) => {
                    if matches!(protocol, LineProtocol::Iec101(_)) {
                        // The simulated devices are IEC 103 relays; an IEC 101
                        // outstation is `stanice iec101 slave` on a port or over TCP.
                        self.err(
                            &at("simulate"),
                            Conflict::NotForProtocol {
                                key: "simulate",
                                protocol: IEC101,
                            },
                        );
                    } else if simulators::registry::find(profile)
                        .is_none_or(|device| device.speaks != Speaks::Iec103)
                    {
                        self.err(
                            &at("simulate"),
                            ConfigProblem::UnknownValue {
                                what: Vocabulary::SimulatedDevice,
                                value: profile.clone(),
                            },
                        );
                    }
                    LineTransport::Simulated(profile.clone())
                }
                _ => {
                    self.err(&[K("node"), I(n), K("line"), I(l)], Conflict::LineTransport);
                    LineTransport::Simulated("ref630".to_owned())
                }
            };
            let settings = self.serial_settings(
                SerialKeys {
                    baud: line.baud,
                    parity: line.parity.as_deref(),
                    stop_bits: line.stop_bits,
                },
                &at,
                &[K("node"), I(n), K("line"), I(l)],
            );
            let timeout = self.millis_in(line.timeout_ms, 500, 5..=60_000, &at("timeout_ms"));
            let poll_interval = self.millis_in(
                line.poll_interval_ms,
                100,
                0..=3_600_000,
                &at("poll_interval_ms"),
            );
            let retries = self.retries_in(line.retries, 2, &at("retries"));
            let mut devices = Vec::new();
            let mut device_names = HashSet::new();
            let mut addresses = HashSet::new();
            for (d, device) in line.device.iter().enumerate() {
                let at = |key: &'static str| -> Vec<Seg> {
                    vec![K("node"), I(n), K("line"), I(l), K("device"), I(d), K(key)]
                };
                if !device_names.insert(device.name.clone()) {
                    self.err(
                        &at("name"),
                        ConfigProblem::Duplicate {
                            what: Unique::DeviceName,
                            value: device.name.clone(),
                            other: line.name.clone(),
                        },
                    );
                }
                let address = match u8::try_from(device.address) {
                    Ok(address) if (1..=254).contains(&address) => address,
                    _ => {
                        self.err(
                            &at("address"),
                            ConfigProblem::OutOfRange {
                                what: "address",
                                value: device.address,
                                min: 1,
                                max: Some(254),
                            },
                        );
                        1
                    }
                };
                let common_address = match device.common_address {
                    None => u16::from(address),
                    Some(given) if matches!(protocol, LineProtocol::Iec103) => {
                        let _ = given;
                        self.err(
                            &at("common_address"),
                            Conflict::NotForProtocol {
                                key: "common_address",
                                protocol: IEC103,
                            },
                        );
                        u16::from(address)
                    }
                    Some(given) => match u16::try_from(given) {
                        Ok(ca) if ca >= 1 => ca,
                        _ => {
                            self.err(
                                &at("common_address"),
                                ConfigProblem::OutOfRange {
                                    what: "common_address",
                                    value: given,
                                    min: 1,
                                    max: Some(u16::MAX.into()),
                                },
                            );
                            1
                        }
                    },
                };
                if !addresses.insert(address) {
                    self.err(
                        &at("address"),
                        ConfigProblem::Duplicate {
                            what: Unique::DeviceAddress,
                            value: address.to_string(),
                            other: line.name.clone(),
                        },
                    );
                }
                let local_indication = device.local_indication.and_then(|[fun, inf]| {
                    match (u8::try_from(fun), u8::try_from(inf)) {
                        (Ok(fun), Ok(inf)) => Some((fun, inf)),
                        (fun_ok, _) => {
                            // the first of the two that does not fit
                            let (what, value) = if fun_ok.is_err() {
                                ("FUN", fun)
                            } else {
                                ("INF", inf)
                            };
                            self.err(
                                &at("local_indication"),
                                ConfigProblem::OutOfRange {
                                    what,
                                    value,
                                    min: 0,
                                    max: Some(u8::MAX.into()),
                                },
                            );
                            None
                        }
                    }
                });
                if let Some(point) = &device.status_point {
                    self.status_point_of_line(raw, point, &at("status_point"));
                }
                devices.push(DeviceConfig {
                    name: device.name.clone(),
                    address,
                    common_address,
                    status_point: device.status_point.clone(),
                    local_indication,
                });
            }
            if let Some(point) = &line.status_point {
                self.status_point_of_line(raw, point, &at("status_point"));
            }
            lines.push(LineConfig {
                name: line.name.clone(),
                protocol,
                status_point: line.status_point.clone(),
                transport,
                settings,
                timeout,
                retries,
                poll_interval,
                devices,
            });
        }
        lines
    }

    /// An IEC 103 line takes none of IEC 101's field sizes (its are fixed).
    fn no_iec101_keys(&mut self, line: &RawLine, at: &dyn Fn(&'static str) -> Vec<Seg>) {
        for (key, value) in [
            ("link_address_size", line.link_address_size),
            ("cot_size", line.cot_size),
            ("common_address_size", line.common_address_size),
            ("ioa_size", line.ioa_size),
        ] {
            if value.is_some() {
                self.err(
                    &at(key),
                    Conflict::NotForProtocol {
                        key,
                        protocol: IEC103,
                    },
                );
            }
        }
    }

    /// The field sizes of an IEC 101 line, each within what the standard allows.
    fn iec101_settings(
        &mut self,
        line: &RawLine,
        at: &dyn Fn(&'static str) -> Vec<Seg>,
    ) -> Iec101Settings {
        let mut size = |key: &'static str, value: Option<i64>, default: u8, max: u8| -> u8 {
            match value {
                None => default,
                Some(given) if (1..=i64::from(max)).contains(&given) => {
                    u8::try_from(given).unwrap_or(default)
                }
                Some(given) => {
                    self.err(
                        &at(key),
                        ConfigProblem::OutOfRange {
                            what: key,
                            value: given,
                            min: 1,
                            max: Some(max.into()),
                        },
                    );
                    default
                }
            }
        };
        let address_size = match size("link_address_size", line.link_address_size, 1, 2) {
            2 => iec60870::ft12::AddressSize::Two,
            _ => iec60870::ft12::AddressSize::One,
        };
        let cot = size("cot_size", line.cot_size, 1, 2);
        let common_address = size("common_address_size", line.common_address_size, 1, 2);
        let ioa = size("ioa_size", line.ioa_size, 2, 3);
        // An FT1.2 variable frame carries 255 octets: control field, link address, ASDU.
        let link_octets = match address_size {
            iec60870::ft12::AddressSize::Two => 2,
            _ => 1,
        };
        let params =
            iec60870::asdu::AsduParams::try_new(cot, common_address, ioa, 255 - 1 - link_octets)
                .unwrap_or(iec60870::asdu::AsduParams::IEC101_DEFAULT);
        Iec101Settings {
            address_size,
            params,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_references() {
        assert_eq!(parse_line_ref("Relay.X"), Ok(None));
        assert_eq!(
            parse_line_ref("line:relays/F1/1/148/3"),
            Ok(Some(LineRef {
                line: "relays".into(),
                device: "F1".into(),
                signal: LineSignal::Iec103 {
                    fun: 1,
                    inf: 148,
                    index: Some(3)
                }
            }))
        );
        assert_eq!(
            parse_line_ref("line:rtus/RTU1/4001"),
            Ok(Some(LineRef {
                line: "rtus".into(),
                device: "RTU1".into(),
                signal: LineSignal::Iec101 { ioa: 4001 }
            }))
        );
        assert!(parse_line_ref("line:rtus/RTU1/16777216").is_err());
        assert!(parse_line_ref("line:relays/F1").is_err());
        assert!(parse_line_ref("line:relays/F1/1/256")
            .unwrap_err()
            .to_string()
            .contains("INF `256`"));
        assert!(parse_line_ref("line://1/2").is_err());
    }
}
