//! The checks of a node's commands (`[[node.command]]`): name and IOA (unique in the
//! node, and no point's IOA), type, target (a PLC variable, `link:NAME/IOA`, or a line
//! device's signal or object), the redundancy groups it is taken from, pulse, age, range
//! and return information (`feedback`, implied for a general command to an IEC 103
//! device).

use super::*;

/// What a node's commands are checked against: the node's points (written and
/// generated) with their names and IOAs, and its server.
pub(in crate::config) struct CommandContext<'a> {
    pub(in crate::config) points: &'a [PointConfig],
    pub(in crate::config) point_names: &'a HashSet<String>,
    pub(in crate::config) point_ioas: &'a HashMap<Ioa, String>,
    pub(in crate::config) server: Option<&'a ServerConfig>,
}

impl Ctx<'_> {
    /// Checks the commands of node `n` (`raw`).
    pub(in crate::config) fn check_commands(
        &mut self,
        n: usize,
        raw: &RawNode,
        node: &CommandContext<'_>,
    ) -> Vec<CommandConfig> {
        let mut commands = Vec::new();
        let mut command_names = HashSet::new();
        let mut command_ioas: HashMap<Ioa, String> = HashMap::new();
        for (c, command) in raw.command.iter().enumerate() {
            let entry = Entry::new(n, "command", c);
            if !command_names.insert(command.name.clone()) {
                self.err(
                    &entry.key("name"),
                    ConfigProblem::Duplicate {
                        what: Unique::CommandName,
                        value: command.name.clone(),
                        other: raw.name.clone(),
                    },
                );
            }
            let type_id = self.command_type(entry, command);
            let address = self.command_ioa(entry, command, &mut command_ioas, node.point_ioas);
            let target = self.command_target(entry, raw, command, type_id);
            self.check_from_groups(entry, raw, command, node.server);
            let pulse = self.command_pulse(entry, command, &target);
            let max_age = command
                .max_age_ms
                .and_then(|ms| self.duration_ms(ms, &entry.key("max_age_ms"), "max_age_ms"));
            let range = self.command_range(entry, command, type_id);
            let feedback = self.command_feedback(entry, raw, command, &target, node);
            commands.push(CommandConfig {
                max_age,
                feedback,
                range,
                name: command.name.clone(),
                type_id,
                ioa: address,
                target,
                select_required: command.select_required,
                remote_enable: command.remote_enable.clone(),
                pulse,
                from_groups: command.from_groups.clone(),
                description: command.description.clone(),
            });
        }
        commands
    }

    /// The command's type: a command type (single command after an error).
    fn command_type(&mut self, entry: Entry, command: &RawCommand) -> TypeId {
        match command.type_id.parse::<TypeId>() {
            Ok(t) if t.is_command() => t,
            Ok(t) => {
                self.err(
                    &entry.key("type"),
                    ConfigProblem::WrongType {
                        type_id: t.to_string(),
                        usage: TypeUse::Command,
                    },
                );
                TypeId::C_SC_NA_1
            }
            Err(_) => {
                self.err(
                    &entry.key("type"),
                    ConfigProblem::UnknownValue {
                        what: Vocabulary::TypeId,
                        value: command.type_id.clone(),
                    },
                );
                TypeId::C_SC_NA_1
            }
        }
    }

    /// The command's IOA, taken in `ioas` (command name by IOA) unless another command or
    /// a point (`point_ioas`) has it.
    fn command_ioa(
        &mut self,
        entry: Entry,
        command: &RawCommand,
        ioas: &mut HashMap<Ioa, String>,
        point_ioas: &HashMap<Ioa, String>,
    ) -> Ioa {
        match ioa(command.ioa) {
            Ok(a) => {
                if let Some(other) = ioas.get(&a) {
                    self.err(
                        &entry.key("ioa"),
                        ConfigProblem::Duplicate {
                            what: Unique::CommandIoa,
                            value: a.to_string(),
                            other: other.clone(),
                        },
                    );
                } else if let Some(point) = point_ioas.get(&a) {
                    // Many controlling stations (lib60870, most SCADA) keep one
                    // information object per address: a command and a point on one
                    // IOA would clash there.
                    self.err(
                        &entry.key("ioa"),
                        ConfigProblem::Duplicate {
                            what: Unique::CommandOnPointIoa,
                            value: a.to_string(),
                            other: point.clone(),
                        },
                    );
                } else {
                    ioas.insert(a, command.name.clone());
                }
                a
            }
            Err(problem) => {
                self.err(&entry.key("ioa"), problem);
                Ioa::IRRELEVANT
            }
        }
    }

    /// Where the command goes: a line device's signal or object, a lower node's command
    /// (`link:NAME/IOA`, the link known to the node) or a PLC variable.
    fn command_target(
        &mut self,
        entry: Entry,
        raw: &RawNode,
        command: &RawCommand,
        type_id: TypeId,
    ) -> CommandTarget {
        let line_target = self.line_command_target(entry, raw, command, type_id);
        match line_target.map(Ok).unwrap_or_else(|| {
            parse_link_ref(&command.target).map(|link| {
                link.map_or_else(
                    || CommandTarget::Variable(command.target.clone()),
                    |(link, ioa)| CommandTarget::Link { link, ioa },
                )
            })
        }) {
            Ok(CommandTarget::Link { link, ioa }) => {
                if !raw.link.iter().any(|l| l.name == link) {
                    self.err(
                        &entry.key("target"),
                        ConfigProblem::Unknown {
                            what: Reference::Link,
                            name: link.clone(),
                            within: raw.name.clone(),
                        },
                    );
                }
                CommandTarget::Link { link, ioa }
            }
            Ok(target) => target,
            Err(problem) => {
                self.err(&entry.key("target"), problem);
                CommandTarget::Variable(command.target.clone())
            }
        }
    }

    /// A `line:` target: a general command to an IEC 103 device's FUN/INF (`=ON`/`=OFF`
    /// fixing its value), or an IEC 101 outstation's object; `None` for any other target.
    fn line_command_target(
        &mut self,
        entry: Entry,
        raw: &RawNode,
        command: &RawCommand,
        type_id: TypeId,
    ) -> Option<CommandTarget> {
        let (reference_text, fixed_value) = match command.target.rsplit_once('=') {
            Some((reference, "ON")) if reference.starts_with("line:") => (reference, Some(true)),
            Some((reference, "OFF")) if reference.starts_with("line:") => (reference, Some(false)),
            _ => (command.target.as_str(), None),
        };
        match line::parse_line_ref(reference_text) {
            Ok(Some(reference)) => {
                self.line_ref_exists(&raw.name, &raw.line, &reference, &entry.key("target"));
                match reference.signal {
                    LineSignal::Iec103 { fun, inf, index } => {
                        if index.is_some() {
                            self.err(&entry.key("target"), Conflict::LineCommandWithIndex);
                        }
                        if !matches!(type_id, TypeId::C_SC_NA_1 | TypeId::C_DC_NA_1) {
                            self.err(
                                &entry.key("type"),
                                ConfigProblem::WrongType {
                                    type_id: type_id.to_string(),
                                    usage: TypeUse::LineCommand,
                                },
                            );
                        }
                        Some(CommandTarget::Line {
                            line: reference.line,
                            device: reference.device,
                            fun,
                            inf,
                            value: fixed_value,
                        })
                    }
                    // Forwarded as it came: the command's own type and value.
                    LineSignal::Iec101 { ioa } => {
                        if fixed_value.is_some() {
                            self.err(
                                &entry.key("target"),
                                Conflict::NotForProtocol {
                                    key: "=ON/=OFF",
                                    protocol: "iec101",
                                },
                            );
                        }
                        Some(CommandTarget::LineObject {
                            line: reference.line,
                            device: reference.device,
                            // In range: `parse_line_ref` checked it.
                            ioa: Ioa::try_new(ioa).unwrap_or(Ioa::IRRELEVANT),
                        })
                    }
                }
            }
            Ok(None) => None,
            Err(problem) => {
                self.err(&entry.key("target"), problem);
                Some(CommandTarget::Variable(command.target.clone()))
            }
        }
    }

    /// Each of the command's `from_groups` is a redundancy group of the node's server.
    fn check_from_groups(
        &mut self,
        entry: Entry,
        raw: &RawNode,
        command: &RawCommand,
        server: Option<&ServerConfig>,
    ) {
        for (g, group) in command.from_groups.iter().enumerate() {
            let known =
                server.is_some_and(|s| s.redundancy_groups.iter().any(|r| &r.name == group));
            if !known {
                self.err(
                    &entry.element("from_groups", g),
                    ConfigProblem::Unknown {
                        what: Reference::RedundancyGroup,
                        name: group.clone(),
                        within: raw.name.clone(),
                    },
                );
            }
        }
    }

    /// The command's pulse (1 ms to an hour); not for a forwarded command.
    fn command_pulse(
        &mut self,
        entry: Entry,
        command: &RawCommand,
        target: &CommandTarget,
    ) -> Option<Duration> {
        match command.pulse_ms {
            None => None,
            Some(ms) if (1..=3_600_000).contains(&ms) => {
                if matches!(target, CommandTarget::Link { .. }) {
                    self.err(&entry.key("pulse_ms"), Conflict::ForwardedPulse);
                }
                Some(Duration::from_millis(ms.unsigned_abs()))
            }
            Some(ms) => {
                self.err(
                    &entry.key("pulse_ms"),
                    ConfigProblem::OutOfRange {
                        what: "pulse_ms",
                        value: ms,
                        min: 1,
                        max: Some(3_600_000),
                    },
                );
                None
            }
        }
    }

    /// The values a set-point command may take.
    fn command_range(
        &mut self,
        entry: Entry,
        command: &RawCommand,
        type_id: TypeId,
    ) -> Option<std::ops::RangeInclusive<f64>> {
        let [low, high] = command.range?;
        let setpoint = matches!(
            type_id,
            TypeId::C_SE_NA_1
                | TypeId::C_SE_NB_1
                | TypeId::C_SE_NC_1
                | TypeId::C_SE_TA_1
                | TypeId::C_SE_TB_1
                | TypeId::C_SE_TC_1
        );
        if !setpoint {
            self.err(
                &entry.key("range"),
                ConfigProblem::WrongType {
                    type_id: type_id.to_string(),
                    usage: TypeUse::Range,
                },
            );
            None
        } else if !(low.is_finite() && high.is_finite() && low <= high) {
            self.err(
                &entry.key("range"),
                ConfigProblem::EmptyRange {
                    low: low.to_string(),
                    high: high.to_string(),
                },
            );
            None
        } else {
            Some(low..=high)
        }
    }

    /// The point returning the command's effect: the one named (a point of the node; not
    /// for a forwarded command), or the one implied for a general command to an IEC 103
    /// device.
    fn command_feedback(
        &mut self,
        entry: Entry,
        raw: &RawNode,
        command: &RawCommand,
        target: &CommandTarget,
        node: &CommandContext<'_>,
    ) -> Option<Feedback> {
        match &command.feedback {
            // A relay reports a general command's effect at the command's own FUN/INF:
            // the point read from there is the command's return information, so that
            // ACT_TERM follows it (it left before the position changed).
            None if command.feedback_timeout_ms.is_none() => {
                implied_line_feedback(target, node.points)
            }
            None => {
                if command.feedback_timeout_ms.is_some() {
                    self.err(
                        &entry.key("feedback_timeout_ms"),
                        ConfigProblem::Missing {
                            what: "feedback",
                            needed_by: "feedback_timeout_ms",
                            hint: "",
                        },
                    );
                }
                None
            }
            Some(point) => {
                if !node.point_names.contains(point) {
                    self.err(
                        &entry.key("feedback"),
                        ConfigProblem::Unknown {
                            what: Reference::Point,
                            name: point.clone(),
                            within: raw.name.clone(),
                        },
                    );
                }
                if matches!(target, CommandTarget::Link { .. }) {
                    self.err(&entry.key("feedback"), Conflict::ForwardedFeedback);
                }
                let timeout = match command.feedback_timeout_ms {
                    None => DEFAULT_FEEDBACK_TIMEOUT,
                    Some(ms) => self
                        .duration_ms(ms, &entry.key("feedback_timeout_ms"), "feedback_timeout_ms")
                        .unwrap_or(DEFAULT_FEEDBACK_TIMEOUT),
                };
                Some(Feedback {
                    point: point.clone(),
                    timeout,
                })
            }
        }
    }
}

/// The return information of a general command to an IEC 103 device when the project
/// names none: the indication the device reports at the command's FUN/INF.
fn implied_line_feedback(target: &CommandTarget, points: &[PointConfig]) -> Option<Feedback> {
    let CommandTarget::Line {
        line,
        device,
        fun,
        inf,
        ..
    } = target
    else {
        return None;
    };
    points
        .iter()
        .find(|point| {
            matches!(&point.source, PointSource::Line {
                line: point_line,
                device: point_device,
                signal: LineSignal::Iec103 { fun: f, inf: i, index: None },
            } if point_line == line && point_device == device && f == fun && i == inf)
        })
        .map(|point| Feedback {
            point: point.name.clone(),
            timeout: DEFAULT_FEEDBACK_TIMEOUT,
        })
}
