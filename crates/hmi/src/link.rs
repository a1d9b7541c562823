//! The HMI's link to the station: an IEC 104 controlling station keeping every point of
//! `points.csv` with its quality, recording changes and commands in the HMI's own store,
//! evaluating alarms and broadcasting everything to the browsers.
//!
//! When the link is lost every point turns invalid at once (and the browsers blink);
//! after reconnection a general interrogation brings the values back. The connection is a
//! [`cs104::link::Link`](iec60870::cs104::link::Link), the same loop the station's
//! concentrator links use; [`Station`] is what observes it.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, OnceLock, RwLock};
use std::time::Duration;

use chrono::{DateTime, Utc};
use iec60870::asdu::{
    Asdu, CommandQualifier, CommonAddress, DoublePointState, Element, Ioa, SetpointQualifier,
    TimeTag, TypeId,
};
use iec60870::cs104::client::{ClientConfig, ClientError, ClientHandle};
use iec60870::cs104::link::{Link, LinkDown, LinkObserver};
use iec60870::time::TimeZonePolicy;
use points::{Point, PointDb, PointSource, PointSpec, Transmission};
use serde::Serialize;
use serde_json::{json, Value};
use store::Recorder;
use store::{
    Actor, CommandOutcome, CommandPhase, CommandRecord, EventRecord, PointValue, SourceTime,
};
use tokio::sync::broadcast;

use crate::alarms::{kpi, Alarm, AlarmRefusal, Alarms, Shelve, SETTLE};
use crate::config::{HmiConfig, PointRow};
use crate::live::{LinkState, LiveMessage};

/// A point as the browsers see it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PointView {
    /// Name.
    pub name: String,
    /// Address.
    pub ioa: u32,
    /// IEC type mnemonic.
    #[serde(rename = "type")]
    pub type_name: String,
    /// Description.
    pub description: String,
    /// bool (single), 0..=3 (double), number, or null before the first value.
    pub value: Value,
    /// Invalid (IV, or the link is down).
    pub invalid: bool,
    /// Quality flags set.
    pub quality: Vec<&'static str>,
    /// Source time.
    pub time: Option<DateTime<Utc>>,
}

/// What a control came to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ControlOutcome {
    /// Confirmed positively.
    Executed,
    /// Confirmed negatively.
    Refused,
    /// Refused by the station, the target being in local mode.
    RefusedLocal,
    /// The user's level is too low (decided by the HMI).
    RefusedPermission,
    /// The control authority is elsewhere (decided by the HMI).
    RefusedAuthority,
    /// No confirmation in time.
    TimedOut,
    /// No link to the station.
    NoLink,
}

impl ControlOutcome {
    fn audit(self) -> CommandOutcome {
        match self {
            ControlOutcome::Executed => CommandOutcome::Executed,
            ControlOutcome::Refused => CommandOutcome::Refused,
            ControlOutcome::RefusedLocal => CommandOutcome::RefusedLocalMode,
            ControlOutcome::RefusedPermission => CommandOutcome::RefusedPermission,
            ControlOutcome::RefusedAuthority => CommandOutcome::RefusedAuthority,
            ControlOutcome::TimedOut => CommandOutcome::TimedOut,
            ControlOutcome::NoLink => CommandOutcome::Failed,
        }
    }
}

/// The station as the HMI knows it.
pub struct Station {
    config: HmiConfig,
    /// The station's points as the HMI last received them (the point model's database,
    /// report by exception).
    points: RwLock<PointDb>,
    up: AtomicBool,
    addresses: Vec<String>,
    common_address: CommonAddress,
    node_label: String,
    live: broadcast::Sender<String>,
    /// Set once, right after the station is built (the link's observer is the station).
    link: OnceLock<Link>,
    recorder: Recorder,
    alarms: Mutex<Alarms>,
    zone: TimeZonePolicy,
    local_address: Option<std::net::IpAddr>,
}

impl std::fmt::Debug for Station {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Station")
            .field("addresses", &self.addresses)
            .field("up", &self.is_up())
            .finish_non_exhaustive()
    }
}

impl PointView {
    /// How the browsers see a point: before its first value, null and invalid.
    fn of(point: &Point) -> PointView {
        PointView {
            name: point.spec.name.clone(),
            ioa: point.spec.address,
            type_name: points_iec::type_id(point.spec.point_type).to_string(),
            description: point.spec.description.clone(),
            value: if point.has_value() {
                json_value(&point.value)
            } else {
                Value::Null
            },
            invalid: point.quality.invalid,
            quality: point.quality.set_flags(),
            time: point.source_time.map(|time| time.time),
        }
    }
}

