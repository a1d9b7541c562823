//! What is wrong in a project, as data: [`ConfigProblem`] and the small enums naming its
//! parts.
//!
//! A [`ConfigError`](super::ConfigError) says *where* (file, line, column, key path); its
//! [`ConfigProblem`] says *what*, in variants a program can match on (an editor marking
//! unknown references, a test asserting a duplicate) and whose `Display` is the message a
//! person reads. The variants group the checks by kind:
//!
//! | kind                         | variants                                                         |
//! |------------------------------|------------------------------------------------------------------|
//! | files                        | [`Unreadable`], [`FileNotFound`], [`NotUtf8`]                     |
//! | TOML and its schema          | [`Syntax`], [`Schema`]                                           |
//! | names                        | [`Unknown`] (a reference), [`Duplicate`], [`UnknownValue`] (a fixed vocabulary), [`Cycle`] |
//! | values                       | [`OutOfRange`], [`InvalidNumber`], [`EmptyRange`], [`Empty`], [`Malformed`], [`StoreUrl`], [`Invalid`] |
//! | IEC types                    | [`WrongType`]                                                    |
//! | keys that need or exclude each other | [`Missing`], [`Conflict`], [`Republish`]                  |
//! | a deployment's hosts file    | [`Hosts`]                                                        |
//! | the node's PLC               | `StDiagnostic` (with the `runtime` feature), [`PlcStart`], [`PlcVariable`], [`UnknownVariable`] |
//!
//! Where a problem is another crate's (toml's parser, serde, the store address parser, the
//! PLC compiler), its own words travel in a `detail` or its own error type: they are the
//! most precise, and rewording them here would drift.
//!
//! [`Unreadable`]: ConfigProblem::Unreadable
//! [`FileNotFound`]: ConfigProblem::FileNotFound
//! [`NotUtf8`]: ConfigProblem::NotUtf8
//! [`Syntax`]: ConfigProblem::Syntax
//! [`Schema`]: ConfigProblem::Schema
//! [`Unknown`]: ConfigProblem::Unknown
//! [`Duplicate`]: ConfigProblem::Duplicate
//! [`UnknownValue`]: ConfigProblem::UnknownValue
//! [`Cycle`]: ConfigProblem::Cycle
//! [`OutOfRange`]: ConfigProblem::OutOfRange
//! [`InvalidNumber`]: ConfigProblem::InvalidNumber
//! [`EmptyRange`]: ConfigProblem::EmptyRange
//! [`Empty`]: ConfigProblem::Empty
//! [`Malformed`]: ConfigProblem::Malformed
//! [`StoreUrl`]: ConfigProblem::StoreUrl
//! [`Invalid`]: ConfigProblem::Invalid
//! [`WrongType`]: ConfigProblem::WrongType
//! [`Missing`]: ConfigProblem::Missing
//! [`Conflict`]: ConfigProblem::Conflict
//! [`Republish`]: ConfigProblem::Republish
//! [`Hosts`]: ConfigProblem::Hosts
//! [`PlcStart`]: ConfigProblem::PlcStart
//! [`PlcVariable`]: ConfigProblem::PlcVariable
//! [`UnknownVariable`]: ConfigProblem::UnknownVariable

use std::fmt;
use std::path::PathBuf;

use iec60870::asdu::Ioa;

use crate::store_url::StoreUrlError;

