//! Service figures: hand-made histories with exact figures, properties over arbitrary
//! histories, and the simulator's lift driven through a few hours.

use std::collections::BTreeMap;
use std::time::{Duration, Instant};

use chrono::{DateTime, TimeDelta, TimeZone as _, Utc};
use devices::ekm66::codec::Direction;
use devices::ekm66::figures::*;
use devices::ekm66::simulator::{SimEvent, Simulator, SimulatorConfig};
use devices::ekm66::tables::{
    door_state, lift_mode, DoorState, FaultGroup, LiftMode, StatusColours,
};
use proptest::prelude::*;

fn base() -> DateTime<Utc> {
    Utc.with_ymd_and_hms(2024, 1, 1, 0, 0, 0).unwrap()
}

/// Minutes after midnight of the base day (negative: the day before).
fn at(minutes: i64) -> DateTime<Utc> {
    base() + TimeDelta::minutes(minutes)
}

fn hours(h: i64) -> TimeDelta {
    TimeDelta::hours(h)
}

fn day() -> Period {
    Period::try_new(at(0), at(24 * 60)).unwrap()
}

fn status(minutes: i64, code: u8) -> Observation {
    Observation::new(at(minutes), Observed::Status(code))
}

fn answering(minutes: i64, up: bool) -> Observation {
    Observation::new(at(minutes), Observed::Answering(up))
}

fn position(minutes: i64, floor: u8) -> Observation {
    Observation::new(at(minutes), Observed::Position(floor))
}

fn direction(minutes: i64, direction: Direction) -> Observation {
    Observation::new(at(minutes), Observed::Direction(direction))
}

fn counters(minutes: i64, values: &[u32]) -> Observation {
    Observation::new(at(minutes), Observed::Counters(values.to_vec()))
}

fn figures(observations: &[Observation]) -> ServiceFigures {
    ServiceFigures::compute(day(), observations, &[], &FiguresConfig::default())
}

#[test]
fn one_hour_out_of_service_in_a_day() {
    let f = figures(&[status(0, 1), status(10 * 60, 20), status(11 * 60, 1)]);
    assert_eq!(f.normal_service, hours(23));
    assert_eq!(f.out_of_service, hours(1));
    assert_eq!(f.unknown, TimeDelta::zero());
    assert_eq!(f.availability, Some(23.0 / 24.0));
    assert_eq!(f.availability_lower, 23.0 / 24.0);
    assert_eq!(f.availability_upper, 23.0 / 24.0);
    assert_eq!(f.failures, 1);
    assert_eq!(f.callbacks, 1);
    assert_eq!(f.episodes, 1);
    assert_eq!(f.mtbf, Some(hours(23)));
    assert_eq!(f.mttr, Some(hours(1)));
    assert_eq!(f.failures_per_year, 365.25);
    // No record of the fault log in this history: failures are not faults.
    assert_eq!(f.faults_per_year, 0.0);
    assert_eq!(f.callbacks_per_year, 365.25);
    assert_eq!(f.status_at_end, Some(1));
    assert_eq!(f.mode_at_end, LiftMode::NormalService);
}

#[test]
fn a_communication_gap_is_unknown() {
    let f = figures(&[
        status(0, 1),
        answering(6 * 60, false),
        answering(8 * 60, true),
    ]);
    assert_eq!(f.normal_service, hours(22));
    assert_eq!(f.unknown, hours(2));
    assert_eq!(f.availability, Some(1.0));
    assert_eq!(f.availability_lower, 22.0 / 24.0);
    assert_eq!(f.availability_upper, 1.0);
    assert_eq!(f.failures, 0);
    assert_eq!(f.mtbf, None);
    assert_eq!(f.mttr, None);

    // No data before the first status, an unknown status code: unknown too.
    let f = figures(&[status(60, 1), status(120, 16), status(180, 1)]);
    assert_eq!(f.unknown, hours(2));
    assert_eq!(f.normal_service, hours(22));

    // Lost at the end: no status at the end.
    let f = figures(&[status(0, 1), answering(23 * 60, false)]);
    assert_eq!(f.status_at_end, None);
    assert_eq!(f.mode_at_end, LiftMode::Unknown);

    // Nothing at all.
    let f = figures(&[]);
    assert_eq!(f.unknown, hours(24));
    assert_eq!(f.availability, None);
    assert_eq!(f.availability_lower, 0.0);
    assert_eq!(f.availability_upper, 1.0);
}

