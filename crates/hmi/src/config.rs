//! The screens folder: `hmi.toml`, `points.csv` and the SVG mimics (docs/HMI.md).

use std::collections::HashSet;
use std::path::{Path, PathBuf};

use iec60870::asdu::TypeId;
use serde::Deserialize;

use crate::HmiError;

/// One row of `points.csv`: what the station serves at an address.
#[derive(Debug, Clone, PartialEq)]
pub struct PointRow {
    /// Information object address.
    pub ioa: u32,
    /// IEC type.
    pub type_id: TypeId,
    /// Name.
    pub name: String,
    /// Description.
    pub description: String,
}

/// A mimic screen.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScreenConfig {
    /// URL-safe id.
    pub id: String,
    /// Title shown in the navigation.
    pub title: String,
    /// The SVG file, relative to the folder.
    pub file: PathBuf,
}

/// A control: who may use a command and how.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControlConfig {
    /// A command name of `points.csv`.
    pub command: String,
    /// Permission level needed, 0..=9.
    pub level: u8,
    /// Select-before-operate.
    #[serde(default)]
    pub select: bool,
    /// Text of the confirmation step.
    #[serde(default)]
    pub confirm: Option<String>,
    /// A single point that is TRUE while the target is in local mode: a refusal is then
    /// reported as "refused by local mode".
    #[serde(default)]
    pub local_point: Option<String>,
    /// The control authority the control needs: refused by the HMI itself (and audited)
    /// unless this point has this state, e.g. board controls only while the station's
    /// "HMI local" point says the authority is with this HMI (railway spec 9.2).
    #[serde(default)]
    pub authority: Option<AuthorityConfig>,
}

/// Which single point says that the HMI holds the control authority.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AuthorityConfig {
    /// A single point of `points.csv`.
    pub point: String,
    /// The state the point has while the authority is with this HMI (default TRUE).
    #[serde(default = "yes")]
    pub state: bool,
    /// The refusal's words when the point does not have the state (default: the control
    /// authority is not with this HMI), e.g. "manual switching is refused in automatic
    /// mode".
    #[serde(default)]
    pub reason: Option<String>,
}

/// Several set-points chosen together in one dialog, with a rule on the combination
/// (`[[choice]]`): the sorting lab's shaft colours, four different ones.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct ChoiceConfig {
    /// URL-safe id (`data-choice="ID"` on a mimic element opens it).
    pub id: String,
    /// The dialog's title.
    pub title: String,
    /// The set-point commands, one per field, sent in this order.
    pub commands: Vec<String>,
    /// The points showing each field's value now (optional, same order).
    #[serde(default)]
    pub points: Vec<String>,
    /// Each field's label (default: the command's description).
    #[serde(default)]
    pub labels: Vec<String>,
    /// The values a field may take.
    pub options: Vec<ChoiceOption>,
    /// Every field a different value.
    #[serde(default)]
    pub distinct: bool,
    /// Said while the combination is allowed.
    #[serde(default = "allowed_words")]
    pub allowed: String,
    /// Said while it is not (and the server's refusal).
    #[serde(default = "forbidden_words")]
    pub forbidden: String,
}

/// One value of a [`ChoiceConfig`] field.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct ChoiceOption {
    /// The number sent.
    pub value: i64,
    /// Its words.
    pub text: String,
}

fn allowed_words() -> String {
    "Allowed combination.".to_owned()
}

fn forbidden_words() -> String {
    "Forbidden combination!".to_owned()
}

impl ChoiceConfig {
    /// Whether `values` is a combination this choice allows: one known value per field,
    /// all different when `distinct`.
    pub fn allows(&self, values: &[i64]) -> bool {
        values.len() == self.commands.len()
            && values
                .iter()
                .all(|v| self.options.iter().any(|o| o.value == *v))
            && (!self.distinct
                || values
                    .iter()
                    .enumerate()
                    .all(|(i, v)| !values.iter().skip(i + 1).any(|w| w == v)))
    }
}