/// The point database of `points.csv`'s monitor rows (the loader checked their types and
/// addresses).
fn point_db(rows: &[PointRow]) -> PointDb {
    let specs = rows
        .iter()
        .filter_map(|row| {
            Some(PointSpec {
                name: row.name.clone(),
                point_type: points_iec::point_type(row.type_id)?,
                address: row.ioa,
                transmission: Transmission::Spontaneous,
                groups: 0,
                deadband: None,
                source: PointSource::Link {
                    link: "station".to_owned(),
                    ioa: row.ioa,
                },
                storage: points::StorageRule::default(),
                description: row.description.clone(),
            })
        })
        .collect();
    PointDb::new("station", specs).unwrap_or_else(|error| {
        tracing::error!(%error, "the point list cannot make a point database; no point is shown");
        PointDb::empty("station")
    })
}

fn json_value(value: &PointValue) -> Value {
    match value {
        PointValue::Bool(b) => json!(b),
        PointValue::DoublePoint(d) => json!(d),
        PointValue::Int(i) => json!(i),
        PointValue::Float(f) if f.is_finite() => json!(f),
        PointValue::Float(_) => Value::Null,
        PointValue::Bits(b) => json!(b),
        PointValue::Text(t) => json!(t),
    }
}

impl Station {
    /// Connects to the station (`addresses`: main and alternates) with common address
    /// `ca`, on the current tokio runtime.
    pub fn spawn(
        config: HmiConfig,
        addresses: Vec<String>,
        ca: CommonAddress,
        recorder: Recorder,
        zone: TimeZonePolicy,
        local_address: Option<std::net::IpAddr>,
    ) -> Arc<Station> {
        let points = point_db(&config.points);
        let (live, _) = broadcast::channel(4096);
        let alarms = Alarms::new(&config.alarms);
        let station = Arc::new(Station {
            node_label: format!("CA{}", ca.get()),
            config,
            points: RwLock::new(points),
            up: AtomicBool::new(false),
            addresses,
            common_address: ca,
            live,
            link: OnceLock::new(),
            recorder,
            alarms: Mutex::new(alarms),
            zone,
            local_address,
        });
        let link = Link::spawn(
            station.link_config(),
            Arc::new(Observer(Arc::clone(&station))),
        );
        let _ = station.link.set(link);
        tokio::spawn(Station::alarm_clock(Arc::downgrade(&station)));
        station
    }

    /// The configuration.
    pub fn config(&self) -> &HmiConfig {
        &self.config
    }

    /// Whether data transfer with the station is started.
    pub fn is_up(&self) -> bool {
        self.up.load(Ordering::Acquire)
    }

    /// The station's address(es).
    pub fn addresses(&self) -> &[String] {
        &self.addresses
    }

    /// Every point.
    pub fn points(&self) -> Vec<PointView> {
        self.db().points().map(PointView::of).collect()
    }

    /// One point by name.
    pub fn point(&self, name: &str) -> Option<PointView> {
        self.db().get(name).map(PointView::of)
    }

