//! `stanice events PROJECT`: reads the project's event store — value changes, or with
//! `--commands` the command audit — filtered by time, point and node, newest last.
//!
//! Times are printed in the project's time zone (or `--time-zone`) as RFC 3339 with the
//! offset. Output is CSV or, with `--json`, one JSON object per line. A reader that stops
//! early (`| head`) ends the command quietly; when more records match than `--limit`
//! shows, standard error says so.

use std::io::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

use chrono::{DateTime, Utc};
use chrono_tz::Tz;
use clap::Args;
use serde_json::json;
use station::store::url::StoreUrl;
use station::store::{
    open_store, CommandQuery, CommandRecord, EventQuery, EventRecord, Order, PointFilter, Quality,
};

use crate::printed_time::{parse_zone, rfc3339};
use crate::run::load_project;

/// Arguments of `stanice events`.
#[derive(Args, Debug)]
pub(crate) struct EventsArgs {
    /// The project folder.
    project: PathBuf,
    /// From this time: RFC 3339 (`2025-01-15T16:00:00Z`) or an age (`30m`, `2h`, `7d`).
    #[arg(long)]
    since: Option<String>,
    /// Up to this time (RFC 3339).
    #[arg(long)]
    until: Option<DateTime<Utc>>,
    /// A point name, or a prefix ending in `*` (`RH2_*`).
    #[arg(long)]
    point: Option<String>,
    /// Only this node's records.
    #[arg(long)]
    node: Option<String>,
    /// The command audit instead of value changes.
    #[arg(long)]
    commands: bool,
    /// At most this many records (the newest); standard error says when more match.
    #[arg(long, default_value_t = 100)]
    limit: usize,
    /// Another store than the project's (`sqlite:PATH`, `postgres://...`).
    #[arg(long)]
    store: Option<String>,
    /// The zone times are printed in (IANA name or `UTC`); default: the project's
    /// `time_zone`.
    #[arg(long, value_name = "ZONE", value_parser = parse_zone)]
    time_zone: Option<Tz>,
    /// One JSON object per line instead of CSV.
    #[arg(long)]
    json: bool,
}

fn parse_since(text: &str, now: DateTime<Utc>) -> anyhow::Result<DateTime<Utc>> {
    if let Ok(time) = text.parse::<DateTime<Utc>>() {
        return Ok(time);
    }
    let (number, unit) = text.split_at(text.len().saturating_sub(1));
    let amount: i64 = number
        .parse()
        .map_err(|_| anyhow::anyhow!("--since {text:?}: expected RFC 3339 or an age like 30m"))?;
    let age = match unit {
        "s" => chrono::Duration::seconds(amount),
        "m" => chrono::Duration::minutes(amount),
        "h" => chrono::Duration::hours(amount),
        "d" => chrono::Duration::days(amount),
        _ => anyhow::bail!("--since {text:?}: the unit is one of s, m, h, d"),
    };
    Ok(now - age)
}

fn quality_flags(quality: Quality) -> String {
    quality.set_flags().join(" ")
}

pub(crate) async fn run(args: EventsArgs) -> anyhow::Result<ExitCode> {
    let project = load_project(&args.project)?;
    let url = args
        .store
        .clone()
        .unwrap_or_else(|| project.station.store.clone());
    // Reading must not leave an empty store behind where a station never ran.
    if let Ok(StoreUrl::SqliteFile { path, .. }) = StoreUrl::parse(&url) {
        if !path.exists() {
            anyhow::bail!(
                "no event store at {}: the project has not run yet (stanice run {}) or its \
                 store is elsewhere (--store)",
                path.display(),
                args.project.display()
            );
        }
    }
    let store = open_store(&url).await?;
    let since = args
        .since
        .as_deref()
        .map(|s| parse_since(s, Utc::now()))
        .transpose()?;
    let limit = args.limit.clamp(1, station::store::MAX_PAGE_SIZE);
    if limit != args.limit {
        eprintln!("note: --limit {} taken as {limit}", args.limit);
    }
    let point = args.point.as_deref().map(PointFilter::parse);
    let zone = args.time_zone.unwrap_or(project.station.time_zone);
    let mut out = std::io::stdout().lock();
    let (written, more) = if args.commands {
        let mut query = CommandQuery::default()
            .with_range(since, args.until)
            .with_order(Order::NewestFirst)
            .with_limit(limit);
        query.point = point;
        query.node = args.node.clone();
        let page = store.query_commands(&query).await?;
        let written = write_commands(&mut out, &page.items, zone, args.json);
        (written, page.next.is_some())
    } else {
        let mut query = EventQuery::default()
            .with_range(since, args.until)
            .with_order(Order::NewestFirst)
            .with_limit(limit);
        query.point = point;
        query.node = args.node.clone();
        let page = store.query_events(&query).await?;
        let written = write_events(&mut out, &page.items, zone, args.json);
        (written, page.next.is_some())
    };
    match written.and_then(|()| out.flush()) {
        // A reader that stops early (`| head -3`) is not an error.
        Err(error) if error.kind() == std::io::ErrorKind::BrokenPipe => {
            return Ok(ExitCode::SUCCESS)
        }
        Err(error) => return Err(error.into()),
        Ok(()) => {}
    }
    if more {
        eprintln!(
            "note: only the newest {limit} records are shown; more match (--limit up to {}, \
             or narrow with --since/--until/--point/--node)",
            station::store::MAX_PAGE_SIZE
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// Value changes, oldest first (the page is newest first).
fn write_events(
    out: &mut impl std::io::Write,
    items: &[EventRecord],
    zone: Tz,
    json: bool,
) -> std::io::Result<()> {
    if !json {
        writeln!(out, "time,node,point,ioa,value,quality,cause,origin")?;
    }
    for e in items.iter().rev() {
        let time = rfc3339(e.event_time(), zone);
        if json {
            let record = json!({
                "time": time,
                "received_time": rfc3339(e.received_time, zone),
                "node": e.node,
                "point": e.point,
                "ioa": e.ioa,
                "value": e.value.to_string(),
                "quality": e.quality.set_flags(),
                "cause": format!("{:?}", e.cause),
                "origin": e.origin,
            });
            writeln!(out, "{record}")?;
        } else {
            writeln!(
                out,
                "{time},{},{},{},{},{},{:?},{}",
                e.node,
                e.point,
                e.ioa.map(|i| i.to_string()).unwrap_or_default(),
                e.value,
                quality_flags(e.quality),
                e.cause,
                e.origin
            )?;
        }
    }
    Ok(())
}

/// Audited commands, oldest first (the page is newest first).
fn write_commands(
    out: &mut impl std::io::Write,
    items: &[CommandRecord],
    zone: Tz,
    json: bool,
) -> std::io::Result<()> {
    if !json {
        writeln!(out, "time,node,point,ioa,value,phase,outcome,actor,detail")?;
    }
    for c in items.iter().rev() {
        let time = rfc3339(c.time, zone);
        if json {
            let record = json!({
                "time": time,
                "node": c.node,
                "point": c.point,
                "ioa": c.ioa,
                "value": c.value.to_string(),
                "phase": format!("{:?}", c.phase),
                "outcome": format!("{:?}", c.outcome),
                "actor": c.actor.to_string(),
                "detail": c.detail,
            });
            writeln!(out, "{record}")?;
        } else {
            writeln!(
                out,
                "{time},{},{},{},{},{:?},{:?},{},{:?}",
                c.node,
                c.point,
                c.ioa.map(|i| i.to_string()).unwrap_or_default(),
                c.value,
                c.phase,
                c.outcome,
                c.actor,
                c.detail
            )?;
        }
    }
    Ok(())
}
