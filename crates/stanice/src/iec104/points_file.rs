//! The outstation's CSV point list.
//!
//! Header `ioa,type,value`, one row per point; `type` is a standard mnemonic. Monitor
//! types (`M_*`) are data points with their initial value; command types (`C_*`) are
//! points that accept commands (value empty or ignored). Optional columns:
//! `select` (`true`: the command point requires select-before-operate), `groups`
//! (interrogation groups 1..=16 separated by `;`), `name` (shown in logs).
//!
//! ```csv
//! ioa,type,value,name
//! 281,M_SP_TB_1,1,RH2 breaker FA1 closed
//! 2021,C_SC_NA_1,,RH2 open QF1
//! ```

use std::collections::HashMap;
use std::path::Path;

use anyhow::{bail, Context};
use iec60870::asdu::text::parse_monitor;
use iec60870::asdu::{Ioa, TypeId};
use iec60870::cs104::server::{CommandPoint, MonitorPoint, ProcessImage};

/// One point of the file.
#[derive(Debug, Clone)]
pub(crate) struct PointRow {
    pub(crate) ioa: Ioa,
}

/// A loaded point list.
#[derive(Debug, Default)]
pub(crate) struct PointList {
    pub(crate) image: ProcessImage,
    pub(crate) monitor: Vec<PointRow>,
    pub(crate) commands: Vec<PointRow>,
    /// Names of monitor points by address.
    pub(crate) monitor_names: HashMap<u32, String>,
    /// Names of command points by address (a command and a monitor point may share an
    /// address: the monitor point then returns the command's effect).
    pub(crate) command_names: HashMap<u32, String>,
}

pub(crate) fn load(path: &Path) -> anyhow::Result<PointList> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read point list {}", path.display()))?;
    parse(&text).map_err(|error| anyhow::anyhow!("{}:{error}", path.display()))
}

/// Parses the file's text; errors start with `line:` so the caller can prefix the path.
pub(crate) fn parse(text: &str) -> anyhow::Result<PointList> {
    let mut reader = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .flexible(true)
        .from_reader(text.as_bytes());
    let headers = reader
        .headers()
        .context("1: cannot read the header")?
        .clone();
    let column = |name: &str| {
        headers
            .iter()
            .position(|header| header.eq_ignore_ascii_case(name))
    };
    let (Some(ioa_column), Some(type_column)) = (column("ioa"), column("type")) else {
        bail!("1: the header must name the columns ioa,type,value");
    };
    let value_column = column("value");
    let select_column = column("select");
    let groups_column = column("groups");
    let name_column = column("name");
    let mut list = PointList::default();
    for record in reader.records() {
        let record = record.map_err(|error| {
            let line = error.position().map_or(0, csv::Position::line);
            anyhow::anyhow!("{line}: {error}")
        })?;
        let line = record.position().map_or(0, csv::Position::line);
        let field = |index: Option<usize>| index.and_then(|index| record.get(index)).unwrap_or("");
        let ioa_text = field(Some(ioa_column));
        let ioa: u32 = ioa_text
            .parse()
            .map_err(|_| anyhow::anyhow!("{line}: ioa '{ioa_text}' is not a number"))?;
        let ioa = Ioa::try_new(ioa).map_err(|error| anyhow::anyhow!("{line}: {error}"))?;
        let type_text = field(Some(type_column));
        let type_id: TypeId = type_text.parse().map_err(|_| {
            anyhow::anyhow!("{line}: unknown type '{type_text}' (use a mnemonic such as M_SP_NA_1)")
        })?;
        let name = field(name_column).to_owned();
        if type_id.is_monitor() {
            let element = parse_monitor(type_id, field(value_column))
                .map_err(|error| anyhow::anyhow!("{line}: {error}"))?;
            let groups = parse_groups(field(groups_column))
                .map_err(|error| anyhow::anyhow!("{line}: {error}"))?;
            list.image
                .add_monitor(MonitorPoint {
                    ioa,
                    event_type: type_id,
                    groups,
                    element,
                    time: None,
                })
                .map_err(|error| anyhow::anyhow!("{line}: {error}"))?;
            list.monitor.push(PointRow { ioa });
            if !name.is_empty() {
                list.monitor_names.insert(ioa.get(), name);
            }
        } else if type_id.is_command() {
            let select_required = match field(select_column).to_ascii_lowercase().as_str() {
                "" | "0" | "false" | "no" => false,
                "1" | "true" | "yes" => true,
                other => bail!("{line}: select must be true or false, not '{other}'"),
            };
            list.image
                .add_command(CommandPoint {
                    ioa,
                    command_type: type_id,
                    select_required,
                    max_age: None,
                })
                .map_err(|error| anyhow::anyhow!("{line}: {error}"))?;
            list.commands.push(PointRow { ioa });
            if !name.is_empty() {
                list.command_names.insert(ioa.get(), name);
            }
        } else {
            bail!("{line}: {type_id} is neither a monitor nor a command type");
        }
    }
    Ok(list)
}

fn parse_groups(text: &str) -> anyhow::Result<u16> {
    let mut groups = 0u16;
    for part in text
        .split(';')
        .map(str::trim)
        .filter(|part| !part.is_empty())
    {
        let group: u8 = part
            .parse()
            .map_err(|_| anyhow::anyhow!("group '{part}' is not a number"))?;
        if !(1..=16).contains(&group) {
            bail!("group {group} is not in 1..=16");
        }
        groups |= 1 << (group - 1);
    }
    Ok(groups)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_monitor_and_command_points() {
        let list = parse(
            "ioa,type,value,name\n281,M_SP_TB_1,1,FA1\n1100,M_ME_NA_1,0.335114,U12\n2021,C_SC_NA_1,,open QF1\n",
        )
        .unwrap();
        assert_eq!(list.monitor.len(), 2);
        assert_eq!(list.commands.len(), 1);
        assert_eq!(
            list.monitor_names.get(&281).map(String::as_str),
            Some("FA1")
        );
    }

    #[test]
    fn a_command_and_its_feedback_point_keep_their_own_names() {
        let list = parse(
            "ioa,type,value,name\n2021,M_DP_NA_1,1,QF1 position\n2021,C_DC_NA_1,,QF1 command\n",
        )
        .unwrap();
        assert_eq!(list.monitor_names[&2021], "QF1 position");
        assert_eq!(list.command_names[&2021], "QF1 command");
    }

    #[test]
    fn reports_the_line_of_an_error() {
        let error = parse("ioa,type,value\n1,M_SP_NA_1,1\n2,M_XX_NA_1,1\n").unwrap_err();
        assert!(
            error.to_string().starts_with("3: unknown type 'M_XX_NA_1'"),
            "{error}"
        );
        let error = parse("ioa,type,value\n1,M_SP_NA_1,maybe\n").unwrap_err();
        assert!(error.to_string().starts_with("2: "), "{error}");
        let error = parse("ioa,type,value\n1,M_SP_NA_1,1\n1,M_SP_NA_1,0\n").unwrap_err();
        assert!(error.to_string().starts_with("3: "), "{error}");
        let error = parse("address,kind\n").unwrap_err();
        assert!(error.to_string().starts_with("1: "), "{error}");
    }
}