#[test]
fn an_episode_begun_before_the_period_is_clipped() {
    let f = figures(&[status(-120, 44), status(60, 1)]);
    assert_eq!(f.out_of_service, hours(1));
    assert_eq!(f.normal_service, hours(23));
    // Not a failure of this period, but an episode of it, counted from `from`.
    assert_eq!(f.failures, 0);
    assert_eq!(f.callbacks, 0);
    assert_eq!(f.episodes, 1);
    assert_eq!(f.episode_time, hours(1));
    assert_eq!(f.mttr, Some(hours(1)));
    assert_eq!(f.mtbf, None);

    // An episode that ended before the period is not in it.
    let f = figures(&[status(-120, 44), status(-60, 1)]);
    assert_eq!(f.episodes, 0);
    assert_eq!(f.normal_service, hours(24));
}

#[test]
fn an_episode_open_at_the_end_counts_until_the_end() {
    let f = figures(&[
        status(0, 1),
        status(24 * 60 - 30, 44),
        status(24 * 60 + 10, 1),
    ]);
    assert_eq!(f.out_of_service, TimeDelta::minutes(30));
    assert_eq!(f.failures, 1);
    assert_eq!(f.callbacks, 1);
    assert_eq!(f.mttr, Some(TimeDelta::minutes(30)));
    assert_eq!(f.status_at_end, Some(44));
    assert_eq!(f.mode_at_end, LiftMode::OutOfService);
}

#[test]
fn short_stops_are_failures_but_not_callbacks() {
    let history = [
        status(0, 1),
        status(60, 19),
        status(62, 1),
        status(120, 44),
        status(130, 1),
    ];
    let f = figures(&history);
    assert_eq!(f.failures, 2);
    assert_eq!(f.callbacks, 1);
    assert_eq!(f.mttr, Some(TimeDelta::minutes(6)));
    let mut config = FiguresConfig::default();
    config.callback_min = TimeDelta::minutes(1);
    let f = ServiceFigures::compute(day(), &history, &[], &config);
    assert_eq!(f.callbacks, 2);
}

#[test]
fn modes_other_than_service_and_unknown_gaps_in_an_episode() {
    let f = figures(&[
        status(0, 1),
        status(60, 46),  // inspection 1 h
        status(120, 23), // fire case 1 h
        status(180, 44), // out of service 1 h
        answering(240, false),
        answering(300, true), // still 44: the same episode
        status(360, 1),
    ]);
    assert_eq!(f.inspection, hours(1));
    assert_eq!(f.other, hours(1));
    assert_eq!(f.unknown, hours(1));
    assert_eq!(f.out_of_service, hours(2));
    assert_eq!(f.normal_service, hours(19));
    assert_eq!(f.failures, 1);
    assert_eq!(f.episodes, 1);
    // The episode runs from its first to its last out-of-service moment.
    assert_eq!(f.mttr, Some(hours(3)));
    assert_eq!(f.availability, Some(19.0 / 23.0));

    // A known other mode between two stops makes two episodes.
    let f = figures(&[
        status(0, 44),
        status(60, 46),
        status(120, 44),
        status(180, 1),
    ]);
    assert_eq!(f.failures, 2);
    assert_eq!(f.mttr, Some(hours(1)));
    assert_eq!(f.mtbf, Some(hours(21) / 2));
}

#[test]
fn counters_reset_and_wrap() {
    let history = [
        counters(-10, &[10, 20]),
        counters(60, &[15, 25]),
        counters(120, &[3, 30]),             // floor 1 reset (or wrapped)
        counters(180, &[8, 31, 4]),          // a third floor appears
        counters(24 * 60, &[100, 100, 100]), // at `to`: outside
    ];
    let f = figures(&history);
    assert_eq!(f.trips_per_floor, [5 + 3 + 5, 5 + 5 + 1, 4]);
    assert_eq!(f.trips, 28);
    assert_eq!(f.trips_per_day, 28.0);

    let mut config = FiguresConfig::default();
    config.counter_modulus = Some(256);
    let f = ServiceFigures::compute(day(), &history, &[], &config);
    assert_eq!(f.trips_per_floor, [5 + 244 + 5, 11, 4]);

    // Without a reading before the period the first one in it is the start.
    let f = figures(&history[1..]);
    assert_eq!(f.trips_per_floor, [3 + 5, 5 + 1, 4]);
    // One reading: no trips.
    let f = figures(&history[1..2]);
    assert_eq!(f.trips_per_floor, [0, 0]);
    assert_eq!(f.trips, 0);
}

