//! The checks of a project: the station (here), each node (`node`, which runs the checks
//! of its parts: `server`, `point`, `lift`, `device` and `generated`, `command`, `line`
//! and `serial`), the links between the nodes (`links`).

mod command;
mod device;
mod generated;
mod lift;
mod line;
mod links;
mod node;
mod point;
mod serial;
mod server;
mod storage;

use command::CommandContext;
use generated::{GeneratedPoint, TakenPoints};
use node::{node_path, Entry};
use serial::SerialKeys;

use super::*;

// ---------------------------------------------------------------------------------------
// Checks

pub(in crate::config) fn parse_ip(text: &str) -> Result<IpAddr, ConfigProblem> {
    text.trim().parse().map_err(|_| ConfigProblem::Malformed {
        text: text.to_owned(),
        form: Form::IpAddress,
    })
}

pub(in crate::config) fn common_address(value: i64) -> Result<CommonAddress, ConfigProblem> {
    match u16::try_from(value) {
        Ok(v) if (1..=65534).contains(&v) => Ok(CommonAddress::new(v)),
        _ => Err(ConfigProblem::OutOfRange {
            what: "common address",
            value,
            min: 1,
            max: Some(65534),
        }),
    }
}

pub(in crate::config) fn ioa(value: i64) -> Result<Ioa, ConfigProblem> {
    u32::try_from(value)
        .ok()
        .filter(|v| *v >= 1)
        .and_then(|v| Ioa::try_new(v).ok())
        .ok_or(ConfigProblem::OutOfRange {
            what: "IOA",
            value,
            min: 1,
            max: Some(Ioa::MAX.get().into()),
        })
}

/// Splits `link:NAME/IOA`; `Ok(None)` for a variable path.
/// An IOA moved by a republishing offset, if still an IOA.
pub(in crate::config) fn shifted(ioa: Ioa, offset: u32) -> Option<Ioa> {
    ioa.get()
        .checked_add(offset)
        .and_then(|i| Ioa::try_new(i).ok())
}

pub(in crate::config) fn parse_link_ref(
    text: &str,
) -> Result<Option<(String, Ioa)>, ConfigProblem> {
    let Some(rest) = text.strip_prefix("link:") else {
        if text.trim().is_empty() {
            return Err(ConfigProblem::Empty {
                what: "variable path",
            });
        }
        return Ok(None);
    };
    let malformed = || ConfigProblem::Malformed {
        text: text.to_owned(),
        form: Form::LinkRef,
    };
    let (name, number) = rest.rsplit_once('/').ok_or_else(malformed)?;
    if name.is_empty() {
        return Err(malformed());
    }
    let number: i64 = number.trim().parse().map_err(|_| malformed())?;
    Ok(Some((name.to_owned(), ioa(number)?)))
}

pub(in crate::config) fn resolve(folder: &Path, relative: &str) -> PathBuf {
    folder.join(relative)
}

/// Whether `text` declares `PROGRAM name` (case-insensitive, name optionally quoted).
pub(in crate::config) fn declares_program(text: &str, name: &str) -> bool {
    let words: Vec<&str> = text
        .split(|c: char| !(c.is_alphanumeric() || c == '_'))
        .filter(|w| !w.is_empty())
        .collect();
    words
        .windows(2)
        .any(|w| matches!(w, [a, b] if a.eq_ignore_ascii_case("program") && b.eq_ignore_ascii_case(name)))
}

pub(in crate::config) fn is_measurement(type_id: TypeId) -> bool {
    type_id.mnemonic().starts_with("M_ME_")
}

