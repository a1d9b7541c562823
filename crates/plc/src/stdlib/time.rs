//! Time and date functions. All values are nanoseconds: TIME/LTIME durations, TOD since
//! midnight, DATE/DT since 1970-01-01.

use crate::syntax::lexer::civil_from_days;

/// Nanoseconds per day.
pub const DAY: i64 = 86_400_000_000_000;

/// Time of day of a DT.
pub fn dt_to_tod(dt: i64) -> i64 {
    dt.rem_euclid(DAY)
}

/// Date of a DT.
pub fn dt_to_date(dt: i64) -> i64 {
    dt - dt.rem_euclid(DAY)
}

/// TOD + TIME, wrapping at midnight.
pub fn add_tod_time(tod: i64, t: i64) -> i64 {
    tod.wrapping_add(t).rem_euclid(DAY)
}

/// The weekday of a DATE/DT as IEC 61131-3 numbers it: 0 = Sunday .. 6 = Saturday (as
/// RuSTy and CODESYS's DAY_OF_WEEK; ISO 8601's 1 = Monday .. 7 = Sunday is
/// `(DAY_OF_WEEK(d) + 6) MOD 7 + 1`).
pub fn day_of_week(dt: i64) -> i64 {
    // 1970-01-01 was a Thursday (4)
    (dt.div_euclid(DAY) + 4).rem_euclid(7)
}

/// (year, month, day, hour, minute, second, nanosecond) of a DT.
pub fn split_dt(dt: i64) -> (i64, u32, u32, i64, i64, i64, i64) {
    let (y, m, d) = civil_from_days(dt.div_euclid(DAY));
    let tod = dt.rem_euclid(DAY);
    (
        y,
        m,
        d,
        tod / 3_600_000_000_000,
        tod / 60_000_000_000 % 60,
        tod / 1_000_000_000 % 60,
        tod % 1_000_000_000,
    )
}

/// A field of a date or a time of day, as the parameters of `CONCAT_*` and `SPLIT_*` name
/// it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Field {
    /// The year (1677 .. 2262: what the 64-bit nanosecond count of DATE and DT holds).
    Year,
    /// 1 .. 12.
    Month,
    /// 1 .. 28, 29, 30 or 31.
    Day,
    /// 0 .. 23.
    Hour,
    /// 0 .. 59.
    Minute,
    /// 0 .. 59.
    Second,
    /// 0 .. 999.
    Millisecond,
    /// 0 .. 999 999: the nanoseconds below the millisecond (the L-forms only).
    Nanosecond,
}

impl Field {
    /// The parameter's name.
    pub fn name(self) -> &'static str {
        match self {
            Field::Year => "YEAR",
            Field::Month => "MONTH",
            Field::Day => "DAY",
            Field::Hour => "HOUR",
            Field::Minute => "MINUTE",
            Field::Second => "SECOND",
            Field::Millisecond => "MILLISECOND",
            Field::Nanosecond => "NANOSECOND",
        }
    }

    /// The values the field takes (a DAY up to 31; the month may have fewer).
    pub fn range(self) -> (i64, i64) {
        match self {
            Field::Year => (MIN_YEAR, MAX_YEAR),
            Field::Month => (1, 12),
            Field::Day => (1, 31),
            Field::Hour => (0, 23),
            Field::Minute | Field::Second => (0, 59),
            Field::Millisecond => (0, 999),
            Field::Nanosecond => (0, 999_999),
        }
    }
}

impl std::fmt::Display for Field {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The first year of DATE and DT (1677-09-22 is their first whole day).
const MIN_YEAR: i64 = 1677;
/// The last year of DATE and DT (2262-04-11 is their last whole day).
const MAX_YEAR: i64 = 2262;

/// What a `CONCAT_*` builds and a `SPLIT_*` takes apart. LDATE, LTOD and LDT are DATE, TOD
/// and DT here (nanoseconds); their functions take and give the nanoseconds below the
/// millisecond as `NANOSECOND` besides the standard's `MILLISECOND`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Parts {
    /// DATE: year, month, day.
    Date,
    /// TOD: hour, minute, second, millisecond.
    Tod,
    /// DT: year .. millisecond.
    Dt,
    /// LDATE: as DATE.
    LDate,
    /// LTOD: as TOD, and nanosecond.
    LTod,
    /// LDT: as DT, and nanosecond.
    LDt,
}

