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

/// ISO weekday of a DATE/DT: 1 = Monday .. 7 = Sunday.
pub fn day_of_week(dt: i64) -> i64 {
    // 1970-01-01 was a Thursday (4)
    (dt.div_euclid(DAY) + 3).rem_euclid(7) + 1
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
