//! The maximum command delay: a time-tagged command older than the limit, or further in
//! the future, gets a negative confirmation, is never executed, and is reported to the
//! application with its age; measured on the station's clock with the tag read in the
//! server's time zone (SU tells the repeated autumn hour apart).

use std::sync::{Arc, Mutex};
use std::time::Duration;

use chrono::{DateTime, TimeZone, Utc};
use iec60870::asdu::{Asdu, Cause, CommandQualifier, Cp56Time2a, Element, TimeTag, TypeId};
use iec60870::cs104::server::{
    ready, Command, CommandFuture, CommandOutcome, CommandRefusal, ProcessImage, ServerConfig,
    ServerHandle, StationHandler,
};
use iec60870::time::TimeZonePolicy;

use crate::common::*;

/// A point under the server's limit, and one with a limit of its own.
const SERVER_LIMITED: u32 = 7000;
const POINT_LIMITED: u32 = 7001;
const SERVER_LIMIT: Duration = Duration::from_secs(10);
const POINT_LIMIT: Duration = Duration::from_secs(2);

/// A station on a clock the test sets, recording what it executes and what the server
/// refused.
#[derive(Default)]
struct ClockedStation {
    now: Mutex<Option<DateTime<Utc>>>,
    executed: Mutex<Vec<Command>>,
    refused: Mutex<Vec<(Command, CommandRefusal)>>,
}

impl ClockedStation {
    fn set_now(&self, now: DateTime<Utc>) {
        *self.now.lock().unwrap() = Some(now);
    }
}

impl StationHandler for ClockedStation {
    fn handle_command(&self, command: Command) -> CommandFuture {
        self.executed.lock().unwrap().push(command);
        ready(CommandOutcome::Executed)
    }

    fn command_refused(&self, command: &Command, refusal: &CommandRefusal) {
        self.refused
            .lock()
            .unwrap()
            .push((command.clone(), refusal.clone()));
    }

    fn now(&self) -> DateTime<Utc> {
        self.now.lock().unwrap().expect("the test sets the clock")
    }

    fn handle_clock_sync(&self, _time: Cp56Time2a, _peer: &iec60870::outstation::Peer) -> bool {
        true
    }
}

struct Fixture {
    station: Arc<ClockedStation>,
    peer: RawPeer,
    /// Keeps the server running (it stops when every handle is gone).
    _server: ServerHandle,
}

async fn fixture(zone: TimeZonePolicy) -> Fixture {
    let station = Arc::new(ClockedStation::default());
    let mut image = ProcessImage::new();
    image
        .add_command(command_point(SERVER_LIMITED, TypeId::C_SC_NA_1, false))
        .unwrap();
    let mut point = command_point(POINT_LIMITED, TypeId::C_SC_NA_1, false);
    point.max_age = Some(POINT_LIMIT);
    image.add_command(point).unwrap();
    let mut config: ServerConfig = server_config();
    config.outstation.max_command_age = Some(SERVER_LIMIT);
    config.outstation.time_zone = zone;
    let server = start_server(config, image, station.clone()).await;
    let mut peer = RawPeer::connect(server.local_addr()).await;
    peer.start().await;
    Fixture {
        station,
        peer,
        _server: server,
    }
}

fn tagged_command(address: u32, time: Cp56Time2a) -> Asdu {
    let mut asdu = request(
        TypeId::C_SC_TA_1,
        Cause::ACTIVATION,
        CA,
        address,
        Element::SingleCommand {
            on: true,
            qualifier: CommandQualifier::EXECUTE,
        },
    );
    asdu.objects[0].time = Some(TimeTag::Cp56(time));
    asdu
}

