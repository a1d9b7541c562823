//! The poller against the simulator on a virtual clock, no I/O: every step jumps to the
//! next deadline or delivery. Status changes, trips, faults, wrap-around of the fault
//! index, restarts of the monitor and of the board, a board that stops answering.

use std::collections::{BTreeSet, VecDeque};
use std::time::{Duration, Instant};

use devices::ekm66::codec::{Direction, FaultRecord, Query, Status};
use devices::ekm66::poller::*;
use devices::ekm66::simulator::*;
use devices::ekm66::tables::STATUS_CODES;

/// The records without their last-index octet (which changes as the board stores more).
fn essence(records: &[FaultRecord]) -> Vec<(u8, devices::ekm66::codec::FaultTime, u8, u8, u8)> {
    records
        .iter()
        .map(|r| (r.index, r.time, r.code, r.floor, r.target))
        .collect()
}

/// A poller and a simulator on a virtual 9600 Bd line.
struct Bench {
    now: Instant,
    poller: Option<Poller>,
    sim: Option<Simulator>,
    to_sim: VecDeque<(Instant, Vec<u8>)>,
    to_poller: VecDeque<(Instant, Vec<u8>)>,
    /// The archive: every Event::Fault, in order.
    archive: Vec<FaultRecord>,
    /// The stored cursor (as the caller persists it after each fault).
    cursor: ArchiveCursor,
    /// Every fault the board stored, in order.
    history: Vec<FaultRecord>,
    statuses: Vec<Status>,
    counters: Vec<Vec<u32>>,
    comm: Vec<CommStatus>,
    resyncs: Vec<ResyncReason>,
    status_changes: Vec<u8>,
    corrupt_next_reply: bool,
}

fn poller_config() -> PollerConfig {
    PollerConfig::default()
}

fn sim_config(seed: u64) -> SimulatorConfig {
    let mut config = SimulatorConfig::default();
    config.seed = seed;
    config.fault_probability = 0.0;
    config.status_probability = 0.0;
    config
}

impl Bench {
    fn new(sim: SimulatorConfig) -> Bench {
        // The virtual clock's origin; nothing reads the real clock after this.
        #[allow(clippy::disallowed_methods)]
        let now = Instant::now();
        Bench {
            now,
            poller: Some(Poller::new(poller_config(), ArchiveCursor::default(), now)),
            sim: Some(Simulator::new(sim, now)),
            to_sim: VecDeque::new(),
            to_poller: VecDeque::new(),
            archive: Vec::new(),
            cursor: ArchiveCursor::default(),
            history: Vec::new(),
            statuses: Vec::new(),
            counters: Vec::new(),
            comm: Vec::new(),
            resyncs: Vec::new(),
            status_changes: Vec::new(),
            corrupt_next_reply: false,
        }
    }

    fn sim(&mut self) -> &mut Simulator {
        self.sim.as_mut().unwrap()
    }

    fn poller(&mut self) -> &mut Poller {
        self.poller.as_mut().unwrap()
    }

    fn line_time(octets: usize) -> Duration {
        serial_line::LineSettings::new(9600).transmit_time(octets)
    }

    fn drain(&mut self) {
        let now = self.now;
        if let Some(poller) = self.poller.as_mut() {
            while let Some(bytes) = poller.poll_transmit(now) {
                let at = now + Self::line_time(bytes.len());
                self.to_sim.push_back((at, bytes));
            }
            while let Some(event) = poller.poll_event() {
                match event {
                    Event::Status(status) => self.statuses.push(status),
                    Event::Counters(counters) => self.counters.push(counters),
                    Event::Fault(record) => {
                        self.archive.push(record);
                        self.cursor = poller.cursor().clone();
                    }
                    Event::Comm(status) => self.comm.push(status),
                    Event::Resync(reason) => self.resyncs.push(reason),
                    Event::Error(_) => {}
                }
            }
        }
        if let Some(sim) = self.sim.as_mut() {
            while let Some(mut bytes) = sim.poll_transmit(now) {
                if std::mem::take(&mut self.corrupt_next_reply) {
                    bytes[7] ^= 0x40;
                }
                let at = now + Self::line_time(bytes.len());
                self.to_poller.push_back((at, bytes));
            }
            while let Some(event) = sim.poll_event() {
                match event {
                    SimEvent::FaultStored(record) => self.history.push(record),
                    SimEvent::StatusChanged(code) => self.status_changes.push(code),
                    _ => {}
                }
            }
        }
    }

