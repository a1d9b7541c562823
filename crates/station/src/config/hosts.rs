//! The deployment overlay: where the nodes of a project run (`stanice run PROJECT --node
//! NAME --hosts FILE`).
//!
//! A project says what its nodes are and how they link; on one machine every server
//! listens on the station's `bind` address and the clients the project names are loopback
//! addresses (`127.0.0.1` for the station's own nodes, `127.0.0.2` for its HMI ...). A
//! hosts file says where the same project runs when each node is a host of its own: the
//! address each node's server listens on (and its upper nodes' links connect to), and
//! which addresses of the deployment stand for each client address the project names.
//! The project file stays as it is; one project runs on one machine and on many.
//!
//! ```toml
//! [nodes]                         # node -> the IP address of its host; once one node is
//! RDRT = "10.77.0.10"             # here, every node of the project must be
//! "RH1.1" = "10.77.1.11"          # (ports stay port_base + port_offset)
//!
//! [clients]                       # a client address of the project (allowed_clients,
//! "127.0.0.1" = ["RDRT", "RH1.1"] # redundancy group clients) -> the addresses replacing
//! "127.0.0.2" = ["10.77.0.2"]     # it; a node name stands for its address in [nodes]
//! ```
//!
//! [`HostsFile::load`] reads and checks the file alone (TOML, its two tables, IP
//! addresses); [`Project::with_hosts`] checks it against the project (every node named
//! is a node, every node has an address, every client address is one the project uses)
//! and returns the project with [`NodeConfig::host`] set and the client addresses
//! replaced. Problems are [`ConfigError`]s at `file:line:col` of the hosts file, as those
//! of `station.toml` are; what is wrong is a [`ConfigProblem`], for the overlay's own
//! rules a [`HostsProblem`].

use super::*;

/// What is wrong with a hosts file against its project.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum HostsProblem {
    /// `[nodes]` names some nodes of the project but not these.
    #[error(
        "no address for {}: once [nodes] names one node, it names every node of the project",
        nodes.iter().map(|node| format!("`{node}`")).collect::<Vec<_>>().join(", ")
    )]
    NodesWithoutAddress {
        /// The nodes left out, in project order.
        nodes: Vec<String>,
    },
    /// A `[clients]` key that no server of the project names.
    #[error("no server of the project names the client `{address}` (in allowed_clients or a redundancy group's clients)")]
    UnusedClient {
        /// The address given.
        address: IpAddr,
    },
    /// A `[clients]` replacement that is neither an address nor a node of `[nodes]`.
    #[error("`{text}` is neither an IP address nor a node with an address in [nodes]")]
    NotAddressOrNode {
        /// The text given.
        text: String,
    },
}

/// A hosts file, read and checked on its own; [`Project::with_hosts`] applies it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct HostsFile {
    file: PathBuf,
    text: String,
    /// Where `[nodes]` is (its key), for a node it leaves out.
    nodes_at: Range<usize>,
    nodes: Vec<NodeHost>,
    clients: Vec<ClientHosts>,
}

/// One `[nodes]` entry.
#[derive(Debug, Clone, PartialEq, Eq)]
struct NodeHost {
    node: String,
    address: IpAddr,
    /// The key's place.
    at: Range<usize>,
}

/// One `[clients]` entry.
#[derive(Debug, Clone, PartialEq, Eq)]
struct ClientHosts {
    address: IpAddr,
    at: Range<usize>,
    /// Each replacement as written (an address or a node name) and its place.
    replacements: Vec<(String, Range<usize>)>,
}

/// Problems of one file, kept as [`Ctx`] keeps those of `station.toml`: the first
/// [`MAX_ERRORS_PER_FILE`], the rest counted.
struct Report<'a> {
    file: &'a Path,
    text: &'a str,
    errors: Vec<ConfigError>,
    omitted: usize,
}