/// What is wrong, without where (the [`ConfigError`](super::ConfigError) holding it says
/// where).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum ConfigProblem {
    /// A file could not be read. `file` is the file named in `station.toml` (an ST
    /// source); `None` when it is the error's own file (`station.toml` itself).
    #[error("cannot read{}: {detail}", quoted_path(file.as_ref()))]
    Unreadable {
        /// The file, when it is not the error's own.
        file: Option<PathBuf>,
        /// Why, as the operating system says it.
        kind: std::io::ErrorKind,
        /// The I/O error's text.
        detail: String,
    },
    /// A file `station.toml` names (ST source, TLS file, CSV table) does not exist.
    #[error("file `{}` not found", path.display())]
    FileNotFound {
        /// The file, resolved against the project folder.
        path: PathBuf,
    },
    /// A file that is not UTF-8 text, at its first invalid byte.
    #[error("not UTF-8 text: byte 0x{byte:02X} (save the file as UTF-8)")]
    NotUtf8 {
        /// The first invalid byte.
        byte: u8,
    },
    /// `station.toml` is not TOML; toml's own message.
    #[error("{detail}")]
    Syntax {
        /// What the TOML parser says.
        detail: String,
    },
    /// A value that does not fit the file's schema (a string where a number belongs, an
    /// unknown or a missing key); serde's message.
    #[error("{detail}")]
    Schema {
        /// Which schema rule, as far as serde's message tells.
        kind: SchemaKind,
        /// What serde says.
        detail: String,
    },
    /// A name that refers to nothing: a node, point, link, line, device, redundancy group,
    /// ST program or PLC variable, or an IOA the lower node does not serve.
    #[error("{}", unknown_text(*what, name, within))]
    Unknown {
        /// What kind of thing was looked for.
        what: Reference,
        /// The name (or, for [`Reference::LowerPoint`] and [`Reference::LowerCommand`],
        /// the IOA) given.
        name: String,
        /// Where it was looked for: the node (for a device, the line; for a lower IOA,
        /// the lower node); empty for a node of the project.
        within: String,
    },
    /// A name or address given twice where it must be unique.
    #[error("{}", duplicate_text(*what, value, other))]
    Duplicate {
        /// What must be unique.
        what: Unique,
        /// The value given twice (a name, a port offset, an IOA, an address).
        value: String,
        /// Who has it already (the first node's key path, a node, point or command
        /// name), or for devices the line they share.
        other: String,
    },
    /// A value outside a fixed vocabulary (time zones, IEC type names, redundancy modes,
    /// line protocols, simulated devices, parities).
    #[error("{}", unknown_value_text(*what, value))]
    UnknownValue {
        /// Which vocabulary.
        what: Vocabulary,
        /// The value given.
        value: String,
    },
    /// The links between nodes form a cycle.
    #[error("the links form a cycle: {}", nodes.join(" -> "))]
    Cycle {
        /// The nodes around the cycle, the first repeated at the end.
        nodes: Vec<String>,
    },
    /// An integer outside its allowed range.
    #[error("{}", out_of_range_text(what, *value, *min, *max))]
    OutOfRange {
        /// What it is: its key (`port_offset`, `timeout_ms`) or what the standard calls
        /// it (`IOA`, `common address`).
        what: &'static str,
        /// The value given.
        value: i64,
        /// The least allowed value.
        min: i64,
        /// The greatest allowed value; `None` when only the minimum bounds it.
        max: Option<i64>,
    },
    /// A number that breaks its rule (not finite, not positive, zero).
    #[error("{what} must be {expected}")]
    InvalidNumber {
        /// Its key.
        what: &'static str,
        /// The value given, as Rust writes it (kept as text so the problem stays `Eq`).
        value: String,
        /// The rule, e.g. `a positive number`.
        expected: &'static str,
    },
    /// A set-point `range` whose low end is above its high end (or not finite).
    #[error("range [{low}, {high}] is empty")]
    EmptyRange {
        /// The low end, as Rust writes it.
        low: String,
        /// The high end, as Rust writes it.
        high: String,
    },
    /// A text that must not be empty.
    #[error("{what} is empty")]
    Empty {
        /// What it is, e.g. `node name`.
        what: &'static str,
    },
    /// A text that does not have its form (an address, a `link:` or `line:` reference).
    #[error("{}", malformed_text(text, form))]
    Malformed {
        /// The text given.
        text: String,
        /// The form it should have.
        form: Form,
    },
    /// `store` is no store address.
    #[error(transparent)]
    StoreUrl(#[from] StoreUrlError),
    /// A value another crate's validation rejected, in its words (serial line settings).
    #[error("{detail}")]
    Invalid {
        /// What it says.
        detail: String,
    },
    /// A `[[node.device]]` of a kind nobody registered.
    #[error("no device kind `{kind}` (known: {})", if known.is_empty() { "none in this build".to_owned() } else { known.join(", ") })]
    UnknownDeviceKind {
        /// The kind given.
        kind: String,
        /// The kinds registered.
        known: Vec<String>,
    },
    /// An IEC 60870-5 type that does not fit its use.
    #[error("{}", wrong_type_text(type_id, usage))]
    WrongType {
        /// The type's mnemonic, e.g. `C_SC_NA_1`.
        type_id: String,
        /// What it is used for.
        usage: TypeUse,
    },
    /// A key that another key (or the thing itself) needs.
    #[error("{}", missing_text(what, needed_by, hint))]
    Missing {
        /// The missing key, e.g. `cycle_ms`.
        what: &'static str,
        /// What needs it, e.g. `cyclic transmission`; empty when the thing itself does.
        needed_by: &'static str,
        /// Why or what it means; empty when it goes without saying.
        hint: &'static str,
    },
    /// Keys or things that exclude each other, or a target that cannot serve.
    #[error(transparent)]
    Conflict(#[from] Conflict),
    /// A point or command republished from a lower node that does not fit the upper one.
    #[error(transparent)]
    Republish(#[from] RepublishClash),
    /// A deployment's hosts file that does not fit the project (a node left out, a client
    /// address the project does not name); see [`HostsFile`](super::HostsFile).
    #[error(transparent)]
    Hosts(#[from] super::HostsProblem),
    /// An error of the PLC compiler in a node's ST sources, at its place there.
    #[cfg(feature = "runtime")]
    #[error("{message}")]
    StDiagnostic {
        /// The compiler's code (its documentation page).
        code: plc::Code,
        /// The compiler's headline.
        message: String,
        /// The compiler's excerpt of the source under the headline (the line with the
        /// place marked, notes such as "did you mean", the code), as `stanice plc check`
        /// prints it; shown after the error's line.
        excerpt: String,
    },
    /// A PLC variable the project names that the node's program lacks, with the nearest
    /// variable the program has when one is clearly meant.
    #[error("no variable '{name}' in the node's PLC program{suggestion}")]
    UnknownVariable {
        /// The path given (`Main.Typo`).
        name: String,
        /// `; did you mean `Main.Type`?`, or empty.
        suggestion: String,
    },
    /// The node's compiled PLC program does not start (its initial values fault).
    #[error("the PLC does not start: {detail}")]
    PlcStart {
        /// What the PLC says.
        detail: String,
    },
    /// A PLC variable the node names exists but cannot be used (e.g. it is not a
    /// scalar); one that does not exist is [`ConfigProblem::UnknownVariable`].
    #[error("{detail} in the node's PLC program")]
    PlcVariable {
        /// What the PLC says.
        detail: String,
    },
}

/// Which schema rule a serde error broke, read from serde's standard wording.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum SchemaKind {
    /// A value of the wrong TOML type (`invalid type: string "x", expected i64`).
    WrongType,
    /// A key the table does not have (`unknown field`).
    UnknownKey,
    /// A required key that is absent (`missing field`).
    MissingKey,
    /// A value outside an enumeration (`unknown variant`).
    UnknownVariant,
    /// Anything else (an invalid value or length).
    Other,
}

impl SchemaKind {
    /// The kind of a serde message: serde's `de::Error` constructors start their texts
    /// this way, and toml passes them on unchanged.
    pub(in crate::config) fn of(message: &str) -> SchemaKind {
        if message.starts_with("invalid type") {
            SchemaKind::WrongType
        } else if message.starts_with("unknown field") {
            SchemaKind::UnknownKey
        } else if message.starts_with("missing field") {
            SchemaKind::MissingKey
        } else if message.starts_with("unknown variant") {
            SchemaKind::UnknownVariant
        } else {
            SchemaKind::Other
        }
    }
}

/// What an unknown name was meant to refer to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Reference {
    /// A node of the project (a link's `node`).
    Node,
    /// A point of the node (status points, `feedback`).
    Point,
    /// A link of the node (`link:LINK/IOA`).
    Link,
    /// A serial line of the node (`line:LINE/...`).
    Line,
    /// A device of a line (`line:LINE/DEVICE/...`).
    Device,
    /// A redundancy group of the node's server (`from_groups`).
    RedundancyGroup,
    /// A `PROGRAM` in the node's ST sources (a task's `programs`).
    Program,
    /// A variable of the node's PLC program.
    PlcVariable,
    /// A point of the lower node, by IOA (`link:LINK/IOA` sources).
    LowerPoint,
    /// A command of the lower node, by IOA (`link:LINK/IOA` targets).
    LowerCommand,
}

/// What must be unique.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Unique {
    /// Node names in the project.
    NodeName,
    /// Task names in a node.
    TaskName,
    /// Point names in a node.
    PointName,
    /// Command names in a node.
    CommandName,
    /// Link names in a node.
    LinkName,
    /// Line names in a node.
    LineName,
    /// Device names on a line.
    DeviceName,
    /// Redundancy group names of a server.
    RedundancyGroup,
    /// Server port offsets in the project.
    PortOffset,
    /// Point IOAs in a node.
    PointIoa,
    /// Command IOAs in a node.
    CommandIoa,
    /// A command's IOA that a point of the node has (one information object per address).
    CommandOnPointIoa,
    /// Device addresses on a line.
    DeviceAddress,
    /// Lift names in a node.
    LiftName,
    /// Field device (and lift) names in a node.
    FieldDeviceName,
}