impl Parts {
    /// The type of the value.
    pub fn ty(self) -> crate::check::Ty {
        use crate::check::Ty;
        match self {
            Parts::Date | Parts::LDate => Ty::Date,
            Parts::Tod | Parts::LTod => Ty::Tod,
            Parts::Dt | Parts::LDt => Ty::Dt,
        }
    }

    /// The fields, in the order of the standard's parameters (NANOSECOND, an extension,
    /// last).
    pub fn fields(self) -> &'static [Field] {
        use Field::*;
        match self {
            Parts::Date | Parts::LDate => &[Year, Month, Day],
            Parts::Tod => &[Hour, Minute, Second, Millisecond],
            Parts::LTod => &[Hour, Minute, Second, Millisecond, Nanosecond],
            Parts::Dt => &[Year, Month, Day, Hour, Minute, Second, Millisecond],
            Parts::LDt => &[
                Year,
                Month,
                Day,
                Hour,
                Minute,
                Second,
                Millisecond,
                Nanosecond,
            ],
        }
    }
}

/// The fields of a date and time. `i128` so that every ANY_INT value (ULINT too) reaches
/// the range checks unchanged.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Fields {
    /// Year.
    pub year: i128,
    /// Month, 1 .. 12.
    pub month: i128,
    /// Day of the month, from 1.
    pub day: i128,
    /// Hour.
    pub hour: i128,
    /// Minute.
    pub minute: i128,
    /// Second.
    pub second: i128,
    /// Millisecond.
    pub millisecond: i128,
    /// Nanoseconds below the millisecond.
    pub nanosecond: i128,
}

impl Fields {
    /// The value of one field.
    pub fn get(&self, f: Field) -> i128 {
        match f {
            Field::Year => self.year,
            Field::Month => self.month,
            Field::Day => self.day,
            Field::Hour => self.hour,
            Field::Minute => self.minute,
            Field::Second => self.second,
            Field::Millisecond => self.millisecond,
            Field::Nanosecond => self.nanosecond,
        }
    }

    /// Sets one field.
    pub fn set(&mut self, f: Field, v: i128) {
        let slot = match f {
            Field::Year => &mut self.year,
            Field::Month => &mut self.month,
            Field::Day => &mut self.day,
            Field::Hour => &mut self.hour,
            Field::Minute => &mut self.minute,
            Field::Second => &mut self.second,
            Field::Millisecond => &mut self.millisecond,
            Field::Nanosecond => &mut self.nanosecond,
        };
        *slot = v;
    }
}

/// Why fields make no date or time of day.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum FieldsError {
    /// A field outside its range (`MONTH` 13, `HOUR` 24).
    #[error("{field} {value} is outside {lo}..{hi}")]
    OutOfRange {
        /// The field.
        field: Field,
        /// Its value.
        value: i128,
        /// The smallest allowed.
        lo: i64,
        /// The largest allowed.
        hi: i64,
    },
    /// A day the month does not have (`DAY` 30 in February).
    #[error("DAY {day} is not in {year}-{month:02}, which has {days} days")]
    NoSuchDay {
        /// Year.
        year: i64,
        /// Month.
        month: i64,
        /// The day asked for.
        day: i64,
        /// The days of that month.
        days: i64,
    },
    /// A date and time before 1677-09-21 00:12:43.145224192 or after 2262-04-11
    /// 23:47:16.854775807 (what 64 bits of nanoseconds since 1970 hold).
    #[error("{year:04}-{month:02}-{day:02}{time} is outside the range of {ty}")]
    Unrepresentable {
        /// Year.
        year: i64,
        /// Month.
        month: i64,
        /// Day.
        day: i64,
        /// The time of day as `-hh:mm:ss` (empty for a DATE).
        time: String,
        /// DATE or DT.
        ty: &'static str,
    },
}

