//! FT1.2 link-layer scenarios on a virtual clock: start-up, lost and corrupted frames
//! with repeats, FCB duplicate detection, ACD and DFC, broadcast, and three secondaries
//! on one line with one dead. No port and no wall clock: every run is the same run.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::disallowed_methods
)]

use std::cell::RefCell;
use std::collections::VecDeque;
use std::rc::Rc;
use std::time::{Duration, Instant};

use iec60870::ft12::*;
use proptest::prelude::*;

#[derive(Default)]
struct DeviceState {
    class1: VecDeque<Vec<u8>>,
    class2: VecDeque<Vec<u8>>,
    received: Vec<(Vec<u8>, bool)>,
    resets: Vec<PrimaryFunction>,
    busy: u32,
    flow_stopped: bool,
    class1_taken: u32,
}

#[derive(Clone, Default)]
struct Device(Rc<RefCell<DeviceState>>);

impl SecondaryApplication for Device {
    fn link_reset(&mut self, function: PrimaryFunction) {
        self.0.borrow_mut().resets.push(function);
    }
    fn user_data(&mut self, asdu: &[u8], broadcast: bool) -> bool {
        let mut state = self.0.borrow_mut();
        if state.busy > 0 {
            state.busy -= 1;
            return false;
        }
        state.received.push((asdu.to_vec(), broadcast));
        true
    }
    fn has_class1(&self) -> bool {
        !self.0.borrow().class1.is_empty()
    }
    fn class1(&mut self) -> Option<Vec<u8>> {
        let mut state = self.0.borrow_mut();
        let next = state.class1.pop_front();
        if next.is_some() {
            state.class1_taken += 1;
        }
        next
    }
    fn class2(&mut self) -> Option<Vec<u8>> {
        self.0.borrow_mut().class2.pop_front()
    }
    fn data_flow_stopped(&self) -> bool {
        self.0.borrow().flow_stopped
    }
}

fn config() -> PrimaryConfig {
    PrimaryConfig {
        line: LineSettings::new(19200),
        response_timeout: Duration::from_millis(50),
        retries: 2,
        poll_interval: Duration::from_millis(100),
        failed_retry_interval: Duration::from_secs(5),
        ..PrimaryConfig::default()
    }
}

fn line(addresses: &[u16]) -> (SimulatedLine, Vec<Device>) {
    let start = Instant::now();
    let mut primary = Primary::new(config(), start);
    let mut devices = Vec::new();
    for &address in addresses {
        primary.add_station(address).expect("address fits");
    }
    let mut line = SimulatedLine::new(primary, start, Duration::from_millis(2));
    for &address in addresses {
        let device = Device::default();
        line.attach(
            Secondary::new(SecondaryConfig::new(address)),
            Box::new(device.clone()),
        );
        devices.push(device);
    }
    (line, devices)
}

/// Steps until `until` of virtual time has passed (bounded in steps), collecting events.
fn run(line: &mut SimulatedLine, until: Duration) -> Vec<PrimaryEvent> {
    let end = line.now() + until;
    let mut events = Vec::new();
    for _ in 0..100_000 {
        if line.now() >= end || !line.step() {
            break;
        }
        while let Some(event) = line.primary().poll_event() {
            events.push(event);
        }
    }
    events
}

/// Steps until an event matches (bounded in steps).
fn run_until(line: &mut SimulatedLine, found: impl Fn(&PrimaryEvent) -> bool) {
    for _ in 0..100_000 {
        assert!(line.step(), "the primary stopped before the event");
        while let Some(event) = line.primary().poll_event() {
            if found(&event) {
                return;
            }
        }
    }
    panic!("no such event");
}

fn requests(events: &[PrimaryEvent], address: u16) -> Vec<PrimaryFunction> {
    events
        .iter()
        .filter_map(|event| match event {
            PrimaryEvent::Exchange {
                address: a,
                request,
                ..
            } if *a == address => Some(*request),
            _ => None,
        })
        .collect()
}

