//! The outstation core without a transport: ASDUs in, ASDUs out through a hand-made
//! link layer, on a clock the test advances. What an IEC 101 serial slave or a fuzzer
//! sees of the core; the IEC 104 server's tests (tests/station) cover the same logic over
//! TCP.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    // Instant::now only as the base of the test's own clock.
    clippy::disallowed_methods
)]

use std::collections::VecDeque;
use std::sync::{Arc, Mutex};
use std::task::{Context, Poll, Waker};
use std::time::{Duration, Instant};

use iec60870::asdu::{
    Asdu, AsduParams, Cause, CommandQualifier, CommonAddress, Element, InformationObject, Ioa,
    Quality, TypeId,
};
use iec60870::outstation::{
    ready, Command, CommandFuture, CommandOutcome, CommandPoint, LinkCore, LinkLayer, MonitorPoint,
    Outstation, OutstationConfig, Peer, ProcessImage, StationHandler,
};

const PARAMS: AsduParams = AsduParams::IEC104;

/// A link layer with a window of `window` unconfirmed ASDUs, as a serial link with one
/// frame outstanding (window 1) or a 104 session (window k).
struct TestLink {
    window: usize,
    unconfirmed: VecDeque<Vec<u8>>,
    delivered: Vec<Asdu>,
}

impl TestLink {
    fn new(window: usize) -> Self {
        Self {
            window,
            unconfirmed: VecDeque::new(),
            delivered: Vec::new(),
        }
    }

    /// The peer confirms everything sent so far.
    fn confirm_all(&mut self, core: &mut LinkCore) {
        for raw in self.unconfirmed.drain(..) {
            self.delivered.push(Asdu::decode(&raw, &PARAMS).unwrap());
        }
        core.acknowledged(self);
    }

    /// Fills and confirms until the core has nothing more to send.
    fn exchange(&mut self, core: &mut LinkCore, now: Instant) -> Vec<Asdu> {
        for _ in 0..1000 {
            core.fill(now, self);
            if self.unconfirmed.is_empty() {
                break;
            }
            self.confirm_all(core);
        }
        std::mem::take(&mut self.delivered)
    }
}

impl LinkLayer for TestLink {
    fn can_send(&self) -> bool {
        self.unconfirmed.len() < self.window
    }

    fn send_asdu(&mut self, _now: Instant, asdu: &[u8]) -> bool {
        self.unconfirmed.push_back(asdu.to_vec());
        true
    }

    fn unconfirmed(&self) -> usize {
        self.unconfirmed.len()
    }

    fn hand_over(&mut self) -> usize {
        let count = self.unconfirmed.len();
        self.unconfirmed.clear();
        count
    }

    fn take_back(&mut self) {}
}

/// Executes every command and sets the command's feedback point (address + 1000) first,
/// as return information.
#[derive(Default)]
struct Station {
    outstation: Mutex<Option<std::sync::Weak<Outstation>>>,
    commands: Mutex<Vec<Command>>,
}

impl StationHandler for Station {
    fn handle_command(&self, command: Command) -> CommandFuture {
        self.commands.lock().unwrap().push(command.clone());
        if !command.select {
            if let Some(outstation) = self
                .outstation
                .lock()
                .unwrap()
                .as_ref()
                .and_then(std::sync::Weak::upgrade)
            {
                let feedback = Ioa::try_new(command.ioa.get() + 1000).unwrap();
                let Element::SingleCommand { on, .. } = command.element else {
                    panic!("single commands only here");
                };
                outstation
                    .update_with_cause(feedback, single(on), None, Cause::RETURN_REMOTE)
                    .unwrap();
            }
        }
        ready(CommandOutcome::Executed)
    }
}

fn single(on: bool) -> Element {
    Element::SinglePoint {
        on,
        quality: Quality::GOOD,
    }
}

fn ca() -> CommonAddress {
    CommonAddress::new(1)
}

