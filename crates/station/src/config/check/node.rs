//! The checks of one node (`[[node]]`), in the order `Ctx::check_node` runs them: its
//! common address, ST sources, server (`server`), tasks, I/O bindings, points (`point`;
//! the points lifts and devices bring in `lift` and `device`), commands (`command`), the
//! PLC variables they all name (here), serial lines (`line`), notifications and tables.

use super::*;

/// The key path `node[n]` followed by `rest`.
pub(in crate::config) fn node_path(n: usize, rest: &[Seg]) -> Vec<Seg> {
    let mut p = vec![K("node"), I(n)];
    p.extend_from_slice(rest);
    p
}

/// One entry of an array of tables in a node (`node[n].point[p]`, `node[n].command[c]`,
/// ...): the key paths its problems are reported at.
#[derive(Clone, Copy)]
pub(in crate::config) struct Entry {
    n: usize,
    table: &'static str,
    i: usize,
}

impl Entry {
    /// Entry `i` of the node `n`'s `table`.
    pub(in crate::config) fn new(n: usize, table: &'static str, i: usize) -> Entry {
        Entry { n, table, i }
    }

    /// The entry as a whole.
    pub(in crate::config) fn path(self) -> Vec<Seg> {
        node_path(self.n, &[K(self.table), I(self.i)])
    }

    /// Its key `key`.
    pub(in crate::config) fn key(self, key: &'static str) -> Vec<Seg> {
        node_path(self.n, &[K(self.table), I(self.i), K(key)])
    }

    /// Element `e` of its array `key`.
    pub(in crate::config) fn element(self, key: &'static str, e: usize) -> Vec<Seg> {
        node_path(self.n, &[K(self.table), I(self.i), K(key), I(e)])
    }
}

/// A node's ST sources: every path (checked to exist) and the text of each one read.
struct Sources {
    paths: Vec<PathBuf>,
    /// (file name as diagnostics show it, text) of each source read.
    files: Vec<(String, String)>,
    /// Whether every source was read (else programs and variables are not looked up).
    all_read: bool,
}