impl Report<'_> {
    fn push(&mut self, span: &Range<usize>, key: String, problem: impl Into<ConfigProblem>) {
        if self.errors.len() >= MAX_ERRORS_PER_FILE {
            self.omitted += 1;
            return;
        }
        let (line, column) = line_col(self.text, span.start);
        self.errors.push(ConfigError {
            file: self.file.to_path_buf(),
            line,
            column,
            key,
            problem: problem.into(),
        });
    }

    /// `value`, or the problems in file order.
    fn finish<T>(mut self, value: T) -> Result<T, ConfigErrors> {
        if self.errors.is_empty() {
            return Ok(value);
        }
        self.errors.sort_by_key(|error| (error.line, error.column));
        let omitted = if self.omitted > 0 {
            vec![(self.file.to_path_buf(), self.omitted)]
        } else {
            Vec::new()
        };
        Err(ConfigErrors {
            errors: self.errors,
            omitted,
        })
    }
}

/// `nodes.RDRT`, `nodes."RH1.1"`: a key path as TOML would write it.
fn key_path(table: &str, key: &str) -> String {
    let bare = !key.is_empty()
        && key
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
    if bare {
        format!("{table}.{key}")
    } else {
        format!("{table}.{key:?}")
    }
}

fn schema(detail: String, kind: SchemaKind) -> ConfigProblem {
    ConfigProblem::Schema { kind, detail }
}