    /// One step: to the next deadline or delivery.
    fn step(&mut self) {
        self.drain();
        let next = [
            self.poller.as_ref().and_then(Poller::poll_timeout),
            self.sim.as_ref().and_then(Simulator::poll_timeout),
            self.to_sim.front().map(|(at, _)| *at),
            self.to_poller.front().map(|(at, _)| *at),
        ]
        .into_iter()
        .flatten()
        .min()
        .unwrap();
        self.now = self.now.max(next);
        let now = self.now;
        while self.to_sim.front().is_some_and(|(at, _)| *at <= now) {
            let (_, bytes) = self.to_sim.pop_front().unwrap();
            if let Some(sim) = self.sim.as_mut() {
                sim.handle_bytes(now, &bytes);
            }
        }
        while self.to_poller.front().is_some_and(|(at, _)| *at <= now) {
            let (_, bytes) = self.to_poller.pop_front().unwrap();
            if let Some(poller) = self.poller.as_mut() {
                // In two pieces, as a UART delivers them.
                let (a, b) = bytes.split_at(bytes.len() / 2);
                poller.handle_bytes(now, a);
                poller.handle_bytes(now, b);
            }
        }
        if let Some(poller) = self.poller.as_mut() {
            poller.handle_timeout(now);
        }
        if let Some(sim) = self.sim.as_mut() {
            sim.handle_timeout(now);
        }
        self.drain();
    }

    fn run_for(&mut self, duration: Duration) {
        let end = self.now + duration;
        let mut steps = 0u64;
        while self.now < end {
            self.step();
            steps += 1;
            assert!(steps < 50_000_000, "the clock does not advance");
        }
    }

    /// Runs until the condition holds, at most `limit` of virtual time.
    fn run_until(&mut self, limit: Duration, mut done: impl FnMut(&Bench) -> bool) {
        let end = self.now + limit;
        while !done(self) {
            assert!(self.now < end, "condition not reached within {limit:?}");
            self.step();
        }
    }

    /// The monitor stops (its cursor is stored) ...
    fn stop_monitor(&mut self) {
        self.poller = None;
        self.to_poller.clear();
    }

    /// ... and starts again from the stored cursor.
    fn start_monitor(&mut self) {
        self.poller = Some(Poller::new(poller_config(), self.cursor.clone(), self.now));
    }

    fn inject(&mut self, codes: &[u8]) {
        for code in codes {
            self.sim().inject_fault(*code);
        }
        self.drain();
    }

    fn synced(&self) -> bool {
        self.archive.len() == self.history.len()
    }

    fn assert_archive_is_history(&self) {
        assert_eq!(
            essence(&self.archive),
            essence(&self.history),
            "archive differs from the board's history"
        );
        let keys: BTreeSet<_> = self.archive.iter().map(FaultKey::from).collect();
        assert_eq!(keys.len(), self.archive.len(), "duplicate in the archive");
    }
}

