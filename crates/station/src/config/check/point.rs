//! The checks of a node's written points (`[[node.point]]`): name and IOA (unique in the
//! node), type, source (a PLC variable, `link:`, `line:`, or none for the status point
//! of a link, a redundancy group, a line or a line's device), measurand scaling,
//! transmission, interrogation groups, deadband and what the history keeps (`storage`). The points lifts and devices bring
//! are checked in `lift` and `device` (`generated`).

use super::*;

impl Ctx<'_> {
    /// Checks the node's written points; their names and IOAs go into `taken`.
    pub(in crate::config) fn check_points(
        &mut self,
        n: usize,
        raw: &RawNode,
        taken: TakenPoints<'_>,
    ) -> Vec<PointConfig> {
        let mut points = Vec::new();
        for (p, point) in raw.point.iter().enumerate() {
            let entry = Entry::new(n, "point", p);
            if !taken.names.insert(point.name.clone()) {
                self.err(
                    &entry.key("name"),
                    ConfigProblem::Duplicate {
                        what: Unique::PointName,
                        value: point.name.clone(),
                        other: raw.name.clone(),
                    },
                );
            }
            let (type_id, point_type) = self.point_type(entry, point);
            let address = self.point_ioa(entry, point, taken.ioas);
            let source = self.point_source_of(entry, raw, point, type_id);
            let scaling = self.point_scaling(entry, point, type_id, &source);
            let transmission = self.point_transmission(entry, point);
            let groups = self.point_groups(entry, point);
            self.check_deadband(entry, point, type_id);
            let storage = self.point_storage(entry, point, point_type, type_id);
            points.push(PointConfig {
                name: point.name.clone(),
                point_type,
                ioa: address,
                source,
                transmission,
                groups,
                deadband: point.deadband,
                invalid_when: point.invalid_when.clone(),
                scaling,
                storage,
                description: point.description.clone(),
            });
        }
        points
    }

    /// The point's type: a monitor type the point database keeps (single point after an
    /// error, so that checking goes on).
    fn point_type(&mut self, entry: Entry, point: &RawPoint) -> (TypeId, PointType) {
        // A fallback after an error, so that checking goes on.
        let single = PointType::new(PointKind::Single, TimeStamp::None);
        match point.type_id.parse::<TypeId>() {
            Ok(t) => match points_iec::point_type(t) {
                Some(point_type) => (t, point_type),
                None => {
                    self.err(
                        &entry.key("type"),
                        ConfigProblem::WrongType {
                            type_id: t.to_string(),
                            usage: TypeUse::Point,
                        },
                    );
                    (TypeId::M_SP_NA_1, single)
                }
            },
            Err(_) => {
                self.err(
                    &entry.key("type"),
                    ConfigProblem::UnknownValue {
                        what: Vocabulary::TypeId,
                        value: point.type_id.clone(),
                    },
                );
                (TypeId::M_SP_NA_1, single)
            }
        }
    }

    /// The point's IOA, taken in `ioas` (point name by IOA) unless another point has it.
    fn point_ioa(
        &mut self,
        entry: Entry,
        point: &RawPoint,
        ioas: &mut HashMap<Ioa, String>,
    ) -> Ioa {
        match ioa(point.ioa) {
            Ok(a) => {
                if let Some(other) = ioas.get(&a) {
                    self.err(
                        &entry.key("ioa"),
                        ConfigProblem::Duplicate {
                            what: Unique::PointIoa,
                            value: a.to_string(),
                            other: other.clone(),
                        },
                    );
                } else {
                    ioas.insert(a, point.name.clone());
                }
                a
            }
            Err(problem) => {
                self.err(&entry.key("ioa"), problem);
                Ioa::IRRELEVANT
            }
        }
    }

    /// The point's source: the one written, or, for the status point of a link, a
    /// redundancy group, a line or a line's device (which may have none), that status.
    fn point_source_of(
        &mut self,
        entry: Entry,
        raw: &RawNode,
        point: &RawPoint,
        type_id: TypeId,
    ) -> PointSource {
        let status_of = raw
            .link
            .iter()
            .find(|l| l.status_point.as_deref() == Some(point.name.as_str()));
        let group_of = raw
            .server
            .as_ref()
            .and_then(|s| s.redundancy_groups.as_ref())
            .and_then(|groups| {
                groups
                    .iter()
                    .find(|g| g.status_point.as_deref() == Some(point.name.as_str()))
            });
        if let (None, None, Some(group)) = (&point.source, status_of, group_of) {
            if !matches!(type_id, TypeId::M_SP_NA_1 | TypeId::M_SP_TB_1) {
                self.err(
                    &entry.key("type"),
                    ConfigProblem::WrongType {
                        type_id: type_id.to_string(),
                        usage: TypeUse::GroupStatus {
                            group: group.name.clone(),
                        },
                    },
                );
            }
        }
        let device_of = raw.line.iter().find_map(|line| {
            line.device
                .iter()
                .find(|device| device.status_point.as_deref() == Some(point.name.as_str()))
                .map(|device| (line.name.clone(), device.name.clone()))
        });
        let line_of = raw
            .line
            .iter()
            .find(|line| line.status_point.as_deref() == Some(point.name.as_str()))
            .map(|line| line.name.clone());
        match (&point.source, status_of) {
            (None, None) if line_of.is_some() => PointSource::LineStatus {
                line: line_of.clone().unwrap_or_default(),
            },
            (None, None) if device_of.is_some() => {
                let (line, device) = device_of.clone().unwrap_or_default();
                PointSource::DeviceStatus { line, device }
            }
            (None, None) if group_of.is_some() => {
                PointSource::ClientStatus(group_of.map(|g| g.name.clone()).unwrap_or_default())
            }
            (None, Some(link)) => {
                if !matches!(type_id, TypeId::M_SP_NA_1 | TypeId::M_SP_TB_1) {
                    self.err(
                        &entry.key("type"),
                        ConfigProblem::WrongType {
                            type_id: type_id.to_string(),
                            usage: TypeUse::LinkStatus {
                                link: link.name.clone(),
                            },
                        },
                    );
                }
                PointSource::LinkStatus(link.name.clone())
            }
            (None, None) => {
                self.err(
                    &entry.path(),
                    ConfigProblem::Missing {
                        what: "source",
                        needed_by: "",
                        hint: "only the status point of a link, a redundancy group, a line or a device has none",
                    },
                );
                PointSource::Variable(String::new())
            }
            (Some(_), Some(link)) => {
                self.err(
                    &entry.key("source"),
                    Conflict::LinkStatusWithSource {
                        link: link.name.clone(),
                    },
                );
                PointSource::LinkStatus(link.name.clone())
            }
            (Some(source), None) => self.written_point_source(entry, raw, point, type_id, source),
        }
    }

    /// A source the project writes: a `line:` signal, a `link:` IOA or a PLC variable.
    fn written_point_source(
        &mut self,
        entry: Entry,
        raw: &RawNode,
        point: &RawPoint,
        type_id: TypeId,
        source: &str,
    ) -> PointSource {
        match line::parse_line_ref(source) {
            Ok(Some(reference)) => {
                self.line_ref_exists(&raw.name, &raw.line, &reference, &entry.key("source"));
                self.check_line_signal_type(entry, point, type_id, &reference);
                PointSource::Line {
                    line: reference.line,
                    device: reference.device,
                    signal: reference.signal,
                }
            }
            Ok(None) => self.point_source(&raw.name, &raw.link, source, &entry.key("source")),
            Err(problem) => {
                self.err(&entry.key("source"), problem);
                PointSource::Variable(source.to_owned())
            }
        }
    }

    /// Whether the point's type fits the IEC 103 signal it reads: an indication for an
    /// indication, a measurement (with its `measurand_limit`) for a measurand.
    fn check_line_signal_type(
        &mut self,
        entry: Entry,
        point: &RawPoint,
        type_id: TypeId,
        reference: &line::LineRef,
    ) {
        let indication = matches!(
            type_id,
            TypeId::M_SP_NA_1 | TypeId::M_SP_TB_1 | TypeId::M_DP_NA_1 | TypeId::M_DP_TB_1
        );
        let iec103 = matches!(reference.signal, LineSignal::Iec103 { .. });
        match (reference.index(), indication, is_measurement(type_id)) {
            // An IEC 101 object carries its own type: any monitor type
            // (checked with the point's type) takes it.
            _ if !iec103 => {}
            (None, false, _) => self.err(
                &entry.key("type"),
                ConfigProblem::WrongType {
                    type_id: type_id.to_string(),
                    usage: TypeUse::LineIndication,
                },
            ),
            (Some(_), _, false) => self.err(
                &entry.key("type"),
                ConfigProblem::WrongType {
                    type_id: type_id.to_string(),
                    usage: TypeUse::LineMeasurand,
                },
            ),
            (Some(_), _, true) if point.measurand_limit.is_none() => self.err(
                &entry.path(),
                ConfigProblem::Missing {
                    what: "measurand_limit",
                    needed_by: "a measurand of a line device",
                    hint: "the engineering value at fraction 1.0",
                },
            ),
            _ => {}
        }
    }

    /// The scaling of a line device's measurand (`measurand_limit`, `full_scale`,
    /// `scale_factor`); `None` for any other point, which may set none of them.
    fn point_scaling(
        &mut self,
        entry: Entry,
        point: &RawPoint,
        type_id: TypeId,
        source: &PointSource,
    ) -> Option<MeasurandScaling> {
        let line_measurand = matches!(
            source,
            PointSource::Line {
                signal: LineSignal::Iec103 { index: Some(_), .. },
                ..
            }
        );
        self.check_scale_factor(entry, point, type_id);
        match (point.measurand_limit, point.full_scale) {
            (None, None) => None,
            (Some(limit), full_scale) if line_measurand => {
                if !(limit.is_finite() && limit > 0.0) {
                    self.err(
                        &entry.key("measurand_limit"),
                        ConfigProblem::InvalidNumber {
                            what: "measurand_limit",
                            value: limit.to_string(),
                            expected: "a positive number",
                        },
                    );
                }
                if let Some(f) = full_scale.filter(|f| !(f.is_finite() && *f > 0.0)) {
                    self.err(
                        &entry.key("full_scale"),
                        ConfigProblem::InvalidNumber {
                            what: "full_scale",
                            value: f.to_string(),
                            expected: "a positive number",
                        },
                    );
                }
                Some(MeasurandScaling {
                    limit,
                    full_scale,
                    factor: point.scale_factor,
                })
            }
            (Some(_), _) => {
                self.err(
                    &entry.key("measurand_limit"),
                    Conflict::MeasurandLimitWithoutMeasurand,
                );
                None
            }
            (None, Some(_)) => {
                self.err(
                    &entry.key("full_scale"),
                    ConfigProblem::Missing {
                        what: "measurand_limit",
                        needed_by: "full_scale",
                        hint: "",
                    },
                );
                None
            }
        }
    }

    /// A `scale_factor` needs a `measurand_limit`, a scaled or floating measurement and a
    /// finite value other than 0.
    fn check_scale_factor(&mut self, entry: Entry, point: &RawPoint, type_id: TypeId) {
        if point.scale_factor.is_some() && point.measurand_limit.is_none() {
            self.err(
                &entry.key("scale_factor"),
                ConfigProblem::Missing {
                    what: "measurand_limit",
                    needed_by: "scale_factor",
                    hint: "",
                },
            );
        }
        if let Some(factor) = point.scale_factor {
            if !matches!(
                type_id,
                TypeId::M_ME_NB_1 | TypeId::M_ME_TB_1 | TypeId::M_ME_TE_1
            ) {
                self.err(
                    &entry.key("scale_factor"),
                    ConfigProblem::WrongType {
                        type_id: type_id.to_string(),
                        usage: TypeUse::ScaleFactor,
                    },
                );
            } else if !(factor.is_finite() && factor != 0.0) {
                self.err(
                    &entry.key("scale_factor"),
                    ConfigProblem::InvalidNumber {
                        what: "scale_factor",
                        value: factor.to_string(),
                        expected: "a finite number other than 0",
                    },
                );
            }
        }
    }

    /// How the point is transmitted: spontaneous, cyclic (with its `cycle_ms`) or on
    /// interrogation only.
    fn point_transmission(&mut self, entry: Entry, point: &RawPoint) -> Transmission {
        match (point.transmission, point.cycle_ms) {
            (RawTransmission::Cyclic, Some(ms)) if ms > 0 => {
                Transmission::Cyclic(Duration::from_millis(ms))
            }
            (RawTransmission::Cyclic, Some(_)) => {
                self.err(
                    &entry.key("cycle_ms"),
                    ConfigProblem::OutOfRange {
                        what: "cycle_ms",
                        value: 0,
                        min: 1,
                        max: None,
                    },
                );
                Transmission::Spontaneous
            }
            (RawTransmission::Cyclic, None) => {
                self.err(
                    &entry.key("transmission"),
                    ConfigProblem::Missing {
                        what: "cycle_ms",
                        needed_by: "cyclic transmission",
                        hint: "",
                    },
                );
                Transmission::Spontaneous
            }
            (_, Some(_)) => {
                self.err(&entry.key("cycle_ms"), Conflict::CycleWithoutCyclic);
                Transmission::Spontaneous
            }
            (RawTransmission::Spontaneous, None) => Transmission::Spontaneous,
            (RawTransmission::InterrogationOnly, None) => Transmission::InterrogationOnly,
        }
    }

    /// The interrogation groups (1 to 16) the point belongs to.
    fn point_groups(&mut self, entry: Entry, point: &RawPoint) -> Vec<u8> {
        let mut groups = Vec::new();
        for (g, group) in point.groups.iter().enumerate() {
            match u8::try_from(*group) {
                Ok(v) if (1..=16).contains(&v) => groups.push(v),
                _ => self.err(
                    &entry.element("groups", g),
                    ConfigProblem::OutOfRange {
                        what: "interrogation group",
                        value: *group,
                        min: 1,
                        max: Some(16),
                    },
                ),
            }
        }
        groups
    }

    /// A deadband is for a measurement, finite and not negative.
    fn check_deadband(&mut self, entry: Entry, point: &RawPoint, type_id: TypeId) {
        let Some(deadband) = point.deadband else {
            return;
        };
        if !is_measurement(type_id) {
            self.err(
                &entry.key("deadband"),
                ConfigProblem::WrongType {
                    type_id: type_id.to_string(),
                    usage: TypeUse::Deadband,
                },
            );
        } else if !(deadband >= 0.0 && deadband.is_finite()) {
            self.err(
                &entry.key("deadband"),
                ConfigProblem::InvalidNumber {
                    what: "deadband",
                    value: deadband.to_string(),
                    expected: "a finite value >= 0",
                },
            );
        }
    }
}
