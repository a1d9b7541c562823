//! The simulated REF630 against the IEC 103 master of the protocol crate: the link-layer
//! frames of the thesis's session octet for octet, and the master reading and commanding
//! the relay over a real pseudo-terminal pair.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

use simulators::ref630::{Device, DeviceProfile};

mod over_a_pseudo_terminal {
    //! The 103 master against the REF630 device over a real pseudo-terminal pair: the
    //! thesis's PCVDEW6 session (spec §6) and a command refused in LOCAL, executed in
    //! REMOTE.

    use std::ops::ControlFlow;
    use std::time::Duration;

    use iec60870::ft12::io::{drive, EndpointAction, Transport};
    use iec60870::ft12::{
        LineSettings, Parity, Primary, PrimaryConfig, Secondary, SecondaryConfig, SecondaryStation,
    };
    use iec60870::iec103::*;
    use simulators::ref630::{Device, DeviceProfile};
    use tokio::sync::mpsc;

    type Relay = SecondaryStation<Device>;

    fn wall_clock() -> chrono::NaiveDateTime {
        chrono::NaiveDate::from_ymd_opt(2017, 4, 7)
            .unwrap()
            .and_hms_milli_opt(15, 43, 0, 870)
            .unwrap()
    }

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn master_reads_and_commands_the_ref630() {
        // A pseudo-terminal keeps no parity: 8N1, or the port refuses FT1.2's 8E1.
        let line = LineSettings {
            parity: Parity::None,
            ..LineSettings::new(9600)
        };
        let relay_line = Transport::Pty.open().await.unwrap();
        let path = relay_line.pty_path.clone().unwrap();
        let (relay_actions, mut relay_inbox) = mpsc::unbounded_channel::<EndpointAction<Relay>>();
        let relay = tokio::spawn(async move {
            let now = tokio::time::Instant::now().into_std();
            let mut profile = DeviceProfile::ref630(1);
            profile.cycle = Duration::from_millis(300);
            let device = Device::new(profile, now, wall_clock());
            let mut station =
                SecondaryStation::new(line, Secondary::new(SecondaryConfig::new(1)), device);
            let _ = drive(relay_line.stream, &mut station, &mut relay_inbox, |_| {
                ControlFlow::Continue(())
            })
            .await;
        });

        let now = tokio::time::Instant::now().into_std();
        let mut primary = Primary::new(
            PrimaryConfig {
                line,
                response_timeout: Duration::from_millis(500),
                poll_interval: Duration::from_millis(50),
                ..PrimaryConfig::default()
            },
            now,
        );
        primary.add_station(1).unwrap();
        let mut master = Master::new(
            primary,
            StartUp {
                clock_sync: false,
                interrogate: true,
                disturbances: true,
            },
            Box::new(wall_clock),
            now,
        );
        master.set_command_timeout(Duration::from_secs(5));
        let master_line = Transport::Serial { path, line }.open().await.unwrap();
        let (_keep, mut inbox) = mpsc::unbounded_channel::<EndpointAction<Master>>();
        let mut received: Vec<Asdu> = Vec::new();
        let mut results = Vec::new();
        let mut records: Vec<Box<DisturbanceRecord>> = Vec::new();
        let mut phase = 0;
        let run = drive(master_line.stream, &mut master, &mut inbox, |master| {
            while let Some(event) = master.poll_event() {
                match event {
                    MasterEvent::Asdu { asdu, .. } => received.push(asdu),
                    MasterEvent::CommandResult {
                        positive,
                        timed_out,
                        ..
                    } => results.push((positive, timed_out)),
                    MasterEvent::Disturbance { record, .. } => records.push(record),
                    _ => {}
                }
            }
            let gi_done = received.iter().any(|asdu| asdu.header.type_id == 8);
            let measured = |received: &[Asdu], rated: bool| {
                received.iter().any(|asdu| match &asdu.body {
                    Body::Measurands(values) if asdu.header.type_id == 9 => {
                        let il1 = values[0].to_physical(2.4);
                        if rated {
                            (il1 - 1.0).abs() < 0.01
                        } else {
                            il1 == 0.0
                        }
                    }
                    _ => false,
                })
            };
            match phase {
                0 if gi_done && measured(&received, false) => {
                    // Rated current and voltage injected (the FREJA300 of step 7).
                    let _ = relay_actions.send(Box::new(|relay: &mut Relay| {
                        relay
                            .app()
                            .inject_rated_multiples(&[1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0]);
                        relay.app().set_local(true);
                    }));
                    phase = 1;
                }
                1 if measured(&received, true)
                    && received.iter().any(|asdu| {
                        asdu.header.inf == 190 && asdu.header.cause == Cause::LOCAL_OPERATION
                    }) =>
                {
                    master.general_command(1, 1, 160, false).unwrap();
                    phase = 2;
                }
                2 if results.len() == 1 => {
                    let _ = relay_actions
                        .send(Box::new(|relay: &mut Relay| relay.app().set_local(false)));
                    phase = 3;
                }
                3 if received.iter().any(|asdu| {
                    asdu.header.inf == 190 && matches!(asdu.body, Body::TimeTagged { dpi: 1, .. })
                }) =>
                {
                    master.general_command(1, 1, 160, false).unwrap();
                    phase = 4;
                }
                4 if received.iter().any(|asdu| {
                    asdu.header.inf == 160 && asdu.header.cause == Cause::REMOTE_OPERATION
                }) =>
                {
                    let _ = relay_actions.send(Box::new(|relay: &mut Relay| {
                        relay.app().earth_fault();
                    }));
                    phase = 5;
                }
                5 if records.len() == 1 => return ControlFlow::Break(()),
                _ => {}
            }
            ControlFlow::Continue(())
        });
        tokio::time::timeout(Duration::from_secs(60), run)
            .await
            .expect("the session within 60 s")
            .unwrap();
        relay.abort();

        // Polls 1-2: identification after reset CU, then the power-on start-up.
        let identification: Vec<(u8, Cause, String)> = received
            .iter()
            .filter(|asdu| asdu.header.type_id == 5)
            .map(|asdu| {
                (
                    asdu.header.inf,
                    asdu.header.cause,
                    asdu.identification_text().unwrap(),
                )
            })
            .collect();
        assert_eq!(
            identification,
            vec![
                (3, Cause::RESET_CU, "REF630 11.3.".to_owned()),
                (5, Cause::POWER_ON, "REF630 11.3.".to_owned())
            ]
        );
        // Polls 3-6: truck TEST off, SERVICE on, breaker on, earth switch off, IV set.
        let gi: Vec<(u8, u8, u8, bool)> = received
            .iter()
            .filter(|asdu| asdu.header.cause == Cause::GENERAL_INTERROGATION)
            .filter_map(|asdu| match asdu.body {
                Body::TimeTagged { dpi, time, .. } => {
                    Some((asdu.header.fun, asdu.header.inf, dpi, time.is_invalid()))
                }
                _ => None,
            })
            .collect();
        assert_eq!(
            gi,
            vec![
                (5, 9, 1, true),
                (5, 10, 2, true),
                (1, 160, 2, true),
                (1, 168, 1, true),
                (1, 190, 1, true)
            ]
        );
        assert_eq!(
            results,
            vec![(false, false), (true, false)],
            "refused in LOCAL, executed in REMOTE"
        );
        let breaker_open = received
            .iter()
            .find(|asdu| asdu.header.inf == 160 && asdu.header.cause == Cause::REMOTE_OPERATION)
            .unwrap();
        assert!(matches!(breaker_open.body, Body::TimeTagged { dpi: 1, .. }));

        // The earth fault's record, uploaded: four channels of 300 samples at 1 kHz, the
        // fault current five times rated in L1, the trip and the breaker's opening tagged.
        let record = &records[0];
        assert_eq!(record.fan, 1);
        assert_eq!(record.interval_us, 1000);
        assert_eq!(record.channels.len(), 4);
        assert!(record
            .channels
            .iter()
            .all(|channel| channel.samples.len() == 300));
        let peak = |acc: u8, range: std::ops::Range<usize>| {
            let channel = record
                .channels
                .iter()
                .find(|channel| channel.acc == acc)
                .unwrap();
            channel.samples[range]
                .iter()
                .map(|sdv| channel.primary(*sdv).abs())
                .fold(0.0, f64::max)
        };
        assert!(
            (peak(1, 120..200) - 500.0 * 2f64.sqrt()).abs() < 10.0,
            "fault current peak"
        );
        assert!(peak(1, 230..300) < 1.0, "breaker open");
        assert!(record
            .tags
            .iter()
            .any(|tag| tag.tag.fun == 160 && tag.tag.inf == 92 && tag.tag.dpi == 2));
        assert!(record
            .tags
            .iter()
            .any(|tag| tag.tag.inf == 160 && tag.tag.dpi == 1));
    }
}