#[test]
fn start_up_is_status_reset_then_class_2_with_fcb_starting_at_one() {
    let start = Instant::now();
    let mut primary = Primary::new(config(), start);
    primary.add_station(1).expect("fits");
    let mut secondary = Secondary::new(SecondaryConfig::new(1));
    let mut device = Device::default();
    let mut now = start;
    let mut sent = Vec::new();
    for _ in 0..5 {
        let request = primary.poll_transmit(now).expect("something to send");
        sent.push(request.clone());
        let mut deframer = Deframer::new(AddressSize::One);
        deframer.push(&request);
        let frame = deframer.next_frame().expect("a frame").expect("valid");
        let answer = secondary.handle(&frame, &mut device).expect("answered");
        now += Duration::from_millis(10);
        primary.handle_bytes(now, &answer.to_bytes(AddressSize::One).expect("encodes"));
        now += Duration::from_millis(100);
    }
    assert_eq!(
        sent,
        vec![
            vec![0x10, 0x49, 0x01, 0x4A, 0x16], // request status of link
            vec![0x10, 0x40, 0x01, 0x41, 0x16], // reset of remote link
            vec![0x10, 0x7B, 0x01, 0x7C, 0x16], // class 2, FCB 1
            vec![0x10, 0x5B, 0x01, 0x5C, 0x16], // class 2, FCB 0
            vec![0x10, 0x7B, 0x01, 0x7C, 0x16], // class 2, FCB 1
        ]
    );
    assert_eq!(primary.link_state(1), Some(LinkState::Up));
    assert_eq!(
        device.0.borrow().resets,
        vec![PrimaryFunction::ResetRemoteLink]
    );
    let events: Vec<_> = std::iter::from_fn(|| primary.poll_event()).collect();
    assert!(events.contains(&PrimaryEvent::LinkUp { address: 1 }));
}

#[test]
fn a_lost_answer_is_repeated_with_the_same_fcb_and_answered_from_the_last_response() {
    let (mut line, devices) = line(&[1]);
    run(&mut line, Duration::from_millis(300));
    assert_eq!(line.primary().link_state(1), Some(LinkState::Up));
    devices[0]
        .0
        .borrow_mut()
        .class1
        .push_back(vec![0x01, 0x81, 0x01, 0x01, 0xA0, 0xA0]);
    devices[0]
        .0
        .borrow_mut()
        .class1
        .push_back(vec![0x01, 0x81, 0x01, 0x01, 0xA0, 0xA1]);
    // The next class 2 poll sees ACD; the first class 1 answer is lost on the line.
    line.fault_next_answer(Fault::Lose); // answer to the class 2 poll that carries ACD
    let events = run(&mut line, Duration::from_millis(400));
    let data: Vec<Vec<u8>> = events
        .iter()
        .filter_map(|event| match event {
            PrimaryEvent::Exchange {
                answer: Answer::UserData(asdu),
                ..
            } => Some(asdu.clone()),
            _ => None,
        })
        .collect();
    assert_eq!(
        data,
        vec![
            vec![0x01, 0x81, 0x01, 0x01, 0xA0, 0xA0],
            vec![0x01, 0x81, 0x01, 0x01, 0xA0, 0xA1]
        ],
        "each event once, in order: {events:?}"
    );
    assert!(events
        .iter()
        .any(|event| matches!(event, PrimaryEvent::Timeout { attempt: 1, .. })));
    let (secondary, _) = line.station(1).expect("attached");
    assert_eq!(
        secondary.stats().repeats,
        1,
        "the repeat was answered from the cache"
    );
    assert_eq!(devices[0].0.borrow().class1_taken, 2);
}

#[test]
fn a_lost_class_1_answer_is_not_taken_twice() {
    let (mut line, devices) = line(&[1]);
    run(&mut line, Duration::from_millis(300));
    devices[0]
        .0
        .borrow_mut()
        .class1
        .push_back(vec![0x05, 0x81, 0x04, 0x01, 0xFF, 0x03]);
    // Class 2 poll (answered with ACD), then the class 1 answer is lost.
    run_until(&mut line, |event| {
        matches!(event, PrimaryEvent::Exchange { acd: true, .. })
    });
    line.fault_next_answer(Fault::Lose);
    let events = run(&mut line, Duration::from_millis(300));
    let user_data = events
        .iter()
        .filter(|event| {
            matches!(
                event,
                PrimaryEvent::Exchange {
                    request: PrimaryFunction::RequestClass1,
                    answer: Answer::UserData(_),
                    ..
                }
            )
        })
        .count();
    assert_eq!(user_data, 1, "{events:?}");
    assert_eq!(devices[0].0.borrow().class1_taken, 1);
}

