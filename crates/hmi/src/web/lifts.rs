//! The lift screens' API (docs/HMI.md, "Lift screens"): the fleet of hmi.toml's
//! `[[lift]]`, the fault archive of the station's store (paged, sorted, filtered, as CSV)
//! and the service figures computed from the lifts' point history.
//!
//! ```text
//!  GET /api/lifts                     fleet, levels, status and fault code tables
//!  GET /api/lifts/faults?...          archive page   --query_lift_faults--> station store
//!  GET /api/lifts/faults.csv?...      every matching row (capped), attachment
//!  GET /api/lifts/figures?days=N      fleet + each lift  --query_events NAME.* + faults-->
//!  GET /api/lifts/{name}/figures      one lift               devices::ekm66::figures
//! ```
//!
//! Read only: nothing here writes to the store or controls a lift. Every parameter is
//! checked ([`AppError::BadParameter`]); the element levels of `[lift_levels]` are
//! enforced here ([`AppError::ElementLevel`]) and only hidden in the browser.

use std::sync::Arc;

use axum::extract::rejection::QueryRejection;
use axum::extract::{Path, Query, State};
use axum::http::{header, HeaderValue};
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use axum::{Json, Router};
use chrono::{NaiveDate, NaiveDateTime, TimeDelta, Utc};
use devices::ekm66::codec::Direction;
use devices::ekm66::figures::{
    FaultAt, FiguresConfig, FleetFigures, Observation, Observed, Period, ServiceFigures,
};
use devices::ekm66::tables::{
    fault_group, fault_text, fault_text_czech, StatusColours, FAULT_CODES, STATUS_CODES,
};
use points::LiftSignal;
use serde::Deserialize;
use serde_json::{json, Value};
use store::{
    EventQuery, EventStore, LiftFaultOrder, LiftFaultQuery, LiftFaultRecord, NotificationQuery,
    Order, PointValue,
};

use super::{AppError, AppState, LoggedIn};
use crate::config::LiftConfig;
use crate::LogText;

pub(super) fn routes() -> Router<AppState> {
    Router::new()
        .route("/api/lifts", get(fleet))
        .route("/api/lifts/faults", get(faults))
        .route("/api/lifts/faults.csv", get(faults_csv))
        .route("/api/lifts/figures", get(fleet_figures))
        .route("/api/lifts/{name}/figures", get(lift_figures))
        .route("/api/lifts/notifications", get(notifications))
}

/// Rows of one archive page at most.
pub(super) const MAX_PAGE: u32 = 1000;
/// Rows of one CSV export at most.
pub(super) const CSV_CAP: u64 = 50_000;
/// Point events read per lift for its figures at most (the figures say `truncated`).
pub(super) const FIGURES_EVENT_CAP: usize = 200_000;
/// The longest period of the figures, in days (ten years).
pub(super) const MAX_DAYS: i64 = 3660;
/// The longest text filter, in characters.
const MAX_TEXT: usize = 100;

impl AppState {
    /// The station's store, or [`AppError::NoArchive`].
    fn archive(&self) -> Result<Arc<dyn EventStore>, AppError> {
        self.archive.clone().ok_or(AppError::NoArchive)
    }
}

/// Whether the user reaches the level of a lift screen element.
fn require(user: &LoggedIn, element: &'static str, needed: u8) -> Result<(), AppError> {
    let has = user.session.level;
    if has < needed {
        tracing::warn!(peer = %user.peer, user = %LogText(&user.session.user), element, needed, has, "refused: level too low");
        return Err(AppError::ElementLevel {
            element,
            needed,
            has,
        });
    }
    Ok(())
}

// ---------------------------------------------------------------------------- the fleet