/// A fixed vocabulary a value must come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Vocabulary {
    /// IANA time zone names.
    TimeZone,
    /// IEC 60870-5 type mnemonics.
    TypeId,
    /// Server redundancy modes.
    RedundancyMode,
    /// Serial line protocols.
    Protocol,
    /// Simulated line devices.
    SimulatedDevice,
    /// Serial parities.
    Parity,
    /// Simulated lift boards.
    SimulatedLift,
    /// The status reply layouts of a lift board.
    StatusLayout,
    /// The time codings of a lift board.
    TimeCoding,
    /// The words `max_command_age_ms` takes besides a number.
    CommandAge,
}

/// The form a text must have.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub enum Form {
    /// An IP address.
    IpAddress,
    /// `IP:PORT`.
    SocketAddress,
    /// `link:LINK/IOA`.
    LinkRef,
    /// `line:LINE/DEVICE/FUN/INF[/INDEX]` (IEC 103) or `line:LINE/DEVICE/IOA` (IEC 101).
    LineRef,
    /// The IOA of an IEC 101 `line:LINE/DEVICE/IOA` reference.
    LineIoa {
        /// The text given there.
        given: String,
    },
    /// A number 0..=255 in a `line:` reference.
    LineNumber {
        /// Which part: `FUN`, `INF` or `INDEX`.
        part: &'static str,
        /// The text given there.
        given: String,
    },
}

