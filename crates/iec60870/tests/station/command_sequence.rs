//! The command sequence on the wire (IEC 60870-5-104 section 7, 101's command procedure):
//! ACT_CON, then the return information (cause 11), then ACT_TERM, for every command
//! type, direct and select-before-operate, with the return information queued before the
//! application decides, while it waits, or not at all.

use std::sync::{Arc, OnceLock};
use std::time::Duration;

use iec60870::asdu::{
    Asdu, Cause, CommandQualifier, Cp56Time2a, DoublePointState, Element, InformationObject,
    Quality, RegulatingStepState, SetpointQualifier, StepPosition, TimeTag, TypeId,
};
use iec60870::cs104::server::{
    ready, Command, CommandFuture, CommandOutcome, ProcessImage, ServerHandle, StationHandler,
};

use crate::common::*;

/// The monitor point that returns a command's effect sits at the command's address plus
/// this.
const FEEDBACK_OFFSET: u32 = 1000;

/// How the station under test produces the return information of the command points in
/// an address range.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Timing {
    /// Queued inside `handle_command`, before the (immediate) outcome: the way a simple
    /// outstation (and `stanice iec104 server`) does it.
    BeforeOutcome,
    /// Confirmed at once; the return information is queued later (the breaker's operate
    /// time), and only then is the command terminated.
    AfterConfirmation,
    /// No feedback point.
    None,
}

/// Address ranges: a hundred per timing, one address per command type (+ 50 for a point
/// that requires select-before-operate).
fn timing_of(address: u32) -> Timing {
    match address / 100 {
        1 => Timing::BeforeOutcome,
        2 => Timing::AfterConfirmation,
        _ => Timing::None,
    }
}

const COMMAND_TYPES: [TypeId; 7] = [
    TypeId::C_SC_NA_1,
    TypeId::C_DC_NA_1,
    TypeId::C_RC_NA_1,
    TypeId::C_SE_NA_1,
    TypeId::C_SE_NB_1,
    TypeId::C_SE_NC_1,
    TypeId::C_BO_NA_1,
];

/// The time-tagged twin of an untagged command type (45 -> 58 ...).
fn tagged(type_id: TypeId) -> TypeId {
    TypeId::try_from(type_id as u8 + 13).unwrap()
}

fn feedback_type(command: TypeId) -> TypeId {
    match command {
        TypeId::C_SC_NA_1 => TypeId::M_SP_NA_1,
        TypeId::C_DC_NA_1 => TypeId::M_DP_NA_1,
        TypeId::C_RC_NA_1 => TypeId::M_ST_NA_1,
        TypeId::C_SE_NA_1 => TypeId::M_ME_NA_1,
        TypeId::C_SE_NB_1 => TypeId::M_ME_NB_1,
        TypeId::C_SE_NC_1 => TypeId::M_ME_NC_1,
        TypeId::C_BO_NA_1 => TypeId::M_BO_NA_1,
        other => panic!("no feedback type for {other}"),
    }
}

/// A command element of the type, select or execute.
fn command_element(type_id: TypeId, select: bool) -> Element {
    let qualifier = CommandQualifier::new(0, select).unwrap();
    let setpoint = SetpointQualifier::new(0, select).unwrap();
    match type_id {
        TypeId::C_SC_NA_1 => Element::SingleCommand {
            on: true,
            qualifier,
        },
        TypeId::C_DC_NA_1 => Element::DoubleCommand {
            state: DoublePointState::On,
            qualifier,
        },
        TypeId::C_RC_NA_1 => Element::RegulatingStep {
            state: RegulatingStepState::Higher,
            qualifier,
        },
        TypeId::C_SE_NA_1 => Element::SetpointNormalized {
            raw: 1234,
            qualifier: setpoint,
        },
        TypeId::C_SE_NB_1 => Element::SetpointScaled {
            value: -321,
            qualifier: setpoint,
        },
        TypeId::C_SE_NC_1 => Element::SetpointFloat {
            value: 12.5,
            qualifier: setpoint,
        },
        TypeId::C_BO_NA_1 => Element::BitstringCommand { bits: 0xA5A5_0F0F },
        other => panic!("not a command type: {other}"),
    }
}

/// The monitor value a command leaves behind (a regulating step: position 1).
fn feedback_of(command: &Element) -> Element {
    command.commanded_value().unwrap_or(Element::StepPosition {
        position: StepPosition::new(1, false).unwrap(),
        quality: Quality::GOOD,
    })
}