async fn fleet(State(state): State<AppState>, user: LoggedIn) -> Json<Value> {
    let config = state.station.config();
    let levels = config.lift_levels;
    let has = user.session.level;
    let statuses: Vec<Value> = STATUS_CODES
        .iter()
        .map(|s| json!({"code": s.code, "english": s.english, "czech": s.czech, "class": s.class.to_string()}))
        .collect();
    let faults: Vec<Value> = FAULT_CODES
        .iter()
        .map(|f| {
            json!({"code": f.code, "hex": format!("{:02X}", f.code), "english": f.english,
                   "czech": f.czech, "group": fault_group(f.code).key()})
        })
        .collect();
    Json(json!({
        "lifts": config.lifts,
        "levels": levels,
        "allowed": {
            "fleet": has >= levels.fleet,
            "lift": has >= levels.lift,
            "archive": has >= levels.archive,
            "export": has >= levels.export.max(levels.archive),
            "figures": has >= levels.figures,
            "notifications": has >= levels.notifications,
        },
        "archive": state.archive.is_some(),
        "statuses": statuses,
        "faults": faults,
    }))
}

// ---------------------------------------------------------------------------- notifications

/// The notification record's query string: `lift`, `offset`, `limit`.
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct NotificationsParams {
    lift: Option<String>,
    offset: Option<String>,
    limit: Option<String>,
}

/// The station's record of the notifications its lifts caused (e-mail, webhook; sent,
/// failed or suppressed), newest first.
async fn notifications(
    State(state): State<AppState>,
    user: LoggedIn,
    query: Result<Query<NotificationsParams>, QueryRejection>,
) -> Result<Json<Value>, AppError> {
    let config = state.station.config();
    require(&user, "notifications", config.lift_levels.notifications)?;
    let Query(params) = query?;
    let mut query = NotificationQuery::default();
    if let Some(lift) = present(&params.lift) {
        if !config.lifts.iter().any(|known| known.name == lift) {
            return Err(bad("lift", format!("no lift `{}`", LogText(lift))));
        }
        query = query.with_source(lift);
    }
    let (offset, limit) = page_window(&params.offset, &params.limit)?;
    let page = state
        .archive()?
        .query_notifications(&query.with_page(offset, limit))
        .await?;
    let rows: Vec<Value> = page
        .items
        .iter()
        .map(|record| {
            json!({
                "time": record.time,
                "lift": record.source,
                "rule": record.rule,
                "channel": record.channel,
                "recipient": record.recipient,
                "subject": record.subject,
                "outcome": record.outcome.to_string(),
                "detail": record.detail,
            })
        })
        .collect();
    Ok(Json(json!({
        "rows": rows,
        "total": page.total,
        "offset": offset,
        "limit": limit,
    })))
}

// ---------------------------------------------------------------------------- the archive

/// The archive's query string; every field is text, checked by [`FaultFilter::parse`]
/// so that each mistake is named. An empty value is an absent one (HTML forms send them).
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct FaultsParams {
    lift: Option<String>,
    code: Option<String>,
    q: Option<String>,
    since: Option<String>,
    until: Option<String>,
    sort: Option<String>,
    desc: Option<String>,
    offset: Option<String>,
    limit: Option<String>,
    lang: Option<String>,
}

fn present(value: &Option<String>) -> Option<&str> {
    value.as_deref().map(str::trim).filter(|v| !v.is_empty())
}

/// The `offset` (default 0) and `limit` (default 50, at most [`MAX_PAGE`]) of a paged
/// list, each mistake named.
fn page_window(offset: &Option<String>, limit: &Option<String>) -> Result<(u64, u32), AppError> {
    let offset = match present(offset) {
        None => 0,
        Some(text) => text
            .parse::<u64>()
            .ok()
            .filter(|o| *o <= 1_000_000_000)
            .ok_or_else(|| bad("offset", "a whole number 0..=1000000000"))?,
    };
    let limit = match present(limit) {
        None => 50,
        Some(text) => text
            .parse::<u32>()
            .ok()
            .filter(|l| (1..=MAX_PAGE).contains(l))
            .ok_or_else(|| bad("limit", format!("a whole number 1..={MAX_PAGE}")))?,
    };
    Ok((offset, limit))
}

fn bad(name: &'static str, message: impl Into<String>) -> AppError {
    AppError::BadParameter {
        name,
        message: message.into(),
    }
}

/// The display language of the `text` column.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Lang {
    English,
    Czech,
}

