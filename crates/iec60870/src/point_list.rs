//! Point lists: the CSV tables that name a station's information objects.
//!
//! One reader for every tool that takes such a table: the test tools' outstations
//! (`stanice iec104 server`, `stanice iec101 slave`: points with initial values) and the
//! HMI's `points.csv` (what `stanice points` writes: names and descriptions of what a
//! station serves). Columns are found by their header, in any order and case:
//!
//! | column | meaning | required |
//! |---|---|---|
//! | `ioa` | information object address | yes |
//! | `type` | the type's mnemonic (`M_SP_TB_1`, `C_SC_NA_1`, ...) | yes |
//! | `value` | a monitor point's initial value, as [`parse_monitor`] reads it | no |
//! | `name` | the point's name | no |
//! | `description` | what it is, for people | no |
//! | `select` | a command point requires select-before-operate (`true`/`false`) | no |
//! | `groups` | interrogation groups 1..=16 separated by `;` | no |
//!
//! Lines starting with `#` are comments; fields are trimmed. Every error names the line.
//!
//! ```
//! use iec60870::point_list;
//! let rows = point_list::parse("ioa,type,value,name\n281,M_SP_TB_1,1,FA1 closed\n2021,C_SC_NA_1,,open QF1\n")?;
//! assert_eq!(rows[0].name, "FA1 closed");
//! assert!(rows[1].type_id.is_command());
//! # Ok::<(), point_list::PointListError>(())
//! ```

use crate::asdu::text::{parse_monitor, ValueError};
use crate::asdu::{Element, Ioa, TypeId};

/// One row of a point list.
#[derive(Debug, Clone, PartialEq)]
pub struct PointRow {
    /// The line of the file it came from (1 is the header).
    pub line: u64,
    /// Information object address.
    pub ioa: Ioa,
    /// Type identification.
    pub type_id: TypeId,
    /// A monitor point's value from the `value` column; `None` for command points and
    /// when the list has no `value` column.
    pub value: Option<Element>,
    /// Name; empty when not given.
    pub name: String,
    /// Description; empty when not given.
    pub description: String,
    /// A command point that requires select-before-operate.
    pub select: bool,
    /// Interrogation groups as a bit set (bit 0 is group 1).
    pub groups: u16,
}

/// A problem in a point list, at a line.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{line}: {problem}")]
pub struct PointListError {
    /// The line (1 is the header; 0 when the reader could not tell).
    pub line: u64,
    /// What is wrong.
    pub problem: PointListProblem,
}

/// What can be wrong in a point list.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PointListProblem {
    /// The header lacks `ioa` or `type`.
    #[error("the header must name the columns ioa and type (and value, name, description, select, groups as needed)")]
    Header,
    /// Not CSV (unbalanced quotes, not UTF-8, ...).
    #[error("{0}")]
    Csv(String),
    /// The address is not a number or out of range.
    #[error("ioa '{0}' is not an information object address")]
    Address(String),
    /// Not a type mnemonic.
    #[error("unknown type '{0}' (use a mnemonic such as M_SP_NA_1)")]
    UnknownType(String),
    /// A type that is neither a monitor nor a command type (system types).
    #[error("{0} is neither a monitor nor a command type")]
    NotAPointType(TypeId),
    /// The value does not fit the type.
    #[error(transparent)]
    Value(#[from] ValueError),
    /// `select` is not a yes or no.
    #[error("select must be true or false, not '{0}'")]
    Select(String),
    /// A group outside 1..=16 or not a number.
    #[error("group '{0}' is not a number in 1..=16")]
    Group(String),
}

/// Reads a point list from its text.
pub fn parse(text: &str) -> Result<Vec<PointRow>, PointListError> {
    let mut reader = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .flexible(true)
        .from_reader(text.as_bytes());
    let headers = reader
        .headers()
        .map_err(|error| at(1, PointListProblem::Csv(error.to_string())))?
        .clone();
    let column = |name: &str| {
        headers
            .iter()
            .position(|header| header.eq_ignore_ascii_case(name))
    };
    let (Some(ioa_column), Some(type_column)) = (column("ioa"), column("type")) else {
        return Err(at(1, PointListProblem::Header));
    };
    let columns = Columns {
        ioa: ioa_column,
        type_id: type_column,
        value: column("value"),
        name: column("name"),
        description: column("description"),
        select: column("select"),
        groups: column("groups"),
    };
    let mut rows = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|error| {
            let line = error.position().map_or(0, csv::Position::line);
            at(line, PointListProblem::Csv(error.to_string()))
        })?;
        let line = record.position().map_or(0, csv::Position::line);
        rows.push(
            columns
                .row(&record, line)
                .map_err(|problem| at(line, problem))?,
        );
    }
    Ok(rows)
}

fn at(line: u64, problem: PointListProblem) -> PointListError {
    PointListError { line, problem }
}

/// Where each column is.
struct Columns {
    ioa: usize,
    type_id: usize,
    value: Option<usize>,
    name: Option<usize>,
    description: Option<usize>,
    select: Option<usize>,
    groups: Option<usize>,
}

