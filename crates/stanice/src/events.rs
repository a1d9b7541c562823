//! `stanice events PROJECT`: reads the project's event store — value changes, or with
//! `--commands` the command audit — filtered by time, point and node, newest last.

use std::path::PathBuf;
use std::process::ExitCode;

use chrono::{DateTime, Utc};
use clap::Args;
use station::store::{open_store, CommandQuery, EventQuery, Order, PointFilter, Quality};

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
    /// At most this many records (the newest).
    #[arg(long, default_value_t = 100)]
    limit: usize,
    /// Another store than the project's (`sqlite:PATH`, `postgres://...`).
    #[arg(long)]
    store: Option<String>,
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
    let store = open_store(&url).await?;
    let since = args
        .since
        .as_deref()
        .map(|s| parse_since(s, Utc::now()))
        .transpose()?;
    let limit = args.limit.clamp(1, station::store::MAX_PAGE_SIZE);
    let point = args.point.as_deref().map(PointFilter::parse);
    if args.commands {
        let mut query = CommandQuery::default()
            .with_range(since, args.until)
            .with_order(Order::NewestFirst)
            .with_limit(limit);
        query.point = point;
        query.node = args.node.clone();
        let page = store.query_commands(&query).await?;
        println!("time,node,point,ioa,value,phase,outcome,actor,detail");
        for c in page.items.iter().rev() {
            println!(
                "{},{},{},{},{},{:?},{:?},{},{:?}",
                c.time.format("%Y-%m-%dT%H:%M:%S%.3fZ"),
                c.node,
                c.point,
                c.ioa.map(|i| i.to_string()).unwrap_or_default(),
                c.value,
                c.phase,
                c.outcome,
                c.actor,
                c.detail
            );
        }
    } else {
        let mut query = EventQuery::default()
            .with_range(since, args.until)
            .with_order(Order::NewestFirst)
            .with_limit(limit);
        query.point = point;
        query.node = args.node.clone();
        let page = store.query_events(&query).await?;
        println!("time,node,point,ioa,value,quality,cause,origin");
        for e in page.items.iter().rev() {
            println!(
                "{},{},{},{},{},{},{:?},{}",
                e.event_time().format("%Y-%m-%dT%H:%M:%S%.3fZ"),
                e.node,
                e.point,
                e.ioa.map(|i| i.to_string()).unwrap_or_default(),
                e.value,
                quality_flags(e.quality),
                e.cause,
                e.origin
            );
        }
    }
    Ok(ExitCode::SUCCESS)
}