    fn db(&self) -> std::sync::RwLockReadGuard<'_, PointDb> {
        self.points.read().unwrap_or_else(|p| p.into_inner())
    }

    /// Subscribes to the live messages (JSON text).
    pub fn subscribe(&self) -> broadcast::Receiver<String> {
        self.live.subscribe()
    }

    /// The alarm list.
    pub fn alarms(&self) -> Vec<Alarm> {
        self.alarms
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .listed()
    }

    /// Acknowledges an alarm, audited (ISA-18.2 keeps who acknowledged what).
    pub fn acknowledge(&self, id: usize, user: &str) -> Option<Alarm> {
        let alarm = self.alarm_book().acknowledge(id)?;
        self.audit_alarm(user, &alarm, true, "alarm acknowledged", None);
        Some(alarm)
    }

    fn alarm_book(&self) -> std::sync::MutexGuard<'_, Alarms> {
        self.alarms.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Shelves an alarm (ISA-18.2: timed or one-shot), audited.
    pub fn shelve(
        &self,
        id: usize,
        how: Shelve,
        reason: Option<String>,
        user: &str,
    ) -> Result<Alarm, AlarmRefusal> {
        let alarm = self.alarm_book().shelve(id, how, reason.clone(), user)?;
        let how = match how {
            Shelve::OneShot => "one-shot, until it returns to normal".to_owned(),
            Shelve::Until(until) => format!("until {}", until.to_rfc3339()),
        };
        self.audit_alarm(user, &alarm, true, &format!("alarm shelved {how}"), reason);
        Ok(alarm)
    }

    /// Unshelves an alarm by hand (it returns acknowledged), audited.
    pub fn unshelve(&self, id: usize, user: &str) -> Result<Alarm, AlarmRefusal> {
        let alarm = self.alarm_book().unshelve(id)?;
        self.audit_alarm(user, &alarm, false, "alarm unshelved", None);
        Ok(alarm)
    }

    /// Takes an alarm out of service, audited.
    pub fn out_of_service(
        &self,
        id: usize,
        reason: String,
        user: &str,
    ) -> Result<Alarm, AlarmRefusal> {
        let alarm = self
            .alarm_book()
            .out_of_service(id, reason.clone(), user, Utc::now())?;
        self.audit_alarm(
            user,
            &alarm,
            true,
            "alarm taken out of service",
            Some(reason),
        );
        Ok(alarm)
    }

    /// Returns an alarm to service, audited.
    pub fn in_service(&self, id: usize, user: &str) -> Result<Alarm, AlarmRefusal> {
        let alarm = self.alarm_book().in_service(id, Utc::now())?;
        self.audit_alarm(user, &alarm, false, "alarm returned to service", None);
        Ok(alarm)
    }

    /// The alarm KPI report of `from..to`; `earlier`: the activations before the HMI's
    /// own log, read from its store ([`kpi::stored_activations`]).
    pub fn alarm_kpi(
        &self,
        earlier: Option<&[crate::alarms::Activation]>,
        from: DateTime<Utc>,
        to: DateTime<Utc>,
    ) -> kpi::KpiReport {
        kpi::report(&self.alarm_book(), earlier, from, to, Utc::now())
    }

    /// The HMI's own log of alarm activations starts then.
    pub fn alarm_log_start(&self) -> DateTime<Utc> {
        self.alarm_book().log_start()
    }

    /// Records an alarm-management action in the HMI's audit (the command records of its
    /// store: the alarm's point, `true` for shelve / out of service, `false` for their
    /// ends, the action and reason in the detail) and tells every browser.
    fn audit_alarm(
        &self,
        user: &str,
        alarm: &Alarm,
        on: bool,
        action: &str,
        reason: Option<String>,
    ) {
        let detail = match &reason {
            Some(reason) => format!("{action}: {} (reason: {reason})", alarm.text),
            None => format!("{action}: {}", alarm.text),
        };
        tracing::info!(user, alarm = %alarm.text, %detail, "alarm management");
        self.recorder.command(CommandRecord {
            id: None,
            time: Utc::now(),
            actor: Actor::User(user.to_owned()),
            node: self.node_label.clone(),
            point: alarm.point.clone(),
            ioa: None,
            value: PointValue::Bool(on),
            phase: CommandPhase::Execute,
            outcome: CommandOutcome::Executed,
            detail,
        });
        self.broadcast_alarm(alarm);
    }

    /// The alarm clock: ends timed shelves within a second of their time (ISA-18.2),
    /// settle windows, chattering and floods. Runs while the station lives.
    async fn alarm_clock(station: std::sync::Weak<Station>) {
        let mut tick = tokio::time::interval(Duration::from_millis(200));
        tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
        loop {
            tick.tick().await;
            let Some(station) = station.upgrade() else {
                return;
            };
            let changed = station.alarm_book().tick(Utc::now());
            for alarm in &changed {
                station.broadcast_alarm(alarm);
            }
        }
    }

    /// Cuts the link to the station (a test of what the operator sees), or restores it.
    pub fn set_link(&self, up: bool) {
        if let Some(link) = self.link.get() {
            if up {
                link.restore();
            } else {
                link.cut();
            }
        }
    }

    /// The client configuration of the link to the station.
    fn link_config(&self) -> ClientConfig {
        let mut config = ClientConfig::new(
            self.addresses.first().cloned().unwrap_or_default(),
            self.common_address,
        );
        config.addresses = self.addresses.clone();
        config.local_address = self.local_address;
        config.interrogate_on_start = true;
        config.reconnect_delay = Duration::from_millis(300);
        config.reconnect_delay_max = Duration::from_secs(5);
        config.command_timeout = Duration::from_secs(5);
        // An operator must not watch stale values as live: if another controlling
        // station's STARTDT took the data (spoofed from our address, or a second HMI in
        // our redundancy group), notice within seconds, show the link down and take the
        // data back.
        config.standby_probe = Some(Duration::from_secs(10));
        config
    }

    /// Sends a live message to every browser.
    fn broadcast(&self, message: LiveMessage) {
        let _ = self.live.send(message.to_text());
    }

    fn broadcast_alarm(&self, alarm: &Alarm) {
        self.broadcast(LiveMessage::Alarm(alarm.clone()));
    }

    fn broadcast_point(&self, point: &PointView) {
        self.broadcast(LiveMessage::Point(point.clone().into()));
    }

    fn set_up(&self, up: bool) {
        if self.up.swap(up, Ordering::AcqRel) == up {
            return;
        }
        tracing::info!(up, "station link");
        self.broadcast(LiveMessage::Link(LinkState::of(self)));
        if up {
            // The general interrogation follows at once: what it and the station's
            // start-up image bring in the next seconds is the initial state, not a flood.
            self.alarm_book().settle(Utc::now() + SETTLE);
            return;
        }
        // Every value is invalid at once: the operator must not act on stale values.
        let changed: Vec<PointView> = {
            let mut db = self.points.write().unwrap_or_else(|p| p.into_inner());
            let changes = db.invalidate_where(|_| true, Utc::now());
            changes
                .iter()
                .filter_map(|change| db.get(change.name.as_str()).map(PointView::of))
                .collect()
        };
        for point in &changed {
            self.broadcast_point(point);
        }
    }

    fn apply(&self, asdu: &Asdu) {
        if asdu.type_id == TypeId::C_IC_NA_1
            && asdu.cot.cause == iec60870::asdu::Cause::ACTIVATION_TERMINATION
        {
            // A long interrogation: the initial state lasts until a second after the end
            // of the one that opened the window (a later one opens none).
            let now = Utc::now();
            let mut book = self.alarm_book();
            if book.settling(now) {
                book.settle(now + chrono::Duration::seconds(1));
            }
        }
        if asdu.cot.negative || !asdu.type_id.is_monitor() {
            return;
        }
        let Some(event_cause) = points_iec::event_cause(asdu.cot.cause) else {
            return;
        };
        let is_event = points_iec::received_as_event(asdu.cot.cause);
        for object in &asdu.objects {
            let Ok((value, quality, source)) = points_iec::from_element(
                asdu.type_id,
                &object.element,
                object.time.as_ref(),
                self.zone,
            ) else {
                continue;
            };
            let received = Utc::now();
            // A value without a time of its own is stamped when the HMI took it.
            let source = source.or(Some(SourceTime::at(received)));
            let (change, view) = {
                let mut db = self.points.write().unwrap_or_else(|p| p.into_inner());
                let address = object.ioa.get();
                let updated = if is_event {
                    db.update_event(
                        address,
                        value.clone(),
                        quality,
                        source,
                        received,
                        event_cause,
                    )
                } else {
                    db.update(
                        address,
                        value.clone(),
                        quality,
                        source,
                        received,
                        event_cause,
                    )
                };
                // Not a point of the list, or not of its type: not shown.
                let Ok(Some(change)) = updated else {
                    continue;
                };
                let Some(view) = db.get(address).map(PointView::of) else {
                    continue;
                };
                (change, view)
            };
            self.broadcast_point(&view);
            self.recorder.event(EventRecord::of_change(
                &change,
                &self.node_label,
                &self.addresses.join(","),
            ));
            if let PointValue::Bool(on) = value {
                let changed = self.alarms.lock().unwrap_or_else(|p| p.into_inner()).point(
                    &view.name,
                    on,
                    quality.invalid,
                    received,
                );
                for alarm in &changed {
                    self.broadcast_alarm(alarm);
                }
            }
        }
    }

    /// Operates a command for `user` (whose level was checked by the caller): select first
    /// when the control requires it, then execute; records the outcome.
    pub async fn operate(&self, user: &str, command: &str, value: f64) -> (ControlOutcome, String) {
        let control = self.config.control(command);
        let Some(row) = self
            .config
            .points
            .iter()
            .find(|p| p.name == command && p.type_id.is_command())
        else {
            return (ControlOutcome::Refused, format!("no command `{command}`"));
        };
        let client = self.link.get().and_then(Link::client);
        let (outcome, detail) = match (client, self.is_up()) {
            (Some(client), true) => {
                let result = async {
                    if control.select {
                        let selected = send(&client, row, value, true).await?;
                        if !selected.0 {
                            return Ok((false, format!("select refused (cause {})", selected.1)));
                        }
                    }
                    let executed = send(&client, row, value, false).await?;
                    Ok::<_, ClientError>((executed.0, format!("cause {}", executed.1)))
                }
                .await;
                match result {
                    Ok((true, _)) => (ControlOutcome::Executed, String::new()),
                    Ok((false, detail)) => {
                        let local = control
                            .local_point
                            .as_deref()
                            .and_then(|p| self.point(p))
                            .is_some_and(|p| p.value == json!(true));
                        if local {
                            (
                                ControlOutcome::RefusedLocal,
                                format!("the target is in local mode ({detail})"),
                            )
                        } else {
                            (
                                ControlOutcome::Refused,
                                format!("refused by the station ({detail})"),
                            )
                        }
                    }
                    Err(ClientError::Timeout(what)) => (
                        ControlOutcome::TimedOut,
                        format!("no {what} from the station"),
                    ),
                    // A value the command's type cannot carry: nothing was sent.
                    Err(ClientError::Encode(why)) => (
                        ControlOutcome::Refused,
                        format!("value refused, nothing sent: {why}"),
                    ),
                    Err(error) => (ControlOutcome::NoLink, error.to_string()),
                }
            }
            _ => (ControlOutcome::NoLink, "no link to the station".into()),
        };
        self.audit(user, command, row.ioa, value, outcome, &detail);
        (outcome, detail)
    }

    /// Records a control attempt (also one refused for permission).
    pub fn audit(
        &self,
        user: &str,
        command: &str,
        ioa: u32,
        value: f64,
        outcome: ControlOutcome,
        detail: &str,
    ) {
        tracing::info!(user, command, value, ?outcome, detail, "control");
        self.recorder.command(CommandRecord {
            id: None,
            time: Utc::now(),
            actor: Actor::User(user.to_owned()),
            node: self.node_label.clone(),
            point: command.to_owned(),
            ioa: Some(ioa),
            value: PointValue::Float(value),
            phase: CommandPhase::Execute,
            outcome: outcome.audit(),
            detail: detail.to_owned(),
        });
        self.broadcast(LiveMessage::Command {
            user: user.to_owned(),
            command: command.to_owned(),
            value,
            outcome,
        });
    }

    /// The recorder of the HMI's store.
    pub fn recorder(&self) -> &Recorder {
        &self.recorder
    }
}