/// An alarm on a single point.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AlarmConfig {
    /// A single point of `points.csv`.
    pub point: String,
    /// The alarm is raised while the point has this value (default TRUE).
    #[serde(default = "yes")]
    pub when: bool,
    /// 1 (highest) ..= 4.
    pub priority: u8,
    /// Text shown.
    pub text: String,
    /// Whether it needs an operator acknowledgement.
    #[serde(default)]
    pub acknowledge: bool,
    /// Suppression by design (ISA-18.2): the alarm is suppressed while this point has
    /// this state (a feeder alarm while its board is under local control on purpose).
    #[serde(default)]
    pub suppress_when: Option<AlarmCondition>,
    /// The link point (`COMM_*`, TRUE while the link is lost) the alarm's point comes
    /// through: while it is TRUE, and for the settle time after it returns, the alarm is
    /// a consequence of the link's alarm and not raised on its own.
    #[serde(default)]
    pub link: Option<String>,
}

/// A single point having a state (`{ point = "...", state = true }`).
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AlarmCondition {
    /// A single point of `points.csv`.
    pub point: String,
    /// The state (default TRUE).
    #[serde(default = "yes")]
    pub state: bool,
}

/// A lift of the fleet the lift screens show (`[[lift]]`): its points are `NAME.status`,
/// `NAME.position`, ... of `points.csv` (the station's `[[node.lift]]` of the same name).
#[derive(Debug, Clone, PartialEq, Eq, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct LiftConfig {
    /// The lift's name: the prefix of its points (`L1` for `L1.status`).
    pub name: String,
    /// Free text (address, type).
    #[serde(default)]
    pub description: String,
    /// Floors served, 1..=floors (its `NAME.floorN_trips` counters).
    pub floors: u8,
}

/// The permission level (0..=9) each lift screen element needs (`[lift_levels]`, lift
/// spec 10). The server refuses the archive, export and figures requests below their
/// level; the browser hides what the user's level does not reach.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct LiftLevels {
    /// The fleet list.
    pub fleet: u8,
    /// The lift view (car, panel, trips per floor).
    pub lift: u8,
    /// The fault archive table.
    pub archive: u8,
    /// The CSV export of the archive.
    pub export: u8,
    /// The service figures.
    pub figures: u8,
    /// The record of the notifications sent (who was told what, when).
    pub notifications: u8,
}

impl Default for LiftLevels {
    fn default() -> Self {
        LiftLevels {
            fleet: 0,
            lift: 0,
            archive: 0,
            export: 3,
            figures: 3,
            notifications: 3,
        }
    }
}