/// Whether `year` is a leap year (Gregorian).
pub fn is_leap_year(year: i64) -> bool {
    (year % 4 == 0 && year % 100 != 0) || year % 400 == 0
}

/// The days of a month (1 .. 12) of a year.
pub fn days_in_month(year: i64, month: i64) -> i64 {
    match month {
        2 if is_leap_year(year) => 29,
        2 => 28,
        4 | 6 | 9 | 11 => 30,
        _ => 31,
    }
}

fn field(fields: &Fields, f: Field) -> Result<i64, FieldsError> {
    let value = fields.get(f);
    let (lo, hi) = f.range();
    match i64::try_from(value) {
        Ok(v) if (lo..=hi).contains(&v) => Ok(v),
        _ => Err(FieldsError::OutOfRange {
            field: f,
            value,
            lo,
            hi,
        }),
    }
}

/// `CONCAT_DATE`, `CONCAT_TOD`, `CONCAT_DT` and their L-forms: the value (nanoseconds)
/// of the fields `parts` has; the others are ignored. Every field is checked: no
/// wrapping into the next minute, day or month.
pub fn concat(parts: Parts, fields: &Fields) -> Result<i64, FieldsError> {
    let f = |x: Field| -> Result<i64, FieldsError> {
        if parts.fields().contains(&x) {
            field(fields, x)
        } else {
            Ok(0)
        }
    };
    // in the order of the parameters, so the first wrong one is reported
    let (year, month, day) = (f(Field::Year)?, f(Field::Month)?, f(Field::Day)?);
    let tod = ((f(Field::Hour)? * 60 + f(Field::Minute)?) * 60 + f(Field::Second)?) * 1_000_000_000
        + f(Field::Millisecond)? * 1_000_000
        + f(Field::Nanosecond)?;
    if parts.ty() == crate::check::Ty::Tod {
        return Ok(tod);
    }
    let days = days_in_month(year, month);
    if day > days {
        return Err(FieldsError::NoSuchDay {
            year,
            month,
            day,
            days,
        });
    }
    // month and day are in range: the casts are exact
    let date = i128::from(crate::syntax::lexer::days_from_civil(
        year,
        u32::try_from(month).unwrap_or(1),
        u32::try_from(day).unwrap_or(1),
    ));
    let is_date = parts.ty() == crate::check::Ty::Date;
    i64::try_from(date * i128::from(DAY) + i128::from(tod)).map_err(|_| {
        FieldsError::Unrepresentable {
            year,
            month,
            day,
            time: if is_date {
                String::new()
            } else {
                format!(
                    "-{:02}:{:02}:{:02}",
                    tod / 3_600_000_000_000,
                    tod / 60_000_000_000 % 60,
                    tod / 1_000_000_000 % 60
                )
            },
            ty: if is_date { "DATE" } else { "DT" },
        }
    })
}

