//! Commands: direct execute, refusals (causes 44 to 47), select-before-operate, slow
//! outcomes and the broadcast address.

use std::sync::Arc;
use std::time::{Duration, Instant};

use iec60870::asdu::{
    Asdu, Cause, CommandQualifier, CommonAddress, Cot, Cp56Time2a, DoublePointState, Element,
    InformationObject, SetpointQualifier, TimeTag, TypeId,
};
use iec60870::cs104::server::{CommandOutcome, ProcessImage, ServerConfig};
use iec60870::cs104::ApciConfig;

use crate::common::*;

const DIRECT_SC: u32 = 5000;
const DIRECT_DC: u32 = 5001;
const SBO_SC: u32 = 5002;
const SBO_SETPOINT: u32 = 5003;
const REFUSED: u32 = 5004;
const SLOW: u32 = 5005;
pub(crate) const NEVER: u32 = 5006;

pub(crate) fn command_image() -> ProcessImage {
    let mut image = ProcessImage::new();
    for (address, command_type, select_required) in [
        (DIRECT_SC, TypeId::C_SC_NA_1, false),
        (DIRECT_DC, TypeId::C_DC_NA_1, false),
        (SBO_SC, TypeId::C_SC_NA_1, true),
        (SBO_SETPOINT, TypeId::C_SE_NC_1, true),
        (REFUSED, TypeId::C_SC_NA_1, false),
        (SLOW, TypeId::C_SC_NA_1, false),
        (NEVER, TypeId::C_SC_NA_1, false),
    ] {
        image
            .add_command(command_point(address, command_type, select_required))
            .unwrap();
    }
    image
        .add_monitor(monitor(100, TypeId::M_SP_TB_1, 0, single(true)))
        .unwrap();
    image
}

pub(crate) fn command_handler() -> Arc<Recorder> {
    Recorder::deciding(|command| match command.ioa.get() {
        REFUSED => iec60870::cs104::server::ready(CommandOutcome::Refused),
        SLOW => Box::pin(async {
            tokio::time::sleep(Duration::from_millis(200)).await;
            CommandOutcome::Executed
        }),
        NEVER => Box::pin(std::future::pending()),
        _ => iec60870::cs104::server::ready(CommandOutcome::Executed),
    })
}

async fn command_server(
    config: ServerConfig,
) -> (iec60870::cs104::server::ServerHandle, Arc<Recorder>) {
    let handler = command_handler();
    let server = start_server(config, command_image(), handler.clone()).await;
    (server, handler)
}

fn sco(on: bool, select: bool) -> Element {
    Element::SingleCommand {
        on,
        qualifier: if select {
            CommandQualifier::SELECT
        } else {
            CommandQualifier::EXECUTE
        },
    }
}

fn dco(state: DoublePointState) -> Element {
    Element::DoubleCommand {
        state,
        qualifier: CommandQualifier::EXECUTE,
    }
}

fn setpoint(value: f32, select: bool) -> Element {
    Element::SetpointFloat {
        value,
        qualifier: if select {
            SetpointQualifier::SELECT
        } else {
            SetpointQualifier::EXECUTE
        },
    }
}

fn single_command(address: u32, element: Element) -> Asdu {
    request(TypeId::C_SC_NA_1, Cause::ACTIVATION, CA, address, element)
}

/// Asserts an ASDU is the mirror of `request` with `cause` and P/N.
fn assert_mirror(asdu: &Asdu, request: &Asdu, cause: Cause, negative: bool) {
    assert_eq!(asdu.type_id, request.type_id, "{asdu}");
    assert_eq!(
        (asdu.cot.cause, asdu.cot.negative),
        (cause, negative),
        "{asdu}"
    );
    assert_eq!(asdu.objects, request.objects, "{asdu}");
}