/// A station whose command points return their effect on a feedback point.
struct FeedbackStation {
    server: OnceLock<ServerHandle>,
}

/// Queues a command's return information.
fn return_information(server: &ServerHandle, command: &Command) {
    let feedback = command.ioa.get() + FEEDBACK_OFFSET;
    server
        .update_with_cause(
            ioa(feedback),
            feedback_of(&command.element.as_execute()),
            None,
            Cause::RETURN_REMOTE,
        )
        .unwrap();
}

impl StationHandler for FeedbackStation {
    fn handle_command(&self, command: Command) -> CommandFuture {
        if command.select {
            return ready(CommandOutcome::Executed);
        }
        match timing_of(command.ioa.get()) {
            Timing::BeforeOutcome => {
                return_information(self.server.get().unwrap(), &command);
                ready(CommandOutcome::Executed)
            }
            Timing::AfterConfirmation => {
                let server = self.server.get().unwrap().clone();
                let termination = Box::pin(async move {
                    // The device's operate time: the confirmation is long gone by now.
                    tokio::time::sleep(Duration::from_millis(30)).await;
                    return_information(&server, &command);
                });
                ready(CommandOutcome::Confirmed(termination))
            }
            Timing::None => ready(CommandOutcome::Executed),
        }
    }
}

fn image() -> ProcessImage {
    let mut image = ProcessImage::new();
    for base in [100, 200, 300] {
        for (index, command_type) in COMMAND_TYPES.into_iter().enumerate() {
            let index = u32::try_from(index).unwrap();
            // A bitstring command has no select bit: no select-before-operate for it.
            let select_variants: &[(u32, bool)] = if command_type == TypeId::C_BO_NA_1 {
                &[(0, false)]
            } else {
                &[(0, false), (50, true)]
            };
            for &(offset, select_required) in select_variants {
                let address = base + index + offset;
                image
                    .add_command(command_point(address, command_type, select_required))
                    .unwrap();
                if timing_of(address) != Timing::None {
                    let feedback_type = feedback_type(command_type);
                    let element = feedback_of(&command_element(command_type, false));
                    image
                        .add_monitor(monitor(
                            address + FEEDBACK_OFFSET,
                            feedback_type,
                            0,
                            element,
                        ))
                        .unwrap();
                }
            }
        }
    }
    image
}

async fn station() -> ServerHandle {
    let station = Arc::new(FeedbackStation {
        server: OnceLock::new(),
    });
    let server = start_server(server_config(), image(), station.clone()).await;
    station.server.set(server.clone()).unwrap();
    server
}

/// What one received ASDU is, for comparing sequences.
#[derive(Debug, Clone, PartialEq)]
enum Seen {
    Confirmation { negative: bool },
    ReturnInformation { ioa: u32 },
    Termination,
    Other(String),
}

fn seen(asdu: &Asdu) -> Seen {
    let address = asdu.objects.first().map_or(0, |object| object.ioa.get());
    match asdu.cot.cause {
        Cause::ACTIVATION_CON => Seen::Confirmation {
            negative: asdu.cot.negative,
        },
        Cause::RETURN_REMOTE => Seen::ReturnInformation { ioa: address },
        Cause::ACTIVATION_TERMINATION => Seen::Termination,
        _ => Seen::Other(asdu.to_string()),
    }
}

fn command_asdu(type_id: TypeId, address: u32, select: bool, time: Option<Cp56Time2a>) -> Asdu {
    let base = TypeId::try_from(type_id as u8 - if time.is_some() { 13 } else { 0 }).unwrap();
    let mut asdu = request(
        type_id,
        Cause::ACTIVATION,
        CA,
        address,
        command_element(base, select),
    );
    if let Some(time) = time {
        asdu.objects[0] = InformationObject {
            time: Some(TimeTag::Cp56(time)),
            ..asdu.objects[0].clone()
        };
    }
    asdu
}

/// Sends a command and returns what came back up to and including its last answer (the
/// confirmation of a select, the termination of an execute).
async fn exchange(peer: &mut RawPeer, command: &Asdu) -> Vec<Seen> {
    peer.send(command).await;
    let select = command.objects[0].element.is_select();
    let mut answers = Vec::new();
    loop {
        let asdu = peer.expect_asdu().await;
        let last = asdu.type_id == command.type_id
            && match asdu.cot.cause {
                Cause::ACTIVATION_TERMINATION => true,
                Cause::ACTIVATION_CON => select || asdu.cot.negative,
                _ => false,
            };
        answers.push(seen(&asdu));
        if last {
            return answers;
        }
    }
}