/// The archive query as checked.
#[derive(Debug)]
struct FaultFilter {
    lifts: Vec<String>,
    /// `None`: every code; `Some(empty)`: nothing can match (a text no fault has).
    codes: Option<Vec<u8>>,
    since: Option<NaiveDateTime>,
    until: Option<NaiveDateTime>,
    order: LiftFaultOrder,
    descending: bool,
    offset: u64,
    limit: u32,
    lang: Lang,
}

/// Lower case without the Czech diacritics: "Dveří" and "dveri" match each other.
fn fold(text: &str) -> String {
    text.chars()
        .flat_map(char::to_lowercase)
        .map(|c| match c {
            'á' => 'a',
            'č' => 'c',
            'ď' => 'd',
            'é' | 'ě' => 'e',
            'í' => 'i',
            'ň' => 'n',
            'ó' => 'o',
            'ř' => 'r',
            'š' => 's',
            'ť' => 't',
            'ú' | 'ů' => 'u',
            'ý' => 'y',
            'ž' => 'z',
            other => other,
        })
        .collect()
}

/// The fault codes whose English or Czech text contains `text` (case and Czech accents
/// ignored), or whose hex code it is.
fn codes_matching(text: &str) -> Vec<u8> {
    let wanted = fold(text);
    FAULT_CODES
        .iter()
        .filter(|f| {
            fold(f.english).contains(&wanted)
                || fold(f.czech).contains(&wanted)
                || format!("{:02x}", f.code) == wanted.trim_start_matches("0x")
        })
        .map(|f| f.code)
        .collect()
}

fn parse_code(text: &str) -> Option<u8> {
    let digits = text
        .strip_prefix("0x")
        .or_else(|| text.strip_prefix("0X"))
        .unwrap_or(text);
    if digits.is_empty() || digits.len() > 2 {
        return None;
    }
    u8::from_str_radix(digits, 16).ok()
}

/// A board time bound: `YYYY-MM-DD`, `YYYY-MM-DDTHH:MM` or `YYYY-MM-DDTHH:MM:SS` (a space
/// for the `T` too). A date alone as `until` takes in that whole day.
fn parse_bound(name: &'static str, text: &str, end: bool) -> Result<NaiveDateTime, AppError> {
    let text = text.replace(' ', "T");
    for format in [
        "%Y-%m-%dT%H:%M:%S",
        "%Y-%m-%dT%H:%M",
        "%Y-%m-%dT%H:%M:%S%.f",
    ] {
        if let Ok(time) = NaiveDateTime::parse_from_str(&text, format) {
            return Ok(time);
        }
    }
    let date = NaiveDate::parse_from_str(&text, "%Y-%m-%d")
        .map_err(|_| bad(name, "a date YYYY-MM-DD or a time YYYY-MM-DDTHH:MM[:SS]"))?;
    let date = if end {
        date.succ_opt()
            .ok_or_else(|| bad(name, "date out of range"))?
    } else {
        date
    };
    Ok(date.and_time(chrono::NaiveTime::MIN))
}

