//! `stanice points PROJECT [--node NAME]`: every data point a node serves, as CSV
//! (`ioa,type,name,description`), commands included, in IOA order.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Args;

use crate::run::load_project;

/// Arguments of `stanice points`.
#[derive(Args, Debug)]
pub(crate) struct PointsArgs {
    /// The project folder.
    project: PathBuf,
    /// The node; default: the top node (the one no other node links to).
    #[arg(long)]
    node: Option<String>,
    /// One JSON object per point (`ioa`, `type`, `name`, `description`) instead of CSV.
    #[arg(long)]
    json: bool,
}

pub(crate) fn run(args: PointsArgs) -> anyhow::Result<ExitCode> {
    let project = load_project(&args.project)?;
    let node = match &args.node {
        Some(name) => project.node(name).ok_or_else(|| {
            anyhow::anyhow!(
                "no node `{name}` in the project{}",
                plc::suggest::did_you_mean(name, project.nodes.iter().map(|n| n.name.as_str()))
            )
        })?,
        None => project
            .top_node()
            .ok_or_else(|| anyhow::anyhow!("the project has no nodes"))?,
    };
    let mut rows: Vec<(u32, String, String, String)> = node
        .points
        .iter()
        .map(|p| {
            (
                p.ioa.get(),
                points_iec::type_id(p.point_type).to_string(),
                p.name.clone(),
                p.description.clone(),
            )
        })
        .chain(node.commands.iter().map(|c| {
            (
                c.ioa.get(),
                c.type_id.to_string(),
                c.name.clone(),
                c.description.clone(),
            )
        }))
        .collect();
    rows.sort_by(|a, b| a.0.cmp(&b.0).then_with(|| a.1.cmp(&b.1)));
    if args.json {
        let lines: Vec<String> = rows
            .into_iter()
            .map(|(ioa, type_id, name, description)| {
                serde_json::json!({"ioa": ioa, "type": type_id, "name": name, "description": description})
                    .to_string()
            })
            .collect();
        crate::console::print_lines(&lines);
        return Ok(ExitCode::SUCCESS);
    }
    let mut out = csv::Writer::from_writer(std::io::stdout());
    let written = (|| -> Result<(), csv::Error> {
        out.write_record(["ioa", "type", "name", "description"])?;
        for (ioa, type_id, name, description) in rows {
            out.write_record([ioa.to_string(), type_id, name, description])?;
        }
        out.flush()?;
        Ok(())
    })();
    match written {
        // A reader that stops early (`| head`) is not an error.
        Err(error)
            if error.is_io_error()
                && matches!(error.kind(), csv::ErrorKind::Io(e) if e.kind() == std::io::ErrorKind::BrokenPipe) =>
        {
            Ok(ExitCode::SUCCESS)
        }
        Err(error) => Err(error.into()),
        Ok(()) => Ok(ExitCode::SUCCESS),
    }
}