#[test]
fn status_trips_and_counters() {
    let mut config = sim_config(7);
    config.status_probability = 1.0;
    let mut bench = Bench::new(config);
    bench.run_for(Duration::from_secs(3 * 3600));
    assert!(bench.comm.first() == Some(&CommStatus::Ok) && bench.comm.len() == 1);
    assert_eq!(bench.poller().errors(), 0);
    // A status every second.
    assert!(
        bench.statuses.len() > 3 * 3600 - 10,
        "{}",
        bench.statuses.len()
    );
    // Trips: every floor seen, both directions, target ahead of the car.
    let positions: BTreeSet<u8> = bench.statuses.iter().map(|s| s.position).collect();
    assert_eq!(positions, (1..=5).collect());
    assert!(bench.statuses.iter().any(|s| s.direction == Direction::Up));
    assert!(bench
        .statuses
        .iter()
        .any(|s| s.direction == Direction::Down));
    // Every one of the 53 status codes shown by the board was read by the poller.
    let seen: BTreeSet<u8> = bench.statuses.iter().map(|s| s.code).collect();
    let changed: BTreeSet<u8> = bench.status_changes.iter().copied().collect();
    assert!(changed.is_subset(&seen), "{changed:?} vs {seen:?}");
    for entry in STATUS_CODES {
        assert!(
            seen.contains(&entry.code),
            "status {} never shown",
            entry.code
        );
    }
    // Counters once a minute, equal to the board's (read at the last minute's start
    // they may lag the board by the trips since).
    assert!(
        (179..=182).contains(&bench.counters.len()),
        "{}",
        bench.counters.len()
    );
    let last = bench.counters.last().unwrap().clone();
    let board = bench.sim().memory().counters.clone();
    assert_eq!(last.len(), 5);
    assert!(last.iter().zip(&board).all(|(a, b)| a <= b));
    assert!(board.iter().zip(&last).map(|(b, a)| b - a).sum::<u32>() <= 3);
    assert!(last.iter().all(|count| *count > 0));
    // The board's time of day advances with the virtual clock.
    let first = bench.statuses.first().unwrap().time;
    assert_eq!((first.hour, first.minute), (8, 0));
    let latest = bench.statuses.last().unwrap().time;
    assert_eq!(latest.hour, 10);
}

#[test]
fn random_faults_through_many_wraps_are_archived_once_in_order() {
    let mut config = sim_config(11);
    config.fault_probability = 0.5;
    config.stack_size = 8;
    let mut bench = Bench::new(config);
    bench.run_for(Duration::from_secs(4 * 3600));
    assert!(
        bench.history.len() > 40,
        "only {} faults",
        bench.history.len()
    );
    // The index wrapped several times.
    assert!(bench.history.iter().filter(|r| r.index == 0).count() > 4);
    bench.run_until(Duration::from_secs(5), Bench::synced);
    bench.assert_archive_is_history();
    assert!(bench.resyncs.is_empty());
}

#[test]
fn a_new_archive_reads_a_full_wrapped_stack_oldest_first() {
    let mut config = sim_config(3);
    config.stack_size = 6;
    let mut bench = Bench::new(config);
    bench.stop_monitor();
    bench.run_for(Duration::from_secs(1));
    bench.inject(&[0x10, 0x11, 0x12, 0x13, 0x14, 0x15, 0x16, 0x17, 0x18]);
    bench.start_monitor();
    bench.run_until(Duration::from_secs(30), |b| b.archive.len() >= 6);
    bench.run_for(Duration::from_secs(5));
    // The first three were overwritten before any monitor ran; the six left, oldest
    // first.
    let codes: Vec<u8> = bench.archive.iter().map(|r| r.code).collect();
    assert_eq!(codes, vec![0x13, 0x14, 0x15, 0x16, 0x17, 0x18]);
    assert_eq!(essence(&bench.archive), essence(&bench.history[3..]));
}