#[tokio::test]
async fn direct_execute_is_confirmed_and_terminated() {
    init_logs();
    let (server, handler) = command_server(server_config()).await;
    let mut config = client_config(server.local_addr());
    config.originator = 7;
    let client = Client::start(config).await;

    let outcome = within(
        WAIT,
        "C_SC",
        client
            .handle
            .command(TypeId::C_SC_NA_1, ioa(DIRECT_SC), sco(true, false), None),
    )
    .await
    .unwrap();
    assert!(outcome.positive && outcome.terminated, "{outcome:?}");
    assert_eq!(outcome.cause, Cause::ACTIVATION_CON);
    let causes: Vec<Cause> = outcome
        .responses
        .iter()
        .map(|asdu| asdu.cot.cause)
        .collect();
    assert_eq!(
        causes,
        vec![Cause::ACTIVATION_CON, Cause::ACTIVATION_TERMINATION]
    );
    assert!(outcome
        .responses
        .iter()
        .all(|asdu| asdu.cot.originator == 7));

    let commands = handler.commands();
    assert_eq!(commands.len(), 1);
    let command = &commands[0];
    assert_eq!(command.type_id, TypeId::C_SC_NA_1);
    assert_eq!(command.common_address, ca());
    assert_eq!(command.ioa, ioa(DIRECT_SC));
    assert_eq!(command.element, sco(true, false));
    assert_eq!(command.originator, 7);
    assert!(!command.select);
    assert_eq!(command.time, None);
    assert_eq!(command.peer.ip(), Some(server.local_addr().ip()));

    // The time-tagged twin is accepted by the same point, the time reaches the handler.
    let time = Cp56Time2a::new(26, 5, 1, 12, 0, 0).unwrap();
    let outcome = client
        .handle
        .command(
            TypeId::C_SC_TA_1,
            ioa(DIRECT_SC),
            sco(false, false),
            Some(time),
        )
        .await
        .unwrap();
    assert!(outcome.positive && outcome.terminated);
    assert_eq!(handler.commands()[1].time, Some(TimeTag::Cp56(time)));

    // A double command ON and OFF.
    for state in [DoublePointState::On, DoublePointState::Off] {
        let outcome = client
            .handle
            .command(TypeId::C_DC_NA_1, ioa(DIRECT_DC), dco(state), None)
            .await
            .unwrap();
        assert!(outcome.positive && outcome.terminated);
    }
    assert_eq!(handler.commands().len(), 4);
}

#[tokio::test]
async fn refused_commands_get_negative_confirmations_with_the_right_cause() {
    init_logs();
    let (server, handler) = command_server(server_config()).await;
    let client = Client::connect(server.local_addr()).await;

    // The handler refuses: negative ACT_CON, no termination.
    let outcome = client
        .handle
        .command(TypeId::C_SC_NA_1, ioa(REFUSED), sco(true, false), None)
        .await
        .unwrap();
    assert!(!outcome.positive && !outcome.terminated);
    assert_eq!(outcome.cause, Cause::ACTIVATION_CON);
    assert_eq!(handler.commands().len(), 1);

    let cases: Vec<(&str, Asdu, Cause)> = vec![
        (
            "unknown IOA",
            single_command(9999, sco(true, false)),
            Cause::UNKNOWN_OBJECT_ADDRESS,
        ),
        (
            "wrong common address",
            request(
                TypeId::C_SC_NA_1,
                Cause::ACTIVATION,
                2,
                DIRECT_SC,
                sco(true, false),
            ),
            Cause::UNKNOWN_COMMON_ADDRESS,
        ),
        (
            "spontaneous cause",
            request(
                TypeId::C_SC_NA_1,
                Cause::SPONTANEOUS,
                CA,
                DIRECT_SC,
                sco(true, false),
            ),
            Cause::UNKNOWN_CAUSE,
        ),
        (
            "request cause",
            request(
                TypeId::C_SC_NA_1,
                Cause::REQUEST,
                CA,
                DIRECT_SC,
                sco(true, false),
            ),
            Cause::UNKNOWN_CAUSE,
        ),
        (
            "monitor type",
            request(TypeId::M_SP_NA_1, Cause::ACTIVATION, CA, 100, single(true)),
            Cause::UNKNOWN_TYPE,
        ),
        (
            "file transfer",
            request(
                TypeId::F_SC_NA_1,
                Cause::FILE_TRANSFER,
                CA,
                0,
                Element::CallOrSelect {
                    file: 1,
                    section: 0,
                    qualifier: 1,
                },
            ),
            Cause::UNKNOWN_TYPE,
        ),
        (
            "C_TS_NA_1 is not used in 104",
            request(
                TypeId::C_TS_NA_1,
                Cause::ACTIVATION,
                CA,
                0,
                Element::Test { pattern: 0x55AA },
            ),
            Cause::UNKNOWN_TYPE,
        ),
        (
            "double command intermediate (DCS 0)",
            request(
                TypeId::C_DC_NA_1,
                Cause::ACTIVATION,
                CA,
                DIRECT_DC,
                dco(DoublePointState::Intermediate),
            ),
            Cause::ACTIVATION_CON,
        ),
        (
            "double command indeterminate (DCS 3)",
            request(
                TypeId::C_DC_NA_1,
                Cause::ACTIVATION,
                CA,
                DIRECT_DC,
                dco(DoublePointState::Indeterminate),
            ),
            Cause::ACTIVATION_CON,
        ),
        (
            "command type not the point's",
            request(
                TypeId::C_DC_NA_1,
                Cause::ACTIVATION,
                CA,
                DIRECT_SC,
                dco(DoublePointState::On),
            ),
            Cause::ACTIVATION_CON,
        ),
    ];
    for (what, asdu, cause) in cases {
        let outcome = within(WAIT, what, client.handle.send(asdu.clone()))
            .await
            .unwrap();
        assert!(!outcome.positive, "{what}: {outcome:?}");
        assert_eq!(outcome.cause, cause, "{what}");
        assert!(!outcome.terminated, "{what}");
        assert_mirror(&outcome.responses[0], &asdu, cause, true);
    }
    // None of them reached the handler.
    assert_eq!(handler.commands().len(), 1);
}

