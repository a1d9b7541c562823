//! The project folder: `station.toml`, the ST sources it names, and every problem found in
//! them with `file:line:col`.
//!
//! [`Project::load`] reads `FOLDER/station.toml`, checks it and returns the typed model, or
//! [`ConfigErrors`] with *all* problems found. Each [`ConfigError`] names the file, the
//! 1-based line and column (in characters) of the offending value, its key path such as
//! `node[2].point[5].ioa` (array indices are 0-based, in file order) and a message; its
//! `Display` is `file:line:col: error: key: message`. Only the first syntax error is
//! reported, alone (what a recovering parser finds after it mostly follows from it, and
//! nothing else can be checked); a type error (a string where a number belongs, an unknown
//! key, a missing required key) stops before the semantic checks, which then all run. At
//! most [`MAX_ERRORS_PER_FILE`] problems are kept per file, the rest counted
//! ([`ConfigErrors::omitted`]).
//!
//! # Format
//!
//! ```toml
//! [station]
//! name = "Vsetín"
//! time_zone = "Europe/Prague"          # IANA name
//! store = "sqlite:events.sqlite"       # default; relative paths resolve against the project
//!                                      # folder; "sqlite::memory:" and postgres://... allowed
//! retention_days = 60                  # default 60, >= 1
//! port_base = 2404                     # default 2404; a node's server port = port_base + port_offset
//! bind = "127.0.0.1"                   # default; the address every node's server listens on
//! plant = "vsetin"                     # optional: which plant simulation drives the I/O
//!
//! [[node]]
//! name = "RH1.1"                       # unique
//! description = "main board concentrator (S7-1500)"   # optional
//! common_address = 11                  # 1..=65534
//! sources = ["plc/rh2_logic.st"]       # ST files relative to the project; must exist
//!
//! [node.server]                        # optional: the node's IEC 104 server
//! port_offset = 7                      # unique among the nodes
//! allowed_clients = ["127.0.0.1"]      # default: any
//! redundancy_groups = [ { name = "dispatch-A", clients = ["127.0.0.1"] } ]
//!                                      # default: one catch-all group "default";
//!                                      # a group without clients is a catch-all;
//!                                      # refuse_commands_when = "BOOL variable": the
//!                                      # group's commands are refused while it is TRUE;
//!                                      # status_point = "COMM_HMI": a point TRUE while no
//!                                      # client of the group is connected
//! tls = { certificate = "tls/rh11.pem", private_key = "tls/rh11.key", trust_anchors = "tls/ca.pem" }
//!                                      # optional; the files must exist
//! redundancy = "groups-by-address"     # default; how clients share data: "single-group"
//!                                      # (one started connection for all clients),
//!                                      # "connection-is-group" (each connection its own
//!                                      # buffer: independent masters), "groups-by-address"
//!                                      # (the redundancy_groups); in the first two the
//!                                      # groups only classify clients for authority and
//!                                      # status points
//! max_command_age_ms = 10000           # optional: time-tagged commands older (or further
//!                                      # in the future) than this are refused
//!
//! [[node.task]]
//! name = "fast"
//! interval_ms = 50                     # >= 1
//! priority = 1                         # 0..=255, default 0
//! programs = ["RH2Logic"]              # PROGRAM names declared in the node's sources
//! watchdog_ms = 200                    # optional
//!
//! [node.set]                           # optional: PLC values written after the cold start
//! "LightingBoard.Zpozdeni" = "T#2s"    # variable path = IEC literal
//!
//! [[node.table]]                       # optional: a CSV file loaded into PLC arrays
//! file = "calendar/vsetin-weekly.csv"  # header row; `#` lines are comments
//! index = "week"                       # the column with each row's array index
//! columns = { off_utc = "LightingBoard.Osvetleni.sunrise_data" }   # cell -> path[index];
//!                                      # HH:MM[:SS] cells become TOD#HH:MM:SS literals
//!
//! [[node.io]]                          # plant signal <-> PLC variable; the pseudo-signal
//! signal = "RH2_P1_SA1_Dalkove"         # "module-fault:MODULE" is TRUE while that I/O
//!                                      # module is pulled or unreachable
//! variable = "RH2Logic.SA1_Dalkove"
//!
//! [[node.point]]
//! name = "RH2_V1_FA1_Zapnut"           # unique per node
//! type = "M_SP_TB_1"                   # a monitor-direction type (1..=40)
//! ioa = 281                            # 1..=16_777_215, unique per node among points
//! source = "RH2Logic.FA1_Zapnut"       # a PLC variable path, or "link:LINK/IOA": the point
//!                                      # IOA of the node behind the link LINK of this node;
//!                                      # omitted for a link's status_point (M_SP_NA_1 or
//!                                      # M_SP_TB_1, TRUE = link down)
//! transmission = "spontaneous"         # spontaneous (default) | cyclic | interrogation-only
//! cycle_ms = 1000                      # required with (and only with) cyclic
//! groups = [1, 3]                      # interrogation groups 1..=16; default none
//! deadband = 0.5                       # measurements (M_ME_*) only; absolute, >= 0
//! invalid_when = "RDRTIO.PoruchaModul9" # optional BOOL variable: TRUE sends the point IV
//! description = "breaker FA1 closed"   # optional
//!
//! [[node.command]]
//! name = "RH2_VypnoutQF1"              # unique per node
//! type = "C_SC_NA_1"                   # a command type (45..=64)
//! ioa = 2021                           # unique per node among commands
//! target = "RH2Logic.Cmd_VypnoutQF1"   # a PLC variable, or "link:LINK/IOA" to forward it down
//! select_required = false              # default false
//! remote_enable = "RH2Logic.SA1_Dalkove"   # optional BOOL variable; FALSE (local mode):
//!                                          # remote commands are refused
//! pulse_ms = 500                       # optional, single/double commands on a variable:
//!                                      # reset to FALSE after this time
//! from_groups = ["hmi"]                # optional: only clients of these redundancy groups
//! max_age_ms = 5000                    # optional: this command's own maximum command delay
//! range = [0, 1439]                    # optional, set-points: values outside are refused
//!                                      # (negative ACT_CON, audited), never clamped
//! feedback = "RH2_QF1_Position"        # optional, commands on a PLC variable: the point of
//!                                      # this node that returns the command's effect; its
//!                                      # first change after an execute is sent as return
//!                                      # information (cause 11) between ACT_CON and ACT_TERM
//! feedback_timeout_ms = 5000           # default 5000: ACT_TERM without return information
//!                                      # after this long (wall-clock time)
//! description = "open QF1"             # optional
//!
//! [[node.link]]                        # IEC 104 client link to a lower node
//! name = "RH2"                         # unique per node
//! node = "RH2"                         # a node of this project with a [node.server], or:
//! # address = "192.0.2.10:2404"        # exactly one of node/address
//! common_address = 21                  # default: the target node's (required with address)
//! interrogate_on_start = true          # default true
//! clock_sync = true                    # default true: this node is the lower one's time source
//! status_point = "COMM_RH2"            # optional: a point of this node showing the link state
//! tls = { certificate = "tls/rh11.pem", private_key = "tls/rh11.key", trust_anchors = "tls/ca.pem" }
//!                                      # optional, required when the lower node's server has
//!                                      # tls: mutual authentication on the link
//! republish = { ioa_offset = 1000 }    # optional, links to project nodes: every point and
//!                                      # command of the lower node (its republished ones
//!                                      # too) appears here, same name, IOA + ioa_offset
//!                                      # (default 0), as a concentrator maps a whole
//!                                      # outstation; explicit points may stand beside them
//! ```
//!
//! # Checks
//!
//! Besides syntax and types: duplicate node, task, point, command and link names; duplicate
//! IOAs within a node (a command may not share an IOA with a point either: most
//! controlling stations keep one information object per address); IOA 0 or above 16 777 215; common
//! address 0 or 65535; point types that are not monitor types and command types that are
//! not commands; `link:` sources and targets that are malformed, name no link of the node,
//! or (for a link to a project node) an IOA the lower node does not serve as a point
//! (sources) or command (targets); links naming an unknown node, the node itself, a node
//! without a server, or both/neither of `node` and `address`; cycles in the link graph; two
//! servers with the same `port_offset` or a port past 65535; `cyclic` without `cycle_ms`;
//! a deadband on a non-measurement type; interrogation groups outside 1..=16; missing ST
//! sources and TLS files; task programs not declared as `PROGRAM` in the node's sources
//! (a textual check, case-insensitive; the PLC compiler checks the rest); a status point
//! naming no point of the node, a status point that is not a single point or has a
//! `source`, a point without `source` that no link names; unknown time zones; `retention_days = 0`; unparsable IP
//! and socket addresses; unsupported store URLs. ST sources must be UTF-8 (a leading
//! byte-order mark is accepted); a file that is not is reported at its first invalid byte.
//!
//! With the `runtime` feature (the default) each node's ST sources are also compiled as
//! the runtime will compile them: compile errors are reported at their place in the ST
//! file, and every PLC variable the node names (point `source` and `invalid_when`,
//! command `target` and `remote_enable`, `io` `variable`, `refuse_commands_when`) must
//! exist, or is reported at its value in station.toml.
//!
//! Positions come from the spans of `toml`'s own parse tree ([`toml::de::DeTable`]): the
//! semantic checks look a key path up in it, and a serde error's byte span is mapped back
//! to the innermost key path containing it.
//!
//! Problems without a position (`station.toml` missing or unreadable) carry line and
//! column 0 and are shown as `file: error: message`.