fn trip(start: i64, from: u8, to: u8) -> Vec<Observation> {
    let up = if to > from {
        Direction::Up
    } else {
        Direction::Down
    };
    vec![
        direction(start, up),
        position(start + 1, to),
        direction(start + 1, Direction::Stopped),
    ]
}

#[test]
fn trips_started_and_the_parking_floor() {
    let mut history = vec![
        status(0, 1),
        position(0, 1),
        direction(0, Direction::Stopped),
    ];
    history.extend(trip(10, 1, 2));
    history.extend(trip(20, 2, 1));
    history.extend(trip(30, 1, 2));
    history.extend(trip(40, 2, 3));
    let f = figures(&history);
    assert_eq!(f.trips_started, 4);
    assert_eq!(f.trips_started_per_floor, BTreeMap::from([(1, 2), (2, 2)]));
    // A tie: the lowest floor.
    assert_eq!(f.parking_floor, Some(1));
    history.extend(trip(50, 3, 2));
    history.extend(trip(60, 2, 3));
    let f = figures(&history);
    assert_eq!(f.parking_floor, Some(2));
    // No trips, no parking floor; a movement without a known stop before is no start.
    let f = figures(&[position(0, 1), direction(10, Direction::Up)]);
    assert_eq!(f.trips_started, 0);
    assert_eq!(f.parking_floor, None);
}

#[test]
fn door_cycles_from_the_status_and_the_movement() {
    let mut history = vec![
        status(0, 1),
        position(0, 2),
        direction(0, Direction::Stopped),
    ];
    // A parking run closes (14), the door-open button opens (31), a departure closes.
    history.push(status(5, 14));
    history.push(status(6, 1));
    history.push(status(7, 31));
    history.push(status(8, 1));
    history.extend(trip(10, 2, 3));
    // At floor 3: loading (8: open), light curtain (29: still open), then a parking run.
    history.push(status(20, 8));
    history.push(status(21, 29));
    history.push(status(22, 14));
    // A door fault breaks the cycle: open, fault, closed is no cycle.
    history.push(status(30, 31));
    history.push(status(31, 19));
    history.push(status(32, 14));
    let f = figures(&history);
    assert_eq!(f.door_cycles, 2);
    assert_eq!(f.door_cycles_per_floor, BTreeMap::from([(2, 1), (3, 1)]));
    assert_eq!(f.door_cycles_per_day, 2.0);
}

#[test]
fn the_minimum_fault_log() {
    let faults = [
        FaultAt {
            time: at(-1),
            code: 0x11,
        },
        FaultAt {
            time: at(10),
            code: 0x11,
        },
        FaultAt {
            time: at(20),
            code: 0x3C,
        },
        FaultAt {
            time: at(30),
            code: 0x3C,
        },
        FaultAt {
            time: at(40),
            code: 0x46,
        },
        FaultAt {
            time: at(50),
            code: 0x06,
        },
        FaultAt {
            time: at(24 * 60),
            code: 0x51,
        },
    ];
    let f = ServiceFigures::compute(day(), &[], &faults, &FiguresConfig::default());
    assert_eq!(f.faults, 5);
    // Five records in a day: 5 × 365.25 a year; no status, so no failure.
    assert_eq!(f.faults_per_year, 5.0 * 365.25);
    assert_eq!(f.failures_per_year, 0.0);
    assert_eq!(f.faults_by_group.len(), FaultGroup::ALL.len());
    assert_eq!(f.faults_by_group[&FaultGroup::SafetyCircuitInTravel], 1);
    assert_eq!(f.faults_by_group[&FaultGroup::DoorSequence], 2);
    assert_eq!(f.faults_by_group[&FaultGroup::InspectionMode], 1);
    assert_eq!(f.faults_by_group[&FaultGroup::Other], 1);
    assert_eq!(f.faults_by_group[&FaultGroup::AlarmButton], 0);
    assert_eq!(
        f.faults_by_code,
        BTreeMap::from([(0x11, 1), (0x3C, 2), (0x46, 1), (0x06, 1)])
    );
}

