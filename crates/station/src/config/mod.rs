//! The project folder: `station.toml`, the ST sources it names, and every problem found in
//! them with `file:line:col`.
//!
//! [`Project::load`] reads `FOLDER/station.toml`, checks it and returns the typed model, or
//! [`ConfigErrors`] with *all* problems found. Each [`ConfigError`] names the file, the
//! 1-based line and column (in characters) of the offending value, its key path such as
//! `node[2].point[5].ioa` (array indices are 0-based, in file order) and a typed
//! [`ConfigProblem`] (module [`problem`]: an unknown reference, a duplicate, a value out of
//! range, a missing file, an ST compile error ...) that programs can match on; its
//! `Display` is `file:line:col: error: key: message`, the message being the problem's.
//! Only the first syntax error is reported, alone (what a recovering parser finds after it
//! mostly follows from it, and nothing else can be checked); a type error (a string where a
//! number belongs, an unknown key, a missing required key) stops before the semantic
//! checks, which then all run. At most [`MAX_ERRORS_PER_FILE`] problems are kept per file,
//! the rest counted ([`ConfigErrors::omitted`]).
//!
//! # Format
//!
//! ```toml
//! [station]
//! name = "Vsetín"
//! time_zone = "Europe/Prague"          # IANA name
//! store = "sqlite:events.sqlite"       # default; relative paths resolve against the project
//!                                      # folder; "sqlite::memory:" and postgres://... allowed;
//!                                      # "sqlite:events.sqlite?cache_mib=8" bounds the page
//!                                      # caches (default 64 MiB + 2 x 2 MiB)
//! retention_days = 60                  # default 60, >= 1
//! store_deadband_percent = 0.5         # optional default of numeric points without their own:
//!                                      # a change within 0.5 % of the last stored value is
//!                                      # sent, not stored
//! store_min_interval_ms = 1000         # optional default: at most one stored change of a
//!                                      # numeric point per second (1..=86_400_000)
//! port_base = 2404                     # default 2404; a node's server port = port_base + port_offset
//! bind = "127.0.0.1"                   # default; the address every node's server listens on
//! plant = "vsetin"                     # optional: which plant simulation drives the I/O
//!
//! [[node]]
//! name = "RH1.1"                       # unique
//! description = "main board concentrator (S7-1500)"   # optional
//! common_address = 11                  # 1..=65534
//! sources = ["plc/logo_board.st"]       # ST files relative to the project; must exist
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
//! max_command_age_ms = 10000           # time-tagged commands older (or further in the
//!                                      # future) than this are refused; default 30000,
//!                                      # "off" for no limit
//!
//! [[node.task]]
//! name = "fast"
//! interval_ms = 50                     # >= 1
//! priority = 1                         # 0..=255, default 0
//! programs = ["LogoBoard"]              # PROGRAM names declared in the node's sources
//! watchdog_ms = 200                    # optional
//!
//! [node.set]                           # optional: PLC values written after the cold start
//! "LightingBoard.Zpozdeni" = "T#2s"    # variable path = IEC literal
//!
//! [node.s7_server]                     # optional: the node's PLC memory served over S7, as an
//! port_offset = 100                    # S7-1500 serves its CPU's (LOGO! boards connect to it);
//! markers = 256                        # listens on port_base + port_offset; bytes of %M, %I,
//! inputs = 128                         # %Q served (defaults 256, 128, 128); a client's write
//! outputs = 128                        # is in the image at the next cycle's start, the bytes
//! pdu_size = 960                       # the PLC changes go out after it; points may read them
//!                                      # (source = "%MX20.0") and commands set markers
//!                                      # (target = "%MX24.0", pulse_ms)
//! [[node.s7_server.connection]]        # a client by the TSAP it calls (the thesis's S7
//! name = "RH2"                         # connections, section 3.3)
//! tsap = "0101"                        # four hex digits
//! status = "Concentrator.CommRH2"      # a BOOL kept TRUE while no such client is connected
//!
//! [[node.table]]                       # optional: a CSV file loaded into PLC arrays
//! file = "calendar/vsetin-weekly.csv"  # header row; `#` lines are comments
//! index = "week"                       # the column with each row's array index
//! columns = { off_utc = "LightingBoard.Osvetleni.sunrise_data" }   # cell -> path[index];
//!                                      # HH:MM[:SS] cells become TOD#HH:MM:SS literals
//!
//! [[node.io]]                          # plant signal <-> PLC variable; the pseudo-signal
//! signal = "RH2_P1_SA1_Dalkove"         # "module-fault:MODULE" is TRUE while that I/O
//!                                      # module is pulled or unreachable; or instead
//!                                      # point = "BAL.weight": a point of the node (a field
//!                                      # device's) read into the PLC, an input invalid
//!                                      # while the point is
//! scale = 1e6                          # optional: inputs are multiplied by it (grams to
//!                                      # micrograms for a DINT address)
//!                                      # or, real I/O: device = "LOGO_RH2" (a [[node.device]]
//!                                      # with items, e.g. kind "s7"), item = "I0.1" and
//!                                      # direction = "input" | "output"
//! variable = "LogoBoard.SA1_Dalkove"    # or a direct address of the process image
//!                                      # (`%IX0.4`, `%ID4`, `%QX1.2`) for a program that
//!                                      # reads its I/O through `AT` variables; a REAL
//!                                      # signal is rounded into an integer address
//!
//! [[node.point]]
//! name = "RH2_V1_FA1_Zapnut"           # unique per node
//! type = "M_SP_TB_1"                   # a monitor-direction type (1..=40)
//! ioa = 281                            # 1..=16_777_215, unique per node among points
//! source = "LogoBoard.FA1_Zapnut"       # a PLC variable path, or "link:LINK/IOA": the point
//!                                      # IOA of the node behind the link LINK of this node;
//!                                      # omitted for a link's status_point (M_SP_NA_1 or
//!                                      # M_SP_TB_1, TRUE = link down); or a direct address
//!                                      # of the process image (`%IX0.0`): the input, whatever
//!                                      # program a lab loads into the node
//! transmission = "spontaneous"         # spontaneous (default) | cyclic | interrogation-only
//! cycle_ms = 1000                      # required with (and only with) cyclic
//! groups = [1, 3]                      # interrogation groups 1..=16; default none
//! deadband = 0.5                       # measurements (M_ME_*) only; absolute, >= 0
//! store_deadband = 0.2                 # numeric points (M_ME_*, M_ST_*, M_IT_*): what the
//!                                      # history keeps; absolute, >= 0; or
//!                                      # store_deadband_percent = 1 (of the last stored value)
//! store_min_interval_ms = 60000        # numeric points: at most one stored change a minute
//!                                      # (a change of quality and answers always stored)
//! invalid_when = "RDRTIO.PoruchaModul9" # optional BOOL variable: TRUE sends the point IV
//! description = "breaker FA1 closed"   # optional
//!
//! [[node.command]]
//! name = "RH2_VypnoutQF1"              # unique per node
//! type = "C_SC_NA_1"                   # a command type (45..=64)
//! ioa = 2021                           # unique per node among commands
//! target = "LogoBoard.Cmd_VypnoutQF1"   # a PLC variable, or "link:LINK/IOA" to forward it down
//! select_required = false              # default false
//! remote_enable = "LogoBoard.SA1_Dalkove"   # optional BOOL variable; FALSE (local mode):
//!                                          # remote commands are refused
//! pulse_ms = 500                       # optional, single/double commands on a variable:
//!                                      # reset to FALSE after this time
//! from_groups = ["hmi"]                # optional: only clients of these redundancy groups
//! max_age_ms = 5000                    # optional: this command's own maximum command delay
//! range = [0, 1439]                    # optional, set-points: values outside are refused
//!                                      # (negative ACT_CON, audited), never clamped
//! feedback = "RH2_QF1_Position"        # optional, commands on a PLC variable or an IEC 103
//!                                      # general command: the point of this node that
//!                                      # returns the command's effect; its first change
//!                                      # after an execute is sent as return information
//!                                      # (cause 11) between ACT_CON and ACT_TERM; for a
//!                                      # general command, default: the point read from the
//!                                      # device at the command's own FUN/INF
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
//!
//! [[node.line]]                        # a serial line this node polls as IEC 103 master
//! name = "relays"                      # (the gateway role: its devices' signals become
//!                                      # this node's points); unique per node
//! protocol = "iec103"                  # the only protocol for now
//! simulate = "ref630"                  # exactly one of: port = "/dev/ttyUSB0",
//!                                      # tcp = "host:port" (terminal server), simulate =
//!                                      # "ref630" (the thesis's relay at each device's
//!                                      # address, inside this process; console: `relay
//!                                      # DEVICE local|remote|inject I U|fault|...`)
//! baud = 9600                          # default 9600 (1200..=115200); parity = "even"
//!                                      # (default), stop_bits = 1
//! timeout_ms = 500                     # response timeout, default 500 (5..=60000)
//! retries = 2                          # default 2 (0..=10)
//! poll_interval_ms = 100               # class 2 polls of a device, default 100
//! status_point = "COMM_LINE"           # optional: a single point, TRUE while no device answers
//!
//! [[node.line.device]]
//! name = "F1"                          # unique per line
//! address = 1                          # link and common address 1..=254, unique per line
//! status_point = "COMM_F1"             # optional: a single point, TRUE while the device
//!                                      # does not answer (then its points are IV)
//! local_indication = [1, 190]          # optional FUN, INF of its LOCAL/REMOTE indication:
//!                                      # commands are refused while it is ON
//!
//! [[node.lift]]                        # a lift watched through its Rekoba EKM66 board
//! name = "L1"                          # unique per node; its points are L1.status ...
//! description = "Nádražní 12, goods lift"   # optional
//! floors = 6                           # 2..=60
//! ioa_base = 1000                      # its points at 1000 + offset (docs/LIFT.md):
//!                                      # status, colour, position, target, direction,
//!                                      # door, not_answering, out_of_service,
//!                                      # inspection, last_fault, errors, faults, trips
//!                                      # (+0..+12) and floorN_trips (+16 + N - 1)
//! port = "/dev/ttyUSB0"                # exactly one of port, tcp = "host:port" (an
//!                                      # RS-232-to-Ethernet converter), simulate = "ekm66"
//!                                      # (a simulated board in this process; console:
//!                                      # `lift L1 fault 0x12`, `lift L1 silent` ...)
//! baud = 9600                          # default 9600; parity = "even" (default), stop_bits = 1
//! timeout_ms = 500                     # reply time-out, default 500 (5..=60000)
//! retries = 3                          # default 3 (0..=10)
//! poll_period_ms = 1000                # status query period, default 1000
//! counters_period_ms = 60000           # trip-counter query period, default 60000
//! status_layout = "any"                # any (default) | adopted (20 octets) | alternative (21)
//! counter_width = 1                    # octets per trip counter: 1 (default), 2 or 4
//! time_coding = "binary"               # binary (default) | bcd
//! year_base = 2000                     # default 2000
//! direction = [0, 1, 2]                # the board's codes for stopped, up, down
//! index_base = 0                       # the fault stack's first index, 0 or 1; default: detected
//! fault_stack = 16                     # simulate only: slots of the fault stack (default 16)
//! seed = 1                             # simulate only: the random source (default: lift's position)
//! speed = 1.0                          # simulate only: board seconds per second
//! fault_probability = 0.05             # simulate only: chance of a fault after a trip
//!
//! [[node.device]]                      # a device of a registered kind (crate::device)
//! name = "B1"                          # unique among the node's devices and lifts
//! kind = "balance"                     # a kind the loader was given (DeviceKinds; built in:
//!                                      # balance, crate::device::balance)
//! description = "sorting lab scale"    # optional
//! ioa_base = 500                       # its points: B1.SIGNAL at ioa_base + the profile's
//!                                      # offsets, and B1.not_answering
//! settings = { serial = "/dev/ttyUSB1" } # the kind's own settings, checked at load (a
//!                                      # balance: serial, tcp or simulate = "red 1"); or
//!                                      # plant = "PORT": a serial port of the project's plant
//!                                      # (the sorter's `balance`), on a pseudo-terminal the
//!                                      # runtime opens, read as through `serial`; an `s7`
//!                                      # device: connect = "host[:port]" or "node:NAME",
//!                                      # rack/slot or tsap, cycle_ms, write_every_ms,
//!                                      # timeout_ms; a `modbus` device: tcp or serial (baud,
//!                                      # parity), unit, cycle_ms, ...; their items are bound
//!                                      # by [[node.io]] device = ... (crate::device::s7,
//!                                      # crate::device::modbus)
//!
//! [node.notify.smtp]                   # optional: notifications of the node's lifts
//! host = "smtp.example.cz"             # (the notify crate's format, docs/LIFT.md):
//! security = "starttls"                # none | starttls (default) | tls; port follows
//! user = "stanice"                     # optional, with password_env = "VARIABLE"
//! password_env = "STANICE_SMTP_PASSWORD"   # (or password = "...")
//! from = "Stanice <stanice@example.cz>"
//!
//! [node.notify.channel.technicians]    # a named channel
//! kind = "email"
//! to = ["novak@example.cz"]
//!
//! [node.notify.channel.tickets]
//! kind = "webhook"                     # a JSON POST of each notice
//! url = "https://tickets.example.cz/api/hook"
//!
//! [[node.notify.rule]]
//! name = "safety"
//! sources = ["L*"]                     # lift names (globs), default all
//! classes = ["safety-circuit", "door-sequence", "comm-lost"]   # fault groups (docs/LIFT.md)
//!                                      # and comm-lost; default all
//! channels = ["technicians", "tickets"]
//! quiet_period_s = 900                 # the same lift and class again within it: suppressed
//! rate_limit = { max = 10, per_s = 3600 }   # at most 10 notices an hour by this rule
//!
//! [mqtt]                               # optional: every node an MQTT Sparkplug B edge node
//! url = "mqtts://broker.example:8883"  # mqtt:// or mqtts:// (default ports 1883, 8883)
//! ca = "tls/broker-ca.pem"             # optional, mqtts:// only: the broker's CA (PEM)
//! username = "station"                 # optional
//! password = "secret"                  # optional, needs username
//! primary_host = "scada"               # optional: publish only while its STATE is online
//! group = "vsetin"                     # optional: the group id; default the station's name
//! redundancy_group = "dispatch"        # default: the redundancy group hosts' commands count
//!                                      # as (authority, from_groups), audited as MQTT host
//! ```
//!
//! Points and commands name a line device's signals: `source = "line:LINE/DEVICE/FUN/INF"`
//! (an indication, for M_SP_* and M_DP_* points: ON is DPI 2), `source =
//! "line:LINE/DEVICE/FUN/INF/INDEX"` (the INDEX-th value of the measurand set FUN/INF,
//! for M_ME_* points, with `measurand_limit = 240.0`, the engineering value at fraction
//! 1.0, and for normalized points optionally `full_scale`; without it the engineering
//! value goes as the raw integer, as the COM600 sent it), `target =
//! "line:LINE/DEVICE/FUN/INF"` (C_SC_NA_1 or C_DC_NA_1: a general command ON/OFF, its
//! acknowledgement becomes the confirmation; `line:LINE/DEVICE/FUN/INF=OFF` sends OFF
//! whatever the command's value, as a single command ON that opens). Scaled points
//! take `scale_factor` (the integer sent is the engineering value times it).
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
//! and socket addresses; unsupported store URLs; an `[mqtt]` url that is not
//! `mqtt://`/`mqtts://`, a `ca` missing or with `mqtt://`, a `password` without `username`,
//! a `primary_host` or `group` that cannot stand in a Sparkplug topic. ST sources must be UTF-8 (a leading
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