#[test]
fn corrupted_frames_are_reported_and_repeated() {
    let (mut line, _devices) = line(&[1]);
    run(&mut line, Duration::from_millis(300));
    line.fault_next_answer(Fault::Corrupt);
    line.fault_next_request(Fault::Corrupt);
    let events = run(&mut line, Duration::from_millis(500));
    assert!(events
        .iter()
        .any(|event| matches!(event, PrimaryEvent::LineError(LineError::Frame(_)))));
    assert_eq!(line.primary().link_state(1), Some(LinkState::Up));
    let timeouts = events
        .iter()
        .filter(|event| matches!(event, PrimaryEvent::Timeout { .. }))
        .count();
    assert_eq!(timeouts, 2, "{events:?}");
}

#[test]
fn acd_drives_class_1_polls_until_empty() {
    let (mut line, devices) = line(&[1]);
    run(&mut line, Duration::from_millis(300));
    for inf in 0..5u8 {
        devices[0]
            .0
            .borrow_mut()
            .class1
            .push_back(vec![0x01, 0x81, 0x09, 0x01, 0xA0, inf]);
    }
    let events = run(&mut line, Duration::from_millis(90));
    let polls = requests(&events, 1);
    let class1 = polls
        .iter()
        .filter(|function| **function == PrimaryFunction::RequestClass1)
        .count();
    assert_eq!(class1, 5, "{polls:?}");
    assert!(devices[0].0.borrow().class1.is_empty());
}

#[test]
fn dfc_holds_user_data_until_the_secondary_is_ready() {
    let (mut line, devices) = line(&[1]);
    run(&mut line, Duration::from_millis(300));
    devices[0].0.borrow_mut().flow_stopped = true;
    // One poll sees DFC.
    run(&mut line, Duration::from_millis(150));
    line.primary()
        .send(1, vec![0x14, 0x81, 0x14, 0x01, 0x01, 0xA0, 0x02, 0x07])
        .expect("queued");
    let events = run(&mut line, Duration::from_millis(300));
    let held = requests(&events, 1);
    assert!(
        held.iter()
            .all(|function| *function == PrimaryFunction::RequestLinkStatus),
        "only link status while DFC: {held:?}"
    );
    assert!(devices[0].0.borrow().received.is_empty());
    devices[0].0.borrow_mut().flow_stopped = false;
    let events = run(&mut line, Duration::from_millis(300));
    assert!(requests(&events, 1).contains(&PrimaryFunction::UserDataConfirmed));
    assert_eq!(devices[0].0.borrow().received.len(), 1);
}

#[test]
fn busy_user_data_is_offered_again() {
    let (mut line, devices) = line(&[1]);
    run(&mut line, Duration::from_millis(300));
    devices[0].0.borrow_mut().busy = 2;
    line.primary()
        .send(1, vec![0x07, 0x81, 0x09, 0x01, 0xFF, 0x00, 0x01])
        .expect("queued");
    let events = run(&mut line, Duration::from_millis(300));
    let answers: Vec<_> = events
        .iter()
        .filter_map(|event| match event {
            PrimaryEvent::Exchange {
                request: PrimaryFunction::UserDataConfirmed,
                answer,
                ..
            } => Some(answer.clone()),
            _ => None,
        })
        .collect();
    assert_eq!(answers, vec![Answer::Busy, Answer::Busy, Answer::Ack]);
    assert_eq!(devices[0].0.borrow().received.len(), 1);
}