/// `SPLIT_DATE`, `SPLIT_TOD`, `SPLIT_DT` and their L-forms: the fields of a value
/// (nanoseconds); a TOD is taken modulo a day, the fields `parts` does not have are 0.
pub fn split(parts: Parts, v: i64) -> Fields {
    let (y, m, d, hour, minute, second, ns) = split_dt(v);
    let mut out = Fields {
        year: i128::from(y),
        month: i128::from(m),
        day: i128::from(d),
        hour: i128::from(hour),
        minute: i128::from(minute),
        second: i128::from(second),
        millisecond: i128::from(ns / 1_000_000),
        nanosecond: i128::from(ns % 1_000_000),
    };
    for f in [
        Field::Year,
        Field::Month,
        Field::Day,
        Field::Hour,
        Field::Minute,
        Field::Second,
        Field::Millisecond,
        Field::Nanosecond,
    ] {
        if !parts.fields().contains(&f) {
            out.set(f, 0);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fields(v: [i128; 8]) -> Fields {
        let [year, month, day, hour, minute, second, millisecond, nanosecond] = v;
        Fields {
            year,
            month,
            day,
            hour,
            minute,
            second,
            millisecond,
            nanosecond,
        }
    }

    #[test]
    fn leap_years() {
        assert!(is_leap_year(2024) && is_leap_year(2000) && is_leap_year(1904));
        assert!(!is_leap_year(1900) && !is_leap_year(2100) && !is_leap_year(2023));
        assert_eq!(days_in_month(2024, 2), 29);
        assert_eq!(days_in_month(2100, 2), 28);
        assert_eq!(days_in_month(2023, 4), 30);
    }

    #[test]
    fn concat_and_split_round_trip() {
        let f = fields([2024, 2, 29, 23, 59, 58, 999, 123_456]);
        let v = concat(Parts::LDt, &f).unwrap();
        assert_eq!(split(Parts::LDt, v), f);
        // the standard's DT has no NANOSECOND: ignored by CONCAT, 0 from SPLIT
        let v = concat(Parts::Dt, &f).unwrap();
        assert_eq!(split(Parts::Dt, v), Fields { nanosecond: 0, ..f });
        assert_eq!(split(Parts::Date, v).hour, 0);
        assert_eq!(
            concat(Parts::Tod, &f).unwrap(),
            split_tod_ns(23, 59, 58, 999)
        );
    }

    fn split_tod_ns(h: i64, m: i64, s: i64, ms: i64) -> i64 {
        ((h * 60 + m) * 60 + s) * 1_000_000_000 + ms * 1_000_000
    }

    #[test]
    fn the_range_of_dt() {
        let first = fields([1677, 9, 22, 0, 0, 0, 0, 0]);
        let v = concat(Parts::Date, &first).unwrap();
        assert_eq!(split(Parts::Date, v), first);
        let last = fields([2262, 4, 11, 23, 47, 16, 854, 775_807]);
        assert_eq!(concat(Parts::LDt, &last), Ok(i64::MAX));
        let after = fields([2262, 4, 11, 23, 47, 16, 854, 775_808]);
        assert!(matches!(
            concat(Parts::LDt, &after),
            Err(FieldsError::Unrepresentable { ty: "DT", .. })
        ));
        let before = fields([1677, 9, 21, 0, 0, 0, 0, 0]);
        let e = concat(Parts::Date, &before).unwrap_err();
        assert_eq!(e.to_string(), "1677-09-21 is outside the range of DATE");
        let e = concat(Parts::Dt, &fields([2262, 4, 11, 23, 59, 0, 0, 0])).unwrap_err();
        assert_eq!(
            e.to_string(),
            "2262-04-11-23:59:00 is outside the range of DT"
        );
    }

    #[test]
    fn invalid_fields() {
        let e = concat(Parts::Date, &fields([2023, 2, 29, 0, 0, 0, 0, 0])).unwrap_err();
        assert_eq!(e.to_string(), "DAY 29 is not in 2023-02, which has 28 days");
        let e = concat(Parts::Date, &fields([2023, 13, 1, 0, 0, 0, 0, 0])).unwrap_err();
        assert_eq!(e.to_string(), "MONTH 13 is outside 1..12");
        let e = concat(Parts::Tod, &fields([0, 0, 0, 24, 0, 0, 0, 0])).unwrap_err();
        assert_eq!(e.to_string(), "HOUR 24 is outside 0..23");
        let huge = i128::from(u64::MAX);
        let e = concat(Parts::Dt, &fields([huge, 1, 1, 0, 0, 0, 0, 0])).unwrap_err();
        assert_eq!(
            e.to_string(),
            "YEAR 18446744073709551615 is outside 1677..2262"
        );
        // fields the form does not have are not looked at
        assert!(concat(Parts::Tod, &fields([0, 0, 0, 1, 2, 3, 4, -5])).is_ok());
    }
}