//!
//! # Layout
//!
//! The model (what a loaded project is) is here; `raw` holds the file as serde reads it,
//! `spans` the key paths and their positions, `error` where problems are, `problem` what
//! they are, and `check` turns the raw file into the model: the station and the order of
//! things in `check`, one node in `check::node`, the links between nodes in
//! `check::links`, serial lines in `check::line`. `hosts` is the deployment overlay: a
//! hosts file ([`HostsFile`]) saying on which address each node runs and which addresses
//! stand for the project's client addresses, applied by [`Project::with_hosts`].
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
    /// The `[mqtt]` table: the nodes publish as Sparkplug B edge nodes.
    pub mqtt: Option<MqttConfig>,
}

/// The `[mqtt]` table: the broker the nodes publish to as Sparkplug B edge nodes (group
/// id the station's name, edge node id the node's name); `--mqtt URL` makes one with
/// only the URL.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MqttConfig {
    /// `mqtt://HOST[:PORT]` or `mqtts://HOST[:PORT]`.
    pub url: String,
    /// The CA certificate (PEM) of a `mqtts://` broker, resolved against the project folder.
    pub ca: Option<PathBuf>,
    /// User name.
    pub username: Option<String>,
    /// Password.
    pub password: Option<String>,
    /// The primary host application whose STATE must be online for the nodes to publish.
    pub primary_host: Option<String>,
    /// The group id instead of the station's name.
    pub group: Option<String>,
    /// The redundancy group hosts' commands count as (default `dispatch`).
    pub redundancy_group: Option<String>,
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
    /// Which changes the history keeps of points without a setting of their own
    /// (`store_deadband_percent`, `store_min_interval_ms`); already applied to every
    /// point's [`PointConfig::storage`].
    pub storage: points::StorageRule,
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
    /// The address of the host the node runs on, from a deployment's hosts file
    /// ([`Project::with_hosts`], `stanice run --hosts`): its servers listen there and links
    /// to it connect there. `None`: the station's `bind` (every node on one machine).
    pub host: Option<IpAddr>,
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
    /// Serial lines the node polls as master (the gateway role).
    pub lines: Vec<LineConfig>,
    /// Lifts the node watches through their controller boards (`[[node.lift]]`); their
    /// points are among [`NodeConfig::points`].
    pub lifts: Vec<LiftConfig>,
    /// Devices of registered kinds (`[[node.device]]`); their points are among
    /// [`NodeConfig::points`].
    pub devices: Vec<FieldDeviceConfig>,
    /// Who is told of what its lifts report (`[node.notify]`: SMTP server, channels,
    /// rules), checked.
    pub notify: Option<notify::NotifyConfig>,
    /// Values written into the PLC after its cold start (variable path -> IEC literal):
    /// parameters such as a board's switch-on delay.
    pub initial_values: Vec<(String, String)>,
    /// Data tables loaded into PLC arrays after the cold start.
    pub tables: Vec<TableConfig>,
    /// The node's PLC memory served over S7 (`[node.s7_server]`).
    pub s7_server: Option<S7ServerConfig>,
}