use std::collections::{HashMap, HashSet};
use std::fmt;
use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::time::Duration;

use iec60870::asdu::{CommonAddress, Ioa, TypeId};
use serde::Deserialize;
use toml::de::{DeTable, DeValue};
use toml::Spanned;

/// The name of the project file inside a project folder.
pub const PROJECT_FILE: &str = "station.toml";

/// A loaded and checked project.
#[derive(Debug, Clone, PartialEq)]
pub struct Project {
    /// The project folder (as given to [`Project::load`]).
    pub folder: PathBuf,
    /// The `[station]` table.
    pub station: StationSettings,
    /// The `[[node]]` tables, in file order.
    pub nodes: Vec<NodeConfig>,
}

/// Station-wide settings, the `[station]` table.
#[derive(Debug, Clone, PartialEq)]
pub struct StationSettings {
    /// The station's name.
    pub name: String,
    /// The local time zone (PLC clocks, DST).
    pub time_zone: chrono_tz::Tz,
    /// The event store URL, with a relative SQLite path resolved against the project folder.
    pub store: String,
    /// How long events are kept, in days (>= 1).
    pub retention_days: u32,
    /// The port of a node's server is `port_base + port_offset`.
    pub port_base: u16,
    /// The address the nodes' servers listen on.
    pub bind: IpAddr,
    /// The plant simulation that drives the I/O, if any.
    pub plant: Option<String>,
}

/// A node (controller), one `[[node]]` table.
#[derive(Debug, Clone, PartialEq)]
pub struct NodeConfig {
    /// Unique name.
    pub name: String,
    /// Free text.
    pub description: String,
    /// The node's common address of ASDU (1..=65534).
    pub common_address: CommonAddress,
    /// ST source files, resolved against the project folder.
    pub sources: Vec<PathBuf>,
    /// The node's IEC 104 server, if it has one.
    pub server: Option<ServerConfig>,
    /// PLC tasks.
    pub tasks: Vec<TaskConfig>,
    /// Plant signal <-> PLC variable bindings.
    pub io: Vec<IoBinding>,
    /// Monitor-direction data points the node serves.
    pub points: Vec<PointConfig>,
    /// Commands the node accepts.
    pub commands: Vec<CommandConfig>,
    /// IEC 104 client links to lower nodes.
    pub links: Vec<LinkConfig>,
    /// Values written into the PLC after its cold start (variable path -> IEC literal):
    /// parameters such as a board's switch-on delay.
    pub initial_values: Vec<(String, String)>,
    /// Data tables loaded into PLC arrays after the cold start.
    pub tables: Vec<TableConfig>,
}

/// A CSV file loaded into PLC arrays, `[[node.table]]`: the lighting calendar is data, not
/// code (spec 4.4).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TableConfig {
    /// The CSV file (a header row; lines starting with `#` are comments).
    pub file: PathBuf,
    /// The column holding each row's array index.
    pub index: String,
    /// Column name -> array variable path; cell `v` of row `i` goes to `path[i]`.
    pub columns: Vec<(String, String)>,
}

/// A node's IEC 104 server, `[node.server]`.
#[derive(Debug, Clone, PartialEq)]
pub struct ServerConfig {
    /// Added to the station's `port_base`.
    pub port_offset: u16,
    /// Clients allowed to connect; empty means any.
    pub allowed_clients: Vec<IpAddr>,
    /// Redundancy groups (at least one).
    pub redundancy_groups: Vec<RedundancyGroup>,
    /// TLS files, resolved against the project folder.
    pub tls: Option<TlsFiles>,
    /// How clients form redundancy groups (`redundancy`); `GroupsByAddress` carries the
    /// groups' addresses.
    pub redundancy: iec60870::cs104::server::RedundancyMode,
    /// The maximum command delay of time-tagged commands (`max_command_age_ms`).
    pub max_command_age: Option<Duration>,
}

/// A redundancy group of a server: the connections of its clients share one event buffer.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RedundancyGroup {
    /// The group's name.
    pub name: String,
    /// Client addresses of the group; empty means a catch-all group.
    pub clients: Vec<IpAddr>,
    /// A BOOL variable of the node: while TRUE, commands from this group's clients are
    /// refused (the TC700's per-link command permission, e.g. dispatch commands blocked
    /// while the local HMI has control, spec 7.5).
    pub refuse_commands_when: Option<String>,
    /// A single point of the node: TRUE while no client of this group is connected (the
    /// TC700's link-failure points 38-41 of its upper links, spec 7.3).
    pub status_point: Option<String>,
}

/// TLS certificate, key and trust anchors (PEM files) of one end of a link.
pub use iec60870::cs104::tls::TlsFiles;

/// A PLC task, `[[node.task]]`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TaskConfig {
    /// Unique per node.
    pub name: String,
    /// Cycle interval (> 0).
    pub interval: Duration,
    /// Priority, 0 highest.
    pub priority: u8,
    /// PROGRAM type names run by the task, in order.
    pub programs: Vec<String>,
    /// Watchdog time, if any.
    pub watchdog: Option<Duration>,
}

/// A plant signal bound to a PLC variable, `[[node.io]]`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct IoBinding {
    /// The plant signal's name.
    pub signal: String,
    /// The PLC variable path, e.g. `RH2Logic.SA1_Dalkove`.
    pub variable: String,
}

/// Where a point's value comes from.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum PointSource {
    /// A PLC variable path of the node.
    Variable(String),
    /// Point `ioa` received over the node's client link `link`.
    Link {
        /// The link's name.
        link: String,
        /// The IOA on the lower node.
        ioa: Ioa,
    },
    /// The state of the node's client link with this name (TRUE = link down), for a point
    /// named by the link's `status_point`; such a point has no `source`.
    LinkStatus(String),
    /// Whether a controlling station of the server's redundancy group with this name is
    /// connected (TRUE = none is), for a point named by the group's `status_point`.
    ClientStatus(String),
}

/// Where a command goes.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum CommandTarget {
    /// A PLC variable path of the node, written when the command arrives.
    Variable(String),
    /// Forwarded down the node's client link `link` as command `ioa`.
    Link {
        /// The link's name.
        link: String,
        /// The IOA on the lower node.
        ioa: Ioa,
    },
}

/// How a point is transmitted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Transmission {
    /// On every change (COT 3), the default.
    #[default]
    Spontaneous,
    /// Periodically (COT 1).
    Cyclic {
        /// The period.
        period: Duration,
    },
    /// Only in interrogation responses.
    InterrogationOnly,
}

/// A monitor-direction data point, `[[node.point]]`.
#[derive(Debug, Clone, PartialEq)]
pub struct PointConfig {
    /// Unique per node.
    pub name: String,
    /// A monitor type ([`TypeId::is_monitor`]).
    pub type_id: TypeId,
    /// Unique per node among points.
    pub ioa: Ioa,
    /// Where the value comes from.
    pub source: PointSource,
    /// How it is sent.
    pub transmission: Transmission,
    /// Interrogation groups 1..=16.
    pub groups: Vec<u8>,
    /// Absolute deadband (measurements only).
    pub deadband: Option<f64>,
    /// A BOOL PLC variable: while TRUE the point is sent invalid (IV), as the TC700 does
    /// for the points of a faulty I/O module (spec 7.2).
    pub invalid_when: Option<String>,
    /// Free text.
    pub description: String,
}

