//! Trends: the points that have one, and the samples of one or more points (pens) over a
//! time range, downsampled in the store to about one sample per pixel column
//! ([`store::TrendQuery`]), as JSON or as CSV.

use std::collections::BTreeMap;

use axum::extract::rejection::QueryRejection;
use axum::extract::{Query, State};
use axum::http::header;
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use axum::{Json, Router};
use chrono::{DateTime, SecondsFormat, Utc};
use serde::Deserialize;
use serde_json::{json, Value};
use store::{TrendBucket, TrendMode, TrendQuery, MAX_TREND_BUCKETS};

use super::{AppError, AppState, LoggedIn};

/// The most pens one trend request draws.
const MAX_PENS: usize = 8;
/// Buckets when the request names no width (a chart about this many pixels wide).
const DEFAULT_BUCKETS: usize = 1_000;
/// The longest range one request may ask for.
const MAX_RANGE_DAYS: i64 = 400;

pub(super) fn routes() -> Router<AppState> {
    Router::new()
        .route("/api/trend", get(trend))
        .route("/api/trends", get(trends))
}

/// The unit of a point, read from its description's last comma-separated word
/// (`"busbar voltage, V"` is in V); `None` when the description names none.
fn unit_of(description: &str) -> Option<String> {
    let (_, unit) = description.rsplit_once(", ")?;
    let unit = unit.trim();
    (!unit.is_empty() && unit.chars().count() <= 8 && !unit.contains(' ')).then(|| unit.to_owned())
}

async fn trends(State(state): State<AppState>, _: LoggedIn) -> Json<Value> {
    let config = state.station.config();
    let list: Vec<Value> = config
        .trends
        .iter()
        .filter_map(|name| config.points.iter().find(|p| &p.name == name))
        .map(|p| json!({"point": p.name, "description": p.description, "unit": unit_of(&p.description)}))
        .collect();
    Json(json!(list))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TrendParameters {
    /// One pen (the single-pen form, answered in its own shape).
    point: Option<String>,
    /// Pens, comma-separated.
    points: Option<String>,
    from: Option<DateTime<Utc>>,
    to: Option<DateTime<Utc>>,
    /// The chart's width in pixels: the number of buckets.
    width: Option<usize>,
    /// `json` (the default) or `csv`.
    format: Option<String>,
    /// `minmax` (every value of a bucket: exact extremes) or `firstlast` (its first and
    /// last value); both read from the store's minute rollups for buckets of 4 minutes or
    /// more; default `minmax`.
    mode: Option<String>,
}

/// One pen's answer.
struct Pen {
    point: String,
    description: String,
    unit: Option<String>,
    buckets: Vec<TrendBucket>,
}

/// One sample of a pen: a value at a time, with a bucket's extremes when it folds several.
struct Sample {
    time: DateTime<Utc>,
    value: f64,
    invalid: bool,
    extremes: Option<(f64, f64)>,
}

/// A bucket's samples: its value at its time for a bucket of one value; its first and
/// last value at their times (`firstlast`); its mean at its first value's time with its
/// min and max (`minmax`).
fn samples(bucket: &TrendBucket) -> Vec<Sample> {
    let one = |time, value| Sample {
        time,
        value,
        invalid: bucket.invalid,
        extremes: None,
    };
    match (bucket.first, bucket.last) {
        _ if bucket.count <= 1 => vec![one(bucket.first_time, bucket.first.unwrap_or(bucket.avg))],
        (Some(first), Some(last)) => {
            vec![one(bucket.first_time, first), one(bucket.last_time, last)]
        }
        _ => vec![Sample {
            extremes: Some((bucket.min, bucket.max)),
            ..one(bucket.first_time, bucket.avg)
        }],
    }
}

/// A sample as JSON: `[time_ms, value, invalid]`, or `[time_ms, mean, invalid, min, max]`.
fn sample_json(sample: &Sample) -> Value {
    let time = sample.time.timestamp_millis();
    match sample.extremes {
        None => json!([time, sample.value, sample.invalid]),
        Some((min, max)) => json!([time, sample.value, sample.invalid, min, max]),
    }
}

fn pen_samples(pen: &Pen) -> Vec<Value> {
    pen.buckets
        .iter()
        .flat_map(samples)
        .map(|s| sample_json(&s))
        .collect()
}

fn bad(name: &'static str, message: impl Into<String>) -> AppError {
    AppError::BadParameter {
        name,
        message: message.into(),
    }
}

async fn trend(
    State(state): State<AppState>,
    _: LoggedIn,
    query: Result<Query<TrendParameters>, QueryRejection>,
) -> Result<Response, AppError> {
    let Query(query) = query?;
    let single = query.points.is_none();
    let names: Vec<String> = match (&query.points, &query.point) {
        (Some(_), Some(_)) => return Err(bad("points", "give `point` or `points`, not both")),
        (Some(list), None) => list
            .split(',')
            .map(|name| name.trim().to_owned())
            .filter(|name| !name.is_empty())
            .collect(),
        (None, Some(point)) => vec![point.clone()],
        (None, None) => return Err(bad("points", "name at least one point")),
    };
    if names.is_empty() || names.len() > MAX_PENS {
        return Err(bad(
            "points",
            format!("a trend has 1 to {MAX_PENS} points, not {}", names.len()),
        ));
    }
    let mut views = Vec::with_capacity(names.len());
    for name in &names {
        let view = state
            .station
            .point(name)
            .ok_or_else(|| AppError::NoPoint(name.clone()))?;
        views.push(view);
    }
    let csv = match query.format.as_deref() {
        None | Some("json") => false,
        Some("csv") => true,
        Some(other) => return Err(bad("format", format!("`{other}` is not json or csv"))),
    };
    let buckets = query.width.unwrap_or(DEFAULT_BUCKETS);
    if buckets == 0 || buckets > MAX_TREND_BUCKETS {
        return Err(bad(
            "width",
            format!("from 1 to {MAX_TREND_BUCKETS} pixels, not {buckets}"),
        ));
    }
    let store = state.store()?;
    let to = query.to.unwrap_or_else(Utc::now);
    let from = query.from.unwrap_or(to - chrono::Duration::hours(24));
    if from >= to {
        return Err(bad("from", "the range must start before it ends"));
    }
    if to - from > chrono::Duration::days(MAX_RANGE_DAYS) {
        return Err(bad(
            "from",
            format!("a trend spans at most {MAX_RANGE_DAYS} days"),
        ));
    }
    let mode = match query.mode.as_deref() {
        None | Some("minmax") => TrendMode::Aggregate,
        Some("firstlast") => TrendMode::FirstLast,
        Some(other) => return Err(bad("mode", format!("`{other}` is not minmax or firstlast"))),
    };
    let mut pens = Vec::with_capacity(views.len());
    for view in views {
        let trend = store
            .query_trend(&TrendQuery::new(view.name.as_str(), from, to, buckets).with_mode(mode))
            .await?;
        pens.push(Pen {
            unit: unit_of(&view.description),
            point: view.name,
            description: view.description,
            buckets: trend,
        });
    }
    if csv {
        return Ok(csv_response(&pens));
    }
    if single {
        // The single-pen shape of earlier versions.
        let pen = pens.first();
        return Ok(Json(json!({
            "point": pen.map(|p| p.point.as_str()),
            "unit": pen.and_then(|p| p.unit.as_deref()),
            "from": from, "to": to,
            "samples": pen.map(pen_samples).unwrap_or_default(),
        }))
        .into_response());
    }
    let series: Vec<Value> = pens
        .iter()
        .map(|pen| {
            json!({"point": pen.point, "description": pen.description, "unit": pen.unit,
                   "samples": pen_samples(pen)})
        })
        .collect();
    let mode = match mode {
        TrendMode::Aggregate => "minmax",
        TrendMode::FirstLast => "firstlast",
    };
    Ok(
        Json(json!({"from": from, "to": to, "width": buckets, "mode": mode, "series": series}))
            .into_response(),
    )
}

/// A CSV field, quoted when it needs to be.
fn csv_field(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_owned()
    }
}