impl FaultFilter {
    fn parse(params: &FaultsParams, fleet: &[LiftConfig]) -> Result<FaultFilter, AppError> {
        let mut lifts = Vec::new();
        if let Some(list) = present(&params.lift) {
            for name in list.split(',').map(str::trim).filter(|n| !n.is_empty()) {
                if !fleet.iter().any(|l| l.name == name) {
                    return Err(bad("lift", format!("no lift `{}`", LogText(name))));
                }
                if !lifts.iter().any(|l: &String| l == name) {
                    lifts.push(name.to_owned());
                }
            }
        }
        let mut codes: Option<Vec<u8>> = None;
        if let Some(list) = present(&params.code) {
            let mut listed = Vec::new();
            for text in list.split(',').map(str::trim).filter(|c| !c.is_empty()) {
                let code = parse_code(text).ok_or_else(|| {
                    bad(
                        "code",
                        format!("`{}` is no hex fault code 00-FF", LogText(text)),
                    )
                })?;
                if !listed.contains(&code) {
                    listed.push(code);
                }
            }
            codes = Some(listed);
        }
        if let Some(text) = present(&params.q) {
            if text.chars().count() > MAX_TEXT {
                return Err(bad("q", format!("at most {MAX_TEXT} characters")));
            }
            let matching = codes_matching(text);
            codes = Some(match codes {
                Some(listed) => listed
                    .into_iter()
                    .filter(|c| matching.contains(c))
                    .collect(),
                None => matching,
            });
        }
        let since = present(&params.since)
            .map(|t| parse_bound("since", t, false))
            .transpose()?;
        let until = present(&params.until)
            .map(|t| parse_bound("until", t, true))
            .transpose()?;
        if let (Some(since), Some(until)) = (since, until) {
            if since >= until {
                return Err(bad("until", "the range ends before it begins"));
            }
        }
        let order = match present(&params.sort).unwrap_or("board_time") {
            "board_time" | "time" | "date" => LiftFaultOrder::BoardTime,
            "received" => LiftFaultOrder::Received,
            "code" => LiftFaultOrder::Code,
            "lift" => LiftFaultOrder::Lift,
            "floor" => LiftFaultOrder::Floor,
            "archived" => LiftFaultOrder::Archived,
            other => {
                return Err(bad(
                    "sort",
                    format!(
                        "`{}`: one of board_time, received, code, lift, floor, archived",
                        LogText(other)
                    ),
                ))
            }
        };
        let descending = match present(&params.desc) {
            None => true,
            Some("true" | "1") => true,
            Some("false" | "0") => false,
            Some(other) => return Err(bad("desc", format!("`{}`: true or false", LogText(other)))),
        };
        let (offset, limit) = page_window(&params.offset, &params.limit)?;
        let lang = match present(&params.lang) {
            None | Some("en") => Lang::English,
            Some("cs") => Lang::Czech,
            Some(other) => return Err(bad("lang", format!("`{}`: en or cs", LogText(other)))),
        };
        Ok(FaultFilter {
            lifts,
            codes,
            since,
            until,
            order,
            descending,
            offset,
            limit,
            lang,
        })
    }

    /// The store's query for `offset`/`limit`, or `None` when nothing can match.
    fn query(&self, offset: u64, limit: u32) -> Option<LiftFaultQuery> {
        let codes = match &self.codes {
            Some(codes) if codes.is_empty() => return None,
            Some(codes) => codes.clone(),
            None => Vec::new(),
        };
        Some(
            LiftFaultQuery::default()
                .with_lifts(self.lifts.iter().cloned())
                .with_codes(codes)
                .with_range(self.since, self.until)
                .with_order(self.order, self.descending)
                .with_page(offset, limit),
        )
    }
}

fn sort_word(order: LiftFaultOrder) -> &'static str {
    match order {
        LiftFaultOrder::Archived => "archived",
        LiftFaultOrder::BoardTime => "board_time",
        LiftFaultOrder::Received => "received",
        LiftFaultOrder::Code => "code",
        LiftFaultOrder::Lift => "lift",
        LiftFaultOrder::Floor => "floor",
    }
}

fn row(record: &LiftFaultRecord, lang: Lang) -> Value {
    let english = fault_text(record.code);
    let czech = fault_text_czech(record.code);
    let text = match lang {
        Lang::English => &english,
        Lang::Czech => &czech,
    };
    json!({
        "id": record.id.map(|id| id.to_string()),
        "lift": record.lift,
        "date": record.board_time.map(|t| t.format("%Y-%m-%d").to_string()),
        "time": record.board_time.map(|t| t.format("%H:%M:%S").to_string()),
        "code": record.code,
        "hex": format!("{:02X}", record.code),
        "english": english,
        "czech": czech,
        "text": text,
        "group": fault_group(record.code).key(),
        "floor": record.floor,
        "target": record.target,
        "received": record.received_time,
        "index": record.stack_index,
    })
}