#[test]
fn input_order_does_not_matter_and_the_period_must_not_be_empty() {
    let mut history = vec![
        status(0, 1),
        position(0, 1),
        direction(0, Direction::Stopped),
    ];
    history.extend(trip(10, 1, 2));
    history.push(status(100, 44));
    history.push(status(200, 1));
    let ordered = figures(&history);
    let mut reversed = history.clone();
    reversed.reverse();
    assert_eq!(figures(&reversed), ordered);
    assert_eq!(
        Period::try_new(at(10), at(10)),
        Err(FiguresError::EmptyPeriod {
            from: at(10),
            to: at(10)
        })
    );
    assert!(Period::try_from((at(10), at(5))).is_err());
    assert_eq!(day().length(), hours(24));
}

#[test]
fn fleet_figures() {
    let a = figures(&[status(0, 1), status(10 * 60, 20), status(11 * 60, 1)]);
    let b = figures(&[status(0, 1)]);
    let c = figures(&[
        status(0, 1),
        status(23 * 60, 44),
        answering(23 * 60 + 30, false),
    ]);
    let fleet = FleetFigures::new([&a, &b, &c], &StatusColours::default());
    assert_eq!(fleet.lifts, 3);
    assert_eq!(fleet.lift_time, hours(72));
    assert_eq!(fleet.normal_service, hours(23 + 24 + 23));
    assert_eq!(fleet.unknown, TimeDelta::minutes(30));
    assert_eq!(fleet.out_of_service, TimeDelta::minutes(90));
    assert_eq!(
        fleet.availability,
        Some(hours(70).as_seconds_f64() / TimeDelta::minutes(72 * 60 - 30).as_seconds_f64())
    );
    assert_eq!(fleet.failures, 2);
    assert_eq!(fleet.mtbf, Some(hours(35)));
    // (60 + 30) minutes over two episodes.
    assert_eq!(fleet.mttr, Some(TimeDelta::minutes(45)));
    assert_eq!(fleet.failures_per_lift_year, 2.0 * 365.25 / 3.0);
    assert_eq!(
        fleet.faults_per_lift_year,
        fleet.faults as f64 * 365.25 / 3.0
    );
    assert_eq!(fleet.lifts_by_class.green, 2);
    assert_eq!(fleet.lifts_by_class.unknown, 1);
    assert_eq!(fleet.lifts_by_mode[&LiftMode::NormalService], 2);
    assert_eq!(fleet.lifts_by_mode[&LiftMode::Unknown], 1);

    let empty = FleetFigures::new([], &StatusColours::default());
    assert_eq!(empty.lifts, 0);
    assert_eq!(empty.availability, None);
    assert_eq!(empty.mtbf, None);
}

// ---------------------------------------------------------------------------------------
// Properties

fn observed() -> impl Strategy<Value = Observed> {
    prop_oneof![
        4 => prop_oneof![Just(1u8), Just(20), Just(44), Just(46), Just(23), Just(31), Just(14), Just(19), Just(16), any::<u8>()]
            .prop_map(Observed::Status),
        2 => (1u8..6).prop_map(Observed::Position),
        2 => prop_oneof![
            Just(Direction::Stopped),
            Just(Direction::Up),
            Just(Direction::Down),
            Just(Direction::Unknown(7))
        ]
        .prop_map(Observed::Direction),
        1 => any::<bool>().prop_map(Observed::Answering),
        1 => prop::collection::vec(0u32..300, 0..5).prop_map(Observed::Counters),
    ]
}

/// Observations from an hour before the day to an hour after it.
fn history() -> impl Strategy<Value = Vec<Observation>> {
    prop::collection::vec((-60i64..25 * 60, observed()), 0..60).prop_map(|items| {
        items
            .into_iter()
            .map(|(minutes, what)| Observation::new(at(minutes), what))
            .collect()
    })
}