/// `[node.s7_server]`: the node's soft PLC served over S7 (ISO-on-TCP) as an S7 CPU
/// serves its memory, so that LOGO! boards connect to it as to the thesis's S7-1500
/// concentrators (the railway-station thesis, section 3.3): a client's writes land in the
/// PLC's process image (`%M`, `%I`, `%Q`) at the start of its next cycle, and reads see
/// the image as the last cycle left it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct S7ServerConfig {
    /// Listens on the station's `bind` address, port `port_base + port_offset`.
    pub port_offset: u16,
    /// Bytes of the process image served: inputs, outputs, markers.
    pub inputs: usize,
    /// Bytes of outputs served.
    pub outputs: usize,
    /// Bytes of markers served.
    pub markers: usize,
    /// The largest PDU granted (an S7-1500 offers 960; a LOGO! asks 240).
    pub pdu_size: u16,
    /// The S7 connections the project expects, by the TSAP their clients call.
    pub connections: Vec<S7ConnectionConfig>,
}

/// `[[node.s7_server.connection]]`: one client of the S7 server (a LOGO! board).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct S7ConnectionConfig {
    /// Its name (`RH2`).
    pub name: String,
    /// The server TSAP the client calls (its remote TSAP, `0101`).
    pub tsap: u16,
    /// A BOOL of the node's PLC the server keeps TRUE while no client of this TSAP is
    /// connected (`NOT CommEnabled`, as a link's status point): the source of the
    /// connection's status point and the `invalid_when` of the points it feeds.
    pub status: Option<String>,
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
    /// The maximum command delay of time-tagged commands (`max_command_age_ms`,
    /// [`DEFAULT_MAX_COMMAND_AGE`] when not given); `None` when turned off.
    pub max_command_age: Option<Duration>,
    /// Events kept per redundancy group while none of its clients takes them
    /// (`event_buffer`, [`DEFAULT_EVENT_BUFFER`] when not given); past it the oldest go.
    pub event_buffer: usize,
}