/// Sends one command; `(positive, cause)`.
async fn send(
    client: &ClientHandle,
    row: &PointRow,
    value: f64,
    select: bool,
) -> Result<(bool, u8), ClientError> {
    let ioa = Ioa::try_new(row.ioa).map_err(|e| ClientError::Encode(e.to_string()))?;
    let (type_id, element) = command_element(row.type_id, value, select)?;
    let outcome = client.command(type_id, ioa, element, None).await?;
    Ok((outcome.positive, outcome.cause.value()))
}

/// The command an operator's value makes for a command point of type `base` (its
/// untagged form: the HMI stamps no time tags).
fn command_element(
    base: TypeId,
    value: f64,
    select: bool,
) -> Result<(TypeId, Element), ClientError> {
    let qualifier =
        CommandQualifier::new(0, select).map_err(|e| ClientError::Encode(e.to_string()))?;
    let set_qualifier =
        SetpointQualifier::new(0, select).map_err(|e| ClientError::Encode(e.to_string()))?;
    Ok(match base {
        TypeId::C_SC_NA_1 | TypeId::C_SC_TA_1 => (
            TypeId::C_SC_NA_1,
            Element::SingleCommand {
                on: value != 0.0,
                qualifier,
            },
        ),
        TypeId::C_DC_NA_1 | TypeId::C_DC_TA_1 => (
            TypeId::C_DC_NA_1,
            Element::DoubleCommand {
                state: if value != 0.0 {
                    DoublePointState::On
                } else {
                    DoublePointState::Off
                },
                qualifier,
            },
        ),
        // A set-point outside what its type can carry is refused, never clamped: the
        // audit must hold the value that was sent, and 99999 silently becoming 32767 is a
        // different command.
        TypeId::C_SE_NB_1 | TypeId::C_SE_TB_1 => {
            let range = f64::from(i16::MIN)..=f64::from(i16::MAX);
            if value.fract() != 0.0 || !range.contains(&value) {
                return Err(ClientError::Encode(format!(
                    "{value} is not a whole number in -32768..=32767 (a scaled set-point)"
                )));
            }
            (
                TypeId::C_SE_NB_1,
                Element::SetpointScaled {
                    // Checked above: whole and in range, so the cast is exact.
                    #[allow(clippy::cast_possible_truncation)]
                    value: value as i16,
                    qualifier: set_qualifier,
                },
            )
        }
        TypeId::C_SE_NC_1 | TypeId::C_SE_TC_1 => {
            #[allow(clippy::cast_possible_truncation)]
            let single = value as f32;
            if !single.is_finite() {
                return Err(ClientError::Encode(format!(
                    "{value} does not fit a short floating-point set-point"
                )));
            }
            (
                TypeId::C_SE_NC_1,
                Element::SetpointFloat {
                    value: single,
                    qualifier: set_qualifier,
                },
            )
        }
        TypeId::C_SE_NA_1 | TypeId::C_SE_TA_1 => {
            // The codec's scaling (raw / 32768), as everywhere else in the project.
            let largest = f64::from(Element::normalized_value(i16::MAX));
            if !(-1.0..=largest).contains(&value) {
                return Err(ClientError::Encode(format!(
                    "{value} is outside -1.0..={largest} (a normalized set-point)"
                )));
            }
            #[allow(clippy::cast_possible_truncation)]
            let raw = Element::normalized_raw(value as f32);
            (
                TypeId::C_SE_NA_1,
                Element::SetpointNormalized {
                    raw,
                    qualifier: set_qualifier,
                },
            )
        }
        other => {
            return Err(ClientError::Encode(format!(
                "{other} is not operated from the HMI"
            )))
        }
    })
}