impl LiftLevels {
    fn all(&self) -> [(&'static str, u8); 6] {
        [
            ("fleet", self.fleet),
            ("lift", self.lift),
            ("archive", self.archive),
            ("export", self.export),
            ("figures", self.figures),
            ("notifications", self.notifications),
        ]
    }
}

fn yes() -> bool {
    true
}

fn default_level() -> u8 {
    5
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawConfig {
    title: String,
    #[serde(default)]
    local_address: Option<std::net::IpAddr>,
    #[serde(default)]
    time_zone: Option<String>,
    #[serde(default)]
    sign_in_note: Option<String>,
    #[serde(default = "default_level")]
    default_control_level: u8,
    #[serde(default)]
    screen: Vec<ScreenConfig>,
    #[serde(default)]
    control: Vec<ControlConfig>,
    #[serde(default)]
    alarm: Vec<AlarmConfig>,
    #[serde(default)]
    trend: Vec<TrendConfig>,
    #[serde(default)]
    lift: Vec<LiftConfig>,
    #[serde(default)]
    lift_levels: LiftLevels,
    #[serde(default)]
    lease: Option<crate::lease::LeaseConfig>,
    #[serde(default)]
    camera: Option<String>,
    #[serde(default)]
    program: Option<crate::trial::ProgramConfig>,
    #[serde(default)]
    choice: Vec<ChoiceConfig>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TrendConfig {
    point: String,
}

/// A loaded screens folder.
#[derive(Debug, Clone)]
pub struct HmiConfig {
    /// The folder.
    pub folder: PathBuf,
    /// Station title.
    pub title: String,
    /// Level for controls not listed.
    pub default_control_level: u8,
    /// The local address the HMI connects to the station from (`local_address`): a
    /// station gives its HMI a redundancy group by address, with the HMI's command
    /// authority. `None`: the system chooses.
    pub local_address: Option<std::net::IpAddr>,
    /// The zone of the station's time tags (`time_zone`: an IANA name, `UTC` or
    /// `local`), as its project's `time_zone` says; `None`: not given (UTC then).
    pub time_zone: Option<iec60870::time::TimeZonePolicy>,
    /// What the station's banner tells about signing in (`sign_in_note`: an example's
    /// users and passwords, say); `None`: nothing.
    pub sign_in_note: Option<String>,
    /// Screens, in navigation order.
    pub screens: Vec<ScreenConfig>,
    /// Controls.
    pub controls: Vec<ControlConfig>,
    /// Alarms.
    pub alarms: Vec<AlarmConfig>,
    /// Points kept for trends.
    pub trends: Vec<String>,
    /// The station's points and commands.
    pub points: Vec<PointRow>,
    /// The lift fleet of the lift screens (none: no lift screens).
    pub lifts: Vec<LiftConfig>,
    /// The levels of the lift screens' elements.
    pub lift_levels: LiftLevels,
    /// The operator lease (`[lease]`): one controlling user at a time.
    pub lease: Option<crate::lease::LeaseConfig>,
    /// A camera's picture or stream (`camera = "http://..."`, an MJPEG stream or a
    /// still), shown beside the screens.
    pub camera: Option<String>,
    /// Students' programs tried from the browser (`[program]`).
    pub program: Option<crate::trial::ProgramConfig>,
    /// Set-points chosen together (`[[choice]]`).
    pub choices: Vec<ChoiceConfig>,
}

impl HmiConfig {
    /// Loads `folder/hmi.toml` and `folder/points.csv` and checks the references between
    /// them; errors name the file (and line for TOML and CSV).
    pub fn load(folder: &Path) -> Result<HmiConfig, HmiError> {
        let file = folder.join("hmi.toml");
        let text = std::fs::read_to_string(&file)
            .map_err(|e| HmiError::Config(format!("{}: {e}", file.display())))?;
        let raw: RawConfig = toml::from_str(&text).map_err(|e| {
            let (line, column) = e
                .span()
                .map(|span| line_col(&text, span.start))
                .unwrap_or((0, 0));
            HmiError::Config(format!(
                "{}:{line}:{column}: {}",
                file.display(),
                e.message()
            ))
        })?;
        let points = load_points(&folder.join("points.csv"))?;
        let config = HmiConfig {
            folder: folder.to_path_buf(),
            title: raw.title,
            default_control_level: raw.default_control_level.min(9),
            local_address: raw.local_address,
            sign_in_note: raw.sign_in_note,
            time_zone: match &raw.time_zone {
                None => None,
                Some(name) => Some(name.parse().map_err(|_| {
                    HmiError::Config(format!(
                        "{}: time_zone {name:?} is no IANA zone name, UTC or local",
                        file.display()
                    ))
                })?),
            },
            screens: raw.screen,
            controls: raw.control,
            alarms: raw.alarm,
            trends: raw.trend.into_iter().map(|t| t.point).collect(),
            points,
            lifts: raw.lift,
            lift_levels: raw.lift_levels,
            lease: raw.lease,
            camera: raw.camera,
            program: raw.program,
            choices: raw.choice,
        };
        config.check(&text)?;
        Ok(config)
    }

    /// Checks the references; an error names `file:line:col` of the entry at fault.
    fn check(&self, text: &str) -> Result<(), HmiError> {
        let file = self.folder.join("hmi.toml");
        let bad_at = |table: &str, index: usize, key: &str, message: String| {
            let (line, column) = locate(text, table, index, key);
            HmiError::Config(format!("{}:{line}:{column}: {message}", file.display()))
        };
        let names: HashSet<&str> = self.points.iter().map(|p| p.name.as_str()).collect();
        let commands: HashSet<&str> = self
            .points
            .iter()
            .filter(|p| p.type_id.is_command())
            .map(|p| p.name.as_str())
            .collect();
        let mut ids = HashSet::new();
        for (index, screen) in self.screens.iter().enumerate() {
            let bad = |key: &str, message: String| bad_at("screen", index, key, message);
            if screen.id.is_empty()
                || !screen
                    .id
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
            {
                return Err(bad(
                    "id",
                    format!("screen id `{}` is not URL-safe", screen.id),
                ));
            }
            if !ids.insert(screen.id.as_str()) {
                return Err(bad("id", format!("duplicate screen id `{}`", screen.id)));
            }
            let path = self.folder.join(&screen.file);
            if !path.is_file() {
                return Err(bad(
                    "file",
                    format!(
                        "screen `{}`: file {} not found",
                        screen.id,
                        screen.file.display()
                    ),
                ));
            }
            // A broken drawing is an error at its line and column now, not a blank
            // screen in an operator's browser later.
            let svg = std::fs::read_to_string(&path)
                .map_err(|error| HmiError::Config(format!("{}: {error}", path.display())))?;
            if let Err(error) = mimic_svg::clean(&svg) {
                return Err(HmiError::Config(format!(
                    "{}:{}:{}: screen `{}`: {}",
                    path.display(),
                    error.line,
                    error.column,
                    screen.id,
                    error.message
                )));
            }
        }
        let single = |name: &str| {
            self.points.iter().any(|p| {
                p.name == name
                    && matches!(
                        p.type_id,
                        TypeId::M_SP_NA_1 | TypeId::M_SP_TA_1 | TypeId::M_SP_TB_1
                    )
            })
        };
        for (index, control) in self.controls.iter().enumerate() {
            let bad = |key: &str, message: String| bad_at("control", index, key, message);
            if !commands.contains(control.command.as_str()) {
                return Err(bad(
                    "command",
                    format!("control `{}` is no command of points.csv", control.command),
                ));
            }
            if control.level > 9 {
                return Err(bad(
                    "level",
                    format!("control `{}`: level above 9", control.command),
                ));
            }
            if let Some(local) = &control.local_point {
                if !names.contains(local.as_str()) {
                    return Err(bad(
                        "local_point",
                        format!("control `{}`: no point `{local}`", control.command),
                    ));
                }
            }
            if let Some(authority) = &control.authority {
                if !single(&authority.point) {
                    return Err(bad(
                        "authority",
                        format!(
                            "control `{}`: authority point `{}` is no single point",
                            control.command, authority.point
                        ),
                    ));
                }
            }
        }
        for (index, alarm) in self.alarms.iter().enumerate() {
            let bad = |key: &str, message: String| bad_at("alarm", index, key, message);
            if !single(&alarm.point) {
                return Err(bad(
                    "point",
                    format!("alarm on `{}`: no single point of that name", alarm.point),
                ));
            }
            if !(1..=4).contains(&alarm.priority) {
                return Err(bad(
                    "priority",
                    format!("alarm on `{}`: priority is 1..=4", alarm.point),
                ));
            }
            if let Some(condition) = &alarm.suppress_when {
                if !single(&condition.point) {
                    return Err(bad(
                        "suppress_when",
                        format!(
                            "alarm on `{}`: suppression point `{}` is no single point",
                            alarm.point, condition.point
                        ),
                    ));
                }
            }
            if let Some(link) = &alarm.link {
                if !single(link) || link == &alarm.point {
                    return Err(bad(
                        "link",
                        format!(
                            "alarm on `{}`: link point `{link}` is no other single point",
                            alarm.point
                        ),
                    ));
                }
            }
        }
        let mut lift_names = HashSet::new();
        for (index, lift) in self.lifts.iter().enumerate() {
            let bad = |key: &str, message: String| bad_at("lift", index, key, message);
            if lift.name.is_empty()
                || !lift
                    .name
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
            {
                return Err(bad(
                    "name",
                    format!("lift name `{}` is not URL-safe", lift.name),
                ));
            }
            if !lift_names.insert(lift.name.as_str()) {
                return Err(bad("name", format!("duplicate lift `{}`", lift.name)));
            }
            if lift.floors == 0 {
                return Err(bad("floors", format!("lift `{}`: no floors", lift.name)));
            }
            let status = format!("{}.status", lift.name);
            if !names.contains(status.as_str()) {
                return Err(bad(
                    "name",
                    format!(
                        "lift `{}`: points.csv has no `{status}` (stanice points PROJECT writes it)",
                        lift.name
                    ),
                ));
            }
        }
        for (key, level) in self.lift_levels.all() {
            if level > 9 {
                let (line, column) = locate_key(text, "[lift_levels]", key);
                return Err(HmiError::Config(format!(
                    "{}:{line}:{column}: lift level `{key}` above 9",
                    file.display()
                )));
            }
        }
        for (index, trend) in self.trends.iter().enumerate() {
            if !names.contains(trend.as_str()) {
                return Err(bad_at(
                    "trend",
                    index,
                    "point",
                    format!("trend of `{trend}`: no such point"),
                ));
            }
        }
        let mut choice_ids = HashSet::new();
        for (index, choice) in self.choices.iter().enumerate() {
            let bad = |key: &str, message: String| bad_at("choice", index, key, message);
            if choice.id.is_empty()
                || !choice
                    .id
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
                || !choice_ids.insert(choice.id.as_str())
            {
                return Err(bad(
                    "id",
                    format!("choice id `{}` is not URL-safe or not unique", choice.id),
                ));
            }
            if choice.commands.is_empty() {
                return Err(bad("commands", "a choice needs its commands".into()));
            }
            if let Some(missing) = choice
                .commands
                .iter()
                .find(|c| !commands.contains(c.as_str()))
            {
                return Err(bad(
                    "commands",
                    format!("choice of `{missing}`: no such command in points.csv"),
                ));
            }
            if let Some(missing) = choice.points.iter().find(|p| !names.contains(p.as_str())) {
                return Err(bad(
                    "points",
                    format!("choice of `{missing}`: no such point in points.csv"),
                ));
            }
            for (key, count) in [
                ("points", choice.points.len()),
                ("labels", choice.labels.len()),
            ] {
                if count != 0 && count != choice.commands.len() {
                    return Err(bad(
                        key,
                        format!("{count} {key} for {} commands", choice.commands.len()),
                    ));
                }
            }
            if choice.options.is_empty() {
                return Err(bad("options", "a choice needs its options".into()));
            }
        }
        if let Some(camera) = &self.camera {
            if camera_origin(camera).is_none() {
                let line = text
                    .lines()
                    .position(|l| l.trim_start().starts_with("camera"))
                    .map_or(0, |index| index + 1);
                let column = 1;
                return Err(HmiError::Config(format!(
                    "{}:{line}:{column}: camera {camera:?} is no http:// or https:// URL",
                    file.display()
                )));
            }
        }
        Ok(())
    }

    /// The origin of the camera's URL (`http://host:port`), for the Content-Security-
    /// Policy that lets the page show it.
    pub fn camera_origin(&self) -> Option<String> {
        self.camera.as_deref().and_then(camera_origin)
    }

    /// The control settings of a command (the defaults when it is not listed).
    pub fn control(&self, command: &str) -> ControlConfig {
        self.controls
            .iter()
            .find(|c| c.command == command)
            .cloned()
            .unwrap_or(ControlConfig {
                command: command.to_owned(),
                level: self.default_control_level,
                select: false,
                confirm: None,
                local_point: None,
                authority: None,
            })
    }
}

/// Reads `points.csv` with the library's point-list reader (`stanice points` writes it:
/// `ioa,type,name,description`); every point needs a name of its own, the screens refer
/// to points by name.
fn load_points(file: &Path) -> Result<Vec<PointRow>, HmiError> {
    let text = std::fs::read_to_string(file)
        .map_err(|e| HmiError::Config(format!("{}: {e}", file.display())))?;
    let rows = iec60870::point_list::parse(&text)
        .map_err(|e| HmiError::Config(format!("{}:{e}", file.display())))?;
    let mut seen = HashSet::new();
    let mut monitor_ioas = HashSet::new();
    let mut points = Vec::with_capacity(rows.len());
    for row in rows {
        if row.name.is_empty() || !seen.insert(row.name.clone()) {
            return Err(HmiError::Config(format!(
                "{}:{}: empty or duplicate name `{}`",
                file.display(),
                row.line,
                row.name
            )));
        }
        // The monitor rows become the HMI's point database: one point per IOA, of a
        // type a point can have.
        if row.type_id.is_monitor() {
            if points_iec::point_type(row.type_id).is_none() {
                return Err(HmiError::Config(format!(
                    "{}:{}: `{}`: {} is not a type the HMI shows (single, double, step, bitstring, measured values, totals)",
                    file.display(),
                    row.line,
                    row.name,
                    row.type_id
                )));
            }
            if !monitor_ioas.insert(row.ioa.get()) {
                return Err(HmiError::Config(format!(
                    "{}:{}: `{}`: IOA {} is another point's too",
                    file.display(),
                    row.line,
                    row.name,
                    row.ioa
                )));
            }
        }
        points.push(PointRow {
            ioa: row.ioa.get(),
            type_id: row.type_id,
            name: row.name,
            description: row.description,
        });
    }
    Ok(points)
}

fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = text.get(..offset).unwrap_or(text);
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, column)
}

/// Where the `key` of the `index`-th `[[table]]` of a TOML text is: (line, column) of its
/// value, or of the table's header when the key is not written (a default). The parsed
/// configuration keeps no spans; the tables of `hmi.toml` are flat, so this finds them.
fn locate(text: &str, table: &str, index: usize, key: &str) -> (usize, usize) {
    let header = format!("[[{table}]]");
    let mut seen = 0;
    let mut found: Option<usize> = None;
    for (number, line) in text.lines().enumerate() {
        let trimmed = line.trim();
        if trimmed.starts_with('[') {
            if found.is_some() {
                break;
            }
            if trimmed == header {
                if seen == index {
                    found = Some(number);
                }
                seen += 1;
            }
            continue;
        }
        if found.is_none() {
            continue;
        }
        let Some(rest) = trimmed.strip_prefix(key) else {
            continue;
        };
        if let Some(value) = rest.trim_start().strip_prefix('=') {
            let value_at = line.len() - value.trim_start().len();
            return (
                number + 1,
                line.get(..value_at).map_or(1, |p| p.chars().count() + 1),
            );
        }
    }
    found.map_or((1, 1), |number| (number + 1, 1))
}

/// Where `key = ...` of the single table `header` (`[lift_levels]`) is: (line, column).
fn locate_key(text: &str, header: &str, key: &str) -> (usize, usize) {
    let mut inside = false;
    for (number, line) in text.lines().enumerate() {
        let trimmed = line.trim();
        if trimmed.starts_with('[') {
            inside = trimmed == header;
            continue;
        }
        if !inside {
            continue;
        }
        if let Some(rest) = trimmed.strip_prefix(key) {
            if rest.trim_start().starts_with('=') {
                return (number + 1, line.len() - trimmed.len() + 1);
            }
        }
    }
    (1, 1)
}

/// `scheme://host[:port]` of an http(s) URL whose host is plain (letters, digits, `.`, `-`,
/// `:` and brackets for IPv6): nothing that could end a CSP source or a header.
pub fn camera_origin(url: &str) -> Option<String> {
    let (scheme, rest) = url.split_once("://")?;
    if scheme != "http" && scheme != "https" {
        return None;
    }
    let host = rest.split(['/', '?', '#']).next().unwrap_or("");
    let plain = |c: char| c.is_ascii_alphanumeric() || matches!(c, '.' | '-' | ':' | '[' | ']');
    if host.is_empty()
        || !host.chars().all(plain)
        || url
            .chars()
            .any(|c| c.is_whitespace() || c == '"' || c == '\'')
    {
        return None;
    }
    Some(format!("{scheme}://{host}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_broken_screen_file_is_an_error_at_its_line_and_column() {
        let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("{e}"));
        let write = |name: &str, text: &str| {
            std::fs::write(dir.path().join(name), text).unwrap_or_else(|e| panic!("{e}"));
        };
        write(
            "points.csv",
            "ioa,type,name,description\n1,M_SP_NA_1,A,a point\n",
        );
        write(
            "hmi.toml",
            "title = \"Test\"\n[[screen]]\nid = \"main\"\ntitle = \"Main\"\nfile = \"main.svg\"\n",
        );
        write(
            "main.svg",
            "<svg xmlns=\"http://www.w3.org/2000/svg\">\n  <g>\n    <rect data-point=\"A\"/>\n  </h>\n</svg>\n",
        );
        let error = HmiConfig::load(dir.path()).err().map(|e| e.to_string());
        let error = error.unwrap_or_default();
        assert!(error.contains("main.svg:4:"), "{error}");
        assert!(error.contains("screen `main`"), "{error}");
    }

    #[test]
    fn a_choice_allows_known_values_and_with_distinct_no_repeats() {
        let choice = ChoiceConfig {
            id: "colours".into(),
            title: "Shaft colours".into(),
            commands: (1..=4).map(|k| format!("SET_Colour{k}")).collect(),
            points: Vec::new(),
            labels: Vec::new(),
            options: (1..=4)
                .map(|value| ChoiceOption {
                    value,
                    text: value.to_string(),
                })
                .collect(),
            distinct: true,
            allowed: allowed_words(),
            forbidden: forbidden_words(),
        };
        assert!(choice.allows(&[4, 3, 2, 1]));
        assert!(!choice.allows(&[1, 1, 3, 4]), "a repeated colour");
        assert!(!choice.allows(&[1, 2, 3, 5]), "an unknown value");
        assert!(!choice.allows(&[1, 2, 3]), "a field missing");
        let repeats = ChoiceConfig {
            distinct: false,
            ..choice
        };
        assert!(repeats.allows(&[1, 1, 1, 1]));
    }

    #[test]
    fn a_camera_url_gives_its_origin_and_nothing_that_could_break_a_header() {
        assert_eq!(
            camera_origin("http://192.0.2.20/mjpg/video.mjpg").as_deref(),
            Some("http://192.0.2.20")
        );
        assert_eq!(
            camera_origin("https://cam.lab.example:8443/still.jpg?size=640").as_deref(),
            Some("https://cam.lab.example:8443")
        );
        for bad in [
            "javascript:alert(1)",
            "ftp://cam/x",
            "http://",
            "http://cam; script-src *",
            "http://cam/x y",
            "http://ca'm/",
        ] {
            assert_eq!(camera_origin(bad), None, "{bad}");
        }
    }

    fn folder(toml: &str) -> tempfile::TempDir {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("points.csv"),
            "ioa,type,name,description\n1,M_SP_NA_1,Local,x\n2,C_SC_NA_1,Open,x\n",
        )
        .unwrap();
        std::fs::write(dir.path().join("hmi.toml"), toml).unwrap();
        dir
    }

