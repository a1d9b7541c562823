//! The checks of a node's IEC 104 server (`[node.server]`): its port offset, allowed
//! clients, redundancy groups and mode, TLS files and command age. (Port offsets unique
//! across the project are checked with the station, in `check`.)

use super::*;

impl Ctx<'_> {
    /// Checks the server `s` of node `n` (`raw`).
    pub(in crate::config) fn check_server(
        &mut self,
        folder: &Path,
        n: usize,
        raw: &RawNode,
        s: &RawServer,
    ) -> ServerConfig {
        let port_offset = u16::try_from(s.port_offset).unwrap_or_else(|_| {
            self.err(
                &node_path(n, &[K("server"), K("port_offset")]),
                ConfigProblem::OutOfRange {
                    what: "port_offset",
                    value: s.port_offset,
                    min: 0,
                    max: Some(u16::MAX.into()),
                },
            );
            0
        });
        let allowed_clients = self.ips(
            &s.allowed_clients,
            &node_path(n, &[K("server"), K("allowed_clients")]),
        );
        let redundancy_groups = self.redundancy_groups(n, raw, s);
        let tls = s
            .tls
            .as_ref()
            .map(|t| self.tls_files(folder, t, &node_path(n, &[K("server"), K("tls")])));
        let redundancy = self.redundancy_mode(n, s, &redundancy_groups);
        let max_command_age = self.max_command_age(n, s);
        let event_buffer = self.event_buffer(n, s);
        ServerConfig {
            port_offset,
            allowed_clients,
            redundancy_groups,
            tls,
            redundancy,
            max_command_age,
            event_buffer,
        }
    }

    /// The events kept per redundancy group (`event_buffer`, 1..=[`MAX_EVENT_BUFFER`]).
    fn event_buffer(&mut self, n: usize, s: &RawServer) -> usize {
        let Some(events) = s.event_buffer else {
            return DEFAULT_EVENT_BUFFER;
        };
        match usize::try_from(events) {
            Ok(events) if (1..=MAX_EVENT_BUFFER).contains(&events) => events,
            _ => {
                self.err(
                    &node_path(n, &[K("server"), K("event_buffer")]),
                    ConfigProblem::OutOfRange {
                        what: "event_buffer",
                        value: events,
                        min: 1,
                        max: Some(MAX_EVENT_BUFFER as i64),
                    },
                );
                DEFAULT_EVENT_BUFFER
            }
        }
    }

    /// The server's redundancy groups: one catch-all group `default` when the project
    /// names none.
    fn redundancy_groups(
        &mut self,
        n: usize,
        raw: &RawNode,
        s: &RawServer,
    ) -> Vec<RedundancyGroup> {
        let Some(groups) = &s.redundancy_groups else {
            return vec![RedundancyGroup {
                name: "default".to_owned(),
                clients: Vec::new(),
                refuse_commands_when: None,
                status_point: None,
            }];
        };
        let mut out = Vec::new();
        if groups.is_empty() {
            self.err(
                &node_path(n, &[K("server"), K("redundancy_groups")]),
                ConfigProblem::Missing {
                    what: "redundancy group",
                    needed_by: "",
                    hint: "at least one is needed; leave redundancy_groups out for one catch-all group",
                },
            );
        }
        let mut names = HashSet::new();
        for (g, group) in groups.iter().enumerate() {
            if !names.insert(group.name.clone()) {
                self.err(
                    &node_path(n, &[K("server"), K("redundancy_groups"), I(g), K("name")]),
                    ConfigProblem::Duplicate {
                        what: Unique::RedundancyGroup,
                        value: group.name.clone(),
                        other: raw.name.clone(),
                    },
                );
            }
            let clients = self.ips(
                &group.clients,
                &node_path(
                    n,
                    &[K("server"), K("redundancy_groups"), I(g), K("clients")],
                ),
            );
            out.push(RedundancyGroup {
                name: group.name.clone(),
                clients,
                refuse_commands_when: group.refuse_commands_when.clone(),
                status_point: group.status_point.clone(),
            });
        }
        out
    }

    /// How the server shares its connections among `groups` (`groups-by-address` unless
    /// the project says otherwise).
    fn redundancy_mode(
        &mut self,
        n: usize,
        s: &RawServer,
        groups: &[RedundancyGroup],
    ) -> iec60870::cs104::server::RedundancyMode {
        let group_configs = groups
            .iter()
            .map(|g| {
                iec60870::cs104::server::RedundancyGroupConfig::new(
                    g.name.clone(),
                    g.clients.clone(),
                )
            })
            .collect();
        let mode_name = s.redundancy.as_deref().unwrap_or("groups-by-address");
        iec60870::cs104::server::RedundancyMode::from_name(mode_name, group_configs).unwrap_or_else(
            || {
                self.err(
                    &node_path(n, &[K("server"), K("redundancy")]),
                    ConfigProblem::UnknownValue {
                        what: Vocabulary::RedundancyMode,
                        value: mode_name.to_owned(),
                    },
                );
                iec60870::cs104::server::RedundancyMode::SingleGroup
            },
        )
    }

    /// The oldest a time-tagged command may be: the default, milliseconds, or `off`.
    fn max_command_age(&mut self, n: usize, s: &RawServer) -> Option<Duration> {
        let age_path = node_path(n, &[K("server"), K("max_command_age_ms")]);
        match &s.max_command_age_ms {
            None => Some(DEFAULT_MAX_COMMAND_AGE),
            Some(RawCommandAge::Millis(ms)) => {
                self.duration_ms(*ms, &age_path, "max_command_age_ms")
            }
            Some(RawCommandAge::Word(word)) if word == "off" => None,
            Some(RawCommandAge::Word(word)) => {
                self.err(
                    &age_path,
                    ConfigProblem::UnknownValue {
                        what: Vocabulary::CommandAge,
                        value: word.clone(),
                    },
                );
                None
            }
        }
    }
}