fn ioa(value: u32) -> Ioa {
    Ioa::try_new(value).unwrap()
}

/// An outstation with monitor points 1..=300 (single points, GI group 1 for the odd ones),
/// a command point at 5000 (select required) with its feedback at 6000, and one link.
fn station() -> (Arc<Outstation>, Arc<Station>, LinkCore) {
    let mut image = ProcessImage::new();
    for address in 1..=300 {
        image
            .add_monitor(MonitorPoint {
                ioa: ioa(address),
                event_type: TypeId::M_SP_NA_1,
                groups: if address % 2 == 1 { 1 } else { 0 },
                element: single(address % 3 == 0),
                time: None,
            })
            .unwrap();
    }
    image
        .add_monitor(MonitorPoint {
            ioa: ioa(6000),
            event_type: TypeId::M_SP_NA_1,
            groups: 0,
            element: single(false),
            time: None,
        })
        .unwrap();
    image
        .add_command(CommandPoint {
            ioa: ioa(5000),
            command_type: TypeId::C_SC_NA_1,
            select_required: true,
            max_age: None,
        })
        .unwrap();
    let mut config = OutstationConfig::new(ca(), PARAMS);
    config.send_end_of_initialisation = false;
    config.select_timeout = Duration::from_secs(10);
    let handler = Arc::new(Station::default());
    let outstation = Arc::new(Outstation::new(config, image, handler.clone()).unwrap());
    *handler.outstation.lock().unwrap() = Some(Arc::downgrade(&outstation));
    let peer = Peer::Serial {
        port: "/dev/ttyTEST".into(),
        link_address: 3,
    };
    let core = outstation.open_link(1, peer).unwrap();
    (outstation, handler, core)
}

fn encode(asdu: &Asdu) -> Vec<u8> {
    let mut bytes = Vec::new();
    asdu.encode(&PARAMS, &mut bytes).unwrap();
    bytes
}

fn request(type_id: TypeId, cause: Cause, address: u32, element: Element) -> Vec<u8> {
    let mut asdu = Asdu::new(type_id, cause, ca());
    asdu.objects
        .push(InformationObject::new(ioa(address), element));
    encode(&asdu)
}

fn command(select: bool, on: bool) -> Vec<u8> {
    let qualifier = if select {
        CommandQualifier::SELECT
    } else {
        CommandQualifier::EXECUTE
    };
    request(
        TypeId::C_SC_NA_1,
        Cause::ACTIVATION,
        5000,
        Element::SingleCommand { on, qualifier },
    )
}

/// Lets the core take the outcomes the handler decided (ready futures: one poll).
fn take_outcomes(core: &mut LinkCore) {
    let mut context = Context::from_waker(Waker::noop());
    while core.awaits_commands() {
        if core.poll_commands(&mut context) == Poll::Pending {
            break;
        }
    }
}

fn summary(asdus: &[Asdu]) -> Vec<(TypeId, Cause, bool)> {
    asdus
        .iter()
        .map(|asdu| (asdu.type_id, asdu.cot.cause, asdu.cot.negative))
        .collect()
}

#[test]
fn group_interrogation_through_a_one_frame_window() {
    let (_outstation, _handler, mut core) = station();
    let mut link = TestLink::new(1);
    let now = Instant::now();
    core.start();
    core.handle_asdu(
        now,
        request(
            TypeId::C_IC_NA_1,
            Cause::ACTIVATION,
            0,
            Element::Interrogation { qualifier: 21 },
        ),
    );
    let answers = link.exchange(&mut core, now);
    let first = answers.first().unwrap();
    assert_eq!(
        (first.type_id, first.cot.cause),
        (TypeId::C_IC_NA_1, Cause::ACTIVATION_CON)
    );
    let last = answers.last().unwrap();
    assert_eq!(
        (last.type_id, last.cot.cause),
        (TypeId::C_IC_NA_1, Cause::ACTIVATION_TERMINATION)
    );
    let reported: Vec<u32> = answers[1..answers.len() - 1]
        .iter()
        .inspect(|asdu| {
            assert_eq!(asdu.type_id, TypeId::M_SP_NA_1);
            assert_eq!(asdu.cot.cause, Cause::interrogated_by_group(1).unwrap());
        })
        .flat_map(|asdu| asdu.objects.iter().map(|object| object.ioa.get()))
        .collect();
    let expected: Vec<u32> = (1..=300).filter(|address| address % 2 == 1).collect();
    assert_eq!(reported, expected, "group 1 is the odd addresses, in order");
}

