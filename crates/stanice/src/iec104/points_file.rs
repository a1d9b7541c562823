//! The test tools' outstation: a process image from a CSV point list.
//!
//! The list is read by the library's one point-list reader
//! ([`iec60870::point_list`]: header `ioa,type,value` with optional `name`,
//! `description`, `select`, `groups`); here its rows become the outstation's monitor
//! points (`M_*`, with their initial value) and command points (`C_*`).
//!
//! ```csv
//! ioa,type,value,name
//! 281,M_SP_TB_1,1,RH2 breaker FA1 closed
//! 2021,C_SC_NA_1,,RH2 open QF1
//! ```

use std::collections::HashMap;
use std::path::Path;

use anyhow::Context;
use iec60870::asdu::text::parse_monitor;
use iec60870::asdu::Ioa;
use iec60870::cs104::server::{CommandPoint, MonitorPoint, ProcessImage};
use iec60870::point_list;

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
    let mut list = PointList::default();
    for row in point_list::parse(text)? {
        let line = row.line;
        let ioa = row.ioa;
        if row.type_id.is_monitor() {
            // A list without a value column gives every monitor point the value of empty
            // text, which the value reader refuses for the types that need one.
            let element = match row.value {
                Some(element) => element,
                None => parse_monitor(row.type_id, "")
                    .map_err(|error| anyhow::anyhow!("{line}: {error}"))?,
            };
            list.image
                .add_monitor(MonitorPoint {
                    ioa,
                    event_type: row.type_id,
                    groups: row.groups,
                    element,
                    time: None,
                })
                .map_err(|error| anyhow::anyhow!("{line}: {error}"))?;
            list.monitor.push(PointRow { ioa });
            if !row.name.is_empty() {
                list.monitor_names.insert(ioa.get(), row.name);
            }
        } else {
            list.image
                .add_command(CommandPoint {
                    ioa,
                    command_type: row.type_id,
                    select_required: row.select,
                    max_age: None,
                })
                .map_err(|error| anyhow::anyhow!("{line}: {error}"))?;
            list.commands.push(PointRow { ioa });
            if !row.name.is_empty() {
                list.command_names.insert(ioa.get(), row.name);
            }
        }
    }
    Ok(list)
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