#[test]
fn broadcast_reaches_every_secondary_and_nobody_answers() {
    let (mut line, devices) = line(&[1, 2, 3]);
    run(&mut line, Duration::from_millis(300));
    line.primary()
        .broadcast(vec![
            0x06, 0x81, 0x08, 0xFF, 0xFF, 0x00, 1, 2, 3, 4, 5, 6, 7,
        ])
        .expect("fits");
    let events = run(&mut line, Duration::from_millis(50));
    assert!(events.contains(&PrimaryEvent::Broadcast {
        function: PrimaryFunction::UserDataNoReply
    }));
    for device in &devices {
        let received = &device.0.borrow().received;
        assert_eq!(received.len(), 1);
        assert!(received[0].1, "marked as broadcast");
    }
    assert!(!events
        .iter()
        .any(|event| matches!(event, PrimaryEvent::LineError(_))));
}

#[test]
fn a_dead_secondary_never_stalls_the_others() {
    let (mut line, _devices) = line(&[1, 2, 3]);
    line.set_alive(2, false);
    let events = run(&mut line, Duration::from_secs(4));
    let polls_1 = line.primary().stats(1).expect("known").class2_polls;
    let polls_3 = line.primary().stats(3).expect("known").class2_polls;
    // Polled every 100 ms for about 4 s.
    assert!(polls_1 >= 35 && polls_3 >= 35, "{polls_1} {polls_3}");
    assert_eq!(line.primary().link_state(2), Some(LinkState::Failed));
    let timeouts_2 = events
        .iter()
        .filter(|event| matches!(event, PrimaryEvent::Timeout { address: 2, .. }))
        .count();
    assert_eq!(
        timeouts_2, 3,
        "one request and two repeats, then quiet for 5 s"
    );

    // It comes back: found at its next retry, reset, polled.
    line.set_alive(2, true);
    let events = run(&mut line, Duration::from_secs(3));
    assert!(
        events.contains(&PrimaryEvent::LinkUp { address: 2 }),
        "{events:?}"
    );
    assert_eq!(line.primary().link_state(2), Some(LinkState::Up));

    // It dies while up: link down, its undelivered command reported, others go on.
    line.set_alive(2, false);
    line.primary()
        .send(2, vec![0x14, 0x81, 0x14, 0x02, 0x01, 0xA0, 0x02, 0x01])
        .expect("queued");
    let before = line.primary().stats(1).expect("known").class2_polls;
    let events = run(&mut line, Duration::from_secs(1));
    assert!(events.contains(&PrimaryEvent::LinkDown { address: 2 }));
    assert!(events
        .iter()
        .any(|event| matches!(event, PrimaryEvent::Undelivered { address: 2, .. })));
    assert!(line.primary().stats(1).expect("known").class2_polls >= before + 8);
}

#[test]
fn manual_mode_sends_only_what_is_asked() {
    let start = Instant::now();
    let mut primary = Primary::new(
        PrimaryConfig {
            automatic: false,
            ..config()
        },
        start,
    );
    primary.add_station(1).expect("fits");
    let mut line = SimulatedLine::new(primary, start, Duration::from_millis(2));
    line.attach(
        Secondary::new(SecondaryConfig::new(1)),
        Box::new(Device::default()),
    );
    assert!(run(&mut line, Duration::from_secs(1)).is_empty());
    line.primary()
        .request(1, PrimaryFunction::RequestClass2)
        .expect("known");
    let events = run(&mut line, Duration::from_secs(1));
    // Not reset yet: the secondary refuses FCV frames.
    assert!(matches!(
        events.first(),
        Some(PrimaryEvent::Exchange {
            answer: Answer::NotFunctioning,
            ..
        })
    ));
    line.primary()
        .request(1, PrimaryFunction::ResetRemoteLink)
        .expect("known");
    line.primary()
        .request(1, PrimaryFunction::RequestClass2)
        .expect("known");
    let events = run(&mut line, Duration::from_secs(1));
    let answers: Vec<_> = events
        .iter()
        .filter_map(|event| match event {
            PrimaryEvent::Exchange { answer, .. } => Some(answer.clone()),
            _ => None,
        })
        .collect();
    assert_eq!(answers, vec![Answer::Ack, Answer::NoData]);
}