impl Ctx<'_> {
    /// An I/O binding of a device's item: the device must be the node's, the item one its
    /// kind takes (checked by the kind), the direction `input` or `output`; the item is
    /// added to the device's.
    fn check_device_io(
        &mut self,
        at: &dyn Fn(&'static str) -> Vec<Seg>,
        raw: &RawNode,
        io: &RawIo,
        device: &str,
        devices: &mut [FieldDeviceConfig],
    ) -> Option<IoSource> {
        let Some(found) = devices.iter_mut().find(|d| d.name == device) else {
            self.err(
                &at("device"),
                ConfigProblem::Unknown {
                    what: Reference::Device,
                    name: device.to_owned(),
                    within: raw.name.clone(),
                },
            );
            return None;
        };
        let Some(item) = &io.item else {
            self.err(
                &at("device"),
                ConfigProblem::Missing {
                    what: "item",
                    needed_by: "an I/O binding of a device",
                    hint: "the device's address, e.g. I0.1 or DB1.DBX0.3",
                },
            );
            return None;
        };
        let output = match io.direction.as_deref() {
            Some("input") => false,
            Some("output") => true,
            Some(_) => {
                self.err(
                    &at("direction"),
                    ConfigProblem::Invalid {
                        detail: "direction is input (the device to the PLC) or output (the PLC to the device)".to_owned(),
                    },
                );
                return None;
            }
            None => {
                self.err(
                    &at("device"),
                    ConfigProblem::Missing {
                        what: "direction",
                        needed_by: "an I/O binding of a device",
                        hint: "input or output",
                    },
                );
                return None;
            }
        };
        let device_item = crate::device::DeviceItem {
            item: item.clone(),
            output,
        };
        if let Some(kind) = self.kinds.get(&found.kind) {
            if let Err(reason) = kind.check_item(&device_item) {
                self.err(&at("item"), ConfigProblem::Invalid { detail: reason });
                return None;
            }
        }
        if output && io.scale.is_some() {
            self.err(
                &at("scale"),
                ConfigProblem::Invalid {
                    detail: "only inputs are scaled".to_owned(),
                },
            );
        }
        if !found.io.contains(&device_item) {
            found.io.push(device_item);
        }
        Some(IoSource::Device {
            device: device.to_owned(),
            item: item.clone(),
            output,
        })
    }

    /// `[node.s7_server]`: sizes within reason, TSAPs of four hex digits, names unique;
    /// the node needs a PLC (its memory is what is served).
    fn check_s7_server(
        &mut self,
        n: usize,
        raw: &RawNode,
        server: &RawS7Server,
    ) -> Option<S7ServerConfig> {
        let at = |rest: &[Seg]| {
            let mut path = vec![K("node"), I(n), K("s7_server")];
            path.extend_from_slice(rest);
            path
        };
        let mut ok = true;
        if raw.sources.is_empty() {
            self.err(
                &at(&[]),
                ConfigProblem::Missing {
                    what: "sources",
                    needed_by: "an S7 server",
                    hint: "it serves the node's PLC memory",
                },
            );
            ok = false;
        }
        let mut range = |key: &'static str, value: Option<i64>, default: i64, max: i64| -> i64 {
            let value = value.unwrap_or(default);
            if !(0..=max).contains(&value) {
                self.err(
                    &at(&[K(key)]),
                    ConfigProblem::OutOfRange {
                        what: key,
                        value,
                        min: 0,
                        max: Some(max),
                    },
                );
                ok = false;
            }
            value.clamp(0, max)
        };
        let port_offset = range("port_offset", Some(server.port_offset), 0, 65_535);
        let inputs = range("inputs", server.inputs, 128, 65_536);
        let outputs = range("outputs", server.outputs, 128, 65_536);
        let markers = range("markers", server.markers, 256, 65_536);
        let pdu_size = range("pdu_size", server.pdu_size, 960, 960);
        if pdu_size < 240 {
            self.err(
                &at(&[K("pdu_size")]),
                ConfigProblem::OutOfRange {
                    what: "pdu_size",
                    value: pdu_size,
                    min: 240,
                    max: Some(960),
                },
            );
            ok = false;
        }
        let mut connections: Vec<S7ConnectionConfig> = Vec::new();
        for (c, connection) in server.connection.iter().enumerate() {
            let tsap = match u16::from_str_radix(&connection.tsap, 16) {
                Ok(tsap) if connection.tsap.len() == 4 => tsap,
                _ => {
                    self.err(
                        &at(&[K("connection"), I(c), K("tsap")]),
                        ConfigProblem::Invalid {
                            detail: format!(
                                "TSAP `{}`: four hex digits, the server TSAP the client calls (`0101`)",
                                connection.tsap
                            ),
                        },
                    );
                    ok = false;
                    continue;
                }
            };
            if let Some(other) = connections
                .iter()
                .find(|other| other.name == connection.name || other.tsap == tsap)
            {
                self.err(
                    &at(&[K("connection"), I(c)]),
                    ConfigProblem::Invalid {
                        detail: format!(
                            "connection `{}` (TSAP {:04X}) repeats connection `{}`'s name or TSAP",
                            connection.name, tsap, other.name
                        ),
                    },
                );
                ok = false;
                continue;
            }
            connections.push(S7ConnectionConfig {
                name: connection.name.clone(),
                tsap,
                status: connection.status.clone(),
            });
        }
        let size = |value: i64| usize::try_from(value).unwrap_or(0);
        ok.then(|| S7ServerConfig {
            port_offset: u16::try_from(port_offset).unwrap_or(0),
            inputs: size(inputs),
            outputs: size(outputs),
            markers: size(markers),
            pdu_size: u16::try_from(pdu_size).unwrap_or(960),
            connections,
        })
    }

    /// The node's I/O bindings: each a plant signal or a point of the node (`points`, its
    /// devices' among them), with a finite `scale`.
    fn check_io(
        &mut self,
        n: usize,
        raw: &RawNode,
        points: &[PointConfig],
        devices: &mut [FieldDeviceConfig],
    ) -> Vec<IoBinding> {
        let mut bindings = Vec::new();
        for (i, io) in raw.io.iter().enumerate() {
            let at = |key: &'static str| vec![K("node"), I(n), K("io"), I(i), K(key)];
            if let Some(device) = &io.device {
                if io.signal.is_some() || io.point.is_some() {
                    self.err(&at("device"), Conflict::IoSignalAndPoint);
                    continue;
                }
                if let Some(source) = self.check_device_io(&at, raw, io, device, devices) {
                    bindings.push(IoBinding {
                        source,
                        variable: io.variable.clone(),
                        scale: io.scale,
                    });
                }
                continue;
            }
            if io.item.is_some() || io.direction.is_some() {
                self.err(
                    &at(if io.item.is_some() {
                        "item"
                    } else {
                        "direction"
                    }),
                    ConfigProblem::Missing {
                        what: "device",
                        needed_by: "an I/O binding with item or direction",
                        hint: "",
                    },
                );
                continue;
            }
            let source = match (&io.signal, &io.point) {
                (Some(signal), None) => IoSource::Signal(signal.clone()),
                (None, Some(point)) => {
                    if !points.iter().any(|p| &p.name == point) {
                        self.err(
                            &at("point"),
                            ConfigProblem::Unknown {
                                what: Reference::Point,
                                name: point.clone(),
                                within: raw.name.clone(),
                            },
                        );
                    }
                    IoSource::Point(point.clone())
                }
                (Some(_), Some(_)) => {
                    self.err(&at("point"), Conflict::IoSignalAndPoint);
                    continue;
                }
                (None, None) => {
                    self.err(
                        &[K("node"), I(n), K("io"), I(i)],
                        ConfigProblem::Missing {
                            what: "signal or point",
                            needed_by: "an I/O binding",
                            hint: "",
                        },
                    );
                    continue;
                }
            };
            if let Some(scale) = io.scale.filter(|scale| !scale.is_finite() || *scale == 0.0) {
                self.err(
                    &at("scale"),
                    ConfigProblem::InvalidNumber {
                        what: "scale",
                        value: scale.to_string(),
                        expected: "a finite number other than 0",
                    },
                );
            }
            bindings.push(IoBinding {
                source,
                variable: io.variable.clone(),
                scale: io.scale,
            });
        }
        bindings
    }

    /// Checks node `n` (`raw`), each part in turn; the node's links are checked with the
    /// other nodes (`links`).
    pub(in crate::config) fn check_node(
        &mut self,
        folder: &Path,
        n: usize,
        raw: &RawNode,
    ) -> NodeConfig {
        let common = common_address(raw.common_address).unwrap_or_else(|problem| {
            self.err(&node_path(n, &[K("common_address")]), problem);
            CommonAddress::new(0)
        });
        let sources = self.check_sources(folder, n, raw);
        let server = raw
            .server
            .as_ref()
            .map(|s| self.check_server(folder, n, raw, s));
        let tasks = self.check_tasks(n, raw, &sources);

        let mut point_names = HashSet::new();
        let mut point_ioas: HashMap<Ioa, String> = HashMap::new();
        let mut points = self.check_points(
            n,
            raw,
            TakenPoints {
                names: &mut point_names,
                ioas: &mut point_ioas,
            },
        );
        let (lifts, lift_points) = self.check_lifts(
            n,
            raw,
            TakenPoints {
                names: &mut point_names,
                ioas: &mut point_ioas,
            },
        );
        points.extend(lift_points);
        let (mut devices, device_points) = self.check_devices(
            n,
            raw,
            TakenPoints {
                names: &mut point_names,
                ioas: &mut point_ioas,
            },
        );
        points.extend(device_points);
        let io = self.check_io(n, raw, &points, &mut devices);

        let commands = self.check_commands(
            n,
            raw,
            &CommandContext {
                points: &points,
                point_names: &point_names,
                point_ioas: &point_ioas,
                server: server.as_ref(),
            },
        );

        #[cfg(feature = "runtime")]
        if sources.all_read && !sources.files.is_empty() {
            self.check_plc_variables(n, raw, &sources.files);
        }

        let lines = self.check_lines(n, raw);
        let notify = self.check_notify(n, raw);
        let tables = self.check_tables(folder, n, raw);
        let s7_server = raw
            .s7_server
            .as_ref()
            .and_then(|server| self.check_s7_server(n, raw, server));
        NodeConfig {
            name: raw.name.clone(),
            description: raw.description.clone(),
            common_address: common,
            sources: sources.paths,
            server,
            host: None,
            tasks,
            io,
            points,
            commands,
            links: Vec::new(),
            lines,
            lifts,
            devices,
            notify,
            initial_values: raw
                .set
                .iter()
                .map(|(path, value)| (path.clone(), value.clone()))
                .collect(),
            tables,
            s7_server,
        }
    }

    /// The node's ST sources: each must exist and be UTF-8 text.
    fn check_sources(&mut self, folder: &Path, n: usize, raw: &RawNode) -> Sources {
        let mut paths = Vec::new();
        let mut files: Vec<(String, String)> = Vec::new();
        for (s, source) in raw.sources.iter().enumerate() {
            let path = node_path(n, &[K("sources"), I(s)]);
            let resolved = self.existing_file(folder, source, &path);
            if resolved.is_file() {
                match std::fs::read(&resolved) {
                    Ok(bytes) => match String::from_utf8(bytes) {
                        Ok(text) => files.push((resolved.display().to_string(), text)),
                        Err(e) => self.push(not_utf8(&resolved, e.as_bytes())),
                    },
                    Err(e) => self.err(
                        &path,
                        ConfigProblem::Unreadable {
                            file: Some(resolved.clone()),
                            kind: e.kind(),
                            detail: e.to_string(),
                        },
                    ),
                }
            }
            paths.push(resolved);
        }
        let all_read = files.len() == raw.sources.len();
        Sources {
            paths,
            files,
            all_read,
        }
    }

    /// The node's PLC tasks: names unique, intervals and watchdogs above 0, each program
    /// declared in the sources (when all of them were read).
    fn check_tasks(&mut self, n: usize, raw: &RawNode, sources: &Sources) -> Vec<TaskConfig> {
        let texts: Vec<&str> = sources
            .files
            .iter()
            .map(|(_, text)| text.as_str())
            .collect();
        let mut tasks = Vec::new();
        let mut task_names = HashSet::new();
        for (t, task) in raw.task.iter().enumerate() {
            let entry = Entry::new(n, "task", t);
            if !task_names.insert(task.name.clone()) {
                self.err(
                    &entry.key("name"),
                    ConfigProblem::Duplicate {
                        what: Unique::TaskName,
                        value: task.name.clone(),
                        other: raw.name.clone(),
                    },
                );
            }
            if task.interval_ms == 0 {
                self.err(
                    &entry.key("interval_ms"),
                    ConfigProblem::OutOfRange {
                        what: "interval_ms",
                        value: 0,
                        min: 1,
                        max: None,
                    },
                );
            }
            if task.watchdog_ms == Some(0) {
                self.err(
                    &entry.key("watchdog_ms"),
                    ConfigProblem::OutOfRange {
                        what: "watchdog_ms",
                        value: 0,
                        min: 1,
                        max: None,
                    },
                );
            }
            if sources.all_read {
                for (p, program) in task.programs.iter().enumerate() {
                    if !texts.iter().any(|text| declares_program(text, program)) {
                        self.err(
                            &entry.element("programs", p),
                            ConfigProblem::Unknown {
                                what: Reference::Program,
                                name: program.clone(),
                                within: raw.name.clone(),
                            },
                        );
                    }
                }
            }
            tasks.push(TaskConfig {
                name: task.name.clone(),
                interval: Duration::from_millis(task.interval_ms),
                priority: task.priority,
                programs: task.programs.clone(),
                watchdog: task.watchdog_ms.map(Duration::from_millis),
            });
        }
        tasks
    }

    /// The node's `[node.notify]` settings, each problem its validation finds reported.
    fn check_notify(&mut self, n: usize, raw: &RawNode) -> Option<notify::NotifyConfig> {
        raw.notify.as_ref().map(|config| {
            if let Err(errors) = config.validate() {
                for error in errors {
                    self.err(
                        &node_path(n, &[K("notify")]),
                        ConfigProblem::Invalid {
                            detail: error.to_string(),
                        },
                    );
                }
            }
            config.clone()
        })
    }

    /// The node's tables (`[[node.table]]`), each file checked to exist.
    fn check_tables(&mut self, folder: &Path, n: usize, raw: &RawNode) -> Vec<TableConfig> {
        raw.table
            .iter()
            .enumerate()
            .map(|(t, table)| TableConfig {
                file: self.existing_file(
                    folder,
                    &table.file,
                    &[K("node"), I(n), K("table"), I(t), K("file")],
                ),
                index: table.index.clone(),
                columns: table
                    .columns
                    .iter()
                    .map(|(column, path)| (column.clone(), path.clone()))
                    .collect(),
            })
            .collect()
    }
    /// Compiles the node's ST sources as the runtime will and looks up every PLC variable
    /// the node names (point sources and `invalid_when`, command targets and
    /// `remote_enable`, I/O variables, `refuse_commands_when`): a typo is then reported at
    /// its value in station.toml, not as a start-up failure without a place. Compile errors
    /// are reported at their place in the ST file.
    #[cfg(feature = "runtime")]
    pub(in crate::config) fn check_plc_variables(
        &mut self,
        n: usize,
        raw: &RawNode,
        files: &[(String, String)],
    ) {
        let (sources, result) = plc::build(files);
        let compiled = match result {
            Ok(compiled) => compiled,
            Err(diagnostics) => {
                for diagnostic in diagnostics.iter().filter(|d| d.is_error()) {
                    let at = sources.line_col(diagnostic.primary);
                    let file = sources
                        .file(diagnostic.primary.file)
                        .map(|f| PathBuf::from(&f.name))
                        .unwrap_or_default();
                    self.push(ConfigError {
                        file,
                        line: at.line,
                        column: at.col,
                        key: String::new(),
                        problem: ConfigProblem::StDiagnostic {
                            code: diagnostic.code,
                            message: diagnostic.message.clone(),
                            // The rendering's first line is the headline this error's
                            // own line repeats.
                            excerpt: diagnostic
                                .render(&sources)
                                .lines()
                                .skip(1)
                                .collect::<Vec<_>>()
                                .join("\n"),
                        },
                    });
                }
                return;
            }
        };
        let plc = match plc::Plc::try_new(compiled, sources) {
            Ok(plc) => plc,
            Err(error) => {
                self.err(
                    &[K("node"), I(n), K("sources")],
                    ConfigProblem::PlcStart {
                        detail: error.to_string(),
                    },
                );
                return;
            }
        };
        let is_variable = |text: &str| matches!(parse_link_ref(text), Ok(None));
        let mut named: Vec<(Vec<Seg>, &str)> = Vec::new();
        let mut addresses: Vec<(Vec<Seg>, &str)> = Vec::new();
        for (p, point) in raw.point.iter().enumerate() {
            if let Some(source) = point.source.as_deref().filter(|s| is_variable(s)) {
                if source.starts_with('%') {
                    // a direct address of the process image: the input whatever program runs
                    addresses.push((vec![K("point"), I(p), K("source")], source));
                } else {
                    named.push((vec![K("point"), I(p), K("source")], source));
                }
            }
            if let Some(variable) = &point.invalid_when {
                named.push((vec![K("point"), I(p), K("invalid_when")], variable));
            }
        }
        for (c, command) in raw.command.iter().enumerate() {
            if is_variable(&command.target) {
                if command.target.starts_with('%') {
                    // a direct address of the process image (a marker an S7 client reads)
                    addresses.push((vec![K("command"), I(c), K("target")], &command.target));
                } else {
                    named.push((vec![K("command"), I(c), K("target")], &command.target));
                }
            }
            if let Some(variable) = &command.remote_enable {
                named.push((vec![K("command"), I(c), K("remote_enable")], variable));
            }
        }
        for (i, io) in raw.io.iter().enumerate() {
            if io.variable.starts_with('%') {
                // a direct address of the process image (`%IX0.4`, `%ID4`, `%QX1.2`)
                addresses.push((vec![K("io"), I(i), K("variable")], &io.variable));
            } else {
                named.push((vec![K("io"), I(i), K("variable")], &io.variable));
            }
        }
        for (rest, address) in addresses {
            if let Err(error) = plc.get_io(address) {
                let mut path = vec![K("node"), I(n)];
                path.extend(rest);
                self.err(
                    &path,
                    ConfigProblem::PlcVariable {
                        detail: error.to_string(),
                    },
                );
            }
        }
        for (c, connection) in raw
            .s7_server
            .iter()
            .flat_map(|server| server.connection.iter())
            .enumerate()
        {
            if let Some(status) = &connection.status {
                named.push((
                    vec![K("s7_server"), K("connection"), I(c), K("status")],
                    status,
                ));
            }
        }
        let groups = raw
            .server
            .as_ref()
            .and_then(|s| s.redundancy_groups.as_ref());
        for (g, group) in groups.into_iter().flatten().enumerate() {
            if let Some(variable) = &group.refuse_commands_when {
                named.push((
                    vec![
                        K("server"),
                        K("redundancy_groups"),
                        I(g),
                        K("refuse_commands_when"),
                    ],
                    variable,
                ));
            }
        }
        for (rest, variable) in named {
            if let Err(error) = plc.leaf(variable) {
                let mut path = vec![K("node"), I(n)];
                path.extend(rest);
                let problem = match error {
                    plc::PlcError::UnknownPath(name) => {
                        let paths: Vec<String> =
                            plc.leaves().into_iter().map(|leaf| leaf.path).collect();
                        ConfigProblem::UnknownVariable {
                            suggestion: plc::suggest::did_you_mean(
                                &name,
                                paths.iter().map(String::as_str),
                            ),
                            name,
                        }
                    }
                    other => ConfigProblem::PlcVariable {
                        detail: other.to_string(),
                    },
                };
                self.err(&path, problem);
            }
        }
    }
}