#[test]
fn select_and_execute_then_return_information_then_termination() {
    let (_outstation, handler, mut core) = station();
    let mut link = TestLink::new(12);
    let now = Instant::now();
    core.start();

    core.handle_asdu(now, command(true, true));
    take_outcomes(&mut core);
    let answers = link.exchange(&mut core, now);
    assert_eq!(
        summary(&answers),
        [(TypeId::C_SC_NA_1, Cause::ACTIVATION_CON, false)]
    );

    core.handle_asdu(now + Duration::from_secs(2), command(false, true));
    take_outcomes(&mut core);
    let answers = link.exchange(&mut core, now + Duration::from_secs(2));
    assert_eq!(
        summary(&answers),
        [
            (TypeId::C_SC_NA_1, Cause::ACTIVATION_CON, false),
            (TypeId::M_SP_NA_1, Cause::RETURN_REMOTE, false),
            (TypeId::C_SC_NA_1, Cause::ACTIVATION_TERMINATION, false),
        ]
    );
    assert_eq!(answers[1].objects[0].ioa.get(), 6000);
    let commands = handler.commands.lock().unwrap();
    assert_eq!(commands.len(), 2);
    assert_eq!(commands[1].peer.to_string(), "/dev/ttyTEST link 3");
}

#[test]
fn an_execute_after_the_select_timeout_is_refused_on_the_given_clock() {
    let (_outstation, handler, mut core) = station();
    let mut link = TestLink::new(12);
    let now = Instant::now();
    core.start();
    core.handle_asdu(now, command(true, true));
    take_outcomes(&mut core);
    link.exchange(&mut core, now);

    // Eleven seconds on the core's clock, none on the wall clock.
    let later = now + Duration::from_secs(11);
    core.handle_asdu(later, command(false, true));
    take_outcomes(&mut core);
    let answers = link.exchange(&mut core, later);
    assert_eq!(
        summary(&answers),
        [(TypeId::C_SC_NA_1, Cause::ACTIVATION_CON, true)],
        "the selection expired: negative confirmation, no execution"
    );
    assert_eq!(handler.commands.lock().unwrap().len(), 1, "only the select");
}

#[test]
fn events_wait_in_the_group_until_a_link_starts_and_survive_a_lost_link() {
    let (outstation, _handler, mut core) = station();
    let now = Instant::now();
    for address in [1, 2, 3] {
        outstation.update(ioa(address), single(true), None).unwrap();
    }
    let mut link = TestLink::new(1);
    link.exchange(&mut core, now);
    assert!(
        link.delivered.is_empty(),
        "nothing before data transfer starts"
    );

    core.start();
    core.fill(now, &mut link);
    assert_eq!(
        link.unconfirmed.len(),
        1,
        "one ASDU of three events in flight"
    );
    // The link dies before the peer confirmed it: the next link gets it again.
    core.close(&link);

    let peer = Peer::Serial {
        port: "/dev/ttyTEST".into(),
        link_address: 3,
    };
    let mut again = outstation.open_link(2, peer).unwrap();
    let mut link = TestLink::new(1);
    again.start();
    let answers = link.exchange(&mut again, now);
    let addresses: Vec<u32> = answers
        .iter()
        .flat_map(|asdu| asdu.objects.iter().map(|object| object.ioa.get()))
        .collect();
    assert_eq!(addresses, [1, 2, 3]);
}
