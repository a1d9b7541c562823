//! The checks of a node's profiled devices (`[[node.device]]`) and the points each one
//! brings: its kind must be registered (`crate::device::DeviceKinds`), and its points
//! follow from the kind's profile, its name and `ioa_base`.

use super::*;
use points::DeviceProfile;

impl Ctx<'_> {
    /// Checks the node's devices and returns them with the points they bring (added to
    /// `taken`). `lifts` are the names of the node's lifts (a device may not share one:
    /// both prefix their points' names).
    pub(in crate::config) fn check_devices(
        &mut self,
        n: usize,
        raw: &RawNode,
        mut taken: TakenPoints<'_>,
    ) -> (Vec<FieldDeviceConfig>, Vec<PointConfig>) {
        let mut devices = Vec::new();
        let mut points = Vec::new();
        let mut names: HashSet<&str> = raw.lift.iter().map(|lift| lift.name.as_str()).collect();
        for (d, device) in raw.device.iter().enumerate() {
            let at = |key: &'static str| -> Vec<Seg> {
                vec![K("node"), I(n), K("device"), I(d), K(key)]
            };
            if device.name.trim().is_empty() || device.name.contains(['.', ' ']) {
                self.err(
                    &at("name"),
                    ConfigProblem::Empty {
                        what: "device name (no dots or spaces)",
                    },
                );
            }
            if !names.insert(&device.name) {
                self.err(
                    &at("name"),
                    ConfigProblem::Duplicate {
                        what: Unique::FieldDeviceName,
                        value: device.name.clone(),
                        other: raw.name.clone(),
                    },
                );
            }
            let ioa_base = match ioa(device.ioa_base) {
                Ok(base) => base,
                Err(problem) => {
                    self.err(&at("ioa_base"), problem);
                    Ioa::IRRELEVANT
                }
            };
            let Some(kind) = self.kinds.get(&device.kind) else {
                self.err(
                    &at("kind"),
                    ConfigProblem::UnknownDeviceKind {
                        kind: device.kind.clone(),
                        known: self.kinds.names().map(str::to_owned).collect(),
                    },
                );
                continue;
            };
            let mut config = FieldDeviceConfig {
                name: device.name.clone(),
                kind: device.kind.clone(),
                description: device.description.clone(),
                ioa_base,
                settings: device.settings.clone(),
                plant_port: None,
                io: Vec::new(),
            };
            // A device on the plant's serial port: the kind checks its settings as for a
            // serial port (the runtime puts the pseudo-terminal's path there).
            let mut checked = config.clone();
            if let Some(port) = config.settings.get(PLANT_PORT_KEY) {
                let Some(port) = port.as_str() else {
                    self.err(
                        &at("settings"),
                        ConfigProblem::Invalid {
                            detail: format!("setting `{PLANT_PORT_KEY}`: the name of a serial port of the plant"),
                        },
                    );
                    continue;
                };
                config.plant_port = Some(port.to_owned());
                if let Some(key) = ["serial", "tcp", "simulate"]
                    .into_iter()
                    .find(|key| config.settings.contains_key(*key))
                {
                    self.err(
                        &at("settings"),
                        Conflict::PlantPortAndLine {
                            key: key.to_owned(),
                        },
                    );
                }
                checked.settings.remove(PLANT_PORT_KEY);
                checked.settings.insert(
                    "serial".to_owned(),
                    toml::Value::String(format!("(plant port {port})")),
                );
            }
            if let Err(error) = kind.check(&checked) {
                self.err(
                    &at("settings"),
                    ConfigProblem::Invalid {
                        detail: error.to_string(),
                    },
                );
            }
            let profile = kind.profile().clone();
            let description = if device.description.is_empty() {
                String::new()
            } else {
                format!(" ({})", device.description)
            };
            let status = GeneratedPoint {
                name: format!("{}.{}", device.name, DeviceProfile::STATUS_SIGNAL),
                base: ioa_base,
                offset: profile.status_offset,
                point_type: PointType::new(PointKind::Single, TimeStamp::Full),
                source: PointSource::DeviceComm {
                    device: device.name.clone(),
                },
                storage: points::StorageRule::default(),
                description: format!(
                    "{} not answering (communication alarm){description}",
                    device.name
                ),
            };
            let signals = profile.signals.iter().map(|signal| GeneratedPoint {
                name: format!("{}.{}", device.name, signal.name),
                base: ioa_base,
                offset: signal.offset,
                point_type: signal.point_type,
                source: PointSource::Device {
                    device: device.name.clone(),
                    signal: signal.name.clone(),
                },
                storage: signal.storage,
                description: format!("{} {}{description}", device.name, signal.description),
            });
            for generated in std::iter::once(status).chain(signals) {
                match self.generated_point(generated, &raw.name, &mut taken, &at) {
                    Some(point) => points.push(point),
                    None => break,
                }
            }
            devices.push(config);
        }
        (devices, points)
    }
}