#[test]
fn monitor_restart_across_wrap_around_no_duplicate_no_gap() {
    let mut config = sim_config(5);
    config.stack_size = 5;
    let mut bench = Bench::new(config);
    bench.run_for(Duration::from_secs(3));
    bench.inject(&[0x01, 0x02, 0x03]);
    bench.run_until(Duration::from_secs(10), Bench::synced);
    for round in 0..6u8 {
        // Away while up to four faults come (fewer than the stack holds): the index
        // wraps while the monitor is down in most rounds.
        bench.stop_monitor();
        bench.run_for(Duration::from_secs(5));
        let codes: Vec<u8> = (0..=(round % 4)).map(|n| 0x20 + round * 4 + n).collect();
        bench.inject(&codes);
        bench.run_for(Duration::from_secs(2));
        bench.start_monitor();
        bench.run_until(Duration::from_secs(20), Bench::synced);
        bench.run_for(Duration::from_secs(3));
        bench.assert_archive_is_history();
    }
    assert!(bench.history.iter().filter(|r| r.index == 0).count() >= 3);
    assert!(bench.resyncs.is_empty(), "{:?}", bench.resyncs);
}

#[test]
fn restart_mid_sync_no_duplicate_no_gap() {
    // The monitor stops in the middle of reading new records: the cursor stored after
    // each one lets the next start read on from there.
    let mut config = sim_config(8);
    config.stack_size = 10;
    let mut bench = Bench::new(config);
    bench.run_for(Duration::from_secs(3));
    bench.inject(&[0x30, 0x31, 0x32, 0x33, 0x34, 0x35, 0x36, 0x37]);
    bench.run_until(Duration::from_secs(10), |b| b.archive.len() >= 3);
    bench.stop_monitor();
    bench.inject(&[0x38, 0x39, 0x3A]);
    bench.start_monitor();
    bench.run_until(Duration::from_secs(20), Bench::synced);
    bench.run_for(Duration::from_secs(3));
    bench.assert_archive_is_history();
}

#[test]
fn board_restart_with_its_memory_and_with_a_cleared_log() {
    let mut config = sim_config(9);
    config.stack_size = 6;
    let mut bench = Bench::new(config.clone());
    bench.run_for(Duration::from_secs(2));
    bench.inject(&[0x41, 0x42, 0x43, 0x44]);
    bench.run_until(Duration::from_secs(10), Bench::synced);

    // Switched off: the monitor loses the communication.
    let memory = bench.sim().memory().clone();
    bench.sim = None;
    bench.to_sim.clear();
    bench.run_until(Duration::from_secs(10), |b| {
        b.comm.last() == Some(&CommStatus::Lost)
    });
    // Back with its non-volatile memory; faults stored while it starts up wrap the index.
    bench.sim = Some(Simulator::with_memory(config.clone(), memory, bench.now));
    bench.inject(&[0x45, 0x46, 0x47]);
    bench.run_until(Duration::from_secs(10), |b| {
        b.comm.last() == Some(&CommStatus::Ok)
    });
    bench.run_until(Duration::from_secs(10), Bench::synced);
    bench.assert_archive_is_history();
    assert!(bench.resyncs.is_empty());

    // A replaced board (empty log): read from the base again, nothing repeated.
    bench.sim = Some(Simulator::new(config, bench.now));
    bench.run_until(Duration::from_secs(10), |b| !b.resyncs.is_empty());
    assert_eq!(bench.resyncs, vec![ResyncReason::Cleared]);
    bench.inject(&[0x48, 0x49]);
    bench.run_until(Duration::from_secs(10), Bench::synced);
    bench.run_for(Duration::from_secs(3));
    bench.assert_archive_is_history();
}

#[test]
fn monitor_away_longer_than_the_stack_holds() {
    let mut config = sim_config(12);
    config.stack_size = 4;
    let mut bench = Bench::new(config);
    bench.run_for(Duration::from_secs(2));
    bench.inject(&[0x50, 0x51]);
    bench.run_until(Duration::from_secs(10), Bench::synced);
    bench.stop_monitor();
    // Six faults into four slots: the first two are overwritten before anyone reads them.
    bench.inject(&[0x52, 0x53, 0x54, 0x55, 0x56, 0x57]);
    bench.start_monitor();
    bench.run_until(Duration::from_secs(20), |b| b.archive.len() >= 6);
    bench.run_for(Duration::from_secs(3));
    assert_eq!(bench.resyncs, vec![ResyncReason::Overwritten]);
    let codes: Vec<u8> = bench.archive.iter().map(|r| r.code).collect();
    assert_eq!(codes, vec![0x50, 0x51, 0x54, 0x55, 0x56, 0x57]);
}

