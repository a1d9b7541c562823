//! IEC 101 master against IEC 101 slave over a real pseudo-terminal pair, with the
//! line's own field sizes (COT 1, CA 1, IOA 2): start-up with clock sync and station
//! interrogation, a spontaneous change, a select/execute command with its confirmation
//! and termination, and the events kept while nobody polls.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

use std::ops::ControlFlow;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use iec60870::asdu::{
    Asdu, AsduParams, Cause, CommandQualifier, CommonAddress, Element, InformationObject, Ioa,
    Quality, TypeId,
};
use iec60870::ft12::io::{drive, EndpointAction, Transport};
use iec60870::ft12::{
    Balanced, BalancedConfig, LineSettings, Parity, Primary, PrimaryConfig, Secondary,
    SecondaryConfig, SecondaryStation,
};
use iec60870::iec101::{BalancedSlave, Master, MasterEvent, Slave, StartUp};
use iec60870::outstation::{
    ready, Command, CommandFuture, CommandOutcome, CommandPoint, MonitorPoint, Outstation,
    OutstationConfig, Peer, ProcessImage, StationHandler,
};
use tokio::sync::mpsc;

const PARAMS: AsduParams = AsduParams::IEC101_DEFAULT;

#[derive(Default)]
struct Handler {
    commands: Mutex<Vec<Command>>,
}

impl StationHandler for Handler {
    fn handle_command(&self, command: Command) -> CommandFuture {
        self.commands.lock().unwrap().push(command);
        ready(CommandOutcome::Executed)
    }
}

fn ioa(value: u32) -> Ioa {
    Ioa::try_new(value).unwrap()
}

fn outstation() -> (Arc<Outstation>, Arc<Handler>) {
    let mut image = ProcessImage::new();
    for address in 1..=20 {
        image
            .add_monitor(MonitorPoint {
                ioa: ioa(address),
                event_type: TypeId::M_SP_TB_1,
                groups: 0,
                element: Element::SinglePoint {
                    on: address % 2 == 0,
                    quality: Quality::GOOD,
                },
                time: None,
            })
            .unwrap();
    }
    image
        .add_command(CommandPoint {
            ioa: ioa(4150),
            command_type: TypeId::C_SC_NA_1,
            select_required: true,
            max_age: None,
        })
        .unwrap();
    let mut config = OutstationConfig::new(CommonAddress::new(7), PARAMS);
    config.send_end_of_initialisation = true;
    let handler = Arc::new(Handler::default());
    let outstation = Arc::new(Outstation::new(config, image, handler.clone()).unwrap());
    (outstation, handler)
}