fn check(f: &ServiceFigures) {
    let total = [
        f.normal_service,
        f.out_of_service,
        f.inspection,
        f.other,
        f.unknown,
    ]
    .into_iter()
    .fold(TimeDelta::zero(), |a, b| a + b);
    assert_eq!(total, f.period.length());
    for time in [
        f.normal_service,
        f.out_of_service,
        f.inspection,
        f.other,
        f.unknown,
    ] {
        assert!(time >= TimeDelta::zero());
    }
    if let Some(availability) = f.availability {
        assert!((0.0..=1.0).contains(&availability));
        assert!(f.availability_lower <= availability + 1e-12);
        assert!(availability <= f.availability_upper + 1e-12);
    }
    assert!((0.0..=1.0).contains(&f.availability_lower));
    assert!((0.0..=1.0).contains(&f.availability_upper));
    assert!(f.callbacks <= f.failures);
    assert!(f.failures <= f.episodes);
    assert!(f.episodes <= f.failures + 1);
    assert_eq!(f.mtbf.is_some(), f.failures > 0);
    assert_eq!(f.mttr.is_some(), f.episodes > 0);
    assert!(f.episode_time <= f.out_of_service + f.unknown);
    assert!(f.episode_time >= f.out_of_service);
    assert_eq!(f.trips, f.trips_per_floor.iter().sum::<u64>());
    assert!(f.trips_started >= f.trips_started_per_floor.values().sum::<u64>());
    assert!(f.door_cycles >= f.door_cycles_per_floor.values().sum::<u64>());
    assert_eq!(
        f.parking_floor.is_some(),
        !f.trips_started_per_floor.is_empty()
    );
    assert_eq!(f.faults, f.faults_by_group.values().sum::<u64>());
    assert_eq!(f.faults, f.faults_by_code.values().sum::<u64>());
}

proptest! {
    #[test]
    fn figures_are_consistent(
        history in history(),
        faults in prop::collection::vec((-60i64..25 * 60, any::<u8>()), 0..20),
        callback_min in 0i64..120,
    ) {
        let faults: Vec<FaultAt> = faults
            .into_iter()
            .map(|(minutes, code)| FaultAt { time: at(minutes), code })
            .collect();
        let mut config = FiguresConfig::default();
        config.callback_min = TimeDelta::minutes(callback_min);
        let f = ServiceFigures::compute(day(), &history, &faults, &config);
        check(&f);
        let fleet = FleetFigures::new([&f, &f], &StatusColours::default());
        prop_assert_eq!(fleet.lifts, 2);
        prop_assert_eq!(fleet.failures, 2 * f.failures);
        prop_assert_eq!(fleet.availability, f.availability);
        prop_assert_eq!(fleet.mttr, f.mttr);
    }

    #[test]
    fn order_and_duplicates_do_not_change_the_figures(
        history in history(),
        seed in any::<u64>(),
    ) {
        // Distinct times, so that the order is the time order alone.
        let mut seen = std::collections::BTreeSet::new();
        let history: Vec<Observation> =
            history.into_iter().filter(|o| seen.insert(o.time)).collect();
        let reference = figures(&history);
        let mut shuffled = history.clone();
        let n = shuffled.len();
        let mut state = seed | 1;
        for i in (1..n).rev() {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            shuffled.swap(i, (state % (i as u64 + 1)) as usize);
        }
        prop_assert_eq!(&figures(&shuffled), &reference);
        let doubled: Vec<Observation> =
            history.iter().flat_map(|o| [o.clone(), o.clone()]).collect();
        prop_assert_eq!(&figures(&doubled), &reference);
    }

    #[test]
    fn any_period_any_history(
        history in history(),
        from in -120i64..26 * 60,
        length in 1i64..48 * 60,
    ) {
        let period = Period::try_new(at(from), at(from + length)).unwrap();
        let f = ServiceFigures::compute(period, &history, &[], &FiguresConfig::default());
        check(&f);
    }
}

// ---------------------------------------------------------------------------------------
// The simulator

/// Station time of a virtual instant.
fn station_time(origin: Instant, start: DateTime<Utc>, now: Instant) -> DateTime<Utc> {
    start + TimeDelta::from_std(now.duration_since(origin)).unwrap()
}