/// What an IEC type is used for, when it does not fit.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub enum TypeUse {
    /// A point: a monitor-direction process type.
    Point,
    /// A command: a command type.
    Command,
    /// The status point of a link (a single point).
    LinkStatus {
        /// The link.
        link: String,
    },
    /// The status point of a redundancy group (a single point).
    GroupStatus {
        /// The group.
        group: String,
    },
    /// The status point of a serial line or device (a single point).
    LineStatus {
        /// The point.
        point: String,
    },
    /// An indication of a line device: a single or double point.
    LineIndication,
    /// A measurand of a line device: a measurement.
    LineMeasurand,
    /// A command to a line device: a single or double command.
    LineCommand,
    /// A point with `scale_factor`: a scaled measurement.
    ScaleFactor,
    /// A point with a deadband: a measurement.
    Deadband,
    /// A command with `range`: a set-point.
    Range,
    /// A point with a storage deadband or rate limit: a numeric type.
    Storage,
}

/// Keys or things that exclude each other.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum Conflict {
    /// A link with both `node` and `address`.
    #[error("give either node or address, not both")]
    NodeAndAddress,
    /// A line with not exactly one of `port`, `tcp` and `simulate`.
    #[error("give exactly one of port, tcp and simulate")]
    LineTransport,
    /// A point with both storage deadbands.
    #[error("give either store_deadband (absolute) or store_deadband_percent, not both")]
    StoreDeadbands,
    /// An I/O binding with both `signal` and `point`.
    #[error("give either signal (a plant signal) or point (a point of the node), not both")]
    IoSignalAndPoint,
    /// A device with `plant` and a line of its own in its settings.
    #[error("a device on the plant's port (plant) takes no `{key}`")]
    PlantPortAndLine {
        /// The other key.
        key: String,
    },
    /// A link from a node to itself.
    #[error("a node cannot link to itself")]
    LinkToItself,
    /// A link to a node without a server.
    #[error("node `{node}` has no [node.server]")]
    NoServer {
        /// The target node.
        node: String,
    },
    /// A link without `tls` to a node whose server requires it.
    #[error("node `{node}`'s server requires TLS: give the link tls")]
    TlsRequired {
        /// The target node.
        node: String,
    },
    /// A link with `tls` to a node whose server has none.
    #[error("node `{node}`'s server has no tls")]
    TlsUnavailable {
        /// The target node.
        node: String,
    },
    /// A server port past 65535.
    #[error("port_base {port_base} + port_offset {port_offset} is past 65535")]
    PortPast65535 {
        /// The station's `port_base`.
        port_base: u16,
        /// The node's `port_offset`.
        port_offset: u16,
    },
    /// A source on a link's status point.
    #[error("the status point of link `{link}` takes no source")]
    LinkStatusWithSource {
        /// The link.
        link: String,
    },
    /// A source on a line's or device's status point.
    #[error("the status point `{point}` takes no source")]
    StatusPointWithSource {
        /// The point.
        point: String,
    },
    /// `cycle_ms` without cyclic transmission.
    #[error("cycle_ms is only allowed with transmission = \"cyclic\"")]
    CycleWithoutCyclic,
    /// `measurand_limit` on a point that is no measurand of a line device.
    #[error(
        "measurand_limit is only for measurands of line devices (line:LINE/DEVICE/FUN/INF/INDEX)"
    )]
    MeasurandLimitWithoutMeasurand,
    /// `line:LINE/DEVICE/FUN/INF/INDEX` as a command target.
    #[error("a command to a line device is line:LINE/DEVICE/FUN/INF")]
    LineCommandWithIndex,
    /// `pulse_ms` on a forwarded command.
    #[error("a forwarded command is pulsed by the node that executes it")]
    ForwardedPulse,
    /// `feedback` on a forwarded command.
    #[error("a forwarded command's return information comes from the node that executes it")]
    ForwardedFeedback,
    /// A `line:` reference in the other protocol's form.
    #[error("line `{line}` is {protocol}: its signals are {form}")]
    LineRefProtocol {
        /// The line.
        line: String,
        /// Its protocol.
        protocol: &'static str,
        /// The form its references take.
        form: &'static str,
    },
    /// A key of the other protocol on a line (field sizes on an IEC 103 line, a
    /// simulated relay on an IEC 101 line, `=ON`/`=OFF` on a forwarded IEC 101 command).
    #[error("{key} is not for an {protocol} line")]
    NotForProtocol {
        /// The key.
        key: &'static str,
        /// The line's protocol.
        protocol: &'static str,
    },
}