#[tokio::test]
async fn undefined_type_identification_is_refused_with_cause_44() {
    init_logs();
    let (server, _) = command_server(server_config()).await;
    let mut peer = RawPeer::connect(server.local_addr()).await;
    peer.start().await;
    // Type 22 is not defined; the rest is a well-formed header and one octet.
    let raw = [22u8, 0x01, 0x06, 0x00, 0x01, 0x00, 0x88, 0x13, 0x00, 0x01];
    peer.send_asdu(&raw).await;
    let answer = peer
        .next_raw(WAIT)
        .await
        .expect("an answer to the undefined type");
    let mut expected = raw.to_vec();
    expected[2] = 0x40 | 44;
    assert_eq!(answer, expected);
    // The connection is still fine.
    peer.send(&interrogation(20)).await;
    let asdus = peer
        .asdus_until(TypeId::C_IC_NA_1, Cause::ACTIVATION_TERMINATION)
        .await;
    assert_eq!(asdus.len(), 3);
}

#[tokio::test]
async fn request_cause_is_accepted_as_activation_when_configured() {
    init_logs();
    let mut config = server_config();
    config.outstation.accept_request_as_activation = true;
    let (server, handler) = command_server(config).await;
    let mut client = Client::connect(server.local_addr()).await;
    let asdu = request(
        TypeId::C_SC_NA_1,
        Cause::REQUEST,
        CA,
        DIRECT_SC,
        sco(true, false),
    );
    let outcome = client.handle.send(asdu.clone()).await.unwrap();
    assert!(outcome.positive, "{outcome:?}");
    assert_eq!(outcome.cause, Cause::ACTIVATION_CON);
    let termination = client
        .asdus_until(TypeId::C_SC_NA_1, Cause::ACTIVATION_TERMINATION, WAIT)
        .await;
    assert_mirror(
        termination.last().unwrap(),
        &asdu,
        Cause::ACTIVATION_TERMINATION,
        false,
    );
    assert_eq!(handler.commands().len(), 1);
    assert_eq!(handler.commands()[0].ioa, ioa(DIRECT_SC));
}