impl Fixture {
    /// Sends a tagged command at `now` on the station's clock; returns whether it was
    /// confirmed positively (checking the cause of the confirmation either way).
    async fn command(&mut self, address: u32, now: DateTime<Utc>, tag: Cp56Time2a) -> bool {
        self.station.set_now(now);
        self.peer.send(&tagged_command(address, tag)).await;
        let confirmation = self.peer.expect_asdu().await;
        assert_eq!(confirmation.type_id, TypeId::C_SC_TA_1);
        assert_eq!(
            confirmation.cot.cause,
            Cause::ACTIVATION_CON,
            "{confirmation}"
        );
        if !confirmation.cot.negative {
            let termination = self.peer.expect_asdu().await;
            assert_eq!(termination.cot.cause, Cause::ACTIVATION_TERMINATION);
        }
        !confirmation.cot.negative
    }

    fn last_refusal(&self) -> CommandRefusal {
        self.station
            .refused
            .lock()
            .unwrap()
            .last()
            .unwrap()
            .1
            .clone()
    }

    fn counts(&self) -> (usize, usize) {
        (
            self.station.executed.lock().unwrap().len(),
            self.station.refused.lock().unwrap().len(),
        )
    }
}

fn utc(y: i32, mo: u32, d: u32, h: u32, mi: u32, s: u32, ms: i64) -> DateTime<Utc> {
    Utc.with_ymd_and_hms(y, mo, d, h, mi, s).unwrap() + chrono::TimeDelta::milliseconds(ms)
}

#[tokio::test]
async fn accepted_inside_the_limit_refused_outside_and_from_the_future() {
    init_logs();
    let mut f = fixture(TimeZonePolicy::Utc).await;
    let sent = utc(2026, 6, 1, 12, 0, 0, 0);
    let tag = TimeZonePolicy::Utc.to_cp56(sent);
    let limit_ms = i64::try_from(SERVER_LIMIT.as_millis()).unwrap();

    // Just inside, exactly at the limit: executed.
    assert!(
        f.command(
            SERVER_LIMITED,
            sent + chrono::TimeDelta::milliseconds(limit_ms - 1),
            tag
        )
        .await
    );
    assert!(
        f.command(
            SERVER_LIMITED,
            sent + chrono::TimeDelta::milliseconds(limit_ms),
            tag
        )
        .await
    );
    assert_eq!(f.counts(), (2, 0));

    // One millisecond over: refused, not executed, reported with its age.
    let late = sent + chrono::TimeDelta::milliseconds(limit_ms + 1);
    assert!(!f.command(SERVER_LIMITED, late, tag).await);
    assert_eq!(f.counts(), (2, 1));
    assert_eq!(
        f.last_refusal(),
        CommandRefusal::Stale {
            age: SERVER_LIMIT + Duration::from_millis(1),
            limit: SERVER_LIMIT
        }
    );
    // An hour old (the finding).
    assert!(
        !f.command(SERVER_LIMITED, sent + chrono::TimeDelta::hours(1), tag)
            .await
    );
    let refused = f.station.refused.lock().unwrap().last().unwrap().0.clone();
    assert_eq!(refused.ioa, ioa(SERVER_LIMITED));
    assert_eq!(refused.time, Some(TimeTag::Cp56(tag)));

    // From the future: a little (clock skew) is fine, beyond the limit is refused.
    assert!(
        f.command(SERVER_LIMITED, sent - chrono::TimeDelta::seconds(5), tag)
            .await
    );
    assert!(
        !f.command(
            SERVER_LIMITED,
            sent - chrono::TimeDelta::milliseconds(limit_ms + 1),
            tag
        )
        .await
    );
    assert!(matches!(
        f.last_refusal(),
        CommandRefusal::FromTheFuture { ahead, limit }
            if ahead == SERVER_LIMIT + Duration::from_millis(1) && limit == SERVER_LIMIT
    ));
    assert_eq!(f.counts(), (3, 3));

    // A point's own limit wins over the server's.
    assert!(
        f.command(
            POINT_LIMITED,
            sent + chrono::TimeDelta::milliseconds(1999),
            tag
        )
        .await
    );
    assert!(
        !f.command(POINT_LIMITED, sent + chrono::TimeDelta::seconds(5), tag)
            .await
    );
    assert!(
        matches!(f.last_refusal(), CommandRefusal::Stale { limit, .. } if limit == POINT_LIMIT)
    );

    // A tag marked invalid cannot prove its age.
    assert!(
        !f.command(SERVER_LIMITED, sent, tag.with_invalid(true))
            .await
    );
    assert_eq!(f.last_refusal(), CommandRefusal::TimeUnusable);

    // The server logs the refusal with the age.
    assert!(!log_lines_with(&["command refused", "3600.000 s old"]).is_empty());
}

