//! Arbitrary ASDUs into the outstation core's link, with data transfer starting and
//! stopping, confirmations, clock jumps, point updates and the link dying interleaved.
//! The core must never panic, never overfill the link's window and only ever send ASDUs
//! that decode.
//!
//! The input is a program of op bytes: `00xxxxxx` hands the next 1..=64 bytes to the core
//! as one ASDU (after a valid header template when bit 5 is set, so that the fuzzer
//! reaches commands and interrogations quickly), `01xxxxxx` fills the window, `10xxxxxx`
//! confirms that many ASDUs, `11xxxxxx` starts, stops, advances the clock, updates a
//! point, polls command outcomes or reopens the link.
#![no_main]

use std::collections::VecDeque;
use std::sync::Arc;
use std::task::{Context, Waker};
use std::time::{Duration, Instant};

use iec60870::asdu::{
    AsduHeader, AsduParams, Cause, CommonAddress, Element, Ioa, Quality, TypeId,
};
use iec60870::outstation::{
    ready, Command, CommandFuture, CommandOutcome, CommandPoint, LinkCore, LinkLayer,
    MonitorPoint, Outstation, OutstationConfig, Peer, ProcessImage, RedundancyMode,
    StationHandler,
};
use libfuzzer_sys::fuzz_target;

const PARAMS: AsduParams = AsduParams::IEC104;
const WINDOW: usize = 4;

struct Link {
    unconfirmed: VecDeque<Vec<u8>>,
}

impl LinkLayer for Link {
    fn can_send(&self) -> bool {
        self.unconfirmed.len() < WINDOW
    }
    fn send_asdu(&mut self, _now: Instant, asdu: &[u8]) -> bool {
        assert!(self.unconfirmed.len() < WINDOW, "the core overfilled the window");
        assert!(
            well_formed(asdu),
            "the core sent an ASDU that does not decode: {asdu:02X?}"
        );
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

/// An ASDU that decodes, or a negative mirror of a request the station cannot serve
/// (cause 44..47: unknown type, cause, common address or object address): the standard's
/// answer is the request sent back, which may be as undecodable as the request was.
fn well_formed(asdu: &[u8]) -> bool {
    let Ok(header) = AsduHeader::decode(asdu, &PARAMS) else {
        return false;
    };
    let cause = header.cot.cause;
    let mirror = header.cot.negative
        && [
            Cause::UNKNOWN_TYPE,
            Cause::UNKNOWN_CAUSE,
            Cause::UNKNOWN_COMMON_ADDRESS,
            Cause::UNKNOWN_OBJECT_ADDRESS,
        ]
        .contains(&cause);
    mirror || iec60870::asdu::Asdu::decode(asdu, &PARAMS).is_ok()
}

struct Executes;

impl StationHandler for Executes {
    fn handle_command(&self, command: Command) -> CommandFuture {
        ready(if command.ioa.get() % 2 == 0 {
            CommandOutcome::Executed
        } else {
            CommandOutcome::Refused
        })
    }
}

fn outstation(redundancy: RedundancyMode) -> Arc<Outstation> {
    let mut image = ProcessImage::new();
    let types = [
        TypeId::M_SP_NA_1,
        TypeId::M_DP_TB_1,
        TypeId::M_ME_NB_1,
        TypeId::M_IT_NA_1,
    ];
    for address in 1..=40u32 {
        let event_type = types[address as usize % types.len()];
        let element = match event_type {
            TypeId::M_DP_TB_1 => Element::DoublePoint {
                state: iec60870::asdu::DoublePointState::Off,
                quality: Quality::GOOD,
            },
            TypeId::M_ME_NB_1 => Element::Scaled {
                value: 0,
                quality: Quality::GOOD,
            },
            TypeId::M_IT_NA_1 => Element::IntegratedTotal(Default::default()),
            _ => Element::SinglePoint {
                on: false,
                quality: Quality::GOOD,
            },
        };
        if let Ok(ioa) = Ioa::try_new(address) {
            let _ = image.add_monitor(MonitorPoint {
                ioa,
                event_type,
                groups: (address % 3) as u16,
                element,
                time: None,
            });
        }
    }
    for (address, command_type) in [
        (100u32, TypeId::C_SC_NA_1),
        (101, TypeId::C_DC_NA_1),
        (102, TypeId::C_SE_NB_1),
        (103, TypeId::C_RC_NA_1),
    ] {
        if let Ok(ioa) = Ioa::try_new(address) {
            let _ = image.add_command(CommandPoint {
                ioa,
                command_type,
                select_required: address % 2 == 1,
                max_age: Some(Duration::from_secs(30)),
            });
        }
    }
    let mut config = OutstationConfig::new(CommonAddress::new(1), PARAMS);
    config.redundancy = redundancy;
    config.event_buffer_capacity = 64;
    match Outstation::new(config, image, Arc::new(Executes)) {
        Ok(outstation) => Arc::new(outstation),
        Err(error) => panic!("test outstation: {error}"),
    }
}

fn peer() -> Peer {
    Peer::Serial {
        port: "fuzz".into(),
        link_address: 1,
    }
}

fuzz_target!(|data: &[u8]| {
    let Some((&head, mut rest)) = data.split_first() else {
        return;
    };
    let redundancy = if head & 1 == 0 {
        RedundancyMode::SingleGroup
    } else {
        RedundancyMode::ConnectionIsGroup
    };
    let station = outstation(redundancy);
    let mut now = Instant::now();
    let mut next_id = 1;
    let Some(mut core): Option<LinkCore> = station.open_link(next_id, peer()) else {
        return;
    };
    let mut link = Link {
        unconfirmed: VecDeque::new(),
    };
    let mut context = Context::from_waker(Waker::noop());
    // A header template (type, VSQ 1, COT 6, CA 1): the op's payload follows it.
    let template = [45u8, 1, 6, 0, 1, 0];

    while let Some((&op, tail)) = rest.split_first() {
        rest = tail;
        match op >> 6 {
            0 => {
                let n = (usize::from(op & 0x1F) * 2 + 1).min(rest.len());
                let (payload, tail) = rest.split_at(n);
                rest = tail;
                let asdu = if op & 0x20 != 0 {
                    let mut bytes = template.to_vec();
                    if let Some((&type_byte, body)) = payload.split_first() {
                        bytes[0] = type_byte;
                        bytes.extend_from_slice(body);
                    }
                    bytes
                } else {
                    payload.to_vec()
                };
                core.check_still_active(&mut link);
                core.handle_asdu(now, asdu);
            }
            1 => core.fill(now, &mut link),
            2 => {
                for _ in 0..(op & 0x3F) {
                    link.unconfirmed.pop_front();
                }
                core.acknowledged(&link);
            }
            _ => match op & 0x07 {
                0 => core.start(),
                1 => core.stop(&link),
                2 => now += Duration::from_millis(u64::from(op >> 3 & 0x07) * 4000),
                3 => {
                    let address = u32::from(op >> 3 & 0x07) * 5 + 1;
                    if let Ok(ioa) = Ioa::try_new(address) {
                        let _ = station.update(
                            ioa,
                            Element::SinglePoint {
                                on: op & 0x20 != 0,
                                quality: Quality::GOOD,
                            },
                            None,
                        );
                    }
                }
                4 | 5 => {
                    let _ = core.poll_commands(&mut context);
                }
                _ => {
                    core.close(&link);
                    link.unconfirmed.clear();
                    next_id += 1;
                    match station.open_link(next_id, peer()) {
                        Some(again) => core = again,
                        None => return,
                    }
                }
            },
        }
        let _ = core.close_reason();
    }
    core.close(&link);
});