/// A point or command republished from a lower node that does not fit the upper one.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum RepublishClash {
    /// Its IOA plus the offset is past 16 777 215.
    #[error("{object} `{name}` (IOA {ioa}) + {offset} is past the largest IOA")]
    PastLargestIoa {
        /// A point or a command.
        object: Object,
        /// Its name.
        name: String,
        /// Its IOA on the lower node.
        ioa: Ioa,
        /// The link's `ioa_offset`.
        offset: u32,
    },
    /// The upper node has a point of that name already.
    #[error("point `{name}` of `{lower}` is already a point of `{upper}`")]
    PointName {
        /// The point.
        name: String,
        /// The lower node.
        lower: String,
        /// The upper node.
        upper: String,
    },
    /// The upper node uses the point's shifted IOA already.
    #[error("point `{name}` of `{lower}` lands on IOA {ioa}, already used at `{upper}`")]
    PointIoa {
        /// The point.
        name: String,
        /// The lower node.
        lower: String,
        /// The IOA at the upper node.
        ioa: Ioa,
        /// The upper node.
        upper: String,
    },
    /// The command's shifted IOA is the address of a point of the upper node.
    #[error(
        "command `{name}` of `{lower}` lands on IOA {ioa}, the address of a point at `{upper}`"
    )]
    CommandOnPoint {
        /// The command.
        name: String,
        /// The lower node.
        lower: String,
        /// The IOA at the upper node.
        ioa: Ioa,
        /// The upper node.
        upper: String,
    },
    /// The upper node has a command of that name or IOA already.
    #[error("command `{name}` of `{lower}` (IOA {ioa} here) clashes with a command of `{upper}`")]
    Command {
        /// The command.
        name: String,
        /// The lower node.
        lower: String,
        /// The IOA at the upper node.
        ioa: Ioa,
        /// The upper node.
        upper: String,
    },
}