async fn faults(
    State(state): State<AppState>,
    user: LoggedIn,
    query: Result<Query<FaultsParams>, QueryRejection>,
) -> Result<Json<Value>, AppError> {
    let config = state.station.config();
    require(&user, "archive", config.lift_levels.archive)?;
    let Query(params) = query?;
    let filter = FaultFilter::parse(&params, &config.lifts)?;
    let archive = state.archive()?;
    let (rows, total) = match filter.query(filter.offset, filter.limit) {
        Some(query) => {
            let page = archive.query_lift_faults(&query).await?;
            let rows: Vec<Value> = page.items.iter().map(|r| row(r, filter.lang)).collect();
            (rows, page.total)
        }
        None => (Vec::new(), 0),
    };
    Ok(Json(json!({
        "rows": rows,
        "total": total,
        "offset": filter.offset,
        "limit": filter.limit,
        "sort": sort_word(filter.order),
        "desc": filter.descending,
        "codes": filter.codes,
    })))
}

/// One CSV field: quoted when it holds a separator, a quote or a line break; a text
/// starting like a spreadsheet formula gets a leading apostrophe.
fn csv_field(out: &mut String, text: &str) {
    let formula = text.starts_with(['=', '+', '-', '@']);
    if formula || text.contains([',', '"', '\n', '\r']) {
        out.push('"');
        if formula {
            out.push('\'');
        }
        out.push_str(&text.replace('"', "\"\""));
        out.push('"');
    } else {
        out.push_str(text);
    }
}

async fn faults_csv(
    State(state): State<AppState>,
    user: LoggedIn,
    query: Result<Query<FaultsParams>, QueryRejection>,
) -> Result<Response, AppError> {
    let config = state.station.config();
    require(&user, "archive", config.lift_levels.archive)?;
    require(&user, "export", config.lift_levels.export)?;
    let Query(params) = query?;
    let filter = FaultFilter::parse(&params, &config.lifts)?;
    let archive = state.archive()?;
    // A byte-order mark, so that spreadsheets read the Czech texts as UTF-8.
    let mut out =
        String::from("\u{feff}date,time,lift,code,english,czech,floor,target,received,index\r\n");
    let mut offset = filter.offset;
    let end = filter.offset.saturating_add(CSV_CAP);
    const PAGE: u32 = 5000;
    while offset < end {
        let Some(query) = filter.query(offset, PAGE) else {
            break;
        };
        let page = archive.query_lift_faults(&query).await?;
        for record in &page.items {
            let (date, time) = record
                .board_time
                .map_or((String::new(), String::new()), |t| {
                    (
                        t.format("%Y-%m-%d").to_string(),
                        t.format("%H:%M:%S").to_string(),
                    )
                });
            for (index, field) in [
                date,
                time,
                record.lift.clone(),
                format!("{:02X}", record.code),
                fault_text(record.code).into_owned(),
                fault_text_czech(record.code).into_owned(),
                record.floor.to_string(),
                record.target.to_string(),
                record
                    .received_time
                    .to_rfc3339_opts(chrono::SecondsFormat::Millis, true),
                record.stack_index.to_string(),
            ]
            .iter()
            .enumerate()
            {
                if index > 0 {
                    out.push(',');
                }
                csv_field(&mut out, field);
            }
            out.push_str("\r\n");
        }
        let got = u64::try_from(page.items.len()).unwrap_or(u64::MAX);
        offset = offset.saturating_add(got);
        if got < u64::from(PAGE) {
            break;
        }
    }
    Ok((
        [
            (
                header::CONTENT_TYPE,
                HeaderValue::from_static("text/csv; charset=utf-8"),
            ),
            (
                header::CONTENT_DISPOSITION,
                HeaderValue::from_static("attachment; filename=\"lift-faults.csv\""),
            ),
        ],
        out,
    )
        .into_response())
}

// ---------------------------------------------------------------------------- figures

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct FiguresParams {
    days: Option<String>,
}

fn period_of(params: &FiguresParams) -> Result<Period, AppError> {
    let days = match present(&params.days) {
        None => 30,
        Some(text) => text
            .parse::<i64>()
            .ok()
            .filter(|d| (1..=MAX_DAYS).contains(d))
            .ok_or_else(|| bad("days", format!("a whole number 1..={MAX_DAYS}")))?,
    };
    let to = Utc::now();
    Period::try_new(to - TimeDelta::days(days), to).map_err(|e| bad("days", e.to_string()))
}