/// A command, `[[node.command]]`.
#[derive(Debug, Clone, PartialEq)]
pub struct CommandConfig {
    /// Unique per node.
    pub name: String,
    /// A command type ([`TypeId::is_command`]).
    pub type_id: TypeId,
    /// Unique per node among commands.
    pub ioa: Ioa,
    /// Where it goes.
    pub target: CommandTarget,
    /// Whether select-before-operate is required.
    pub select_required: bool,
    /// A BOOL variable; while FALSE (local mode) remote commands are refused.
    pub remote_enable: Option<String>,
    /// For single and double commands on a PLC variable: the value is held this long and
    /// then reset (FALSE), like a relay output pulse. Without it the value persists
    /// until the next command. A command's QU (short/long pulse, persistent) is honoured
    /// as well: QU 1 and 2 pulse for this time (500 ms when not set), QU 3 persists.
    pub pulse: Option<Duration>,
    /// Only clients of these redundancy groups may send it (empty: any client), as the
    /// TC700 accepts its HMI-local command only over the HMI link (spec 7.4).
    pub from_groups: Vec<String>,
    /// Its own maximum command delay for time-tagged commands (`max_age_ms`), instead of
    /// the server's.
    pub max_age: Option<Duration>,
    /// The point that returns the command's effect, and how long an execute waits for it
    /// before it is terminated without (`feedback`, `feedback_timeout_ms`).
    pub feedback: Option<Feedback>,
    /// The values a set-point may take (`range`, inclusive; in engineering units: the
    /// scaled value, the normalized fraction, the float).
    pub range: Option<std::ops::RangeInclusive<f64>>,
    /// Free text.
    pub description: String,
}

/// The return information of a command: a point of the node and the wait for it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Feedback {
    /// The point's name.
    pub point: String,
    /// How long an execute waits for the point to change.
    pub timeout: Duration,
}

/// How long an execute waits for its return information when the project sets no
/// `feedback_timeout_ms`.
pub const DEFAULT_FEEDBACK_TIMEOUT: Duration = Duration::from_secs(5);

/// The other end of a client link.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum LinkTarget {
    /// A node of this project (its address follows from its server's port).
    Node(String),
    /// An explicit address.
    Address(SocketAddr),
}

/// An IEC 104 client link to a lower node, `[[node.link]]`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LinkConfig {
    /// Unique per node; `link:NAME/IOA` sources refer to it.
    pub name: String,
    /// Whom it connects to.
    pub target: LinkTarget,
    /// The lower node's common address.
    pub common_address: CommonAddress,
    /// Send a general interrogation after connecting.
    pub interrogate_on_start: bool,
    /// Synchronise the lower node's clock (this node is its time source).
    pub clock_sync: bool,
    /// A point of this node showing the link's state.
    pub status_point: Option<String>,
    /// Every point and command of the lower node republished here, IOA + this offset.
    pub republish: Option<u32>,
    /// TLS with mutual authentication (IEC 62351-3): this node's certificate and key, and
    /// the authorities the lower node's certificate must chain to. Required exactly when
    /// the lower node's server requires TLS.
    pub tls: Option<TlsFiles>,
}

impl Project {
    /// Reads and checks `folder/station.toml` and the files it names.
    pub fn load(folder: &Path) -> Result<Project, ConfigErrors> {
        let file = folder.join(PROJECT_FILE);
        let bytes = std::fs::read(&file).map_err(|e| {
            ConfigErrors::single(ConfigError::unpositioned(
                &file,
                format!("cannot read: {e}"),
            ))
        })?;
        let text = String::from_utf8(bytes)
            .map_err(|e| ConfigErrors::single(not_utf8(&file, e.as_bytes())))?;
        Project::parse(folder, &file, &text)
    }

    /// Checks `text` as the project file `file` of `folder` (files it names are resolved
    /// against `folder`). [`Project::load`] reads the file and calls this; also useful for editors that check unsaved text.
    pub fn parse(folder: &Path, file: &Path, text: &str) -> Result<Project, ConfigErrors> {
        let (tree, syntax) = DeTable::parse_recoverable(text);
        let mut ctx = Ctx {
            file: file.to_path_buf(),
            text,
            tree,
            errors: Vec::new(),
            omitted: Vec::new(),
        };
        // Only the first syntax error: the parser's recovery after it is a guess, and one
        // unclosed `[` made it report every later line (17,161 errors for the Vsetín file).
        if let Some(error) = syntax.first() {
            let span = error.span().unwrap_or(0..0);
            ctx.push_at(span, String::new(), error.message().to_owned());
            return Err(ctx.into_errors());
        }
        let raw: RawProject = match toml::from_str(text) {
            Ok(raw) => raw,
            Err(error) => {
                let span = error.span().unwrap_or(0..0);
                let key = ctx.key_at(span.start);
                ctx.push_at(span, key, error.message().to_owned());
                return Err(ctx.into_errors());
            }
        };
        let project = ctx.check(folder, raw);
        if ctx.errors.is_empty() {
            Ok(project)
        } else {
            Err(ctx.into_errors())
        }
    }

    /// The node called `name`.
    pub fn node(&self, name: &str) -> Option<&NodeConfig> {
        self.nodes.iter().find(|n| n.name == name)
    }

    /// The top node: the first node with a server that no other node links to (the one
    /// serving the dispatch systems).
    pub fn top_node(&self) -> Option<&NodeConfig> {
        self.nodes.iter().find(|candidate| {
            candidate.server.is_some()
                && !self.nodes.iter().any(|other| {
                    other.links.iter().any(
                        |link| matches!(&link.target, LinkTarget::Node(target) if *target == candidate.name),
                    )
                })
        })
    }

    /// The project with another port base (the CLI's `--port-base`).
    pub fn with_port_base(mut self, port_base: u16) -> Project {
        self.station.port_base = port_base;
        self
    }

    /// The address a link connects to: the target node's server address or the explicit
    /// address. `None` when the target node has no server or its port passes 65535.
    pub fn link_address(&self, link: &LinkConfig) -> Option<SocketAddr> {
        match &link.target {
            LinkTarget::Address(address) => Some(*address),
            LinkTarget::Node(name) => self.node(name)?.server_address(&self.station),
        }
    }
}

impl NodeConfig {
    /// The node's server address, `bind:port_base+port_offset`; `None` without a server or
    /// when the port passes 65535.
    pub fn server_address(&self, station: &StationSettings) -> Option<SocketAddr> {
        let server = self.server.as_ref()?;
        let port = station.port_base.checked_add(server.port_offset)?;
        Some(SocketAddr::new(station.bind, port))
    }

    /// The point called `name`.
    pub fn point(&self, name: &str) -> Option<&PointConfig> {
        self.points.iter().find(|p| p.name == name)
    }

    /// The link called `name`.
    pub fn link(&self, name: &str) -> Option<&LinkConfig> {
        self.links.iter().find(|l| l.name == name)
    }
}

/// One problem in a project.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ConfigError {
    /// The file.
    pub file: PathBuf,
    /// 1-based line; 0 when the problem has no position.
    pub line: usize,
    /// 1-based column in characters; 0 when the problem has no position.
    pub column: usize,
    /// Key path such as `node[2].point[5].ioa`; empty for syntax errors.
    pub key: String,
    /// What is wrong.
    pub message: String,
}

impl ConfigError {
    fn unpositioned(file: &Path, message: String) -> ConfigError {
        ConfigError {
            file: file.to_path_buf(),
            line: 0,
            column: 0,
            key: String::new(),
            message,
        }
    }
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file.display())?;
        if self.line > 0 {
            write!(f, ":{}:{}", self.line, self.column)?;
        }
        f.write_str(": error: ")?;
        if !self.key.is_empty() {
            write!(f, "{}: ", self.key)?;
        }
        f.write_str(&self.message)
    }
}

impl std::error::Error for ConfigError {}

/// A UTF-8 byte-order mark (Windows editors write one); accepted at the start of an ST
/// source, as the PLC compiler accepts it.
const BYTE_ORDER_MARK: &[u8] = b"\xEF\xBB\xBF";