/// A point or a command.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Object {
    /// A monitor-direction point.
    Point,
    /// A command.
    Command,
}

impl fmt::Display for Object {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Object::Point => "point",
            Object::Command => "command",
        })
    }
}

// The texts below are the messages the loader printed before its problems were typed:
// tests and users grep for them.

fn quoted_path(file: Option<&PathBuf>) -> String {
    file.map(|f| format!(" `{}`", f.display()))
        .unwrap_or_default()
}

fn unknown_text(what: Reference, name: &str, within: &str) -> String {
    match what {
        Reference::Node => format!("no node `{name}` in the project"),
        Reference::Point => format!("node `{within}` has no point `{name}`"),
        Reference::Link => format!("node `{within}` has no link `{name}`"),
        Reference::Line => format!("node `{within}` has no line `{name}`"),
        Reference::Device => format!("line `{within}` has no device `{name}`"),
        Reference::RedundancyGroup => {
            format!("node `{within}` has no redundancy group `{name}`")
        }
        Reference::Program => {
            format!("no PROGRAM `{name}` is declared in the node's sources")
        }
        Reference::PlcVariable => format!("no variable '{name}' in the node's PLC program"),
        Reference::LowerPoint => format!("node `{within}` serves no point with IOA {name}"),
        Reference::LowerCommand => {
            format!("node `{within}` accepts no command with IOA {name}")
        }
    }
}

fn duplicate_text(what: Unique, value: &str, other: &str) -> String {
    match what {
        Unique::NodeName => format!("duplicate node name `{value}` (also {other})"),
        Unique::TaskName => format!("duplicate task name `{value}`"),
        Unique::PointName => format!("duplicate point name `{value}`"),
        Unique::CommandName => format!("duplicate command name `{value}`"),
        Unique::LinkName => format!("duplicate link name `{value}`"),
        Unique::LineName => format!("duplicate line name `{value}`"),
        Unique::DeviceName => format!("duplicate device name `{value}` on line `{other}`"),
        Unique::RedundancyGroup => format!("duplicate redundancy group `{value}`"),
        Unique::PortOffset => format!("port_offset {value} is also used by node `{other}`"),
        Unique::PointIoa => format!("IOA {value} is also used by point `{other}`"),
        Unique::CommandIoa => format!("IOA {value} is also used by command `{other}`"),
        Unique::CommandOnPointIoa => format!("IOA {value} is also the address of point `{other}`"),
        Unique::DeviceAddress => format!("address {value} is used twice on line `{other}`"),
        Unique::LiftName => format!("duplicate lift name `{value}`"),
        Unique::FieldDeviceName => {
            format!("duplicate device name `{value}` (devices and lifts of a node need their own)")
        }
    }
}

fn unknown_value_text(what: Vocabulary, value: &str) -> String {
    match what {
        Vocabulary::TimeZone => {
            format!("unknown time zone `{value}` (an IANA name such as Europe/Prague)")
        }
        Vocabulary::TypeId => format!("unknown type `{value}`"),
        Vocabulary::RedundancyMode => format!(
            "unknown redundancy mode `{value}` (one of {})",
            iec60870::cs104::server::RedundancyMode::NAMES.join(", ")
        ),
        Vocabulary::Protocol => format!(
            "protocol `{value}`: a line is \"iec103\" (protection relays) or \"iec101\" (outstations)"
        ),
        Vocabulary::SimulatedDevice => format!(
            "no simulated IEC 103 device `{value}`; known: {}",
            quoted(&simulators::registry::names(simulators::registry::Speaks::Iec103))
        ),
        Vocabulary::Parity => format!("parity `{value}`: expected even, odd or none"),
        Vocabulary::SimulatedLift => format!(
            "no simulated lift board `{value}`; known: {}",
            quoted(&simulators::registry::names(simulators::registry::Speaks::Ekm66))
        ),
        Vocabulary::StatusLayout => format!(
            "status layout `{value}`: expected \"any\" (both, by the length octet), \"adopted\" (20 octets) or \"alternative\" (21 octets)"
        ),
        Vocabulary::TimeCoding => {
            format!("time coding `{value}`: expected \"binary\" or \"bcd\"")
        }
        Vocabulary::CommandAge => format!(
            "max_command_age_ms `{value}`: expected milliseconds (default 30000) or \"off\" (no limit)"
        ),
    }
}