fn number(value: &PointValue) -> Option<i64> {
    match value {
        PointValue::Int(i) => Some(*i),
        PointValue::Float(f) if f.is_finite() => Some(f.round() as i64),
        PointValue::Bool(b) => Some(i64::from(*b)),
        PointValue::DoublePoint(d) => Some(i64::from(*d)),
        PointValue::Bits(b) => Some(i64::from(*b)),
        _ => None,
    }
}

/// The floors' trip counters as the figures take them: the newest value of each floor.
struct Counters(Vec<u32>);

impl Counters {
    fn set(&mut self, floor: usize, value: i64) -> bool {
        let value = u32::try_from(value.max(0)).unwrap_or(u32::MAX);
        match floor.checked_sub(1).and_then(|i| self.0.get_mut(i)) {
            Some(slot) => {
                *slot = value;
                true
            }
            None => false,
        }
    }
}

/// What a point event of the lift says, if anything the figures use.
fn observe(
    suffix: &str,
    value: &PointValue,
    invalid: bool,
    counters: &mut Counters,
) -> Option<Observed> {
    let n = number(value)?;
    let byte = || u8::try_from(n).ok();
    match LiftSignal::from_suffix(suffix)? {
        LiftSignal::NotAnswering => Some(Observed::Answering(n == 0)),
        _ if invalid => None,
        LiftSignal::Status => byte().map(Observed::Status),
        LiftSignal::Position => byte().map(Observed::Position),
        LiftSignal::Direction => Some(Observed::Direction(match n {
            0 => Direction::Stopped,
            1 => Direction::Up,
            2 => Direction::Down,
            other => Direction::Unknown(u8::try_from(other).unwrap_or(u8::MAX)),
        })),
        LiftSignal::FloorTrips(floor) => counters
            .set(usize::from(floor), n)
            .then(|| Observed::Counters(counters.0.clone())),
        _ => None,
    }
}

/// One lift's figures over `period` from the station's store; `true` when its history
/// was longer than [`FIGURES_EVENT_CAP`] events (the figures then end early).
async fn lift_figures_of(
    archive: &dyn EventStore,
    lift: &LiftConfig,
    period: Period,
) -> Result<(ServiceFigures, bool), AppError> {
    let prefix = format!("{}.", lift.name);
    let mut counters = Counters(vec![0; usize::from(lift.floors)]);
    let mut observations = Vec::new();
    // The state at the start: the newest value of each signal before the period.
    let mut before: Vec<String> = [
        LiftSignal::Status,
        LiftSignal::Position,
        LiftSignal::Direction,
        LiftSignal::NotAnswering,
    ]
    .iter()
    .map(|signal| signal.suffix())
    .collect();
    before.extend((1..=lift.floors).map(|floor| LiftSignal::FloorTrips(floor).suffix()));
    for suffix in &before {
        let page = archive
            .query_events(
                &EventQuery::default()
                    .with_point(format!("{prefix}{suffix}"))
                    .with_range(None, Some(period.from()))
                    .with_order(Order::NewestFirst)
                    .with_limit(1),
            )
            .await?;
        if let Some(event) = page.items.first() {
            if let Some(what) = observe(suffix, &event.value, event.quality.invalid, &mut counters)
            {
                observations.push(Observation::new(event.event_time(), what));
            }
        }
    }
    let mut after = None;
    let mut read = 0usize;
    let mut truncated = false;
    loop {
        let page = archive
            .query_events(
                &EventQuery::default()
                    .with_point_prefix(prefix.clone())
                    .with_range(Some(period.from()), Some(period.to()))
                    .with_order(Order::OldestFirst)
                    .with_limit(1000)
                    .with_after(after),
            )
            .await?;
        read += page.items.len();
        for event in &page.items {
            let Some(suffix) = event.point.strip_prefix(&prefix) else {
                continue;
            };
            if let Some(what) = observe(suffix, &event.value, event.quality.invalid, &mut counters)
            {
                observations.push(Observation::new(event.event_time(), what));
            }
        }
        after = page.next;
        if after.is_none() {
            break;
        }
        if read >= FIGURES_EVENT_CAP {
            truncated = true;
            break;
        }
    }
    // The faults archived in the period, by the station's clock: a board's own clock may
    // be years off (never set, or a simulator's), its records are counted when they came.
    let mut faults = Vec::new();
    let mut offset = 0u64;
    loop {
        let query = LiftFaultQuery::default()
            .with_lifts([lift.name.clone()])
            .with_received_range(Some(period.from()), Some(period.to()))
            .with_order(LiftFaultOrder::Archived, false)
            .with_page(offset, 5000);
        let page = archive.query_lift_faults(&query).await?;
        let got = page.items.len();
        faults.extend(
            page.items
                .iter()
                .filter(|r| period.contains(r.received_time))
                .map(|r| FaultAt {
                    time: r.received_time,
                    code: r.code,
                }),
        );
        offset = offset.saturating_add(u64::try_from(got).unwrap_or(u64::MAX));
        if got < 5000 || offset >= CSV_CAP {
            break;
        }
    }
    let figures =
        ServiceFigures::compute(period, &observations, &faults, &FiguresConfig::default());
    Ok((figures, truncated))
}