/// The events a server keeps per redundancy group unless `event_buffer` says otherwise:
/// about 26 days of the Vsetín dispatch node's traffic (3,850 events a day), so an outage
/// of weeks replays whole. The memory is what the buffer holds: 64 bytes an event, the
/// allocation rounded up to a power of two, so a full default buffer takes 8.4 MB per
/// group (the soak's heap profile found these buffers growing in groups no client uses).
pub const DEFAULT_EVENT_BUFFER: usize = 100_000;

/// The largest `event_buffer` a server accepts.
pub const MAX_EVENT_BUFFER: usize = 10_000_000;

/// The maximum command delay of a project's servers unless `max_command_age_ms` says
/// otherwise: a time-tagged command that waited longer in some queue (a slow WAN, a
/// replayed capture) is refused rather than carried out late.
pub const DEFAULT_MAX_COMMAND_AGE: Duration = Duration::from_secs(30);

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

impl RedundancyGroup {
    /// The group a client at `ip` belongs to, chosen as the server chooses it: the first
    /// group naming its address, else the first catch-all group.
    pub fn of_client(groups: &[RedundancyGroup], ip: Option<IpAddr>) -> Option<&RedundancyGroup> {
        groups
            .iter()
            .find(|g| ip.is_some_and(|ip| g.clients.contains(&ip)))
            .or_else(|| groups.iter().find(|g| g.clients.is_empty()))
    }
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

/// A plant signal or a point of the node bound to a PLC variable, `[[node.io]]`.
#[derive(Debug, Clone, PartialEq)]
pub struct IoBinding {
    /// Where the value comes from (or, for a plant output, goes to).
    pub source: IoSource,
    /// The PLC variable path, e.g. `LogoBoard.SA1_Dalkove`, or a direct address of the
    /// process image (`%ID4`).
    pub variable: String,
    /// A factor an input's value is multiplied by before the PLC gets it.
    pub scale: Option<f64>,
}

/// The device setting that puts a device on a serial port of the project's plant
/// ([`FieldDeviceConfig::plant_port`]).
pub const PLANT_PORT_KEY: &str = "plant";

/// The other end of an I/O binding.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum IoSource {
    /// A signal of the project's plant (its direction decides which way the value goes),
    /// or the pseudo-signal `module-fault:MODULE`.
    Signal(String),
    /// A point of the node, read into the PLC (a field device's reading): the input is
    /// invalid while the point is.
    Point(String),
    /// An item of a field device of the node (real I/O in place of the plant's): read
    /// into the PLC (invalid while the device does not answer) or driven by it.
    Device {
        /// The device's name.
        device: String,
        /// The item (an S7 address, ...).
        item: String,
        /// Driven by the PLC.
        output: bool,
    },
}