impl Columns {
    fn row(&self, record: &csv::StringRecord, line: u64) -> Result<PointRow, PointListProblem> {
        let field = |index: Option<usize>| index.and_then(|index| record.get(index)).unwrap_or("");
        let ioa_text = field(Some(self.ioa));
        let ioa = ioa_text
            .parse::<u32>()
            .ok()
            .and_then(|ioa| Ioa::try_new(ioa).ok())
            .ok_or_else(|| PointListProblem::Address(ioa_text.to_owned()))?;
        let type_text = field(Some(self.type_id));
        let type_id: TypeId = type_text
            .parse()
            .map_err(|_| PointListProblem::UnknownType(type_text.to_owned()))?;
        if !type_id.is_monitor() && !type_id.is_command() {
            return Err(PointListProblem::NotAPointType(type_id));
        }
        let value = match self.value {
            Some(_) if type_id.is_monitor() => Some(parse_monitor(type_id, field(self.value))?),
            _ => None,
        };
        let select = match field(self.select).to_ascii_lowercase().as_str() {
            "" | "0" | "false" | "no" => false,
            "1" | "true" | "yes" => true,
            other => return Err(PointListProblem::Select(other.to_owned())),
        };
        Ok(PointRow {
            line,
            ioa,
            type_id,
            value,
            name: field(self.name).to_owned(),
            description: field(self.description).to_owned(),
            select,
            groups: parse_groups(field(self.groups))?,
        })
    }
}

/// `1;3;16` as a bit set.
fn parse_groups(text: &str) -> Result<u16, PointListProblem> {
    let mut groups = 0u16;
    for part in text
        .split(';')
        .map(str::trim)
        .filter(|part| !part.is_empty())
    {
        let group = part
            .parse::<u8>()
            .ok()
            .filter(|group| (1..=16).contains(group))
            .ok_or_else(|| PointListProblem::Group(part.to_owned()))?;
        groups |= 1 << (group - 1);
    }
    Ok(groups)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn reads_columns_by_header_in_any_order() {
        let rows = parse(
            "# the RH2 board\nname,TYPE,ioa,value,groups,select\nFA1,M_SP_TB_1,281,1,1;3,\nQF1,C_SC_NA_1,2021,,,true\n",
        )
        .unwrap();
        assert_eq!(rows.len(), 2);
        assert_eq!(rows[0].ioa.get(), 281);
        assert_eq!(rows[0].line, 3);
        assert_eq!(rows[0].groups, 0b101);
        assert!(matches!(
            rows[0].value,
            Some(Element::SinglePoint { on: true, .. })
        ));
        assert_eq!(rows[1].value, None);
        assert!(rows[1].select);
        assert_eq!(rows[1].name, "QF1");
    }

    #[test]
    fn a_list_without_values_has_none() {
        let rows =
            parse("ioa,type,name,description\n1,M_SP_TB_1,RDRT_SP1,surge arrester tripped\n")
                .unwrap();
        assert_eq!(rows[0].value, None);
        assert_eq!(rows[0].description, "surge arrester tripped");
    }

    #[test]
    fn every_problem_names_its_line() {
        let problem = |text: &str| parse(text).unwrap_err();
        let error = problem("ioa,type,value\n1,M_SP_NA_1,1\n2,M_XX_NA_1,1\n");
        assert_eq!(error.line, 3);
        assert_eq!(
            error.problem,
            PointListProblem::UnknownType("M_XX_NA_1".into())
        );
        assert!(error.to_string().starts_with("3: unknown type 'M_XX_NA_1'"));
        assert!(matches!(
            problem("ioa,type,value\n1,M_SP_NA_1,maybe\n"),
            PointListError {
                line: 2,
                problem: PointListProblem::Value(_)
            }
        ));
        assert_eq!(problem("address,kind\n").problem, PointListProblem::Header);
        assert_eq!(
            problem("ioa,type\nx,M_SP_NA_1\n").problem,
            PointListProblem::Address("x".into())
        );
        assert_eq!(
            problem("ioa,type\n16777216,M_SP_NA_1\n").problem,
            PointListProblem::Address("16777216".into())
        );
        assert_eq!(
            problem("ioa,type\n1,C_IC_NA_1\n").problem,
            PointListProblem::NotAPointType(TypeId::C_IC_NA_1)
        );
        assert_eq!(
            problem("ioa,type,select\n1,C_SC_NA_1,maybe\n").problem,
            PointListProblem::Select("maybe".into())
        );
        assert_eq!(
            problem("ioa,type,groups\n1,M_SP_NA_1,17\n").problem,
            PointListProblem::Group("17".into())
        );
        assert_eq!(problem("ioa,type\n\"1,M_SP_NA_1\n").line, 2);
    }

    proptest! {
        /// Whatever the text, the reader answers with rows or an error, never a panic.
        #[test]
        fn any_text_is_read_or_refused(text in "(ioa,type(,value|,name|,select|,groups)*\n)?[-0-9A-Za-z_,;\"# \n.]{0,200}") {
            let _ = parse(&text);
        }

        /// Rows written from values read back as the same rows.
        #[test]
        fn rows_read_back(ioas in proptest::collection::btree_set(0u32..=0xFF_FFFF, 1..20), on in any::<bool>(), groups in 0u16..) {
            let mut text = String::from("ioa,type,value,groups\n");
            for ioa in &ioas {
                let list: Vec<String> = (1..=16u8).filter(|g| groups & (1 << (g - 1)) != 0).map(|g| g.to_string()).collect();
                text.push_str(&format!("{ioa},M_SP_NA_1,{},{}\n", u8::from(on), list.join(";")));
            }
            let rows = parse(&text).unwrap();
            prop_assert_eq!(rows.len(), ioas.len());
            for (row, ioa) in rows.iter().zip(&ioas) {
                prop_assert_eq!(row.ioa.get(), *ioa);
                prop_assert_eq!(row.groups, groups);
                let is_on = matches!(row.value, Some(Element::SinglePoint { on: v, .. }) if v == on);
                prop_assert!(is_on);
            }
        }
    }
}