    fn error_of(toml: &str) -> String {
        let dir = folder(toml);
        let error = HmiConfig::load(dir.path()).unwrap_err().to_string();
        let file = dir.path().join("hmi.toml").display().to_string();
        error.strip_prefix(&file).unwrap().to_owned()
    }

    #[test]
    fn errors_name_file_line_and_column() {
        // Broken TOML.
        assert!(
            error_of("title = \"x\"\n[[control]\n").starts_with(":2:"),
            "{}",
            error_of("title = \"x\"\n[[control]\n")
        );
        // A wrong reference: the line and column of the value at fault.
        let toml = "title = \"x\"\n\n[[control]]\ncommand = \"Open\"\nlevel = 1\n\n[[control]]\ncommand = \"Nothing\"\nlevel = 1\n";
        assert!(error_of(toml).starts_with(":8:11: "), "{}", error_of(toml));
        let toml = "title = \"x\"\n[[control]]\ncommand = \"Open\"\nlevel = 1\n  authority = { point = \"Open\" }\n";
        assert!(error_of(toml).starts_with(":5:15: "), "{}", error_of(toml));
        let toml = "title = \"x\"\n[[alarm]]\npoint = \"Local\"\ntext = \"t\"\npriority = 7\n";
        assert!(error_of(toml).starts_with(":5:12: "), "{}", error_of(toml));
        // Authority on a single point is accepted.
        let dir = folder("title = \"x\"\n[[control]]\ncommand = \"Open\"\nlevel = 1\nauthority = { point = \"Local\", state = true }\n");
        let config = HmiConfig::load(dir.path()).unwrap();
        assert_eq!(
            config.control("Open").authority.unwrap().point,
            "Local".to_owned()
        );
    }
}