impl std::fmt::Display for IoSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            IoSource::Signal(name) => write!(f, "signal `{name}`"),
            IoSource::Point(name) => write!(f, "point `{name}`"),
            IoSource::Device { device, item, .. } => {
                write!(f, "item `{item}` of device `{device}`")
            }
        }
    }
}

use crate::device::DeviceKinds;
/// Where a point's value comes from (the point database's type, so a source stays one
/// type from the project to the database).
pub use points::{LineSignal, PointSource};
use points::{PointKind, PointType, TimeStamp};

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
    /// Forwarded as it came (type, value, select/execute, time tag) to information object
    /// `ioa` of an IEC 101 outstation on a serial line.
    LineObject {
        /// The line's name.
        line: String,
        /// The device's name.
        device: String,
        /// The outstation's IOA.
        ioa: Ioa,
    },
    /// A general command (IEC 103 ASDU 20) to FUN/INF of a device on a serial line.
    Line {
        /// The line's name.
        line: String,
        /// The device's name.
        device: String,
        /// Function type.
        fun: u8,
        /// Information number.
        inf: u8,
        /// A fixed general command (`=ON`/`=OFF` after the reference: a single command
        /// ON that opens, as the thesis's "remote open"); `None` follows the command's
        /// own value.
        value: Option<bool>,
    },
}

