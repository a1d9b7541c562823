//! The checks of the links between nodes: targets, addresses, republishing, cycles.

use super::*;

impl Ctx<'_> {
    /// Builds every node's links (they need all nodes) and checks the link graph.
    pub(in crate::config) fn check_links(
        &mut self,
        folder: &Path,
        raw: &RawProject,
        nodes: &mut [NodeConfig],
    ) {
        let index: HashMap<&str, usize> = raw
            .node
            .iter()
            .enumerate()
            .rev()
            .map(|(i, n)| (n.name.as_str(), i))
            .collect();
        // edges[n] = (target node, link index)
        let mut edges: Vec<Vec<(usize, usize)>> = vec![Vec::new(); raw.node.len()];
        let mut built: Vec<Vec<LinkConfig>> = vec![Vec::new(); raw.node.len()];
        for (n, node) in raw.node.iter().enumerate() {
            let mut names = HashSet::new();
            for (l, link) in node.link.iter().enumerate() {
                let at = |key: &'static str| vec![K("node"), I(n), K("link"), I(l), K(key)];
                if !names.insert(link.name.clone()) {
                    self.err(
                        &at("name"),
                        ConfigProblem::Duplicate {
                            what: Unique::LinkName,
                            value: link.name.clone(),
                            other: node.name.clone(),
                        },
                    );
                }
                let mut target_node = None;
                let target = match (&link.node, &link.address) {
                    (Some(_), Some(_)) => {
                        self.err(&at("address"), Conflict::NodeAndAddress);
                        None
                    }
                    (None, None) => {
                        self.err(
                            &[K("node"), I(n), K("link"), I(l)],
                            ConfigProblem::Missing {
                                what: "node or address",
                                needed_by: "a link",
                                hint: "",
                            },
                        );
                        None
                    }
                    (Some(name), None) => match index.get(name.as_str()) {
                        None => {
                            self.err(
                                &at("node"),
                                ConfigProblem::Unknown {
                                    what: Reference::Node,
                                    name: name.clone(),
                                    within: String::new(),
                                },
                            );
                            None
                        }
                        Some(&t) if t == n => {
                            self.err(&at("node"), Conflict::LinkToItself);
                            None
                        }
                        Some(&t) => {
                            if raw.node.get(t).is_some_and(|t| t.server.is_none()) {
                                self.err(&at("node"), Conflict::NoServer { node: name.clone() });
                            }
                            let lower_tls = raw
                                .node
                                .get(t)
                                .and_then(|t| t.server.as_ref())
                                .is_some_and(|server| server.tls.is_some());
                            match (lower_tls, link.tls.is_some()) {
                                (true, false) => self
                                    .err(&at("node"), Conflict::TlsRequired { node: name.clone() }),
                                (false, true) => self.err(
                                    &at("tls"),
                                    Conflict::TlsUnavailable { node: name.clone() },
                                ),
                                _ => {}
                            }
                            if let Some(e) = edges.get_mut(n) {
                                e.push((t, l));
                            }
                            target_node = Some(t);
                            Some(LinkTarget::Node(name.clone()))
                        }
                    },
                    (None, Some(address)) => match address.trim().parse::<SocketAddr>() {
                        Ok(a) => Some(LinkTarget::Address(a)),
                        Err(_) => {
                            self.err(
                                &at("address"),
                                ConfigProblem::Malformed {
                                    text: address.clone(),
                                    form: Form::SocketAddress,
                                },
                            );
                            None
                        }
                    },
                };
                let common = match link.common_address {
                    Some(value) => common_address(value).unwrap_or_else(|problem| {
                        self.err(&at("common_address"), problem);
                        CommonAddress::new(0)
                    }),
                    None => match target_node.and_then(|t| nodes.get(t)) {
                        Some(t) => t.common_address,
                        None => {
                            if matches!(target, Some(LinkTarget::Address(_))) {
                                self.err(
                                    &[K("node"), I(n), K("link"), I(l)],
                                    ConfigProblem::Missing {
                                        what: "common_address",
                                        needed_by: "a link with an address",
                                        hint: "",
                                    },
                                );
                            }
                            CommonAddress::new(0)
                        }
                    },
                };
                if let Some(status) = &link.status_point {
                    if !node.point.iter().any(|p| &p.name == status) {
                        self.err(
                            &at("status_point"),
                            ConfigProblem::Unknown {
                                what: Reference::Point,
                                name: status.clone(),
                                within: node.name.clone(),
                            },
                        );
                    }
                }
                // link: references into a project node must name what that node serves
                if let Some(lower) = target_node.and_then(|t| nodes.get(t)) {
                    let lower_points: HashSet<u32> =
                        lower.points.iter().map(|p| p.ioa.get()).collect();
                    let lower_commands: HashSet<Ioa> =
                        lower.commands.iter().map(|c| c.ioa).collect();
                    let mut problems = Vec::new();
                    if let Some(this) = nodes.get(n) {
                        for (p, point) in this.points.iter().enumerate() {
                            if let PointSource::Link { link: name, ioa } = &point.source {
                                if name == &link.name && !lower_points.contains(ioa) {
                                    problems.push((
                                        vec![K("node"), I(n), K("point"), I(p), K("source")],
                                        ConfigProblem::Unknown {
                                            what: Reference::LowerPoint,
                                            name: ioa.to_string(),
                                            within: lower.name.clone(),
                                        },
                                    ));
                                }
                            }
                        }
                        for (c, command) in this.commands.iter().enumerate() {
                            if let CommandTarget::Link { link: name, ioa } = &command.target {
                                if name == &link.name && !lower_commands.contains(ioa) {
                                    problems.push((
                                        vec![K("node"), I(n), K("command"), I(c), K("target")],
                                        ConfigProblem::Unknown {
                                            what: Reference::LowerCommand,
                                            name: ioa.to_string(),
                                            within: lower.name.clone(),
                                        },
                                    ));
                                }
                            }
                        }
                    }
                    for (path, problem) in problems {
                        self.err(&path, problem);
                    }
                }
                let tls = link.tls.as_ref().map(|tls| {
                    self.tls_files(folder, tls, &[K("node"), I(n), K("link"), I(l), K("tls")])
                });
                if let (Some(target), Some(list)) = (target, built.get_mut(n)) {
                    list.push(LinkConfig {
                        tls,
                        name: link.name.clone(),
                        target,
                        common_address: common,
                        interrogate_on_start: link.interrogate_on_start,
                        clock_sync: link.clock_sync,
                        status_point: link.status_point.clone(),
                        republish: None,
                    });
                }
            }
        }
        for (node, links) in nodes.iter_mut().zip(built) {
            node.links = links;
        }
        let cycles_before = self.errors.len();
        self.check_cycles(raw, &edges);
        if self.errors.len() == cycles_before {
            self.expand_republish(raw, nodes, &edges);
        }
    }

    /// Adds the points and commands of `republish` links, lower nodes first (the link
    /// graph is known to be acyclic here), so that republishing is transitive.
    pub(in crate::config) fn expand_republish(
        &mut self,
        raw: &RawProject,
        nodes: &mut [NodeConfig],
        edges: &[Vec<(usize, usize)>],
    ) {
        fn visit(
            n: usize,
            edges: &[Vec<(usize, usize)>],
            done: &mut [bool],
            order: &mut Vec<usize>,
        ) {
            if done.get(n).copied().unwrap_or(true) {
                return;
            }
            if let Some(flag) = done.get_mut(n) {
                *flag = true;
            }
            for &(t, _) in edges.get(n).map(Vec::as_slice).unwrap_or_default() {
                visit(t, edges, done, order);
            }
            order.push(n);
        }
        let mut done = vec![false; raw.node.len()];
        let mut order = Vec::new();
        for n in 0..raw.node.len() {
            visit(n, edges, &mut done, &mut order);
        }
        for n in order {
            let Some(raw_node) = raw.node.get(n) else {
                continue;
            };
            for &(t, l) in edges.get(n).map(Vec::as_slice).unwrap_or_default() {
                let Some(raw_link) = raw_node.link.get(l) else {
                    continue;
                };
                let Some(republish) = &raw_link.republish else {
                    continue;
                };
                let at = vec![K("node"), I(n), K("link"), I(l), K("republish")];
                let offset = match u32::try_from(republish.ioa_offset) {
                    Ok(offset) if offset <= Ioa::MAX.get() => offset,
                    _ => {
                        self.err(
                            &at,
                            ConfigProblem::OutOfRange {
                                what: "ioa_offset",
                                value: republish.ioa_offset,
                                min: 0,
                                max: Some(Ioa::MAX.get().into()),
                            },
                        );
                        continue;
                    }
                };
                let Some(lower) = nodes.get(t).cloned() else {
                    continue;
                };
                let Some(this) = nodes.get_mut(n) else {
                    continue;
                };
                let mut names: HashSet<String> =
                    this.points.iter().map(|p| p.name.clone()).collect();
                let mut ioas: HashSet<u32> = this.points.iter().map(|p| p.ioa.get()).collect();
                // Points and commands share one address space at the controlling station.
                ioas.extend(this.commands.iter().map(|c| c.ioa.get()));
                let mut problems = Vec::new();
                for point in &lower.points {
                    let ioa = shifted(point.ioa, offset);
                    let Some(ioa) = ioa else {
                        problems.push(RepublishClash::PastLargestIoa {
                            object: Object::Point,
                            name: point.name.clone(),
                            ioa: point.ioa,
                            offset,
                        });
                        continue;
                    };
                    if !names.insert(point.name.clone()) {
                        problems.push(RepublishClash::PointName {
                            name: point.name.clone(),
                            lower: lower.name.clone(),
                            upper: this.name.clone(),
                        });
                        continue;
                    }
                    if !ioas.insert(ioa.get()) {
                        problems.push(RepublishClash::PointIoa {
                            name: point.name.clone(),
                            lower: lower.name.clone(),
                            ioa,
                            upper: this.name.clone(),
                        });
                        continue;
                    }
                    this.points.push(PointConfig {
                        name: point.name.clone(),
                        point_type: point.point_type,
                        ioa,
                        source: PointSource::Link {
                            link: raw_link.name.clone(),
                            ioa: point.ioa.get(),
                        },
                        transmission: Transmission::Spontaneous,
                        groups: point.groups.clone(),
                        deadband: None,
                        invalid_when: None,
                        scaling: point.scaling,
                        storage: point.storage,
                        description: point.description.clone(),
                    });
                }
                let mut command_names: HashSet<String> =
                    this.commands.iter().map(|c| c.name.clone()).collect();
                let mut command_ioas: HashSet<u32> =
                    this.commands.iter().map(|c| c.ioa.get()).collect();
                for command in &lower.commands {
                    let ioa = shifted(command.ioa, offset);
                    let Some(ioa) = ioa else {
                        problems.push(RepublishClash::PastLargestIoa {
                            object: Object::Command,
                            name: command.name.clone(),
                            ioa: command.ioa,
                            offset,
                        });
                        continue;
                    };
                    if ioas.contains(&ioa.get()) && !command_ioas.contains(&ioa.get()) {
                        problems.push(RepublishClash::CommandOnPoint {
                            name: command.name.clone(),
                            lower: lower.name.clone(),
                            ioa,
                            upper: this.name.clone(),
                        });
                        continue;
                    }
                    if !command_names.insert(command.name.clone())
                        || !command_ioas.insert(ioa.get())
                    {
                        problems.push(RepublishClash::Command {
                            name: command.name.clone(),
                            lower: lower.name.clone(),
                            ioa,
                            upper: this.name.clone(),
                        });
                        continue;
                    }
                    this.commands.push(CommandConfig {
                        name: command.name.clone(),
                        type_id: command.type_id,
                        ioa,
                        target: CommandTarget::Link {
                            link: raw_link.name.clone(),
                            ioa: command.ioa,
                        },
                        select_required: command.select_required,
                        remote_enable: None,
                        pulse: None,
                        from_groups: Vec::new(),
                        max_age: command.max_age,
                        feedback: None,
                        range: command.range.clone(),
                        description: command.description.clone(),
                    });
                }
                if let Some(link) = this.links.iter_mut().find(|x| x.name == raw_link.name) {
                    link.republish = Some(offset);
                }
                for problem in problems {
                    self.err(&at, problem);
                }
            }
        }
    }

    /// Reports each back edge of a depth-first search of the link graph.
    pub(in crate::config) fn check_cycles(
        &mut self,
        raw: &RawProject,
        edges: &[Vec<(usize, usize)>],
    ) {
        #[derive(Clone, Copy, PartialEq)]
        enum Mark {
            New,
            Open,
            Done,
        }
        let count = edges.len();
        let mut marks = vec![Mark::New; count];
        let name = |i: usize| raw.node.get(i).map_or("?", |n| n.name.as_str());
        for start in 0..count {
            if marks.get(start) != Some(&Mark::New) {
                continue;
            }
            // iterative DFS: stack of (node, next edge index)
            let mut stack: Vec<(usize, usize)> = vec![(start, 0)];
            if let Some(m) = marks.get_mut(start) {
                *m = Mark::Open;
            }
            while let Some(&mut (node, ref mut next)) = stack.last_mut() {
                let edge = edges.get(node).and_then(|e| e.get(*next)).copied();
                *next += 1;
                match edge {
                    None => {
                        if let Some(m) = marks.get_mut(node) {
                            *m = Mark::Done;
                        }
                        stack.pop();
                    }
                    Some((target, link)) => match marks.get(target) {
                        Some(Mark::New) => {
                            if let Some(m) = marks.get_mut(target) {
                                *m = Mark::Open;
                            }
                            stack.push((target, 0));
                        }
                        Some(Mark::Open) => {
                            let from = stack.iter().position(|(n, _)| *n == target).unwrap_or(0);
                            let mut cycle: Vec<String> = stack
                                .get(from..)
                                .unwrap_or(&[])
                                .iter()
                                .map(|(n, _)| name(*n).to_owned())
                                .collect();
                            cycle.push(name(target).to_owned());
                            self.err(
                                &[K("node"), I(node), K("link"), I(link), K("node")],
                                ConfigProblem::Cycle { nodes: cycle },
                            );
                        }
                        _ => {}
                    },
                }
            }
        }
    }
}