fn out_of_range_text(what: &str, value: i64, min: i64, max: Option<i64>) -> String {
    // The common address has two reserved values a reader may not know of.
    let note = if what == "common address" {
        " (0 is unused, 65535 is broadcast)"
    } else {
        ""
    };
    match max {
        Some(max) => format!("{what} {value} is outside {min}..={max}{note}"),
        None => format!("{what} must be at least {min}"),
    }
}

fn malformed_text(text: &str, form: &Form) -> String {
    match form {
        Form::IpAddress => format!("`{text}` is not an IP address"),
        Form::SocketAddress => format!("`{text}` is not an IP:PORT address"),
        Form::LinkRef => format!("`{text}` is not of the form link:LINK/IOA"),
        Form::LineRef => format!(
            "`{text}` is not of the form line:LINE/DEVICE/FUN/INF or line:LINE/DEVICE/FUN/INF/INDEX (IEC 103) or line:LINE/DEVICE/IOA (IEC 101)"
        ),
        Form::LineIoa { given } => {
            format!("`{text}`: IOA `{given}` is not an address 0..=16777215")
        }
        Form::LineNumber { part, given } => {
            format!("`{text}`: {part} `{given}` is not a number 0..=255")
        }
    }
}

fn wrong_type_text(type_id: &str, usage: &TypeUse) -> String {
    const SINGLE: &str = "must be M_SP_NA_1 or M_SP_TB_1";
    match usage {
        TypeUse::Point => format!("{type_id} is not a type a point can be declared with (single, double, step, bitstring, measured values, integrated totals: M_SP_*, M_DP_*, M_ST_*, M_BO_*, M_ME_*, M_IT_*)"),
        TypeUse::Command => format!("{type_id} is not a command type"),
        TypeUse::LinkStatus { link } => format!("the status point of link `{link}` {SINGLE}"),
        TypeUse::GroupStatus { group } => {
            format!("the status point of redundancy group `{group}` {SINGLE}")
        }
        TypeUse::LineStatus { point } => format!("the status point `{point}` {SINGLE}"),
        TypeUse::LineIndication => format!(
            "an indication of a line device needs a single or double point type, not {type_id}"
        ),
        TypeUse::LineMeasurand => format!(
            "a measurand of a line device needs a measurement type (M_ME_*), not {type_id}"
        ),
        TypeUse::LineCommand => format!(
            "a command to a line device is C_SC_NA_1 or C_DC_NA_1 (a general command ON/OFF), not {type_id}"
        ),
        TypeUse::ScaleFactor => format!(
            "scale_factor is for scaled values (M_ME_NB_1, M_ME_TB_1, M_ME_TE_1), not {type_id}"
        ),
        TypeUse::Deadband => {
            format!("a deadband needs a measurement type (M_ME_*), not {type_id}")
        }
        TypeUse::Range => format!("range applies to set-points, not {type_id}"),
        TypeUse::Storage => format!(
            "a storage deadband or rate limit thins out numbers (measurements, step positions, integrated totals), not {type_id}: every change of it is stored"
        ),
    }
}

fn missing_text(what: &str, needed_by: &str, hint: &str) -> String {
    let mut text = if needed_by.is_empty() {
        format!("missing {what}")
    } else {
        format!("{needed_by} needs {what}")
    };
    if !hint.is_empty() {
        text.push_str(&format!(" ({hint})"));
    }
    text
}

/// `"a", "b"`: names as a message lists them.
fn quoted(names: &[&str]) -> String {
    names
        .iter()
        .map(|name| format!("\"{name}\""))
        .collect::<Vec<_>>()
        .join(", ")
}