/// The problem with a file that is not UTF-8, at its first invalid byte (line and column
/// in characters, as an editor shows them; after a byte-order mark). The PLC crate has
/// the same rule (`plc::syntax::decode`), but the loader also builds without it.
fn not_utf8(file: &Path, bytes: &[u8]) -> ConfigError {
    let body = bytes.strip_prefix(BYTE_ORDER_MARK).unwrap_or(bytes);
    let valid = std::str::from_utf8(body)
        .err()
        .map_or(body.len(), |e| e.valid_up_to());
    let before = std::str::from_utf8(body.get(..valid).unwrap_or_default()).unwrap_or("");
    let (line, column) = line_col(before, before.len());
    let byte = body.get(valid).copied().unwrap_or(0);
    ConfigError {
        file: file.to_path_buf(),
        line,
        column,
        key: String::new(),
        message: format!("not UTF-8 text: byte 0x{byte:02X} (save the file as UTF-8)"),
    }
}

/// Problems kept per file; later ones are only counted ([`ConfigErrors::omitted`]): past
/// the first few, a list of problems buries the ones that matter.
pub const MAX_ERRORS_PER_FILE: usize = 10;

/// All problems found in a project (at least one), in the order found: at most
/// [`MAX_ERRORS_PER_FILE`] per file, the rest counted.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub struct ConfigErrors {
    errors: Vec<ConfigError>,
    omitted: Vec<(PathBuf, usize)>,
}

impl ConfigErrors {
    fn single(error: ConfigError) -> ConfigErrors {
        ConfigErrors {
            errors: vec![error],
            omitted: Vec::new(),
        }
    }

    /// The problems kept.
    pub fn errors(&self) -> &[ConfigError] {
        &self.errors
    }

    /// The problems kept, by value.
    pub fn into_errors(self) -> Vec<ConfigError> {
        self.errors
    }

    /// Per file, how many problems were found beyond the [`MAX_ERRORS_PER_FILE`] kept.
    pub fn omitted(&self) -> &[(PathBuf, usize)] {
        &self.omitted
    }

    /// Every problem found, kept or omitted.
    pub fn total(&self) -> usize {
        self.errors.len() + self.omitted.iter().map(|(_, n)| n).sum::<usize>()
    }
}

impl fmt::Display for ConfigErrors {
    /// One problem per line, then `file: ... and N more error(s)` per file with more.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, error) in self.errors.iter().enumerate() {
            if i > 0 {
                f.write_str("\n")?;
            }
            write!(f, "{error}")?;
        }
        for (file, count) in &self.omitted {
            write!(f, "\n{}: ... and {count} more error(s)", file.display())?;
        }
        Ok(())
    }
}

// ---------------------------------------------------------------------------------------
// Raw (serde) model