#[test]
fn index_base_one_is_detected() {
    let mut config = sim_config(13);
    config.index_base = 1;
    config.stack_size = 3;
    let mut bench = Bench::new(config);
    bench.run_for(Duration::from_secs(5));
    assert!(bench.archive.is_empty());
    bench.inject(&[0x02, 0x03]);
    bench.run_until(Duration::from_secs(10), Bench::synced);
    assert_eq!(bench.cursor.base, Some(1));
    assert_eq!(bench.archive[0].index, 1);
    bench.inject(&[0x04, 0x05, 0x10]);
    bench.run_until(Duration::from_secs(10), Bench::synced);
    bench.assert_archive_is_history();
    assert_eq!(bench.archive.last().unwrap().index, 2);
}

#[test]
fn a_lift_that_stops_answering_reports_communication_lost() {
    let mut bench = Bench::new(sim_config(14));
    bench.run_for(Duration::from_secs(3));
    assert_eq!(bench.comm, vec![CommStatus::Ok]);
    let errors = bench.poller().errors();
    bench.sim().set_silent(true);
    let silent_at = bench.now;
    bench.run_until(Duration::from_secs(10), |b| {
        b.comm.last() == Some(&CommStatus::Lost)
    });
    // Within a cycle, four sends of 500 ms each and the transmit times.
    assert!(
        bench.now - silent_at < Duration::from_secs(4),
        "{:?}",
        bench.now - silent_at
    );
    // Four time-outs of the one query (first send and three retries).
    assert_eq!(bench.poller().errors() - errors, 4);
    assert_eq!(bench.poller().comm_status(), CommStatus::Lost);
    bench.run_for(Duration::from_secs(5));
    assert_eq!(bench.comm, vec![CommStatus::Ok, CommStatus::Lost]);
    bench.sim().set_silent(false);
    bench.run_until(Duration::from_secs(3), |b| {
        b.comm.last() == Some(&CommStatus::Ok)
    });
}

#[test]
fn an_invalid_reply_is_never_stored() {
    let mut bench = Bench::new(sim_config(15));
    bench.run_for(Duration::from_secs(3));
    let statuses = bench.statuses.len();
    let errors = bench.poller().errors();
    // Corrupt the next reply (the status of the next cycle): its checksum fails, it is
    // counted and the query repeated, and the repeat's valid reply is stored.
    bench.run_until(Duration::from_secs(2), |b| {
        b.to_sim
            .front()
            .is_some_and(|(_, q)| q == &Query::Status.encode())
    });
    bench.corrupt_next_reply = true;
    bench.run_until(Duration::from_secs(3), |b| b.statuses.len() > statuses);
    assert_eq!(bench.statuses.len(), statuses + 1);
    let last = bench.statuses.last().unwrap();
    assert_eq!(last.code, 1, "{last:?}");
    assert!(bench.poller().errors() > errors);
    assert_eq!(bench.comm, vec![CommStatus::Ok]);
}

#[test]
fn faults_arriving_during_base_detection_do_not_fool_it() {
    // Index 0 read empty, then the first faults arrive before index 1 is read: the
    // record at 1 must not make the base 1.
    let mut bench = Bench::new(sim_config(16));
    bench.run_until(Duration::from_secs(5), |b| {
        b.to_sim
            .front()
            .is_some_and(|(_, q)| q == &Query::FaultRecord(1).encode())
    });
    bench.inject(&[0x21, 0x22, 0x23]);
    bench.run_until(Duration::from_secs(10), Bench::synced);
    bench.run_for(Duration::from_secs(2));
    assert_eq!(bench.cursor.base, Some(0));
    bench.assert_archive_is_history();
}