/// How a point is transmitted: the point model's.
pub use points::Transmission;

/// A monitor-direction data point, `[[node.point]]`.
#[derive(Debug, Clone, PartialEq)]
pub struct PointConfig {
    /// Unique per node.
    pub name: String,
    /// The point's type (the project names it by its IEC monitor type, `M_SP_TB_1`;
    /// `points_iec::type_id` gives it back).
    pub point_type: PointType,
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
    /// For a measurand from a serial-line device: how its fraction becomes the value.
    pub scaling: Option<MeasurandScaling>,
    /// Which of its changes the history keeps (`store_deadband`,
    /// `store_deadband_percent`, `store_min_interval_ms`, over the station's defaults; a
    /// device signal that changes on every poll while something is wrong brings its own).
    pub storage: points::StorageRule,
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

/// How an IEC 103 measurand (a fraction of the device's limit) becomes a point's value:
/// the engineering value is `fraction * limit`; a float point carries it, a scaled point
/// its rounded integer, a normalized point `value / full_scale`, or without `full_scale`
/// the engineering value as the raw integer (what the COM600 of the thesis sent, spec
/// IEC-A4).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeasurandScaling {
    /// The engineering value at fraction 1.0 (the device's MaxIL1, MaxUL1 ...).
    pub limit: f64,
    /// The engineering value at normalized 1.0, for normalized points.
    pub full_scale: Option<f64>,
    /// For scaled points: the integer sent is `round(value * factor)` (default 1).
    pub factor: Option<f64>,
}