fn expected(address: u32, select: bool) -> Vec<Seen> {
    if select {
        return vec![Seen::Confirmation { negative: false }];
    }
    let mut sequence = vec![Seen::Confirmation { negative: false }];
    if timing_of(address) != Timing::None {
        sequence.push(Seen::ReturnInformation {
            ioa: address + FEEDBACK_OFFSET,
        });
    }
    sequence.push(Seen::Termination);
    sequence
}

#[tokio::test]
async fn confirmation_then_return_information_then_termination_for_every_command_type() {
    init_logs();
    let server = station().await;
    let mut peer = RawPeer::connect(server.local_addr()).await;
    peer.start().await;
    let time = iec60870::time::TimeZonePolicy::Utc.to_cp56(chrono::Utc::now());
    for base in [100, 200, 300] {
        for (index, command_type) in COMMAND_TYPES.into_iter().enumerate() {
            let address = base + u32::try_from(index).unwrap();
            for type_id in [command_type, tagged(command_type)] {
                let time = (type_id != command_type).then_some(time);
                // Direct execute.
                let answers =
                    exchange(&mut peer, &command_asdu(type_id, address, false, time)).await;
                assert_eq!(
                    answers,
                    expected(address, false),
                    "{type_id} to {address} ({:?})",
                    timing_of(address)
                );
                if command_type == TypeId::C_BO_NA_1 {
                    continue;
                }
                // Select-before-operate on the point that requires it.
                let sbo = address + 50;
                let answers = exchange(&mut peer, &command_asdu(type_id, sbo, true, time)).await;
                assert_eq!(answers, expected(sbo, true), "select {type_id} to {sbo}");
                let answers = exchange(&mut peer, &command_asdu(type_id, sbo, false, time)).await;
                assert_eq!(
                    answers,
                    expected(sbo, false),
                    "execute {type_id} to {sbo} ({:?})",
                    timing_of(sbo)
                );
            }
        }
    }
}

#[tokio::test]
async fn spontaneous_events_are_not_held_back_by_a_command_waiting_for_its_outcome() {
    init_logs();
    let (release, released) = tokio::sync::oneshot::channel::<()>();
    let released = std::sync::Mutex::new(Some(released));
    let handler = Recorder::deciding(move |_| {
        let released = released.lock().unwrap().take();
        Box::pin(async move {
            if let Some(released) = released {
                let _ = released.await;
            }
            CommandOutcome::Executed
        })
    });
    let mut image = ProcessImage::new();
    image
        .add_command(command_point(5000, TypeId::C_SC_NA_1, false))
        .unwrap();
    image
        .add_monitor(monitor(1, TypeId::M_ME_NB_1, 0, scaled(0)))
        .unwrap();
    image
        .add_monitor(monitor(2, TypeId::M_SP_NA_1, 0, single(false)))
        .unwrap();
    let server = start_server(server_config(), image, handler.clone()).await;
    let mut peer = RawPeer::connect(server.local_addr()).await;
    peer.start().await;
    peer.send(&command_asdu(TypeId::C_SC_NA_1, 5000, false, None))
        .await;
    let recorder = Arc::clone(&handler);
    eventually(WAIT, "the command to reach the station", || {
        recorder.commands().len() == 1
    })
    .await;
    // While the command waits: a spontaneous event goes out at once, return
    // information waits for the confirmation.
    server.update(ioa(1), scaled(7), None).unwrap();
    let event = peer.expect_asdu().await;
    assert_eq!(
        (event.type_id, event.cot.cause),
        (TypeId::M_ME_NB_1, Cause::SPONTANEOUS)
    );
    server
        .update_with_cause(ioa(2), single(true), None, Cause::RETURN_REMOTE)
        .unwrap();
    if let Some(early) = peer.next_asdu(Duration::from_millis(200)).await {
        panic!("{early} came before the confirmation");
    }
    release.send(()).unwrap();
    let answers: Vec<Seen> = [
        peer.expect_asdu().await,
        peer.expect_asdu().await,
        peer.expect_asdu().await,
    ]
    .iter()
    .map(seen)
    .collect();
    assert_eq!(
        answers,
        vec![
            Seen::Confirmation { negative: false },
            Seen::ReturnInformation { ioa: 2 },
            Seen::Termination
        ]
    );
}