/// `time,A,B`: one row per distinct sample time, RFC 3339 with the offset; an empty
/// cell where a pen has no sample at that time.
fn csv_response(pens: &[Pen]) -> Response {
    let mut rows: BTreeMap<DateTime<Utc>, Vec<Option<f64>>> = BTreeMap::new();
    for (column, pen) in pens.iter().enumerate() {
        for sample in pen.buckets.iter().flat_map(samples) {
            let row = rows
                .entry(sample.time)
                .or_insert_with(|| vec![None; pens.len()]);
            if let Some(cell) = row.get_mut(column) {
                *cell = Some(sample.value);
            }
        }
    }
    let mut text = String::from("time");
    for pen in pens {
        text.push(',');
        text.push_str(&csv_field(&pen.point));
    }
    text.push('\n');
    for (time, cells) in rows {
        text.push_str(&time.to_rfc3339_opts(SecondsFormat::Millis, false));
        for cell in cells {
            text.push(',');
            if let Some(value) = cell {
                text.push_str(&value.to_string());
            }
        }
        text.push('\n');
    }
    (
        [
            (header::CONTENT_TYPE, "text/csv; charset=utf-8"),
            (
                header::CONTENT_DISPOSITION,
                "attachment; filename=\"trend.csv\"",
            ),
        ],
        text,
    )
        .into_response()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_come_from_the_description() {
        assert_eq!(unit_of("busbar voltage, V").as_deref(), Some("V"));
        assert_eq!(unit_of("load power, kW").as_deref(), Some("kW"));
        assert_eq!(unit_of("a breaker"), None);
        assert_eq!(unit_of("one, two three"), None);
    }

    #[test]
    fn csv_fields_are_quoted_when_needed() {
        assert_eq!(csv_field("RH11_U"), "RH11_U");
        assert_eq!(csv_field("a,b"), "\"a,b\"");
        assert_eq!(csv_field("a\"b"), "\"a\"\"b\"");
    }
}