/// The station observes its own link. (The link's task holds the station for as long as
/// the link runs, as the HMI's server does.)
struct Observer(Arc<Station>);

impl LinkObserver for Observer {
    fn started(&self, _client: &ClientHandle) {
        self.0.set_up(true);
    }

    fn down(&self, _why: &LinkDown) {
        self.0.set_up(false);
    }

    fn asdu(&self, asdu: &Asdu) {
        self.0.apply(asdu);
    }
}

/// The time tag of an element, if any (for tests and views).
pub fn time_of(tag: Option<&TimeTag>, zone: TimeZonePolicy) -> Option<DateTime<Utc>> {
    tag.and_then(TimeTag::as_cp56)
        .and_then(|t| zone.from_cp56(t))
        .map(|s| s.time)
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::panic)]
mod tests {
    use super::*;

    fn scaled(value: f64) -> Result<i16, ClientError> {
        match command_element(TypeId::C_SE_NB_1, value, false)?.1 {
            Element::SetpointScaled { value, .. } => Ok(value),
            other => panic!("{other:?}"),
        }
    }

    fn normalized(value: f64) -> Result<i16, ClientError> {
        match command_element(TypeId::C_SE_NA_1, value, false)?.1 {
            Element::SetpointNormalized { raw, .. } => Ok(raw),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn set_points_outside_their_type_are_refused_not_clamped() {
        assert_eq!(scaled(1440.0).unwrap(), 1440);
        assert_eq!(scaled(-5.0).unwrap(), -5);
        for refused in [99_999.0, 32_768.0, -32_769.0, 2.5, f64::NAN] {
            assert!(scaled(refused).is_err(), "{refused} was sent");
        }
        assert!(command_element(TypeId::C_SE_NC_1, 1e300, false).is_err());
    }

    #[test]
    fn normalized_set_points_scale_as_the_codec_does() {
        // raw / 32768 everywhere: -1.0 is -32768 (not -32767), 0.5 is 16384.
        assert_eq!(normalized(-1.0).unwrap(), -32768);
        assert_eq!(normalized(0.5).unwrap(), 16384);
        assert_eq!(
            normalized(f64::from(Element::normalized_value(i16::MAX))).unwrap(),
            i16::MAX
        );
        assert!(normalized(1.0).is_err());
    }
}