#[test]
fn single_character_answers() {
    let start = Instant::now();
    let mut primary = Primary::new(config(), start);
    primary.add_station(7).expect("fits");
    let mut line = SimulatedLine::new(primary, start, Duration::from_millis(1));
    line.attach(
        Secondary::new(SecondaryConfig {
            single_character: true,
            ..SecondaryConfig::new(7)
        }),
        Box::new(Device::default()),
    );
    let events = run(&mut line, Duration::from_millis(500));
    assert_eq!(line.primary().link_state(7), Some(LinkState::Up));
    assert!(events.iter().any(|event| matches!(
        event,
        PrimaryEvent::Exchange {
            request: PrimaryFunction::RequestClass2,
            answer: Answer::NoData,
            ..
        }
    )));
}

fn any_frame() -> impl Strategy<Value = (AddressSize, Frame)> {
    let size = prop_oneof![
        Just(AddressSize::None),
        Just(AddressSize::One),
        Just(AddressSize::Two)
    ];
    size.prop_flat_map(|size| {
        let max_address = match size {
            AddressSize::None => 0u16,
            AddressSize::One => 0xFF,
            AddressSize::Two => 0xFFFF,
        };
        let max_asdu = 254 - size.octets();
        let frame = prop_oneof![
            Just(Frame::SingleCharacter),
            (any::<u8>(), 0..=max_address).prop_map(|(control, address)| Frame::Fixed {
                control: Control::from_octet(control),
                address
            }),
            (
                any::<u8>(),
                0..=max_address,
                proptest::collection::vec(any::<u8>(), 0..=max_asdu)
            )
                .prop_map(|(control, address, asdu)| Frame::Variable {
                    control: Control::from_octet(control),
                    address,
                    asdu
                }),
        ];
        (Just(size), frame)
    })
}

proptest! {
    #[test]
    fn frames_round_trip_through_any_split((size, frame) in any_frame(), split in 0usize..300) {
        let bytes = frame.to_bytes(size).expect("encodes");
        prop_assert_eq!(bytes.len(), frame.encoded_len(size));
        let mut deframer = Deframer::new(size);
        let (head, tail) = bytes.split_at(split.min(bytes.len()));
        deframer.push(head);
        let mut frames = Vec::new();
        while let Some(next) = deframer.next_frame() { frames.push(next); }
        deframer.push(tail);
        while let Some(next) = deframer.next_frame() { frames.push(next); }
        prop_assert_eq!(frames, vec![Ok(frame)]);
    }

    #[test]
    fn a_frame_is_found_behind_noise(
        (size, frame) in any_frame(),
        noise in proptest::collection::vec(any::<u8>().prop_filter("no start character", |b| ![0x10, 0x68, 0xE5].contains(b)), 1..40),
    ) {
        let mut deframer = Deframer::new(size);
        deframer.push(&noise);
        deframer.push(&frame.to_bytes(size).expect("encodes"));
        let mut frames = Vec::new();
        let mut errors = 0;
        while let Some(next) = deframer.next_frame() {
            match next { Ok(found) => frames.push(found), Err(_) => errors += 1 }
        }
        prop_assert_eq!(frames, vec![frame]);
        prop_assert_eq!(errors, 1);
    }

    #[test]
    fn any_bytes_never_panic_and_the_buffer_stays_bounded(
        chunks in proptest::collection::vec(proptest::collection::vec(any::<u8>(), 0..64), 0..32),
        two in any::<bool>(),
    ) {
        let mut deframer = Deframer::new(if two { AddressSize::Two } else { AddressSize::One });
        for chunk in chunks {
            deframer.push(&chunk);
            while deframer.next_frame().is_some() {}
        }
        // What stays buffered is less than one frame.
        deframer.push(&[]);
        prop_assert!(deframer.next_frame().is_none());
    }
}

/// Two ends of a balanced link wired together on a virtual clock, with a fault hook on
/// the frames from A to B.
struct BalancedPair {
    a: Balanced,
    b: Balanced,
    now: Instant,
    a_events: Vec<BalancedEvent>,
    b_events: Vec<BalancedEvent>,
    b_alive: bool,
    lose_next_from_b: bool,
}