/// Where a serial line is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum LineTransport {
    /// A serial port device.
    Serial(String),
    /// A terminal server over TCP (`host:port`).
    Tcp(String),
    /// Simulated devices inside this process (`ref630`: the thesis's relay at each
    /// device's address), operated from the console (`relay DEVICE local`, ...).
    Simulated(String),
}

/// A device on a serial line, `[[node.line.device]]`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DeviceConfig {
    /// Unique on its line.
    pub name: String,
    /// Link address, 1..=254.
    pub address: u8,
    /// Common address of ASDU (`common_address`; the link address when not given). IEC
    /// 103 devices use their link address.
    pub common_address: u16,
    /// A single point of the node, TRUE while the device does not answer.
    pub status_point: Option<String>,
    /// FUN/INF of the device's LOCAL/REMOTE indication: commands to the device are
    /// refused while it is ON.
    pub local_indication: Option<(u8, u8)>,
}

/// The protocol of a serial line.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum LineProtocol {
    /// IEC 60870-5-103 protection devices (`protocol = "iec103"`).
    Iec103,
    /// IEC 60870-5-101 outstations (`protocol = "iec101"`), with the line's field sizes.
    Iec101(Iec101Settings),
}

/// The field sizes of an IEC 101 line (`link_address_size`, `cot_size`,
/// `common_address_size`, `ioa_size`; defaults 1, 1, 1, 2).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Iec101Settings {
    /// The link address field: one or two octets.
    pub address_size: iec60870::ft12::AddressSize,
    /// Cause of transmission, common address and IOA sizes.
    pub params: iec60870::asdu::AsduParams,
}

/// A serial line the node polls as master, `[[node.line]]` (IEC 103 or IEC 101).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LineConfig {
    /// Unique per node.
    pub name: String,
    /// The protocol and what it needs.
    pub protocol: LineProtocol,
    /// Where it is.
    pub transport: LineTransport,
    /// Speed and character format.
    pub settings: iec60870::ft12::LineSettings,
    /// Response timeout.
    pub timeout: Duration,
    /// Repeats of an unanswered request.
    pub retries: u8,
    /// Least time between two class 2 polls of a device.
    pub poll_interval: Duration,
    /// A single point of the node, TRUE while no device of the line answers.
    pub status_point: Option<String>,
    /// The devices.
    pub devices: Vec<DeviceConfig>,
}

/// Where a lift's controller board is reached.
#[derive(Debug, Clone, PartialEq)]
pub enum LiftTransport {
    /// A serial port (RS-232 in the machine room).
    Serial(String),
    /// An RS-232-to-Ethernet converter (`host:port`).
    Tcp(String),
    /// A simulated EKM66 board inside this process, operated from the console (`lift
    /// NAME fault 0x12`, ...).
    Simulated(devices::ekm66::simulator::SimulatorConfig),
}

/// A lift watched through its EKM66 controller board, `[[node.lift]]`: read-only, the
/// lift is never controlled. Its points are generated: `NAME.status`, `NAME.position`
/// ... at `ioa_base` + [`LiftSignal::offset`](points::LiftSignal::offset).
#[derive(Debug, Clone, PartialEq)]
pub struct LiftConfig {
    /// Unique per node; the prefix of its points' names.
    pub name: String,
    /// Free text (address, maker, type).
    pub description: String,
    /// Floors served, 1..=floors.
    pub floors: u8,
    /// The IOA of its first point.
    pub ioa_base: Ioa,
    /// Where the board is.
    pub transport: LiftTransport,
    /// The polling (periods, time-out, retries, line settings, reply decoders).
    pub poller: devices::ekm66::poller::PollerConfig,
}