#[tokio::test]
async fn select_before_operate() {
    init_logs();
    let (server, handler) = command_server(server_config()).await;
    let client = Client::connect(server.local_addr()).await;
    let command = |address, element| {
        let handle = client.handle.clone();
        async move {
            let type_id = if matches!(element, Element::SetpointFloat { .. }) {
                TypeId::C_SE_NC_1
            } else {
                TypeId::C_SC_NA_1
            };
            within(
                WAIT,
                "a command",
                handle.command(type_id, ioa(address), element, None),
            )
            .await
            .unwrap()
        }
    };

    // Execute without select on a select-required point: refused, handler not asked.
    let outcome = command(SBO_SC, sco(true, false)).await;
    assert!(!outcome.positive);
    assert!(handler.commands().is_empty());

    // Select: ACT_CON only (no termination); then the matching execute: ACT_CON, ACT_TERM.
    let outcome = command(SBO_SC, sco(true, true)).await;
    assert!(outcome.positive && !outcome.terminated, "{outcome:?}");
    assert_eq!(outcome.responses.len(), 1);
    let outcome = command(SBO_SC, sco(true, false)).await;
    assert!(outcome.positive && outcome.terminated, "{outcome:?}");
    let selects: Vec<bool> = handler.commands().iter().map(|c| c.select).collect();
    assert_eq!(selects, vec![true, false]);

    // The selection was used up.
    assert!(!command(SBO_SC, sco(true, false)).await.positive);

    // Select, then execute with another value: refused, and the selection is gone.
    assert!(command(SBO_SC, sco(true, true)).await.positive);
    assert!(!command(SBO_SC, sco(false, false)).await.positive);
    assert!(!command(SBO_SC, sco(true, false)).await.positive);

    // Set point: select 12.5, execute 12.5.
    assert!(command(SBO_SETPOINT, setpoint(12.5, true)).await.positive);
    let outcome = command(SBO_SETPOINT, setpoint(12.5, false)).await;
    assert!(outcome.positive && outcome.terminated);
    assert_eq!(
        handler.commands().last().unwrap().element,
        setpoint(12.5, false)
    );

    // Deactivation (cause 8) of a selection: DEACT_CON, then the execute is refused.
    assert!(command(SBO_SC, sco(true, true)).await.positive);
    let deactivation = request(
        TypeId::C_SC_NA_1,
        Cause::DEACTIVATION,
        CA,
        SBO_SC,
        sco(true, true),
    );
    let outcome = client.handle.send(deactivation.clone()).await.unwrap();
    assert!(outcome.positive, "{outcome:?}");
    assert_eq!(outcome.cause, Cause::DEACTIVATION_CON);
    assert_mirror(
        &outcome.responses[0],
        &deactivation,
        Cause::DEACTIVATION_CON,
        false,
    );
    assert!(!command(SBO_SC, sco(true, false)).await.positive);
    // Deactivating nothing: negative DEACT_CON.
    let outcome = client.handle.send(deactivation).await.unwrap();
    assert!(!outcome.positive);
    assert_eq!(outcome.cause, Cause::DEACTIVATION_CON);
}

#[tokio::test]
async fn a_selection_expires_after_the_select_timeout() {
    init_logs();
    let mut config = server_config();
    config.outstation.select_timeout = Duration::from_millis(300);
    let (server, _) = command_server(config).await;
    let client = Client::connect(server.local_addr()).await;
    let select = client
        .handle
        .command(TypeId::C_SC_NA_1, ioa(SBO_SC), sco(true, true), None)
        .await
        .unwrap();
    assert!(select.positive);
    // Time passing is what is tested here.
    tokio::time::sleep(Duration::from_millis(400)).await;
    let execute = client
        .handle
        .command(TypeId::C_SC_NA_1, ioa(SBO_SC), sco(true, false), None)
        .await
        .unwrap();
    assert!(!execute.positive, "an expired selection was executed");

    // Within the timeout it works.
    assert!(
        client
            .handle
            .command(TypeId::C_SC_NA_1, ioa(SBO_SC), sco(true, true), None)
            .await
            .unwrap()
            .positive
    );
    let execute = client
        .handle
        .command(TypeId::C_SC_NA_1, ioa(SBO_SC), sco(true, false), None)
        .await
        .unwrap();
    assert!(execute.positive && execute.terminated);
}

#[tokio::test]
async fn a_selection_belongs_to_its_connection_and_originator() {
    init_logs();
    let (server, handler) = command_server(server_config()).await;
    let address = server.local_addr();
    let mut a = RawPeer::connect(address).await;
    a.start().await;
    let select = single_command(SBO_SC, sco(true, true));
    a.send(&select).await;
    assert_mirror(
        &a.expect_asdu().await,
        &select,
        Cause::ACTIVATION_CON,
        false,
    );

    // B takes the group over and tries to execute A's selection: refused.
    let mut b = RawPeer::connect(address).await;
    b.start().await;
    let execute = single_command(SBO_SC, sco(true, false));
    b.send(&execute).await;
    assert_mirror(
        &b.expect_asdu().await,
        &execute,
        Cause::ACTIVATION_CON,
        true,
    );
    // ... and B's attempt did not cancel A's selection: A, started again, executes it.
    a.write_raw(&[0x68, 0x04, 0x07, 0x00, 0x00, 0x00]).await;
    a.pump_for(Duration::from_millis(50)).await;
    a.send(&execute).await;
    let answers = a
        .asdus_until(TypeId::C_SC_NA_1, Cause::ACTIVATION_TERMINATION)
        .await;
    assert_mirror(&answers[0], &execute, Cause::ACTIVATION_CON, false);
    let selects: Vec<bool> = handler.commands().iter().map(|c| c.select).collect();
    assert_eq!(selects, vec![true, false]);

    // The originator address is part of the selection.
    let mut selected = single_command(SBO_SC, sco(false, true));
    selected.cot = Cot::new(Cause::ACTIVATION).with_originator(1);
    a.send(&selected).await;
    assert!(!a.expect_asdu().await.cot.negative);
    let mut other = single_command(SBO_SC, sco(false, false));
    other.cot = Cot::new(Cause::ACTIVATION).with_originator(2);
    a.send(&other).await;
    let answer = a.expect_asdu().await;
    assert_eq!(answer.cot.originator, 2);
    assert!(answer.cot.negative, "executed with another originator");
}