fn period_json(period: &Period) -> Value {
    json!({"from": period.from(), "to": period.to()})
}

async fn fleet_figures(
    State(state): State<AppState>,
    user: LoggedIn,
    query: Result<Query<FiguresParams>, QueryRejection>,
) -> Result<Json<Value>, AppError> {
    let config = state.station.config();
    require(&user, "figures", config.lift_levels.figures)?;
    let Query(params) = query?;
    let period = period_of(&params)?;
    let archive = state.archive()?;
    let mut each = Vec::new();
    for lift in &config.lifts {
        each.push((lift, lift_figures_of(archive.as_ref(), lift, period).await?));
    }
    let fleet = FleetFigures::new(each.iter().map(|(_, (f, _))| f), &StatusColours::default());
    let lifts: Vec<Value> = each
        .iter()
        .map(|(lift, (figures, truncated))| {
            json!({"name": lift.name, "description": lift.description,
                   "figures": figures, "truncated": truncated})
        })
        .collect();
    Ok(Json(json!({
        "period": period_json(&period),
        "fleet": fleet,
        "lifts": lifts,
    })))
}

async fn lift_figures(
    State(state): State<AppState>,
    user: LoggedIn,
    Path(name): Path<String>,
    query: Result<Query<FiguresParams>, QueryRejection>,
) -> Result<Json<Value>, AppError> {
    let config = state.station.config();
    require(&user, "figures", config.lift_levels.figures)?;
    let Query(params) = query?;
    let lift = config
        .lifts
        .iter()
        .find(|l| l.name == name)
        .ok_or_else(|| AppError::NoLift(LogText(&name).to_string()))?;
    let period = period_of(&params)?;
    let archive = state.archive()?;
    let (figures, truncated) = lift_figures_of(archive.as_ref(), lift, period).await?;
    Ok(Json(json!({
        "period": period_json(&period),
        "name": lift.name,
        "description": lift.description,
        "figures": figures,
        "truncated": truncated,
    })))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_filter_matches_english_and_czech_without_accents() {
        let door = codes_matching("door");
        assert!(!door.is_empty());
        let dvere = codes_matching("DVEŘ");
        assert!(!dvere.is_empty());
        assert_eq!(codes_matching("dver"), dvere);
        assert!(codes_matching("no fault reads like this").is_empty());
        assert_eq!(parse_code("3C"), Some(0x3C));
        assert_eq!(parse_code("0x3c"), Some(0x3C));
        assert_eq!(parse_code("100"), None);
        assert_eq!(parse_code(""), None);
    }

    #[test]
    fn bounds_and_csv_fields() {
        let day = parse_bound("until", "2025-03-01", true).unwrap();
        assert_eq!(day.to_string(), "2025-03-02 00:00:00");
        assert!(parse_bound("since", "2025-13-01", false).is_err());
        assert!(parse_bound("since", "2025-03-01T10:20", false).is_ok());
        let mut out = String::new();
        csv_field(&mut out, "a,\"b\"");
        csv_field(&mut out, "=1+1");
        assert_eq!(out, "\"a,\"\"b\"\"\"\"'=1+1\"");
    }
}