fn yes() -> bool {
    true
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawProject {
    station: RawStation,
    #[serde(default)]
    node: Vec<RawNode>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawStation {
    name: String,
    time_zone: String,
    store: Option<String>,
    retention_days: Option<u32>,
    port_base: Option<u16>,
    bind: Option<String>,
    plant: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawNode {
    name: String,
    #[serde(default)]
    description: String,
    common_address: i64,
    #[serde(default)]
    sources: Vec<String>,
    server: Option<RawServer>,
    #[serde(default)]
    task: Vec<RawTask>,
    #[serde(default)]
    io: Vec<RawIo>,
    #[serde(default)]
    point: Vec<RawPoint>,
    #[serde(default)]
    command: Vec<RawCommand>,
    #[serde(default)]
    link: Vec<RawLink>,
    #[serde(default)]
    set: std::collections::BTreeMap<String, String>,
    #[serde(default)]
    table: Vec<RawTable>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTable {
    file: String,
    index: String,
    columns: std::collections::BTreeMap<String, String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawServer {
    port_offset: i64,
    #[serde(default)]
    allowed_clients: Vec<String>,
    redundancy_groups: Option<Vec<RawGroup>>,
    tls: Option<RawTls>,
    redundancy: Option<String>,
    max_command_age_ms: Option<i64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawGroup {
    name: String,
    #[serde(default)]
    clients: Vec<String>,
    refuse_commands_when: Option<String>,
    status_point: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTls {
    certificate: String,
    private_key: String,
    trust_anchors: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTask {
    name: String,
    interval_ms: u64,
    #[serde(default)]
    priority: u8,
    #[serde(default)]
    programs: Vec<String>,
    watchdog_ms: Option<u64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawIo {
    signal: String,
    variable: String,
}

#[derive(Deserialize, Default, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
enum RawTransmission {
    #[default]
    Spontaneous,
    Cyclic,
    InterrogationOnly,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawPoint {
    name: String,
    #[serde(rename = "type")]
    type_id: String,
    ioa: i64,
    source: Option<String>,
    #[serde(default)]
    transmission: RawTransmission,
    cycle_ms: Option<u64>,
    #[serde(default)]
    groups: Vec<i64>,
    deadband: Option<f64>,
    invalid_when: Option<String>,
    #[serde(default)]
    description: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCommand {
    name: String,
    #[serde(rename = "type")]
    type_id: String,
    ioa: i64,
    target: String,
    #[serde(default)]
    select_required: bool,
    remote_enable: Option<String>,
    pulse_ms: Option<i64>,
    max_age_ms: Option<i64>,
    range: Option<[f64; 2]>,
    feedback: Option<String>,
    feedback_timeout_ms: Option<i64>,
    #[serde(default)]
    from_groups: Vec<String>,
    #[serde(default)]
    description: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawLink {
    name: String,
    node: Option<String>,
    address: Option<String>,
    common_address: Option<i64>,
    #[serde(default = "yes")]
    interrogate_on_start: bool,
    #[serde(default = "yes")]
    clock_sync: bool,
    status_point: Option<String>,
    republish: Option<RawRepublish>,
    tls: Option<RawTls>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRepublish {
    #[serde(default)]
    ioa_offset: i64,
}

// ---------------------------------------------------------------------------------------
// Key paths and positions

/// One step of a key path.
#[derive(Clone, Copy)]
enum Seg {
    Key(&'static str),
    Index(usize),
}

use Seg::{Index as I, Key as K};

fn key_string(path: &[Seg]) -> String {
    let mut out = String::new();
    for seg in path {
        match seg {
            Seg::Key(key) => {
                if !out.is_empty() {
                    out.push('.');
                }
                out.push_str(key);
            }
            Seg::Index(index) => out.push_str(&format!("[{index}]")),
        }
    }
    out
}

struct Ctx<'a> {
    file: PathBuf,
    text: &'a str,
    tree: Spanned<DeTable<'a>>,
    errors: Vec<ConfigError>,
    /// Problems past [`MAX_ERRORS_PER_FILE`], per file.
    omitted: Vec<(PathBuf, usize)>,
}

/// 1-based line and column (in characters) of a byte offset.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let mut offset = offset.min(text.len());
    while offset > 0 && !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = text.get(..offset).unwrap_or("");
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let column = before.get(line_start..).unwrap_or("").chars().count() + 1;
    (line, column)
}

fn table_get<'t, 'i>(table: &'t DeTable<'i>, key: &str) -> Option<&'t Spanned<DeValue<'i>>> {
    table
        .iter()
        .find(|(k, _)| k.get_ref().as_ref() == key)
        .map(|(_, v)| v)
}

impl Ctx<'_> {
    fn push_at(&mut self, span: Range<usize>, key: String, message: String) {
        let (line, column) = line_col(self.text, span.start);
        self.push(ConfigError {
            file: self.file.clone(),
            line,
            column,
            key,
            message,
        });
    }

    /// Keeps `error` unless its file has [`MAX_ERRORS_PER_FILE`] already; then counts it.
    fn push(&mut self, error: ConfigError) {
        let kept = self.errors.iter().filter(|e| e.file == error.file).count();
        if kept < MAX_ERRORS_PER_FILE {
            self.errors.push(error);
        } else if let Some((_, count)) = self.omitted.iter_mut().find(|(f, _)| *f == error.file) {
            *count += 1;
        } else {
            self.omitted.push((error.file, 1));
        }
    }

    fn into_errors(self) -> ConfigErrors {
        ConfigErrors {
            errors: self.errors,
            omitted: self.omitted,
        }
    }

    /// The span of the value at `path`, or of its deepest present ancestor.
    fn span(&self, path: &[Seg]) -> Range<usize> {
        let mut span = 0..0;
        let mut table: Option<&DeTable<'_>> = Some(self.tree.get_ref());
        let mut array: Option<&[Spanned<DeValue<'_>>]> = None;
        for seg in path {
            let value = match (seg, table, array) {
                (Seg::Key(key), Some(t), _) => table_get(t, key),
                (Seg::Index(i), _, Some(a)) => a.get(*i),
                _ => None,
            };
            let Some(value) = value else { break };
            span = value.span();
            table = None;
            array = None;
            match value.get_ref() {
                DeValue::Table(t) => table = Some(t),
                DeValue::Array(a) => array = Some(a),
                _ => {}
            }
        }
        span
    }

    fn err(&mut self, path: &[Seg], message: impl Into<String>) {
        let span = self.span(path);
        self.push_at(span, key_string(path), message.into());
    }

    /// The key path of the innermost value containing `offset` (for serde errors).
    fn key_at(&self, offset: usize) -> String {
        /// The latest place at or before `offset` where `value` (or, for an array, one of
        /// its elements) starts: headers of arrays of tables are spread over the file.
        fn latest_start(value: &Spanned<DeValue<'_>>, offset: usize) -> Option<usize> {
            match value.get_ref() {
                DeValue::Array(array) => array
                    .iter()
                    .map(|v| v.span().start)
                    .filter(|start| *start <= offset)
                    .max(),
                _ => Some(value.span().start).filter(|start| *start <= offset),
            }
        }
        fn walk(value: &DeValue<'_>, offset: usize, path: &mut Vec<String>) {
            match value {
                DeValue::Table(table) => {
                    let covering = table.iter().find(|(key, value)| {
                        value.span().contains(&offset) || key.span().contains(&offset)
                    });
                    // a value whose span does not cover the offset: a table or an array of
                    // tables declared by a header before it
                    let found = covering.or_else(|| {
                        table
                            .iter()
                            .filter(|(_, v)| {
                                matches!(v.get_ref(), DeValue::Table(_) | DeValue::Array(_))
                            })
                            .filter_map(|(k, v)| latest_start(v, offset).map(|s| (s, (k, v))))
                            .max_by_key(|(start, _)| *start)
                            .map(|(_, entry)| entry)
                    });
                    if let Some((key, value)) = found {
                        path.push(format!(".{}", key.get_ref()));
                        walk(value.get_ref(), offset, path);
                    }
                }
                DeValue::Array(array) => {
                    let found = array
                        .iter()
                        .enumerate()
                        .find(|(_, v)| v.span().contains(&offset))
                        .or_else(|| {
                            array
                                .iter()
                                .enumerate()
                                .rfind(|(_, v)| v.span().start <= offset)
                        });
                    if let Some((index, value)) = found {
                        path.push(format!("[{index}]"));
                        walk(value.get_ref(), offset, path);
                    }
                }
                _ => {}
            }
        }
        let mut path = Vec::new();
        let root = DeValue::Table(self.tree.get_ref().clone());
        walk(&root, offset, &mut path);
        let joined: String = path.concat();
        joined.strip_prefix('.').unwrap_or(&joined).to_owned()
    }
}

// ---------------------------------------------------------------------------------------
// Checks

fn parse_ip(text: &str) -> Result<IpAddr, String> {
    text.trim()
        .parse()
        .map_err(|_| format!("`{text}` is not an IP address"))
}

fn common_address(value: i64) -> Result<CommonAddress, String> {
    match u16::try_from(value) {
        Ok(v) if (1..=65534).contains(&v) => Ok(CommonAddress::new(v)),
        _ => Err(format!(
            "common address {value} is outside 1..=65534 (0 is unused, 65535 is broadcast)"
        )),
    }
}

fn ioa(value: i64) -> Result<Ioa, String> {
    u32::try_from(value)
        .ok()
        .filter(|v| *v >= 1)
        .and_then(|v| Ioa::try_new(v).ok())
        .ok_or_else(|| format!("IOA {value} is outside 1..=16777215"))
}

/// Splits `link:NAME/IOA`; `Ok(None)` for a variable path.
/// An IOA moved by a republishing offset, if still an IOA.
fn shifted(ioa: Ioa, offset: u32) -> Option<Ioa> {
    ioa.get()
        .checked_add(offset)
        .and_then(|i| Ioa::try_new(i).ok())
}

fn parse_link_ref(text: &str) -> Result<Option<(String, Ioa)>, String> {
    let Some(rest) = text.strip_prefix("link:") else {
        if text.trim().is_empty() {
            return Err("empty variable path".to_owned());
        }
        return Ok(None);
    };
    let malformed = || format!("`{text}` is not of the form link:LINK/IOA");
    let (name, number) = rest.rsplit_once('/').ok_or_else(malformed)?;
    if name.is_empty() {
        return Err(malformed());
    }
    let number: i64 = number.trim().parse().map_err(|_| malformed())?;
    Ok(Some((name.to_owned(), ioa(number)?)))
}

fn resolve(folder: &Path, relative: &str) -> PathBuf {
    folder.join(relative)
}

/// Whether `text` declares `PROGRAM name` (case-insensitive, name optionally quoted).
fn declares_program(text: &str, name: &str) -> bool {
    let words: Vec<&str> = text
        .split(|c: char| !(c.is_alphanumeric() || c == '_'))
        .filter(|w| !w.is_empty())
        .collect();
    words
        .windows(2)
        .any(|w| matches!(w, [a, b] if a.eq_ignore_ascii_case("program") && b.eq_ignore_ascii_case(name)))
}

fn is_measurement(type_id: TypeId) -> bool {
    type_id.mnemonic().starts_with("M_ME_")
}

impl Ctx<'_> {
    fn check(&mut self, folder: &Path, raw: RawProject) -> Project {
        let station = self.check_station(folder, &raw.station);
        let mut nodes = Vec::new();
        let mut seen_names: HashMap<String, usize> = HashMap::new();
        let mut seen_ports: HashMap<u16, String> = HashMap::new();
        for (n, node) in raw.node.iter().enumerate() {
            if node.name.trim().is_empty() {
                self.err(&[K("node"), I(n), K("name")], "node name is empty");
            } else if let Some(first) = seen_names.get(&node.name) {
                self.err(
                    &[K("node"), I(n), K("name")],
                    format!("duplicate node name `{}` (also node[{first}])", node.name),
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
                        format!(
                            "port_offset {} is also used by node `{other}`",
                            server.port_offset
                        ),
                    );
                } else {
                    seen_ports.insert(server.port_offset, built.name.clone());
                }
                if station.port_base.checked_add(server.port_offset).is_none() {
                    self.err(
                        &path,
                        format!(
                            "port_base {} + port_offset {} is past 65535",
                            station.port_base, server.port_offset
                        ),
                    );
                }
            }
            nodes.push(built);
        }
        self.check_links(folder, &raw, &mut nodes);
        Project {
            folder: folder.to_path_buf(),
            station,
            nodes,
        }
    }

    fn check_station(&mut self, folder: &Path, raw: &RawStation) -> StationSettings {
        let time_zone = match raw.time_zone.parse::<chrono_tz::Tz>() {
            Ok(tz) => tz,
            Err(_) => {
                self.err(
                    &[K("station"), K("time_zone")],
                    format!(
                        "unknown time zone `{}` (an IANA name such as Europe/Prague)",
                        raw.time_zone
                    ),
                );
                chrono_tz::UTC
            }
        };
        let retention_days = raw.retention_days.unwrap_or(60);
        if retention_days == 0 {
            self.err(
                &[K("station"), K("retention_days")],
                "retention_days must be at least 1",
            );
        }
        let store_text = raw.store.as_deref().unwrap_or("sqlite:events.sqlite");
        // One parser for every store address (crate::store_url); a relative SQLite path
        // is the project folder's.
        let store = match crate::store_url::StoreUrl::parse(store_text) {
            Ok(url) => url.resolved_in(folder).to_string(),
            Err(error) => {
                self.err(&[K("station"), K("store")], error.to_string());
                store_text.to_owned()
            }
        };
        let bind = match raw.bind.as_deref().map(parse_ip) {
            None => IpAddr::V4(Ipv4Addr::LOCALHOST),
            Some(Ok(ip)) => ip,
            Some(Err(message)) => {
                self.err(&[K("station"), K("bind")], message);
                IpAddr::V4(Ipv4Addr::LOCALHOST)
            }
        };
        StationSettings {
            name: raw.name.clone(),
            time_zone,
            store,
            retention_days,
            port_base: raw.port_base.unwrap_or(2404),
            bind,
            plant: raw.plant.clone(),
        }
    }

    fn point_source(
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
                    self.err(path, format!("node `{node}` has no link `{link}`"));
                }
                PointSource::Link { link, ioa }
            }
            Err(message) => {
                self.err(path, message);
                PointSource::Variable(source.to_owned())
            }
        }
    }

    /// A duration in milliseconds of at most a day; an error at `path` otherwise.
    fn duration_ms(&mut self, ms: i64, path: &[Seg], key: &str) -> Option<Duration> {
        if (1..=86_400_000).contains(&ms) {
            Some(Duration::from_millis(ms.unsigned_abs()))
        } else {
            self.err(path, format!("{key} {ms} is outside 1..=86400000"));
            None
        }
    }

    fn ips(&mut self, texts: &[String], path: &[Seg]) -> Vec<IpAddr> {
        let mut out = Vec::new();
        for (i, text) in texts.iter().enumerate() {
            match parse_ip(text) {
                Ok(ip) => out.push(ip),
                Err(message) => {
                    let mut p = path.to_vec();
                    p.push(I(i));
                    self.err(&p, message);
                }
            }
        }
        out
    }

    /// The TLS files at `path` (`[..., "tls"]`), each checked to exist.
    fn tls_files(&mut self, folder: &Path, raw: &RawTls, path: &[Seg]) -> TlsFiles {
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

    fn existing_file(&mut self, folder: &Path, relative: &str, path: &[Seg]) -> PathBuf {
        let resolved = resolve(folder, relative);
        if !resolved.is_file() {
            self.err(path, format!("file `{}` not found", resolved.display()));
        }
        resolved
    }

    fn check_node(&mut self, folder: &Path, n: usize, raw: &RawNode) -> NodeConfig {
        let node = |rest: &[Seg]| -> Vec<Seg> {
            let mut p = vec![K("node"), I(n)];
            p.extend_from_slice(rest);
            p
        };
        let common = common_address(raw.common_address).unwrap_or_else(|message| {
            self.err(&node(&[K("common_address")]), message);
            CommonAddress::new(0)
        });

        // sources
        let mut sources = Vec::new();
        // (file name as diagnostics show it, text) of each source read
        let mut files: Vec<(String, String)> = Vec::new();
        for (s, source) in raw.sources.iter().enumerate() {
            let path = node(&[K("sources"), I(s)]);
            let resolved = self.existing_file(folder, source, &path);
            if resolved.is_file() {
                match std::fs::read(&resolved) {
                    Ok(bytes) => match String::from_utf8(bytes) {
                        Ok(text) => files.push((resolved.display().to_string(), text)),
                        Err(e) => self.push(not_utf8(&resolved, e.as_bytes())),
                    },
                    Err(e) => self.err(&path, format!("cannot read `{}`: {e}", resolved.display())),
                }
            }
            sources.push(resolved);
        }
        let all_sources_read = files.len() == raw.sources.len();
        let texts: Vec<&str> = files.iter().map(|(_, text)| text.as_str()).collect();

        // server
        let server = raw.server.as_ref().map(|s| {
            let port_offset = u16::try_from(s.port_offset).unwrap_or_else(|_| {
                self.err(
                    &node(&[K("server"), K("port_offset")]),
                    format!("port_offset {} is outside 0..=65535", s.port_offset),
                );
                0
            });
            let allowed_clients = self.ips(
                &s.allowed_clients,
                &node(&[K("server"), K("allowed_clients")]),
            );
            let redundancy_groups = match &s.redundancy_groups {
                None => vec![RedundancyGroup {
                    name: "default".to_owned(),
                    clients: Vec::new(),
                    refuse_commands_when: None,
                    status_point: None,
                }],
                Some(groups) => {
                    let mut out = Vec::new();
                    if groups.is_empty() {
                        self.err(
                            &node(&[K("server"), K("redundancy_groups")]),
                            "at least one redundancy group is needed",
                        );
                    }
                    let mut names = HashSet::new();
                    for (g, group) in groups.iter().enumerate() {
                        if !names.insert(group.name.clone()) {
                            self.err(
                                &node(&[K("server"), K("redundancy_groups"), I(g), K("name")]),
                                format!("duplicate redundancy group `{}`", group.name),
                            );
                        }
                        let clients = self.ips(
                            &group.clients,
                            &node(&[K("server"), K("redundancy_groups"), I(g), K("clients")]),
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
            };
            let tls = s
                .tls
                .as_ref()
                .map(|t| self.tls_files(folder, t, &node(&[K("server"), K("tls")])));
            let group_configs = redundancy_groups
                .iter()
                .map(|g| {
                    iec60870::cs104::server::RedundancyGroupConfig::new(
                        g.name.clone(),
                        g.clients.clone(),
                    )
                })
                .collect();
            let mode_name = s.redundancy.as_deref().unwrap_or("groups-by-address");
            let redundancy =
                iec60870::cs104::server::RedundancyMode::from_name(mode_name, group_configs)
                    .unwrap_or_else(|| {
                        self.err(
                            &node(&[K("server"), K("redundancy")]),
                            format!(
                                "unknown redundancy mode `{mode_name}` (one of {})",
                                iec60870::cs104::server::RedundancyMode::NAMES.join(", ")
                            ),
                        );
                        iec60870::cs104::server::RedundancyMode::SingleGroup
                    });
            let max_command_age = s.max_command_age_ms.and_then(|ms| {
                self.duration_ms(
                    ms,
                    &node(&[K("server"), K("max_command_age_ms")]),
                    "max_command_age_ms",
                )
            });
            ServerConfig {
                port_offset,
                allowed_clients,
                redundancy_groups,
                tls,
                redundancy,
                max_command_age,
            }
        });

        // tasks
        let mut tasks = Vec::new();
        let mut task_names = HashSet::new();
        for (t, task) in raw.task.iter().enumerate() {
            if !task_names.insert(task.name.clone()) {
                self.err(
                    &node(&[K("task"), I(t), K("name")]),
                    format!("duplicate task name `{}`", task.name),
                );
            }
            if task.interval_ms == 0 {
                self.err(
                    &node(&[K("task"), I(t), K("interval_ms")]),
                    "interval_ms must be at least 1",
                );
            }
            if task.watchdog_ms == Some(0) {
                self.err(
                    &node(&[K("task"), I(t), K("watchdog_ms")]),
                    "watchdog_ms must be at least 1",
                );
            }
            if all_sources_read {
                for (p, program) in task.programs.iter().enumerate() {
                    if !texts.iter().any(|text| declares_program(text, program)) {
                        self.err(
                            &node(&[K("task"), I(t), K("programs"), I(p)]),
                            format!("no PROGRAM `{program}` is declared in the node's sources"),
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

        let io = raw
            .io
            .iter()
            .map(|b| IoBinding {
                signal: b.signal.clone(),
                variable: b.variable.clone(),
            })
            .collect();

        // points
        let mut points = Vec::new();
        let mut point_names = HashSet::new();
        let mut point_ioas: HashMap<Ioa, String> = HashMap::new();
        for (p, point) in raw.point.iter().enumerate() {
            let at = |key: &'static str| node(&[K("point"), I(p), K(key)]);
            if !point_names.insert(point.name.clone()) {
                self.err(
                    &at("name"),
                    format!("duplicate point name `{}`", point.name),
                );
            }
            let type_id = match point.type_id.parse::<TypeId>() {
                Ok(t) if t.is_monitor() && t != TypeId::M_EI_NA_1 => t,
                Ok(t) => {
                    self.err(
                        &at("type"),
                        format!("{t} is not a monitor-direction process type"),
                    );
                    TypeId::M_SP_NA_1
                }
                Err(_) => {
                    self.err(&at("type"), format!("unknown type `{}`", point.type_id));
                    TypeId::M_SP_NA_1
                }
            };
            let address = match ioa(point.ioa) {
                Ok(a) => {
                    if let Some(other) = point_ioas.get(&a) {
                        self.err(
                            &at("ioa"),
                            format!("IOA {a} is also used by point `{other}`"),
                        );
                    } else {
                        point_ioas.insert(a, point.name.clone());
                    }
                    a
                }
                Err(message) => {
                    self.err(&at("ioa"), message);
                    Ioa::IRRELEVANT
                }
            };
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
                        &at("type"),
                        format!(
                            "the status point of redundancy group `{}` must be M_SP_NA_1 or M_SP_TB_1",
                            group.name
                        ),
                    );
                }
            }
            let source = match (&point.source, status_of) {
                (None, None) if group_of.is_some() => {
                    PointSource::ClientStatus(group_of.map(|g| g.name.clone()).unwrap_or_default())
                }
                (None, Some(link)) => {
                    if !matches!(type_id, TypeId::M_SP_NA_1 | TypeId::M_SP_TB_1) {
                        self.err(
                            &at("type"),
                            format!(
                                "the status point of link `{}` must be M_SP_NA_1 or M_SP_TB_1",
                                link.name
                            ),
                        );
                    }
                    PointSource::LinkStatus(link.name.clone())
                }
                (None, None) => {
                    self.err(
                        &node(&[K("point"), I(p)]),
                        "missing source (only the status point of a link or a redundancy group has none)",
                    );
                    PointSource::Variable(String::new())
                }
                (Some(_), Some(link)) => {
                    self.err(
                        &at("source"),
                        format!("the status point of link `{}` takes no source", link.name),
                    );
                    PointSource::LinkStatus(link.name.clone())
                }
                (Some(source), None) => {
                    self.point_source(&raw.name, &raw.link, source, &at("source"))
                }
            };
            let transmission = match (point.transmission, point.cycle_ms) {
                (RawTransmission::Cyclic, Some(ms)) if ms > 0 => Transmission::Cyclic {
                    period: Duration::from_millis(ms),
                },
                (RawTransmission::Cyclic, Some(_)) => {
                    self.err(&at("cycle_ms"), "cycle_ms must be at least 1");
                    Transmission::Spontaneous
                }
                (RawTransmission::Cyclic, None) => {
                    self.err(&at("transmission"), "cyclic transmission needs cycle_ms");
                    Transmission::Spontaneous
                }
                (_, Some(_)) => {
                    self.err(
                        &at("cycle_ms"),
                        "cycle_ms is only allowed with transmission = \"cyclic\"",
                    );
                    Transmission::Spontaneous
                }
                (RawTransmission::Spontaneous, None) => Transmission::Spontaneous,
                (RawTransmission::InterrogationOnly, None) => Transmission::InterrogationOnly,
            };
            let mut groups = Vec::new();
            for (g, group) in point.groups.iter().enumerate() {
                match u8::try_from(*group) {
                    Ok(v) if (1..=16).contains(&v) => groups.push(v),
                    _ => self.err(
                        &node(&[K("point"), I(p), K("groups"), I(g)]),
                        format!("interrogation group {group} is outside 1..=16"),
                    ),
                }
            }
            if let Some(deadband) = point.deadband {
                if !is_measurement(type_id) {
                    self.err(
                        &at("deadband"),
                        format!("a deadband needs a measurement type (M_ME_*), not {type_id}"),
                    );
                } else if !(deadband >= 0.0 && deadband.is_finite()) {
                    self.err(&at("deadband"), "deadband must be a finite value >= 0");
                }
            }
            points.push(PointConfig {
                name: point.name.clone(),
                type_id,
                ioa: address,
                source,
                transmission,
                groups,
                deadband: point.deadband,
                invalid_when: point.invalid_when.clone(),
                description: point.description.clone(),
            });
        }

        // commands
        let mut commands = Vec::new();
        let mut command_names = HashSet::new();
        let mut command_ioas: HashMap<Ioa, String> = HashMap::new();
        for (c, command) in raw.command.iter().enumerate() {
            let at = |key: &'static str| node(&[K("command"), I(c), K(key)]);
            if !command_names.insert(command.name.clone()) {
                self.err(
                    &at("name"),
                    format!("duplicate command name `{}`", command.name),
                );
            }
            let type_id = match command.type_id.parse::<TypeId>() {
                Ok(t) if t.is_command() => t,
                Ok(t) => {
                    self.err(&at("type"), format!("{t} is not a command type"));
                    TypeId::C_SC_NA_1
                }
                Err(_) => {
                    self.err(&at("type"), format!("unknown type `{}`", command.type_id));
                    TypeId::C_SC_NA_1
                }
            };
            let address = match ioa(command.ioa) {
                Ok(a) => {
                    if let Some(other) = command_ioas.get(&a) {
                        self.err(
                            &at("ioa"),
                            format!("IOA {a} is also used by command `{other}`"),
                        );
                    } else if let Some(point) = point_ioas.get(&a) {
                        // Many controlling stations (lib60870, most SCADA) keep one
                        // information object per address: a command and a point on one
                        // IOA would clash there.
                        self.err(
                            &at("ioa"),
                            format!("IOA {a} is also the address of point `{point}`"),
                        );
                    } else {
                        command_ioas.insert(a, command.name.clone());
                    }
                    a
                }
                Err(message) => {
                    self.err(&at("ioa"), message);
                    Ioa::IRRELEVANT
                }
            };
            let target = match parse_link_ref(&command.target) {
                Ok(None) => CommandTarget::Variable(command.target.clone()),
                Ok(Some((link, ioa))) => {
                    if !raw.link.iter().any(|l| l.name == link) {
                        self.err(
                            &at("target"),
                            format!("node `{}` has no link `{link}`", raw.name),
                        );
                    }
                    CommandTarget::Link { link, ioa }
                }
                Err(message) => {
                    self.err(&at("target"), message);
                    CommandTarget::Variable(command.target.clone())
                }
            };
            for (g, group) in command.from_groups.iter().enumerate() {
                let known = server.as_ref().is_some_and(|s: &ServerConfig| {
                    s.redundancy_groups.iter().any(|r| &r.name == group)
                });
                if !known {
                    self.err(
                        &[K("node"), I(n), K("command"), I(c), K("from_groups"), I(g)],
                        format!("node `{}` has no redundancy group `{group}`", raw.name),
                    );
                }
            }
            let pulse = match command.pulse_ms {
                None => None,
                Some(ms) if (1..=3_600_000).contains(&ms) => {
                    if matches!(target, CommandTarget::Link { .. }) {
                        self.err(
                            &at("pulse_ms"),
                            "a forwarded command is pulsed by the node that executes it",
                        );
                    }
                    Some(Duration::from_millis(ms.unsigned_abs()))
                }
                Some(ms) => {
                    self.err(
                        &at("pulse_ms"),
                        format!("pulse_ms {ms} is outside 1..=3600000"),
                    );
                    None
                }
            };
            let max_age = command
                .max_age_ms
                .and_then(|ms| self.duration_ms(ms, &at("max_age_ms"), "max_age_ms"));
            let range = command.range.and_then(|[low, high]| {
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
                        &at("range"),
                        format!("range applies to set-points, not {type_id}"),
                    );
                    None
                } else if !(low.is_finite() && high.is_finite() && low <= high) {
                    self.err(&at("range"), format!("range [{low}, {high}] is empty"));
                    None
                } else {
                    Some(low..=high)
                }
            });
            let feedback = match &command.feedback {
                None => {
                    if command.feedback_timeout_ms.is_some() {
                        self.err(
                            &at("feedback_timeout_ms"),
                            "feedback_timeout_ms needs feedback",
                        );
                    }
                    None
                }
                Some(point) => {
                    if !point_names.contains(point) {
                        self.err(
                            &at("feedback"),
                            format!("node `{}` has no point `{point}`", raw.name),
                        );
                    }
                    if matches!(target, CommandTarget::Link { .. }) {
                        self.err(
                            &at("feedback"),
                            "a forwarded command's return information comes from the node that executes it",
                        );
                    }
                    let timeout = match command.feedback_timeout_ms {
                        None => DEFAULT_FEEDBACK_TIMEOUT,
                        Some(ms) => self
                            .duration_ms(ms, &at("feedback_timeout_ms"), "feedback_timeout_ms")
                            .unwrap_or(DEFAULT_FEEDBACK_TIMEOUT),
                    };
                    Some(Feedback {
                        point: point.clone(),
                        timeout,
                    })
                }
            };
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

        #[cfg(feature = "runtime")]
        if all_sources_read && !files.is_empty() {
            self.check_plc_variables(n, raw, &files);
        }

        NodeConfig {
            name: raw.name.clone(),
            description: raw.description.clone(),
            common_address: common,
            sources,
            server,
            tasks,
            io,
            points,
            commands,
            links: Vec::new(),
            initial_values: raw
                .set
                .iter()
                .map(|(path, value)| (path.clone(), value.clone()))
                .collect(),
            tables: raw
                .table
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
                .collect(),
        }
    }

    /// Compiles the node's ST sources as the runtime will and looks up every PLC variable
    /// the node names (point sources and `invalid_when`, command targets and
    /// `remote_enable`, I/O variables, `refuse_commands_when`): a typo is then reported at
    /// its value in station.toml, not as a start-up failure without a place. Compile errors
    /// are reported at their place in the ST file.
    #[cfg(feature = "runtime")]
    fn check_plc_variables(&mut self, n: usize, raw: &RawNode, files: &[(String, String)]) {
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
                        message: diagnostic.message.clone(),
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
                    format!("the PLC does not start: {error}"),
                );
                return;
            }
        };
        let is_variable = |text: &str| matches!(parse_link_ref(text), Ok(None));
        let mut named: Vec<(Vec<Seg>, &str)> = Vec::new();
        for (p, point) in raw.point.iter().enumerate() {
            if let Some(source) = point.source.as_deref().filter(|s| is_variable(s)) {
                named.push((vec![K("point"), I(p), K("source")], source));
            }
            if let Some(variable) = &point.invalid_when {
                named.push((vec![K("point"), I(p), K("invalid_when")], variable));
            }
        }
        for (c, command) in raw.command.iter().enumerate() {
            if is_variable(&command.target) {
                named.push((vec![K("command"), I(c), K("target")], &command.target));
            }
            if let Some(variable) = &command.remote_enable {
                named.push((vec![K("command"), I(c), K("remote_enable")], variable));
            }
        }
        for (i, io) in raw.io.iter().enumerate() {
            named.push((vec![K("io"), I(i), K("variable")], &io.variable));
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
                self.err(&path, format!("{error} in the node's PLC program"));
            }
        }
    }

    /// Builds every node's links (they need all nodes) and checks the link graph.
    fn check_links(&mut self, folder: &Path, raw: &RawProject, nodes: &mut [NodeConfig]) {
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
                    self.err(&at("name"), format!("duplicate link name `{}`", link.name));
                }
                let mut target_node = None;
                let target = match (&link.node, &link.address) {
                    (Some(_), Some(_)) => {
                        self.err(&at("address"), "give either node or address, not both");
                        None
                    }
                    (None, None) => {
                        self.err(
                            &[K("node"), I(n), K("link"), I(l)],
                            "a link needs node or address",
                        );
                        None
                    }
                    (Some(name), None) => match index.get(name.as_str()) {
                        None => {
                            self.err(&at("node"), format!("no node `{name}` in the project"));
                            None
                        }
                        Some(&t) if t == n => {
                            self.err(&at("node"), "a node cannot link to itself");
                            None
                        }
                        Some(&t) => {
                            if raw.node.get(t).is_some_and(|t| t.server.is_none()) {
                                self.err(
                                    &at("node"),
                                    format!("node `{name}` has no [node.server]"),
                                );
                            }
                            let lower_tls = raw
                                .node
                                .get(t)
                                .and_then(|t| t.server.as_ref())
                                .is_some_and(|server| server.tls.is_some());
                            match (lower_tls, link.tls.is_some()) {
                                (true, false) => self.err(
                                    &at("node"),
                                    format!(
                                        "node `{name}`'s server requires TLS: give the link tls"
                                    ),
                                ),
                                (false, true) => self
                                    .err(&at("tls"), format!("node `{name}`'s server has no tls")),
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
                                format!("`{address}` is not an IP:PORT address"),
                            );
                            None
                        }
                    },
                };
                let common = match link.common_address {
                    Some(value) => common_address(value).unwrap_or_else(|message| {
                        self.err(&at("common_address"), message);
                        CommonAddress::new(0)
                    }),
                    None => match target_node.and_then(|t| nodes.get(t)) {
                        Some(t) => t.common_address,
                        None => {
                            if matches!(target, Some(LinkTarget::Address(_))) {
                                self.err(
                                    &[K("node"), I(n), K("link"), I(l)],
                                    "a link with an address needs common_address",
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
                            format!("node `{}` has no point `{status}`", node.name),
                        );
                    }
                }
                // link: references into a project node must name what that node serves
                if let Some(lower) = target_node.and_then(|t| nodes.get(t)) {
                    let lower_points: HashSet<Ioa> = lower.points.iter().map(|p| p.ioa).collect();
                    let lower_commands: HashSet<Ioa> =
                        lower.commands.iter().map(|c| c.ioa).collect();
                    let mut problems = Vec::new();
                    if let Some(this) = nodes.get(n) {
                        for (p, point) in this.points.iter().enumerate() {
                            if let PointSource::Link { link: name, ioa } = &point.source {
                                if name == &link.name && !lower_points.contains(ioa) {
                                    problems.push((
                                        vec![K("node"), I(n), K("point"), I(p), K("source")],
                                        format!(
                                            "node `{}` serves no point with IOA {ioa}",
                                            lower.name
                                        ),
                                    ));
                                }
                            }
                        }
                        for (c, command) in this.commands.iter().enumerate() {
                            if let CommandTarget::Link { link: name, ioa } = &command.target {
                                if name == &link.name && !lower_commands.contains(ioa) {
                                    problems.push((
                                        vec![K("node"), I(n), K("command"), I(c), K("target")],
                                        format!(
                                            "node `{}` accepts no command with IOA {ioa}",
                                            lower.name
                                        ),
                                    ));
                                }
                            }
                        }
                    }
                    for (path, message) in problems {
                        self.err(&path, message);
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
    fn expand_republish(
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
                            format!(
                                "ioa_offset {} is outside 0..=16777215",
                                republish.ioa_offset
                            ),
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
                        problems.push(format!(
                            "point `{}` (IOA {}) + {offset} is past the largest IOA",
                            point.name, point.ioa
                        ));
                        continue;
                    };
                    if !names.insert(point.name.clone()) {
                        problems.push(format!(
                            "point `{}` of `{}` is already a point of `{}`",
                            point.name, lower.name, this.name
                        ));
                        continue;
                    }
                    if !ioas.insert(ioa.get()) {
                        problems.push(format!(
                            "point `{}` of `{}` lands on IOA {ioa}, already used at `{}`",
                            point.name, lower.name, this.name
                        ));
                        continue;
                    }
                    this.points.push(PointConfig {
                        name: point.name.clone(),
                        type_id: point.type_id,
                        ioa,
                        source: PointSource::Link {
                            link: raw_link.name.clone(),
                            ioa: point.ioa,
                        },
                        transmission: Transmission::Spontaneous,
                        groups: point.groups.clone(),
                        deadband: None,
                        invalid_when: None,
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
                        problems.push(format!(
                            "command `{}` (IOA {}) + {offset} is past the largest IOA",
                            command.name, command.ioa
                        ));
                        continue;
                    };
                    if ioas.contains(&ioa.get()) && !command_ioas.contains(&ioa.get()) {
                        problems.push(format!(
                            "command `{}` of `{}` lands on IOA {ioa}, the address of a point at `{}`",
                            command.name, lower.name, this.name
                        ));
                        continue;
                    }
                    if !command_names.insert(command.name.clone())
                        || !command_ioas.insert(ioa.get())
                    {
                        problems.push(format!(
                            "command `{}` of `{}` (IOA {ioa} here) clashes with a command of `{}`",
                            command.name, lower.name, this.name
                        ));
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
                for message in problems {
                    self.err(&at, message);
                }
            }
        }
    }

    /// Reports each back edge of a depth-first search of the link graph.
    fn check_cycles(&mut self, raw: &RawProject, edges: &[Vec<(usize, usize)>]) {
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
                            let mut cycle: Vec<&str> = stack
                                .get(from..)
                                .unwrap_or(&[])
                                .iter()
                                .map(|(n, _)| name(*n))
                                .collect();
                            cycle.push(name(target));
                            self.err(
                                &[K("node"), I(node), K("link"), I(link), K("node")],
                                format!("the links form a cycle: {}", cycle.join(" -> ")),
                            );
                        }
                        _ => {}
                    },
                }
            }
        }
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