impl BalancedPair {
    fn new() -> BalancedPair {
        let now = Instant::now();
        let config = |dir| BalancedConfig {
            line: LineSettings::new(9600),
            response_timeout: Duration::from_millis(100),
            test_interval: Duration::from_secs(2),
            restart_interval: Duration::from_secs(1),
            ..BalancedConfig::new(5, dir)
        };
        BalancedPair {
            a: Balanced::new(config(true), now),
            b: Balanced::new(config(false), now),
            now,
            a_events: Vec::new(),
            b_events: Vec::new(),
            b_alive: true,
            lose_next_from_b: false,
        }
    }

    /// Runs for `duration` of virtual time in steps of at most 1 ms.
    fn run(&mut self, duration: Duration) {
        let end = self.now + duration;
        while self.now < end {
            self.a.handle_timeout(self.now);
            self.b.handle_timeout(self.now);
            while let Some(bytes) = self.a.poll_transmit(self.now) {
                if self.b_alive {
                    self.b.handle_bytes(self.now, &bytes);
                }
            }
            while let Some(bytes) = self.b.poll_transmit(self.now) {
                if std::mem::take(&mut self.lose_next_from_b) || !self.b_alive {
                    continue;
                }
                self.a.handle_bytes(self.now, &bytes);
            }
            self.a_events
                .extend(std::iter::from_fn(|| self.a.poll_event()));
            self.b_events
                .extend(std::iter::from_fn(|| self.b.poll_event()));
            self.now += Duration::from_millis(1);
        }
    }
}

fn user_data(events: &[BalancedEvent]) -> Vec<Vec<u8>> {
    events
        .iter()
        .filter_map(|event| match event {
            BalancedEvent::UserData(asdu) => Some(asdu.clone()),
            _ => None,
        })
        .collect()
}

#[test]
fn balanced_link_starts_both_ways_and_carries_data_once_despite_a_lost_ack() {
    let mut pair = BalancedPair::new();
    pair.run(Duration::from_millis(300));
    assert!(pair.a.is_up() && pair.b.is_up());
    assert!(pair.a_events.contains(&BalancedEvent::LinkUp));
    assert!(pair.b_events.contains(&BalancedEvent::RemoteReset));

    pair.a.send(vec![0x64, 0x01, 0x06, 0x05, 0x00, 0x00, 0x14]);
    pair.b.send(vec![0x01, 0x01, 0x03, 0x05, 0x01, 0x00, 0x01]);
    pair.run(Duration::from_millis(300));
    assert_eq!(
        user_data(&pair.b_events),
        vec![vec![0x64, 0x01, 0x06, 0x05, 0x00, 0x00, 0x14]]
    );
    assert_eq!(
        user_data(&pair.a_events),
        vec![vec![0x01, 0x01, 0x03, 0x05, 0x01, 0x00, 0x01]]
    );

    // B's ACK is lost: A repeats with the same FCB, B acknowledges again and does not
    // pass the data on twice.
    pair.a.send(vec![0x2D, 0x01, 0x06, 0x05, 0x36, 0x10, 0x01]);
    pair.lose_next_from_b = true;
    pair.run(Duration::from_millis(500));
    assert_eq!(user_data(&pair.b_events).len(), 2, "{:?}", pair.b_events);
    assert!(pair
        .a_events
        .iter()
        .any(|event| matches!(event, BalancedEvent::Timeout { attempt: 1, .. })));
    assert_eq!(pair.a.unconfirmed(), 0);
}

#[test]
fn balanced_link_goes_down_keeps_its_data_and_restarts() {
    let mut pair = BalancedPair::new();
    pair.run(Duration::from_millis(300));
    pair.b_alive = false;
    // Idle: the test of link finds the other end gone.
    pair.run(Duration::from_secs(3));
    assert!(pair.a_events.contains(&BalancedEvent::LinkDown));
    assert!(!pair.a.is_up());
    pair.a.send(vec![0x01, 0x01, 0x03, 0x05, 0x01, 0x00, 0x01]);
    pair.b_alive = true;
    pair.run(Duration::from_secs(3));
    assert!(pair.a.is_up());
    assert_eq!(
        user_data(&pair.b_events),
        vec![vec![0x01, 0x01, 0x03, 0x05, 0x01, 0x00, 0x01]]
    );
}
