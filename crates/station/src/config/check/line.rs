//! The checks of a node's serial lines (`[[node.line]]`) and of the `line:` references
//! of its points and commands.

use super::*;

/// A signal named by `line:LINE/DEVICE/FUN/INF[/INDEX]`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(in crate::config) struct LineRef {
    pub(in crate::config) line: String,
    pub(in crate::config) device: String,
    pub(in crate::config) fun: u8,
    pub(in crate::config) inf: u8,
    pub(in crate::config) index: Option<u8>,
}

/// Reads a `line:` reference; `Ok(None)` when the text is no line reference.
pub(in crate::config) fn parse_line_ref(text: &str) -> Result<Option<LineRef>, String> {
    let Some(rest) = text.strip_prefix("line:") else {
        return Ok(None);
    };
    let malformed = || {
        format!("`{text}` is not of the form line:LINE/DEVICE/FUN/INF or line:LINE/DEVICE/FUN/INF/INDEX")
    };
    let parts: Vec<&str> = rest.split('/').collect();
    let number = |part: &str, what: &str| -> Result<u8, String> {
        part.trim()
            .parse::<u8>()
            .map_err(|_| format!("`{text}`: {what} `{part}` is not a number 0..=255"))
    };
    let (line, device, fun, inf, index) = match parts[..] {
        [line, device, fun, inf] => (line, device, fun, inf, None),
        [line, device, fun, inf, index] => (line, device, fun, inf, Some(index)),
        _ => return Err(malformed()),
    };
    if line.is_empty() || device.is_empty() {
        return Err(malformed());
    }
    Ok(Some(LineRef {
        line: line.to_owned(),
        device: device.to_owned(),
        fun: number(fun, "FUN")?,
        inf: number(inf, "INF")?,
        index: index.map(|index| number(index, "INDEX")).transpose()?,
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
                format!("node `{node}` has no line `{}`", reference.line),
            ),
            Some(line)
                if !line
                    .device
                    .iter()
                    .any(|device| device.name == reference.device) =>
            {
                self.err(
                    path,
                    format!(
                        "line `{}` has no device `{}`",
                        reference.line, reference.device
                    ),
                )
            }
            Some(_) => {}
        }
    }

    /// A line's or device's status point: a single point of the node without a source.
    fn status_point_of_line(&mut self, raw: &RawNode, point: &str, path: &[Seg]) {
        match raw.point.iter().find(|p| p.name == point) {
            None => self.err(path, format!("node `{}` has no point `{point}`", raw.name)),
            Some(p) if !matches!(p.type_id.as_str(), "M_SP_NA_1" | "M_SP_TB_1") => self.err(
                path,
                format!("the status point `{point}` must be M_SP_NA_1 or M_SP_TB_1"),
            ),
            Some(p) if p.source.is_some() => {
                self.err(path, format!("the status point `{point}` takes no source"))
            }
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
                self.err(&at("name"), format!("duplicate line name `{}`", line.name));
            }
            if line.protocol != "iec103" {
                self.err(
                    &at("protocol"),
                    format!("protocol `{}`: only \"iec103\" lines are supported (IEC 101 lines are not yet)", line.protocol),
                );
            }
            let transport = match (&line.port, &line.tcp, &line.simulate) {
                (Some(port), None, None) => LineTransport::Serial(port.clone()),
                (None, Some(tcp), None) => LineTransport::Tcp(tcp.clone()),
                (None, None, Some(profile)) => {
                    if profile != "ref630" {
                        self.err(
                            &at("simulate"),
                            format!("no simulated device `{profile}`; known: \"ref630\""),
                        );
                    }
                    LineTransport::Simulated(profile.clone())
                }
                _ => {
                    self.err(
                        &[K("node"), I(n), K("line"), I(l)],
                        "give exactly one of port, tcp and simulate",
                    );
                    LineTransport::Simulated("ref630".to_owned())
                }
            };
            let mut settings = iec60870::ft12::LineSettings::new(9600);
            if let Some(baud) = line.baud {
                settings.baud = u32::try_from(baud).unwrap_or(0);
            }
            if let Some(parity) = &line.parity {
                match parity.parse() {
                    Ok(parity) => settings.parity = parity,
                    Err(message) => self.err(&at("parity"), message),
                }
            }
            if let Some(stop_bits) = line.stop_bits {
                settings.stop_bits = u8::try_from(stop_bits).unwrap_or(0);
            }
            if let Err(message) = settings.validate() {
                let key = if message.contains("baud") {
                    "baud"
                } else {
                    "stop_bits"
                };
                self.err(&at(key), message);
            }
            let mut millis = |value: Option<i64>,
                              default: u64,
                              range: std::ops::RangeInclusive<u64>,
                              key: &'static str| {
                let value = value.map_or(Ok(default), u64::try_from).unwrap_or(u64::MAX);
                if range.contains(&value) {
                    Duration::from_millis(value)
                } else {
                    self.err(
                        &at(key),
                        format!(
                            "{key} {value} is outside {}..={}",
                            range.start(),
                            range.end()
                        ),
                    );
                    Duration::from_millis(default)
                }
            };
            let timeout = millis(line.timeout_ms, 500, 5..=60_000, "timeout_ms");
            let poll_interval = millis(
                line.poll_interval_ms,
                100,
                0..=3_600_000,
                "poll_interval_ms",
            );
            let retries = match line.retries.map(u8::try_from) {
                None => 2,
                Some(Ok(retries)) if retries <= 10 => retries,
                Some(_) => {
                    self.err(&at("retries"), "retries must be within 0..=10");
                    2
                }
            };
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
                        format!(
                            "duplicate device name `{}` on line `{}`",
                            device.name, line.name
                        ),
                    );
                }
                let address = match u8::try_from(device.address) {
                    Ok(address) if (1..=254).contains(&address) => address,
                    _ => {
                        self.err(
                            &at("address"),
                            format!("address {} is outside 1..=254", device.address),
                        );
                        1
                    }
                };
                if !addresses.insert(address) {
                    self.err(
                        &at("address"),
                        format!("address {address} is used twice on line `{}`", line.name),
                    );
                }
                let local_indication = device.local_indication.and_then(|[fun, inf]| {
                    match (u8::try_from(fun), u8::try_from(inf)) {
                        (Ok(fun), Ok(inf)) => Some((fun, inf)),
                        _ => {
                            self.err(
                                &at("local_indication"),
                                "FUN and INF must be within 0..=255",
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
                    status_point: device.status_point.clone(),
                    local_indication,
                });
            }
            if let Some(point) = &line.status_point {
                self.status_point_of_line(raw, point, &at("status_point"));
            }
            lines.push(LineConfig {
                name: line.name.clone(),
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
                fun: 1,
                inf: 148,
                index: Some(3)
            }))
        );
        assert!(parse_line_ref("line:relays/F1/1").is_err());
        assert!(parse_line_ref("line:relays/F1/1/256")
            .unwrap_err()
            .contains("INF `256`"));
        assert!(parse_line_ref("line://1/2").is_err());
    }
}