#[tokio::test]
async fn untagged_commands_are_not_checked() {
    init_logs();
    let mut f = fixture(TimeZonePolicy::Utc).await;
    f.station.set_now(utc(2026, 6, 1, 12, 0, 0, 0));
    f.peer
        .send(&request(
            TypeId::C_SC_NA_1,
            Cause::ACTIVATION,
            CA,
            SERVER_LIMITED,
            Element::SingleCommand {
                on: false,
                qualifier: CommandQualifier::EXECUTE,
            },
        ))
        .await;
    let confirmation = f.peer.expect_asdu().await;
    assert!(!confirmation.cot.negative, "{confirmation}");
}

#[tokio::test]
async fn the_age_is_exact_across_midnight_and_the_year_end() {
    init_logs();
    let mut f = fixture(TimeZonePolicy::Utc).await;
    let tag = Cp56Time2a::new(25, 12, 31, 23, 59, 58_000).unwrap();
    // 5 s later, in the next year.
    assert!(
        f.command(SERVER_LIMITED, utc(2026, 1, 1, 0, 0, 3, 0), tag)
            .await
    );
    // 10.5 s later.
    assert!(
        !f.command(SERVER_LIMITED, utc(2026, 1, 1, 0, 0, 8, 500), tag)
            .await
    );
    assert!(matches!(
        f.last_refusal(),
        CommandRefusal::Stale { age, .. } if age == Duration::from_millis(10_500)
    ));
}

#[tokio::test]
async fn local_time_tags_are_read_in_the_station_zone_across_both_dst_changes() {
    init_logs();
    let prague = TimeZonePolicy::Zone(chrono_tz::Europe::Prague);
    let mut f = fixture(prague).await;

    // Spring: 01:59:59 CET is followed by 03:00:00 CEST; the station's clock says
    // 01:00:02 UTC (03:00:02 CEST), so the tag is 3 s old, not an hour and 3 s.
    let before_the_gap = Cp56Time2a::new(26, 3, 29, 1, 59, 59_000).unwrap();
    assert!(
        f.command(SERVER_LIMITED, utc(2026, 3, 29, 1, 0, 2, 0), before_the_gap)
            .await
    );

    // Autumn: 02:00-03:00 local happens twice. The clock says 01:00:05 UTC = 02:00:05
    // CET (second pass). A tag 02:59:58 with SU set is the first pass (00:59:58 UTC): 7 s
    // old, accepted.
    let now = utc(2026, 10, 25, 1, 0, 5, 0);
    let first_pass_end = Cp56Time2a::new(26, 10, 25, 2, 59, 58_000)
        .unwrap()
        .with_summer_time(true);
    assert!(f.command(SERVER_LIMITED, now, first_pass_end).await);
    // 02:00:00 with SU set is the start of the first pass (00:00:00 UTC): an hour old.
    let first_pass_start = Cp56Time2a::new(26, 10, 25, 2, 0, 0)
        .unwrap()
        .with_summer_time(true);
    assert!(!f.command(SERVER_LIMITED, now, first_pass_start).await);
    assert!(matches!(
        f.last_refusal(),
        CommandRefusal::Stale { age, .. } if age == Duration::from_secs(3605)
    ));
    // The same wall-clock time without SU is the second pass: 5 s old, accepted.
    assert!(
        f.command(
            SERVER_LIMITED,
            now,
            first_pass_start.with_summer_time(false)
        )
        .await
    );

    // The same tag read as UTC would be two hours off: a UTC station refuses it.
    let mut utc_station = fixture(TimeZonePolicy::Utc).await;
    assert!(
        !utc_station
            .command(SERVER_LIMITED, now, first_pass_end)
            .await
    );
}