#[tokio::test]
async fn a_slow_command_outcome_is_still_confirmed_and_does_not_block_the_link() {
    init_logs();
    let (server, _) = command_server(server_config()).await;
    let client = Client::connect(server.local_addr()).await;
    let began = Instant::now();
    let handle = client.handle.clone();
    let slow = tokio::spawn(async move {
        handle
            .command(TypeId::C_SC_NA_1, ioa(SLOW), sco(true, false), None)
            .await
    });
    // Meanwhile other requests are served.
    let read = within(WAIT, "read", client.handle.read(ioa(100)))
        .await
        .unwrap();
    assert!(read.positive);
    let direct = within(
        WAIT,
        "direct",
        client
            .handle
            .command(TypeId::C_SC_NA_1, ioa(DIRECT_SC), sco(true, false), None),
    )
    .await
    .unwrap();
    assert!(direct.positive && direct.terminated);
    assert!(
        began.elapsed() < Duration::from_millis(200),
        "blocked by the slow command"
    );

    let outcome = within(WAIT, "the slow command", slow)
        .await
        .unwrap()
        .unwrap();
    assert!(outcome.positive && outcome.terminated, "{outcome:?}");
    assert!(began.elapsed() >= Duration::from_millis(200));
}

#[tokio::test]
async fn broadcast_address_is_accepted_only_for_station_wide_commands() {
    init_logs();
    let (server, handler) = command_server(server_config()).await;
    let mut client = Client::connect(server.local_addr()).await;
    let broadcast = CommonAddress::broadcast(&params()).get();

    // Interrogation to everybody: one confirmation and one termination with our address.
    let gi = request(
        TypeId::C_IC_NA_1,
        Cause::ACTIVATION,
        broadcast,
        0,
        Element::Interrogation { qualifier: 20 },
    );
    let outcome = client.handle.send(gi).await.unwrap();
    assert!(outcome.positive && outcome.terminated, "{outcome:?}");
    for answer in &outcome.responses {
        assert_eq!(answer.common_address, ca(), "{answer}");
    }
    let asdus = client
        .asdus_until(TypeId::C_IC_NA_1, Cause::ACTIVATION_TERMINATION, WAIT)
        .await;
    assert_eq!(asdus.len(), 3, "ACT_CON, the single point, ACT_TERM");

    // Clock synchronisation to everybody.
    let time = Cp56Time2a::new(26, 1, 2, 3, 4, 5_006).unwrap();
    let sync = request(
        TypeId::C_CS_NA_1,
        Cause::ACTIVATION,
        broadcast,
        0,
        Element::ClockSync { time },
    );
    let outcome = client.handle.send(sync).await.unwrap();
    assert!(outcome.positive);
    assert_eq!(outcome.responses[0].common_address, ca());
    assert_eq!(handler.clock_syncs.lock().unwrap().clone(), vec![time]);

    // A single command to everybody: unknown common address.
    let command = request(
        TypeId::C_SC_NA_1,
        Cause::ACTIVATION,
        broadcast,
        DIRECT_SC,
        sco(true, false),
    );
    let outcome = client.handle.send(command).await.unwrap();
    assert!(!outcome.positive);
    assert_eq!(outcome.cause, Cause::UNKNOWN_COMMON_ADDRESS);
    assert!(handler.commands().is_empty());
}

#[tokio::test]
async fn a_command_with_several_objects_is_refused() {
    init_logs();
    let (server, handler) = command_server(server_config()).await;
    let mut peer = RawPeer::connect_with(server.local_addr(), None, ApciConfig::default()).await;
    peer.start().await;
    let asdu = single_command(DIRECT_SC, sco(true, false))
        .with_object(InformationObject::new(ioa(DIRECT_DC), sco(true, false)));
    peer.send(&asdu).await;
    let answer = peer.expect_asdu().await;
    assert!(answer.cot.negative);
    assert!(handler.commands().is_empty());
}