/// The link-layer frames of the spec's session (§6, derived frames for link address 1),
/// octet for octet, against the REF630 device behind an FT1.2 secondary.
#[test]
fn the_sessions_frames_octet_for_octet() {
    use iec60870::ft12::{AddressSize, Deframer, Frame, Secondary, SecondaryConfig};
    let now = std::time::Instant::now();
    let time = chrono::NaiveDate::from_ymd_opt(2017, 4, 7)
        .unwrap()
        .and_hms_opt(8, 28, 32)
        .unwrap();
    let mut device = Device::new(DeviceProfile::ref630(1), now, time);
    iec60870::ft12::TimedApplication::handle_timeout(&mut device, now);
    let mut secondary = Secondary::new(SecondaryConfig::new(1));
    let mut exchange = |request: &[u8]| -> Vec<u8> {
        let mut deframer = Deframer::new(AddressSize::One);
        deframer.push(request);
        let frame: Frame = deframer.next_frame().unwrap().unwrap();
        secondary
            .handle(&frame, &mut device)
            .map(|answer| answer.to_bytes(AddressSize::One).unwrap())
            .unwrap_or_default()
    };
    // Reset remote link: ACK with ACD (the identification waits in class 1).
    assert_eq!(
        exchange(&[0x10, 0x40, 0x01, 0x41, 0x16]),
        [0x10, 0x20, 0x01, 0x21, 0x16]
    );
    // Request link status: status of link, ACD still set.
    assert_eq!(
        exchange(&[0x10, 0x49, 0x01, 0x4A, 0x16]),
        [0x10, 0x2B, 0x01, 0x2C, 0x16]
    );
    // Class 2, FCB 1: the measurands of the start-up cycle, nothing injected.
    let mut measurands = vec![
        0x68, 0x1A, 0x1A, 0x68, 0x28, 0x01, 0x09, 0x09, 0x02, 0x01, 0x01, 0x94,
    ];
    measurands.extend_from_slice(&[0; 18]);
    let sum = measurands[4..]
        .iter()
        .fold(0u8, |sum, octet| sum.wrapping_add(*octet));
    measurands.extend_from_slice(&[sum, 0x16]);
    assert_eq!(exchange(&[0x10, 0x7B, 0x01, 0x7C, 0x16]), measurands);
    // Class 2, FCB 0, before the next cycle: no data (ACD set).
    assert_eq!(
        exchange(&[0x10, 0x5B, 0x01, 0x5C, 0x16]),
        [0x10, 0x29, 0x01, 0x2A, 0x16]
    );
    // The same frame again (our answer lost): the same answer, not a new poll.
    assert_eq!(
        exchange(&[0x10, 0x5B, 0x01, 0x5C, 0x16]),
        [0x10, 0x29, 0x01, 0x2A, 0x16]
    );
    // Class 1, FCB 1: identification after reset CU, ACD set (power on follows).
    let mut identification = vec![
        0x68, 0x15, 0x15, 0x68, 0x28, 0x01, 0x05, 0x81, 0x04, 0x01, 0xA0, 0x03, 0x02,
    ];
    identification.extend_from_slice(b"REF630 11.3.");
    let sum = identification[4..]
        .iter()
        .fold(0u8, |sum, octet| sum.wrapping_add(*octet));
    identification.extend_from_slice(&[sum, 0x16]);
    assert_eq!(exchange(&[0x10, 0x7A, 0x01, 0x7B, 0x16]), identification);
    // Class 1, FCB 0: power on, then nothing waits (ACD clear).
    let power_on = exchange(&[0x10, 0x5A, 0x01, 0x5B, 0x16]);
    assert_eq!(
        &power_on[..13],
        [0x68, 0x15, 0x15, 0x68, 0x08, 0x01, 0x05, 0x81, 0x06, 0x01, 0xA0, 0x05, 0x02]
    );
    // Class 1, FCB 1: no data, fixed frame 10 09 01 0A 16 of the spec.
    assert_eq!(
        exchange(&[0x10, 0x7A, 0x01, 0x7B, 0x16]),
        [0x10, 0x09, 0x01, 0x0A, 0x16]
    );
    // Reset FCB: ACK with ACD (the identification with COT 3 waits).
    assert_eq!(
        exchange(&[0x10, 0x47, 0x01, 0x48, 0x16]),
        [0x10, 0x20, 0x01, 0x21, 0x16]
    );
}