fn command(select: bool) -> Vec<u8> {
    let qualifier = if select {
        CommandQualifier::SELECT
    } else {
        CommandQualifier::EXECUTE
    };
    let mut asdu = Asdu::new(TypeId::C_SC_NA_1, Cause::ACTIVATION, CommonAddress::new(7));
    asdu.objects.push(InformationObject::new(
        ioa(4150),
        Element::SingleCommand {
            on: true,
            qualifier,
        },
    ));
    asdu.to_bytes(&PARAMS).unwrap()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn master_and_slave_over_a_pseudo_terminal() {
    master_and_slave(false).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn balanced_master_and_slave_over_a_pseudo_terminal() {
    master_and_slave(true).await;
}

fn balanced_config(dir: bool) -> BalancedConfig {
    BalancedConfig {
        line: LineSettings::new(9600),
        response_timeout: Duration::from_millis(300),
        ..BalancedConfig::new(3, dir)
    }
}

async fn master_and_slave(balanced: bool) {
    let (outstation, handler) = outstation();
    let slave_line = Transport::Pty.open().await.expect("a pty pair");
    let path = slave_line.pty_path.clone().unwrap();
    // A pseudo-terminal keeps no parity: 8N1, or the port refuses FT1.2's 8E1.
    let line = LineSettings {
        parity: Parity::None,
        ..LineSettings::new(9600)
    };
    let slave_outstation = outstation.clone();
    let slave = tokio::spawn(async move {
        let now = tokio::time::Instant::now().into_std();
        let peer = Peer::Serial {
            port: "pty".into(),
            link_address: 3,
        };
        if balanced {
            let (_keep, mut actions) = mpsc::unbounded_channel();
            let link = Balanced::new(balanced_config(false), now);
            let mut station = BalancedSlave::new(&slave_outstation, 1, peer, link).unwrap();
            let _ = drive(slave_line.stream, &mut station, &mut actions, |_| {
                ControlFlow::Continue(())
            })
            .await;
            return;
        }
        let (_keep, mut actions) = mpsc::unbounded_channel();
        let slave = Slave::new(&slave_outstation, 1, peer, now).unwrap();
        let mut station =
            SecondaryStation::new(line, Secondary::new(SecondaryConfig::new(3)), slave);
        let _ = drive(slave_line.stream, &mut station, &mut actions, |_| {
            ControlFlow::Continue(())
        })
        .await;
    });

    let start_up = StartUp {
        clock_sync: true,
        interrogate: true,
        originator: 0,
    };
    let clock: iec60870::iec101::Clock = Box::new(|| {
        chrono::NaiveDate::from_ymd_opt(2026, 11, 24)
            .unwrap()
            .and_hms_opt(1, 2, 3)
            .unwrap()
    });
    let now = tokio::time::Instant::now().into_std();
    let mut master = if balanced {
        let link = Balanced::new(balanced_config(true), now);
        Master::balanced(link, 3, CommonAddress::new(7), PARAMS, start_up, clock)
    } else {
        let primary = Primary::new(
            PrimaryConfig {
                line,
                response_timeout: Duration::from_millis(300),
                poll_interval: Duration::from_millis(50),
                ..PrimaryConfig::default()
            },
            now,
        );
        let mut master = Master::new(primary, PARAMS, start_up, clock);
        master.add_station(3, CommonAddress::new(7)).unwrap();
        master
    };
    let master_line = Transport::Serial { path, line }.open().await.unwrap();
    let (actions_tx, mut actions) = mpsc::unbounded_channel::<EndpointAction<Master>>();
    let mut received: Vec<Asdu> = Vec::new();
    let mut phase = 0;
    let changer = outstation.clone();
    let result = tokio::time::timeout(
        Duration::from_secs(60),
        drive(master_line.stream, &mut master, &mut actions, |master| {
            while let Some(event) = master.poll_event() {
                if let MasterEvent::Asdu { asdu, .. } = event {
                    received.push(Asdu::decode(&asdu, &PARAMS).unwrap());
                }
            }
            let has = |received: &[Asdu], type_id: TypeId, cause: Cause| {
                received
                    .iter()
                    .any(|asdu| asdu.type_id == type_id && asdu.cot.cause == cause)
            };
            match phase {
                // Start-up: end of initialisation, clock sync confirmed, interrogation
                // confirmed, answered and terminated.
                0 if has(&received, TypeId::C_IC_NA_1, Cause::ACTIVATION_TERMINATION) => {
                    changer
                        .update(
                            ioa(5),
                            Element::SinglePoint {
                                on: true,
                                quality: Quality::GOOD,
                            },
                            None,
                        )
                        .unwrap();
                    phase = 1;
                }
                1 if has(&received, TypeId::M_SP_TB_1, Cause::SPONTANEOUS) => {
                    master.send(3, command(true)).unwrap();
                    phase = 2;
                }
                2 if has(&received, TypeId::C_SC_NA_1, Cause::ACTIVATION_CON) => {
                    master.send(3, command(false)).unwrap();
                    phase = 3;
                }
                3 if has(&received, TypeId::C_SC_NA_1, Cause::ACTIVATION_TERMINATION) => {
                    return ControlFlow::Break(());
                }
                _ => {}
            }
            ControlFlow::Continue(())
        }),
    )
    .await;
    drop(actions_tx);
    result.expect("the whole sequence within 60 s").unwrap();
    let types: Vec<(TypeId, Cause)> = received
        .iter()
        .map(|asdu| (asdu.type_id, asdu.cot.cause))
        .collect();
    // Polled, the end of initialisation is the first thing the master can get. Balanced,
    // both ends start at once and the master's clock sync may be answered first.
    let end_of_initialisation = (TypeId::M_EI_NA_1, Cause::INITIALISED);
    if balanced {
        assert!(types.contains(&end_of_initialisation), "{types:?}");
    } else {
        assert_eq!(types.first(), Some(&end_of_initialisation), "{types:?}");
    }
    assert!(
        types.contains(&(TypeId::C_CS_NA_1, Cause::ACTIVATION_CON)),
        "{types:?}"
    );
    let interrogated: usize = received
        .iter()
        .filter(|asdu| asdu.cot.cause == Cause::INTERROGATED_BY_STATION)
        .map(|asdu| asdu.objects.len())
        .sum();
    assert_eq!(interrogated, 20, "every point once in the interrogation");
    let spontaneous = received
        .iter()
        .find(|asdu| asdu.cot.cause == Cause::SPONTANEOUS)
        .unwrap();
    assert_eq!(spontaneous.objects[0].ioa.get(), 5);
    assert!(
        spontaneous.objects[0].time.is_some(),
        "time-tagged event type"
    );
    let confirmations: Vec<Cause> = received
        .iter()
        .filter(|asdu| asdu.type_id == TypeId::C_SC_NA_1)
        .map(|asdu| asdu.cot.cause)
        .collect();
    assert_eq!(
        confirmations,
        vec![
            Cause::ACTIVATION_CON,
            Cause::ACTIVATION_CON,
            Cause::ACTIVATION_TERMINATION
        ]
    );
    let commands = handler.commands.lock().unwrap();
    assert_eq!(commands.len(), 2, "select, then execute");
    assert!(commands[0].select && !commands[1].select);
    slave.abort();
}