impl Ctx<'_> {
    pub(in crate::config) fn check(&mut self, folder: &Path, raw: RawProject) -> Project {
        let station = self.check_station(folder, &raw.station);
        let mut nodes = Vec::new();
        let mut seen_names: HashMap<String, usize> = HashMap::new();
        let mut seen_ports: HashMap<u16, String> = HashMap::new();
        for (n, node) in raw.node.iter().enumerate() {
            if node.name.trim().is_empty() {
                self.err(
                    &[K("node"), I(n), K("name")],
                    ConfigProblem::Empty { what: "node name" },
                );
            } else if let Some(first) = seen_names.get(&node.name) {
                self.err(
                    &[K("node"), I(n), K("name")],
                    ConfigProblem::Duplicate {
                        what: Unique::NodeName,
                        value: node.name.clone(),
                        other: format!("node[{first}]"),
                    },
                );
            } else {
                seen_names.insert(node.name.clone(), n);
            }
            let built = self.check_node(folder, n, node);
            if let Some(server) = &built.server {
                let path = [K("node"), I(n), K("server"), K("port_offset")];
                if let Some(other) = seen_ports.get(&server.port_offset) {
                    self.err(
                        &path,
                        ConfigProblem::Duplicate {
                            what: Unique::PortOffset,
                            value: server.port_offset.to_string(),
                            other: other.clone(),
                        },
                    );
                } else {
                    seen_ports.insert(server.port_offset, built.name.clone());
                }
                if station.port_base.checked_add(server.port_offset).is_none() {
                    self.err(
                        &path,
                        Conflict::PortPast65535 {
                            port_base: station.port_base,
                            port_offset: server.port_offset,
                        },
                    );
                }
            }
            if let Some(server) = &built.s7_server {
                // an S7 server listens on port_base + offset too
                let path = [K("node"), I(n), K("s7_server"), K("port_offset")];
                if let Some(other) = seen_ports.get(&server.port_offset) {
                    self.err(
                        &path,
                        ConfigProblem::Duplicate {
                            what: Unique::PortOffset,
                            value: server.port_offset.to_string(),
                            other: other.clone(),
                        },
                    );
                } else {
                    seen_ports.insert(server.port_offset, format!("{} (S7)", built.name));
                }
            }
            nodes.push(built);
        }
        self.check_links(folder, &raw, &mut nodes);
        storage::apply_station_storage(&mut nodes, station.storage);
        // `connect = "node:NAME"`: a node of the project with an S7 server.
        for (n, node) in nodes.iter().enumerate() {
            for (d, device) in node.devices.iter().enumerate() {
                let Some(target) = device
                    .settings
                    .get("connect")
                    .and_then(toml::Value::as_str)
                    .and_then(|connect| connect.strip_prefix(crate::device::s7::NODE_PREFIX))
                else {
                    continue;
                };
                if !nodes
                    .iter()
                    .any(|other| other.name == target && other.s7_server.is_some())
                {
                    self.err(
                        &[K("node"), I(n), K("device"), I(d), K("settings")],
                        ConfigProblem::Invalid {
                            detail: format!(
                                "connect: no node `{target}` with an S7 server ([node.s7_server])"
                            ),
                        },
                    );
                }
            }
        }
        if station.plant.is_none() {
            for (n, node) in nodes.iter().enumerate() {
                for (d, device) in node.devices.iter().enumerate() {
                    if device.plant_port.is_some() {
                        self.err(
                            &[K("node"), I(n), K("device"), I(d), K("settings")],
                            ConfigProblem::Missing {
                                what: "a plant",
                                needed_by: "a device on the plant's serial port",
                                hint: "[station] plant = \"...\"",
                            },
                        );
                    }
                }
            }
        }
        let mqtt = raw.mqtt.as_ref().map(|mqtt| self.check_mqtt(folder, mqtt));
        Project {
            folder: folder.to_path_buf(),
            station,
            nodes,
            mqtt,
        }
    }

    /// The `[mqtt]` table: a broker URL of its scheme, a CA only over TLS (the file must
    /// exist), a password only with a user, ids that can stand in a Sparkplug topic.
    pub(in crate::config) fn check_mqtt(&mut self, folder: &Path, raw: &RawMqtt) -> MqttConfig {
        let (tls, host) = match raw.url.split_once("://") {
            Some(("mqtt" | "tcp", rest)) => (Some(false), rest),
            Some(("mqtts" | "ssl", rest)) => (Some(true), rest),
            _ => (None, ""),
        };
        let host = host.trim_end_matches('/');
        if tls.is_none() || host.is_empty() || host.starts_with(':') || host.contains('/') {
            self.err(
                &[K("mqtt"), K("url")],
                ConfigProblem::Invalid {
                    detail: format!(
                        "`{}` is not an MQTT broker URL (mqtt://HOST[:PORT] or mqtts://HOST[:PORT])",
                        raw.url
                    ),
                },
            );
        }
        let ca = raw.ca.as_deref().map(|ca| {
            if tls == Some(false) {
                self.err(
                    &[K("mqtt"), K("ca")],
                    ConfigProblem::Invalid {
                        detail: "a CA is for mqtts:// brokers; this URL is mqtt://".to_owned(),
                    },
                );
            }
            self.existing_file(folder, ca, &[K("mqtt"), K("ca")])
        });
        if raw.password.is_some() && raw.username.is_none() {
            self.err(
                &[K("mqtt"), K("password")],
                ConfigProblem::Missing {
                    what: "username",
                    needed_by: "a password",
                    hint: "",
                },
            );
        }
        if raw
            .redundancy_group
            .as_deref()
            .is_some_and(|g| g.trim().is_empty())
        {
            self.err(
                &[K("mqtt"), K("redundancy_group")],
                ConfigProblem::Empty {
                    what: "redundancy group",
                },
            );
        }
        for (key, id) in [("primary_host", &raw.primary_host), ("group", &raw.group)] {
            if let Some(id) = id {
                if id.is_empty() || id.contains(['/', '+', '#']) {
                    self.err(
                        &[K("mqtt"), K(key)],
                        ConfigProblem::Invalid {
                            detail: format!(
                                "`{id}` cannot be a Sparkplug id (empty, or with `/`, `+` or `#`)"
                            ),
                        },
                    );
                }
            }
        }
        MqttConfig {
            url: raw.url.clone(),
            ca,
            username: raw.username.clone(),
            password: raw.password.clone(),
            primary_host: raw.primary_host.clone(),
            group: raw.group.clone(),
            redundancy_group: raw.redundancy_group.clone(),
        }
    }

    pub(in crate::config) fn check_station(
        &mut self,
        folder: &Path,
        raw: &RawStation,
    ) -> StationSettings {
        let time_zone = match raw.time_zone.parse::<chrono_tz::Tz>() {
            Ok(tz) => tz,
            Err(_) => {
                self.err(
                    &[K("station"), K("time_zone")],
                    ConfigProblem::UnknownValue {
                        what: Vocabulary::TimeZone,
                        value: raw.time_zone.clone(),
                    },
                );
                chrono_tz::UTC
            }
        };
        let retention_days = raw.retention_days.unwrap_or(60);
        if retention_days == 0 {
            self.err(
                &[K("station"), K("retention_days")],
                ConfigProblem::OutOfRange {
                    what: "retention_days",
                    value: 0,
                    min: 1,
                    max: None,
                },
            );
        }
        let store_text = raw.store.as_deref().unwrap_or("sqlite:events.sqlite");
        // One parser for every store address (crate::store_url); a relative SQLite path
        // is the project folder's.
        let store = match crate::store_url::StoreUrl::parse(store_text) {
            Ok(url) => url.resolved_in(folder).to_string(),
            Err(error) => {
                self.err(&[K("station"), K("store")], error);
                store_text.to_owned()
            }
        };
        let bind = match raw.bind.as_deref().map(parse_ip) {
            None => IpAddr::V4(Ipv4Addr::LOCALHOST),
            Some(Ok(ip)) => ip,
            Some(Err(problem)) => {
                self.err(&[K("station"), K("bind")], problem);
                IpAddr::V4(Ipv4Addr::LOCALHOST)
            }
        };
        let storage = self.station_storage(raw);
        StationSettings {
            name: raw.name.clone(),
            time_zone,
            store,
            retention_days,
            storage,
            port_base: raw.port_base.unwrap_or(2404),
            bind,
            plant: raw.plant.clone(),
        }
    }

    pub(in crate::config) fn point_source(
        &mut self,
        node: &str,
        links: &[RawLink],
        source: &str,
        path: &[Seg],
    ) -> PointSource {
        match parse_link_ref(source) {
            Ok(None) => PointSource::Variable(source.to_owned()),
            Ok(Some((link, ioa))) => {
                if !links.iter().any(|l| l.name == link) {
                    self.err(
                        path,
                        ConfigProblem::Unknown {
                            what: Reference::Link,
                            name: link.clone(),
                            within: node.to_owned(),
                        },
                    );
                }
                PointSource::Link {
                    link,
                    ioa: ioa.get(),
                }
            }
            Err(problem) => {
                self.err(path, problem);
                PointSource::Variable(source.to_owned())
            }
        }
    }

    /// A duration in milliseconds of at most a day; an error at `path` otherwise.
    pub(in crate::config) fn duration_ms(
        &mut self,
        ms: i64,
        path: &[Seg],
        key: &'static str,
    ) -> Option<Duration> {
        const MAX: i64 = 86_400_000;
        if (1..=MAX).contains(&ms) {
            Some(Duration::from_millis(ms.unsigned_abs()))
        } else {
            self.err(
                path,
                ConfigProblem::OutOfRange {
                    what: key,
                    value: ms,
                    min: 1,
                    max: Some(MAX),
                },
            );
            None
        }
    }

    pub(in crate::config) fn ips(&mut self, texts: &[String], path: &[Seg]) -> Vec<IpAddr> {
        let mut out = Vec::new();
        for (i, text) in texts.iter().enumerate() {
            match parse_ip(text) {
                Ok(ip) => out.push(ip),
                Err(problem) => {
                    let mut p = path.to_vec();
                    p.push(I(i));
                    self.err(&p, problem);
                }
            }
        }
        out
    }

    /// The TLS files at `path` (`[..., "tls"]`), each checked to exist.
    pub(in crate::config) fn tls_files(
        &mut self,
        folder: &Path,
        raw: &RawTls,
        path: &[Seg],
    ) -> TlsFiles {
        let mut at = |key: &'static str, relative: &str| {
            let mut key_path = path.to_vec();
            key_path.push(K(key));
            self.existing_file(folder, relative, &key_path)
        };
        TlsFiles {
            certificate: at("certificate", &raw.certificate),
            private_key: at("private_key", &raw.private_key),
            trust_anchors: at("trust_anchors", &raw.trust_anchors),
        }
    }

    pub(in crate::config) fn existing_file(
        &mut self,
        folder: &Path,
        relative: &str,
        path: &[Seg],
    ) -> PathBuf {
        let resolved = resolve(folder, relative);
        if !resolved.is_file() {
            self.err(
                path,
                ConfigProblem::FileNotFound {
                    path: resolved.clone(),
                },
            );
        }
        resolved
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_col_counts_characters() {
        let text = "a = 1\nname = \"Vsetín\" x";
        let offset = text.find('x').unwrap();
        assert_eq!(line_col(text, offset), (2, 17));
        assert_eq!(line_col(text, 0), (1, 1));
        assert_eq!(line_col(text, 10_000), (2, 18));
    }

    #[test]
    fn link_refs() {
        assert_eq!(parse_link_ref("A.B"), Ok(None));
        assert_eq!(
            parse_link_ref("link:RH2/281"),
            Ok(Some(("RH2".to_owned(), Ioa::from(281u16))))
        );
        assert!(parse_link_ref("link:RH2").is_err());
        assert!(parse_link_ref("link:/5").is_err());
        assert!(parse_link_ref("link:X/0").is_err());
        assert!(parse_link_ref("").is_err());
    }

    #[test]
    fn program_declarations() {
        assert!(declares_program(
            "PROGRAM RH2Logic\nEND_PROGRAM",
            "rh2logic"
        ));
        assert!(declares_program("program \"Main\" VAR END_VAR", "Main"));
        assert!(!declares_program("END_PROGRAM RH2Logic", "RH2Logic"));
        assert!(!declares_program("FUNCTION_BLOCK RH2Logic", "RH2Logic"));
    }
}