/// A device of a registered kind, `[[node.device]]` (see [`crate::device`]). Its points
/// are generated from the kind's profile: `NAME.SIGNAL` at `ioa_base` + the signal's
/// offset, and `NAME.not_answering`.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldDeviceConfig {
    /// Unique per node among devices and lifts; the prefix of its points' names.
    pub name: String,
    /// The kind's name.
    pub kind: String,
    /// Free text.
    pub description: String,
    /// The IOA of its points' offset 0.
    pub ioa_base: Ioa,
    /// The kind's own settings (`[node.device.settings]`), read by its driver.
    pub settings: toml::Table,
    /// The serial port of the project's plant the device is on (`plant = "PORT"` in its
    /// settings): the runtime opens a pseudo-terminal for the port and gives the driver
    /// its path as `serial`.
    pub plant_port: Option<String>,
    /// The device's items the node's PLC reads and drives (`[[node.io]] device = ...`).
    pub io: Vec<crate::device::DeviceItem>,
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
        Project::load_with(folder, &DeviceKinds::builtin())
    }

    /// [`Project::load`] with the device kinds `kinds` (the built-in ones and any a
    /// program adds) for `[[node.device]]`.
    pub fn load_with(folder: &Path, kinds: &DeviceKinds) -> Result<Project, ConfigErrors> {
        let file = folder.join(PROJECT_FILE);
        let text = read_config_text(&file)?;
        Project::parse_with(folder, &file, &text, kinds)
    }

    /// Checks `text` as the project file `file` of `folder` (files it names are resolved
    /// against `folder`). [`Project::load`] reads the file and calls this; also useful for editors that check unsaved text.
    pub fn parse(folder: &Path, file: &Path, text: &str) -> Result<Project, ConfigErrors> {
        Project::parse_with(folder, file, text, &DeviceKinds::builtin())
    }

    /// [`Project::parse`] with the device kinds `kinds`.
    pub fn parse_with(
        folder: &Path,
        file: &Path,
        text: &str,
        kinds: &DeviceKinds,
    ) -> Result<Project, ConfigErrors> {
        let (tree, syntax) = DeTable::parse_recoverable(text);
        let mut ctx = Ctx {
            file: file.to_path_buf(),
            text,
            kinds,
            tree,
            errors: Vec::new(),
            omitted: Vec::new(),
        };
        // Only the first syntax error: the parser's recovery after it is a guess, and one
        // unclosed `[` made it report every later line (17,161 errors for the Vsetín file).
        if let Some(error) = syntax.first() {
            let span = error.span().unwrap_or(0..0);
            let detail = error.message().to_owned();
            ctx.push_at(span, String::new(), ConfigProblem::Syntax { detail });
            return Err(ctx.into_errors());
        }
        let raw: RawProject = match toml::from_str(text) {
            Ok(raw) => raw,
            Err(error) => {
                let span = error.span().unwrap_or(0..0);
                let key = ctx.key_at(span.start);
                let detail = error.message().to_owned();
                let kind = SchemaKind::of(&detail);
                ctx.push_at(span, key, ConfigProblem::Schema { kind, detail });
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

/// A configuration file's text (`station.toml`, a hosts file): unreadable or not UTF-8 is
/// an error naming the file.
fn read_config_text(file: &Path) -> Result<String, ConfigErrors> {
    let bytes = std::fs::read(file).map_err(|e| {
        ConfigErrors::single(ConfigError::unpositioned(
            file,
            ConfigProblem::Unreadable {
                file: None,
                kind: e.kind(),
                detail: e.to_string(),
            },
        ))
    })?;
    String::from_utf8(bytes).map_err(|e| ConfigErrors::single(not_utf8(file, e.as_bytes())))
}

impl NodeConfig {
    /// The node's server address, `HOST:port_base+port_offset` (HOST its [`host`](Self::host)
    /// or else the station's `bind`); `None` without a server or when the port passes 65535.
    pub fn server_address(&self, station: &StationSettings) -> Option<SocketAddr> {
        let server = self.server.as_ref()?;
        let port = station.port_base.checked_add(server.port_offset)?;
        Some(SocketAddr::new(self.listen_ip(station), port))
    }

    /// The address of the node's S7 server (`[node.s7_server]`), as
    /// [`server_address`](Self::server_address) says for its IEC 104 one; `None` without
    /// one or when the port passes 65535.
    pub fn s7_server_address(&self, station: &StationSettings) -> Option<SocketAddr> {
        let server = self.s7_server.as_ref()?;
        let port = station.port_base.checked_add(server.port_offset)?;
        Some(SocketAddr::new(self.listen_ip(station), port))
    }

    /// Where the node's servers listen: its host's address, or the station's `bind`.
    pub fn listen_ip(&self, station: &StationSettings) -> IpAddr {
        self.host.unwrap_or(station.bind)
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

mod check;
mod error;
mod hosts;
pub mod problem;
mod raw;
mod spans;

use error::*;
pub use error::{ConfigError, ConfigErrors, MAX_ERRORS_PER_FILE};
pub use hosts::{HostsFile, HostsProblem};
pub use problem::ConfigProblem;
use problem::*;
use raw::*;
use spans::*;