/// What a TOML value is, for messages.
fn value_kind(value: &DeValue<'_>) -> &'static str {
    match value {
        DeValue::String(_) => "a string",
        DeValue::Integer(_) => "an integer",
        DeValue::Float(_) => "a float",
        DeValue::Boolean(_) => "a boolean",
        DeValue::Datetime(_) => "a datetime",
        DeValue::Array(_) => "an array",
        DeValue::Table(_) => "a table",
    }
}

impl HostsFile {
    /// Reads and checks the hosts file `file` (TOML, its tables, the addresses).
    pub fn load(file: &Path) -> Result<HostsFile, ConfigErrors> {
        let text = read_config_text(file)?;
        HostsFile::parse(file, &text)
    }

    /// Checks `text` as the hosts file `file`.
    pub fn parse(file: &Path, text: &str) -> Result<HostsFile, ConfigErrors> {
        let mut report = Report {
            file,
            text,
            errors: Vec::new(),
            omitted: 0,
        };
        let tree = match DeTable::parse(text) {
            Ok(tree) => tree,
            Err(error) => {
                let span = error.span().unwrap_or(0..0);
                let detail = error.message().to_owned();
                report.push(&span, String::new(), ConfigProblem::Syntax { detail });
                return report.finish(HostsFile::empty(file, text));
            }
        };
        let mut hosts = HostsFile::empty(file, text);
        for (key, value) in tree.get_ref() {
            let name: &str = key.get_ref();
            match (name, value.get_ref()) {
                ("nodes", DeValue::Table(table)) => {
                    hosts.nodes_at = key.span();
                    hosts.read_nodes(table, &mut report);
                }
                ("clients", DeValue::Table(table)) => hosts.read_clients(table, &mut report),
                (name @ ("nodes" | "clients"), other) => report.push(
                    &value.span(),
                    name.to_owned(),
                    schema(
                        format!("invalid type: {}, expected a table", value_kind(other)),
                        SchemaKind::WrongType,
                    ),
                ),
                (name, _) => report.push(
                    &key.span(),
                    name.to_owned(),
                    schema(
                        format!("unknown field `{name}`, expected `nodes` or `clients`"),
                        SchemaKind::UnknownKey,
                    ),
                ),
            }
        }
        report.finish(hosts)
    }

    fn empty(file: &Path, text: &str) -> HostsFile {
        HostsFile {
            file: file.to_path_buf(),
            text: text.to_owned(),
            nodes_at: 0..0,
            nodes: Vec::new(),
            clients: Vec::new(),
        }
    }

    fn read_nodes(&mut self, table: &DeTable<'_>, report: &mut Report<'_>) {
        for (key, value) in table {
            let node: &str = key.get_ref();
            let path = key_path("nodes", node);
            let DeValue::String(text) = value.get_ref() else {
                report.push(
                    &value.span(),
                    path,
                    schema(
                        format!(
                            "invalid type: {}, expected a string (an IP address)",
                            value_kind(value.get_ref())
                        ),
                        SchemaKind::WrongType,
                    ),
                );
                continue;
            };
            match super::check::parse_ip(text) {
                Ok(address) => self.nodes.push(NodeHost {
                    node: node.to_owned(),
                    address,
                    at: key.span(),
                }),
                Err(problem) => report.push(&value.span(), path, problem),
            }
        }
    }

    fn read_clients(&mut self, table: &DeTable<'_>, report: &mut Report<'_>) {
        for (key, value) in table {
            let text: &str = key.get_ref();
            let path = key_path("clients", text);
            let address = super::check::parse_ip(text).map_err(|problem| {
                report.push(&key.span(), path.clone(), problem);
            });
            let DeValue::Array(items) = value.get_ref() else {
                report.push(
                    &value.span(),
                    path,
                    schema(
                        format!(
                            "invalid type: {}, expected an array of addresses and node names",
                            value_kind(value.get_ref())
                        ),
                        SchemaKind::WrongType,
                    ),
                );
                continue;
            };
            let mut replacements = Vec::new();
            for (i, item) in items.iter().enumerate() {
                match item.get_ref() {
                    DeValue::String(text) => replacements.push((text.to_string(), item.span())),
                    other => report.push(
                        &item.span(),
                        format!("{path}[{i}]"),
                        schema(
                            format!(
                                "invalid type: {}, expected a string (an IP address or a node name)",
                                value_kind(other)
                            ),
                            SchemaKind::WrongType,
                        ),
                    ),
                }
            }
            if let Ok(address) = address {
                self.clients.push(ClientHosts {
                    address,
                    at: key.span(),
                    replacements,
                });
            }
        }
    }

    /// The file it was read from.
    pub fn file(&self) -> &Path {
        &self.file
    }

    /// The address of `node`'s host, if `[nodes]` gives one.
    pub fn address_of(&self, node: &str) -> Option<IpAddr> {
        self.nodes
            .iter()
            .find(|entry| entry.node == node)
            .map(|entry| entry.address)
    }

    /// The nodes and their addresses, in file order.
    pub fn nodes(&self) -> impl Iterator<Item = (&str, IpAddr)> {
        self.nodes
            .iter()
            .map(|entry| (entry.node.as_str(), entry.address))
    }

    /// The addresses replacing the project's client `address` (itself when `[clients]`
    /// does not name it), node names resolved.
    fn clients_for(&self, address: IpAddr) -> Vec<IpAddr> {
        match self.clients.iter().find(|entry| entry.address == address) {
            None => vec![address],
            Some(entry) => entry
                .replacements
                .iter()
                .filter_map(|(text, _)| self.replacement(text))
                .collect(),
        }
    }

    /// A replacement's address: an IP address, or the address of the node it names.
    fn replacement(&self, text: &str) -> Option<IpAddr> {
        super::check::parse_ip(text)
            .ok()
            .or_else(|| self.address_of(text))
    }

    /// `addresses` with every client address replaced, each address once, in order.
    fn replace(&self, addresses: &[IpAddr]) -> Vec<IpAddr> {
        let mut out: Vec<IpAddr> = Vec::new();
        for address in addresses.iter().flat_map(|a| self.clients_for(*a)) {
            if !out.contains(&address) {
                out.push(address);
            }
        }
        out
    }
}

impl Project {
    /// The project deployed as `hosts` says: each node's [`NodeConfig::host`] from
    /// `[nodes]` (its server listens there, links to it connect there), the client
    /// addresses of its servers (allowed clients, redundancy groups) replaced as
    /// `[clients]` says. Every problem of the file against the project is returned, at its
    /// place in the hosts file.
    pub fn with_hosts(mut self, hosts: &HostsFile) -> Result<Project, ConfigErrors> {
        let mut report = Report {
            file: &hosts.file,
            text: &hosts.text,
            errors: Vec::new(),
            omitted: 0,
        };
        for entry in &hosts.nodes {
            if self.node(&entry.node).is_none() {
                report.push(
                    &entry.at,
                    key_path("nodes", &entry.node),
                    ConfigProblem::Unknown {
                        what: Reference::Node,
                        name: entry.node.clone(),
                        within: String::new(),
                    },
                );
            }
        }
        let left_out: Vec<String> = self
            .nodes
            .iter()
            .filter(|node| hosts.address_of(&node.name).is_none())
            .map(|node| node.name.clone())
            .collect();
        if !hosts.nodes.is_empty() && !left_out.is_empty() {
            report.push(
                &hosts.nodes_at,
                "nodes".to_owned(),
                HostsProblem::NodesWithoutAddress { nodes: left_out },
            );
        }
        let named: HashSet<IpAddr> = self
            .nodes
            .iter()
            .filter_map(|node| node.server.as_ref())
            .flat_map(|server| {
                server.allowed_clients.iter().chain(
                    server
                        .redundancy_groups
                        .iter()
                        .flat_map(|group| &group.clients),
                )
            })
            .copied()
            .collect();
        for entry in &hosts.clients {
            let path = key_path("clients", &entry.address.to_string());
            if !named.contains(&entry.address) {
                report.push(
                    &entry.at,
                    path.clone(),
                    HostsProblem::UnusedClient {
                        address: entry.address,
                    },
                );
            }
            for (i, (text, at)) in entry.replacements.iter().enumerate() {
                if hosts.replacement(text).is_none() {
                    report.push(
                        at,
                        format!("{path}[{i}]"),
                        HostsProblem::NotAddressOrNode { text: text.clone() },
                    );
                }
            }
        }
        if !report.errors.is_empty() {
            return report.finish(self);
        }
        for node in &mut self.nodes {
            node.host = hosts.address_of(&node.name);
            let Some(server) = &mut node.server else {
                continue;
            };
            server.allowed_clients = hosts.replace(&server.allowed_clients);
            for group in &mut server.redundancy_groups {
                group.clients = hosts.replace(&group.clients);
            }
            // The server's own copy of the groups (what it admits clients by).
            if let iec60870::cs104::server::RedundancyMode::GroupsByAddress(groups) =
                &mut server.redundancy
            {
                *groups = server
                    .redundancy_groups
                    .iter()
                    .map(|group| {
                        iec60870::cs104::server::RedundancyGroupConfig::new(
                            group.name.clone(),
                            group.clients.clone(),
                        )
                    })
                    .collect();
            }
        }
        Ok(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const PROJECT: &str = r#"
[station]
name = "Two"
time_zone = "UTC"

[[node]]
name = "TOP"
common_address = 1
[node.server]
port_offset = 0
redundancy_groups = [{ name = "hmi", clients = ["127.0.0.2"] }, { name = "dispatch" }]
[[node.link]]
name = "LOW"
node = "LOW.1"

[[node]]
name = "LOW.1"
common_address = 2
[node.server]
port_offset = 1
allowed_clients = ["127.0.0.1"]
"#;

    fn project() -> Project {
        let folder = Path::new(".");
        Project::parse(folder, &folder.join("station.toml"), PROJECT).unwrap()
    }

    fn hosts(text: &str) -> Result<HostsFile, ConfigErrors> {
        HostsFile::parse(Path::new("hosts.toml"), text)
    }

    fn messages(errors: &ConfigErrors) -> Vec<String> {
        errors.errors().iter().map(ToString::to_string).collect()
    }

    #[test]
    fn nodes_get_their_hosts_and_clients_are_replaced() {
        let hosts = hosts(
            r#"
[nodes]
TOP = "10.77.0.10"
"LOW.1" = "10.77.1.11"

[clients]
"127.0.0.1" = ["TOP", "LOW.1", "TOP"]
"127.0.0.2" = ["10.77.0.2", "10.77.0.3"]
"#,
        )
        .unwrap();
        let project = project().with_hosts(&hosts).unwrap();
        let top = project.node("TOP").unwrap();
        let low = project.node("LOW.1").unwrap();
        assert_eq!(
            top.server_address(&project.station),
            Some("10.77.0.10:2404".parse().unwrap())
        );
        let link = top.link("LOW").unwrap();
        assert_eq!(
            project.link_address(link),
            Some("10.77.1.11:2405".parse().unwrap())
        );
        let low_server = low.server.as_ref().unwrap();
        let ip = |text: &str| text.parse::<IpAddr>().unwrap();
        assert_eq!(
            low_server.allowed_clients,
            vec![ip("10.77.0.10"), ip("10.77.1.11")]
        );
        let top_server = top.server.as_ref().unwrap();
        assert_eq!(
            top_server.redundancy_groups[0].clients,
            vec![ip("10.77.0.2"), ip("10.77.0.3")]
        );
        let iec60870::cs104::server::RedundancyMode::GroupsByAddress(groups) =
            &top_server.redundancy
        else {
            panic!("groups by address: {:?}", top_server.redundancy);
        };
        assert_eq!(groups[0].clients, vec![ip("10.77.0.2"), ip("10.77.0.3")]);
        assert!(groups[1].clients.is_empty(), "the catch-all stays");
    }

    #[test]
    fn without_a_hosts_file_nothing_moves() {
        let project = project();
        let top = project.node("TOP").unwrap();
        assert_eq!(top.host, None);
        assert_eq!(
            top.server_address(&project.station),
            Some("127.0.0.1:2404".parse().unwrap())
        );
        // An empty file changes nothing either.
        let same = project.clone().with_hosts(&hosts("").unwrap()).unwrap();
        assert_eq!(same, project);
    }

    #[test]
    fn problems_of_the_file_alone_are_placed() {
        let errors = hosts(
            "[nodes]\nTOP = \"10.77.0.300\"\n\"LOW.1\" = 7\n[clients]\n\"localhost\" = [\"TOP\"]\n\"127.0.0.2\" = \"TOP\"\n[other]\n",
        )
        .unwrap_err();
        assert_eq!(
            messages(&errors),
            [
                "hosts.toml:2:7: error: nodes.TOP: `10.77.0.300` is not an IP address",
                "hosts.toml:3:11: error: nodes.\"LOW.1\": invalid type: an integer, expected a string (an IP address)",
                "hosts.toml:5:1: error: clients.localhost: `localhost` is not an IP address",
                "hosts.toml:6:15: error: clients.\"127.0.0.2\": invalid type: a string, expected an array of addresses and node names",
                "hosts.toml:7:2: error: other: unknown field `other`, expected `nodes` or `clients`",
            ]
        );
        let syntax = hosts("[nodes\nTOP = 1").unwrap_err();
        assert_eq!(syntax.errors().len(), 1);
        assert_eq!(syntax.errors()[0].line, 1);
        assert!(matches!(
            syntax.errors()[0].problem,
            ConfigProblem::Syntax { .. }
        ));
    }

    #[test]
    fn problems_against_the_project_are_placed() {
        let hosts = hosts(
            "[nodes]\nTOP = \"10.77.0.10\"\nRH9 = \"10.77.0.9\"\n\n[clients]\n\"127.0.0.9\" = [\"10.0.0.1\"]\n\"127.0.0.1\" = [\"TOP\", \"LOW.1\", \"nowhere\"]\n",
        )
        .unwrap();
        let errors = project().with_hosts(&hosts).unwrap_err();
        assert_eq!(
            messages(&errors),
            [
                "hosts.toml:1:2: error: nodes: no address for `LOW.1`: once [nodes] names one node, it names every node of the project",
                "hosts.toml:3:1: error: nodes.RH9: no node `RH9` in the project",
                "hosts.toml:6:1: error: clients.\"127.0.0.9\": no server of the project names the client `127.0.0.9` (in allowed_clients or a redundancy group's clients)",
                "hosts.toml:7:23: error: clients.\"127.0.0.1\"[1]: `LOW.1` is neither an IP address nor a node with an address in [nodes]",
                "hosts.toml:7:32: error: clients.\"127.0.0.1\"[2]: `nowhere` is neither an IP address nor a node with an address in [nodes]",
            ]
        );
        assert!(matches!(
            errors.errors()[0].problem,
            ConfigProblem::Hosts(HostsProblem::NodesWithoutAddress { .. })
        ));
    }

    proptest::proptest! {
        /// Whatever text it is given, the parser answers (a file or its problems) and
        /// never panics; a problem is placed inside the text.
        #[test]
        fn any_text_is_answered(text in "[\\[\\]a-zA-Z0-9.=\" \n#,_-]{0,200}") {
            if let Err(errors) = hosts(&text) {
                for error in errors.errors() {
                    proptest::prop_assert!(error.line >= 1);
                    proptest::prop_assert!(error.line <= text.lines().count().max(1) + 1);
                }
            }
        }
    }
}
