//! The project file as serde reads it, before any check.

use super::*;

// ---------------------------------------------------------------------------------------
// Raw (serde) model

pub(in crate::config) fn yes() -> bool {
    true
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(in crate::config) struct RawProject {
    pub(in crate::config) station: RawStation,
    #[serde(default)]
    pub(in crate::config) node: Vec<RawNode>,
    pub(in crate::config) mqtt: Option<RawMqtt>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(in crate::config) struct RawMqtt {
    pub(in crate::config) url: String,
    pub(in crate::config) ca: Option<String>,
    pub(in crate::config) username: Option<String>,
    pub(in crate::config) password: Option<String>,
    pub(in crate::config) primary_host: Option<String>,
    pub(in crate::config) group: Option<String>,
    pub(in crate::config) redundancy_group: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(in crate::config) struct RawStation {
    pub(in crate::config) name: String,
    pub(in crate::config) time_zone: String,
    pub(in crate::config) store: Option<String>,
    pub(in crate::config) retention_days: Option<u32>,
    pub(in crate::config) store_deadband_percent: Option<f64>,
    pub(in crate::config) store_min_interval_ms: Option<i64>,
    pub(in crate::config) port_base: Option<u16>,
    pub(in crate::config) bind: Option<String>,
    pub(in crate::config) plant: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(in crate::config) struct RawNode {
    pub(in crate::config) name: String,
    #[serde(default)]
    pub(in crate::config) description: String,
    pub(in crate::config) common_address: i64,
    #[serde(default)]
    pub(in crate::config) sources: Vec<String>,
    pub(in crate::config) server: Option<RawServer>,
    #[serde(default)]
    pub(in crate::config) task: Vec<RawTask>,
    #[serde(default)]
    pub(in crate::config) io: Vec<RawIo>,
    #[serde(default)]
    pub(in crate::config) point: Vec<RawPoint>,
    #[serde(default)]
    pub(in crate::config) command: Vec<RawCommand>,
    #[serde(default)]
    pub(in crate::config) link: Vec<RawLink>,
    #[serde(default)]
    pub(in crate::config) line: Vec<RawLine>,
    #[serde(default)]
    pub(in crate::config) lift: Vec<RawLift>,
    #[serde(default)]
    pub(in crate::config) device: Vec<RawFieldDevice>,
    pub(in crate::config) notify: Option<notify::NotifyConfig>,
    #[serde(default)]
    pub(in crate::config) set: std::collections::BTreeMap<String, String>,
    #[serde(default)]
    pub(in crate::config) table: Vec<RawTable>,
    pub(in crate::config) s7_server: Option<RawS7Server>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(in crate::config) struct RawS7Server {
    pub(in crate::config) port_offset: i64,
    pub(in crate::config) inputs: Option<i64>,
    pub(in crate::config) outputs: Option<i64>,
    pub(in crate::config) markers: Option<i64>,
    pub(in crate::config) pdu_size: Option<i64>,
    #[serde(default)]
    pub(in crate::config) connection: Vec<RawS7Connection>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(in crate::config) struct RawS7Connection {
    pub(in crate::config) name: String,
    pub(in crate::config) tsap: String,
    pub(in crate::config) status: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(in crate::config) struct RawTable {
    pub(in crate::config) file: String,
    pub(in crate::config) index: String,
    pub(in crate::config) columns: std::collections::BTreeMap<String, String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(in crate::config) struct RawServer {
    pub(in crate::config) port_offset: i64,
    #[serde(default)]
    pub(in crate::config) allowed_clients: Vec<String>,
    pub(in crate::config) redundancy_groups: Option<Vec<RawGroup>>,
    pub(in crate::config) tls: Option<RawTls>,
    pub(in crate::config) redundancy: Option<String>,
    pub(in crate::config) max_command_age_ms: Option<RawCommandAge>,
    pub(in crate::config) event_buffer: Option<i64>,
}

/// `max_command_age_ms`: milliseconds, or `"off"` for no limit.
#[derive(Deserialize)]
#[serde(untagged)]
pub(in crate::config) enum RawCommandAge {
    Millis(i64),
    Word(String),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(in crate::config) struct RawGroup {
    pub(in crate::config) name: String,
    #[serde(default)]
    pub(in crate::config) clients: Vec<String>,
    pub(in crate::config) refuse_commands_when: Option<String>,
    pub(in crate::config) status_point: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(in crate::config) struct RawTls {
    pub(in crate::config) certificate: String,
    pub(in crate::config) private_key: String,
    pub(in crate::config) trust_anchors: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(in crate::config) struct RawTask {
    pub(in crate::config) name: String,
    pub(in crate::config) interval_ms: u64,
    #[serde(default)]
    pub(in crate::config) priority: u8,
    #[serde(default)]
    pub(in crate::config) programs: Vec<String>,
    pub(in crate::config) watchdog_ms: Option<u64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(in crate::config) struct RawIo {
    pub(in crate::config) signal: Option<String>,
    pub(in crate::config) point: Option<String>,
    pub(in crate::config) device: Option<String>,
    pub(in crate::config) item: Option<String>,
    pub(in crate::config) direction: Option<String>,
    pub(in crate::config) variable: String,
    pub(in crate::config) scale: Option<f64>,
}

#[derive(Deserialize, Default, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub(in crate::config) enum RawTransmission {
    #[default]
    Spontaneous,
    Cyclic,
    InterrogationOnly,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(in crate::config) struct RawPoint {
    pub(in crate::config) name: String,
    #[serde(rename = "type")]
    pub(in crate::config) type_id: String,
    pub(in crate::config) ioa: i64,
    pub(in crate::config) source: Option<String>,
    #[serde(default)]
    pub(in crate::config) transmission: RawTransmission,
    pub(in crate::config) cycle_ms: Option<u64>,
    #[serde(default)]
    pub(in crate::config) groups: Vec<i64>,
    pub(in crate::config) deadband: Option<f64>,
    pub(in crate::config) store_deadband: Option<f64>,
    pub(in crate::config) store_deadband_percent: Option<f64>,
    pub(in crate::config) store_min_interval_ms: Option<i64>,
    pub(in crate::config) invalid_when: Option<String>,
    pub(in crate::config) measurand_limit: Option<f64>,
    pub(in crate::config) full_scale: Option<f64>,
    pub(in crate::config) scale_factor: Option<f64>,
    #[serde(default)]
    pub(in crate::config) description: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(in crate::config) struct RawCommand {
    pub(in crate::config) name: String,
    #[serde(rename = "type")]
    pub(in crate::config) type_id: String,
    pub(in crate::config) ioa: i64,
    pub(in crate::config) target: String,
    #[serde(default)]
    pub(in crate::config) select_required: bool,
    pub(in crate::config) remote_enable: Option<String>,
    pub(in crate::config) pulse_ms: Option<i64>,
    pub(in crate::config) max_age_ms: Option<i64>,
    pub(in crate::config) range: Option<[f64; 2]>,
    pub(in crate::config) feedback: Option<String>,
    pub(in crate::config) feedback_timeout_ms: Option<i64>,
    #[serde(default)]
    pub(in crate::config) from_groups: Vec<String>,
    #[serde(default)]
    pub(in crate::config) description: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(in crate::config) struct RawLink {
    pub(in crate::config) name: String,
    pub(in crate::config) node: Option<String>,
    pub(in crate::config) address: Option<String>,
    pub(in crate::config) common_address: Option<i64>,
    #[serde(default = "yes")]
    pub(in crate::config) interrogate_on_start: bool,
    #[serde(default = "yes")]
    pub(in crate::config) clock_sync: bool,
    pub(in crate::config) status_point: Option<String>,
    pub(in crate::config) republish: Option<RawRepublish>,
    pub(in crate::config) tls: Option<RawTls>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(in crate::config) struct RawRepublish {
    #[serde(default)]
    pub(in crate::config) ioa_offset: i64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(in crate::config) struct RawLine {
    pub(in crate::config) name: String,
    pub(in crate::config) protocol: String,
    pub(in crate::config) port: Option<String>,
    pub(in crate::config) tcp: Option<String>,
    pub(in crate::config) simulate: Option<String>,
    pub(in crate::config) baud: Option<i64>,
    pub(in crate::config) parity: Option<String>,
    pub(in crate::config) stop_bits: Option<i64>,
    pub(in crate::config) timeout_ms: Option<i64>,
    pub(in crate::config) retries: Option<i64>,
    pub(in crate::config) poll_interval_ms: Option<i64>,
    pub(in crate::config) status_point: Option<String>,
    pub(in crate::config) link_address_size: Option<i64>,
    pub(in crate::config) cot_size: Option<i64>,
    pub(in crate::config) common_address_size: Option<i64>,
    pub(in crate::config) ioa_size: Option<i64>,
    #[serde(default)]
    pub(in crate::config) device: Vec<RawDevice>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(in crate::config) struct RawDevice {
    pub(in crate::config) name: String,
    pub(in crate::config) address: i64,
    pub(in crate::config) common_address: Option<i64>,
    pub(in crate::config) status_point: Option<String>,
    pub(in crate::config) local_indication: Option<[i64; 2]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(in crate::config) struct RawLift {
    pub(in crate::config) name: String,
    #[serde(default)]
    pub(in crate::config) description: String,
    pub(in crate::config) floors: i64,
    pub(in crate::config) ioa_base: i64,
    pub(in crate::config) port: Option<String>,
    pub(in crate::config) tcp: Option<String>,
    pub(in crate::config) simulate: Option<String>,
    pub(in crate::config) baud: Option<i64>,
    pub(in crate::config) parity: Option<String>,
    pub(in crate::config) stop_bits: Option<i64>,
    pub(in crate::config) timeout_ms: Option<i64>,
    pub(in crate::config) retries: Option<i64>,
    pub(in crate::config) poll_period_ms: Option<i64>,
    pub(in crate::config) counters_period_ms: Option<i64>,
    pub(in crate::config) status_layout: Option<String>,
    pub(in crate::config) counter_width: Option<i64>,
    pub(in crate::config) time_coding: Option<String>,
    pub(in crate::config) year_base: Option<i64>,
    pub(in crate::config) direction: Option<[i64; 3]>,
    pub(in crate::config) index_base: Option<i64>,
    pub(in crate::config) fault_stack: Option<i64>,
    pub(in crate::config) seed: Option<i64>,
    pub(in crate::config) speed: Option<f64>,
    pub(in crate::config) fault_probability: Option<f64>,
}

/// `[[node.device]]`: a device of a registered kind (see `crate::device`).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(in crate::config) struct RawFieldDevice {
    pub(in crate::config) name: String,
    pub(in crate::config) kind: String,
    #[serde(default)]
    pub(in crate::config) description: String,
    pub(in crate::config) ioa_base: i64,
    /// The kind's own settings (address, port, simulation), read by its driver.
    #[serde(default)]
    pub(in crate::config) settings: toml::Table,
}