#[test]
fn the_simulated_lift() {
    let mut config = SimulatorConfig::default();
    config.seed = 7;
    config.floors = 6;
    config.status_probability = 0.3;
    config.fault_probability = 0.05;
    // The virtual clock's origin; nothing reads the real clock after this.
    #[allow(clippy::disallowed_methods)]
    let origin = Instant::now();
    let start = Utc.with_ymd_and_hms(2022, 3, 14, 8, 0, 0).unwrap();
    let mut sim = Simulator::new(config, origin);
    let end = origin + Duration::from_secs(5 * 3600);

    let mut history = Vec::new();
    let mut faults = Vec::new();
    let first = sim.status();
    history.push(Observation::new(start, Observed::Status(first.code)));
    history.push(Observation::new(start, Observed::Position(first.position)));
    history.push(Observation::new(
        start,
        Observed::Direction(first.direction),
    ));
    history.push(Observation::new(
        start,
        Observed::Counters(sim.memory().counters.clone()),
    ));
    let mut last = (first, sim.memory().counters.clone());
    // Every status change with its time, to count the failures independently.
    let mut statuses = vec![(start, first.code)];
    let mut now = origin;
    while now < end {
        now = sim.poll_timeout().unwrap().min(end);
        sim.handle_timeout(now);
        let time = station_time(origin, start, now);
        while let Some(event) = sim.poll_event() {
            if let SimEvent::FaultStored(record) = event {
                faults.push(FaultAt {
                    time,
                    code: record.code,
                });
            }
        }
        let status = sim.status();
        let counters = sim.memory().counters.clone();
        if status.code != last.0.code {
            history.push(Observation::new(time, Observed::Status(status.code)));
            statuses.push((time, status.code));
        }
        if status.position != last.0.position {
            history.push(Observation::new(time, Observed::Position(status.position)));
        }
        if status.direction != last.0.direction {
            history.push(Observation::new(
                time,
                Observed::Direction(status.direction),
            ));
        }
        if counters != last.1 {
            history.push(Observation::new(time, Observed::Counters(counters.clone())));
        }
        last = (status, counters);
    }
    // A communication gap of ten minutes (the monitor's view; the board went on).
    let gap_from = start + TimeDelta::minutes(100);
    let gap_to = start + TimeDelta::minutes(110);
    history.push(Observation::new(gap_from, Observed::Answering(false)));
    history.push(Observation::new(gap_to, Observed::Answering(true)));

    // Four hours, from a quarter of an hour in.
    let from = start + TimeDelta::minutes(15);
    let to = from + TimeDelta::hours(4);
    let period = Period::try_new(from, to).unwrap();
    let f = ServiceFigures::compute(period, &history, &faults, &FiguresConfig::default());
    check(&f);

    assert_eq!(f.unknown, TimeDelta::minutes(10));
    // The status episodes last 5-20 s after some trips: mostly in service.
    let availability = f.availability.unwrap();
    assert!(availability > 0.8 && availability < 1.0, "{availability}");
    assert!(f.out_of_service > TimeDelta::zero() && f.inspection > TimeDelta::zero());

    // The failures: transitions into out of service seen in the status changes (the
    // gap holds none or joins nothing here: checked by recounting outside it).
    let mut failures = 0;
    let mut previous = LiftMode::Unknown;
    for (time, code) in &statuses {
        let mode = lift_mode(*code);
        if mode == LiftMode::OutOfService
            && previous != LiftMode::OutOfService
            && period.contains(*time)
        {
            failures += 1;
        }
        previous = mode;
    }
    let in_gap = statuses.iter().any(|(time, code)| {
        *time >= gap_from && *time <= gap_to && lift_mode(*code) == LiftMode::OutOfService
    });
    if !in_gap {
        assert_eq!(f.failures, failures);
    }
    assert!(f.failures > 10, "{}", f.failures);
    // Episodes of at most 20 s: no callback.
    assert_eq!(f.callbacks, 0);
    assert!(f.mttr.unwrap() <= TimeDelta::seconds(20));

    // Trips: every trip started in the period arrives in it, but for one in flight at
    // each end.
    let counted = f.trips as i64;
    let started = f.trips_started as i64;
    assert!(counted > 200, "{counted}");
    assert!(
        (counted - started).abs() <= 1,
        "counted {counted}, started {started}"
    );
    assert_eq!(
        f.trips_started_per_floor.values().sum::<u64>(),
        f.trips_started
    );
    assert_eq!(f.trips_per_floor.len(), 6);
    assert!(f
        .parking_floor
        .is_some_and(|floor| (1..=6).contains(&floor)));
    // Doors: every cycle opens with an open-door status (8, 29, 31, 34, 36).
    let openings = statuses
        .iter()
        .filter(|(time, code)| period.contains(*time) && door_state(*code) == Some(DoorState::Open))
        .count() as u64;
    assert!(
        f.door_cycles > 0 && f.door_cycles <= openings + 1,
        "{} {openings}",
        f.door_cycles
    );

    // The fault log: every fault stored in the period.
    let in_period = faults
        .iter()
        .filter(|fault| period.contains(fault.time))
        .count() as u64;
    assert!(in_period > 0);
    assert_eq!(f.faults, in_period);

    // As a one-lift fleet.
    let fleet = FleetFigures::new([&f], &StatusColours::default());
    assert_eq!(fleet.availability, f.availability);
    assert_eq!(fleet.trips, f.trips);
}
