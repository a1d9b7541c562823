//! Transmission of disturbance data (IEC 60870-5-103, ASDU 23-31): a fault record's
//! channels and tags, uploaded from the protection device channel by channel.
//!
//! ```text
//! master                                   device
//!   (ASDU 23 list of recorded disturbances, spontaneous after a fault or on TOO 24)
//!   24 TOO 1  select fault FAN        ->   26 ready for disturbance data (NOC, NOE, INT)
//!   24 TOO 2  request data            ->   28 ready for tags
//!   24 TOO 16 request tags            ->   29 tags ... 31 TOO 38 end of tags
//!   25 TOO 68 tags received           ->   27 ready for channel ACC (RPV, RSV, RFA)
//!   24 TOO 8  request channel ACC     ->   30 values ... 31 TOO 35 end of channel
//!   25 TOO 66 channel received        ->   27 next channel ... or 31 TOO 32 end of data
//!   25 TOO 64 data received               (the record's SOF gets TM: transmitted)
//! ```
//!
//! [`DisturbanceSender`] is the device's half, [`DisturbanceReceiver`] the master's; both
//! turn the other's ASDUs into their own, so they run over any link and in tests without
//! one.

use chrono::NaiveDateTime;

use super::asdu::{Asdu, Body, DisturbanceTag, RecordedDisturbance};
use super::cause::Cause;
use crate::time::{Cp32Time2a, Cp56Time2a};

/// Type of order: selection of fault.
pub const TOO_SELECT_FAULT: u8 = 1;
/// Type of order: request for disturbance data.
pub const TOO_REQUEST_DATA: u8 = 2;
/// Type of order: abortion of disturbance data.
pub const TOO_ABORT_DATA: u8 = 3;
/// Type of order: request for channel.
pub const TOO_REQUEST_CHANNEL: u8 = 8;
/// Type of order: request for tags.
pub const TOO_REQUEST_TAGS: u8 = 16;
/// Type of order: request for the list of recorded disturbances.
pub const TOO_REQUEST_LIST: u8 = 24;
/// End of disturbance data transmission without abortion.
pub const TOO_END_OF_DATA: u8 = 32;
/// End of channel transmission without abortion.
pub const TOO_END_OF_CHANNEL: u8 = 35;
/// End of tag transmission without abortion.
pub const TOO_END_OF_TAGS: u8 = 38;
/// Disturbance data transmitted successfully.
pub const TOO_DATA_RECEIVED: u8 = 64;
/// Channel transmitted successfully.
pub const TOO_CHANNEL_RECEIVED: u8 = 66;
/// Tags transmitted successfully.
pub const TOO_TAGS_RECEIVED: u8 = 68;

/// Type of disturbance values: instantaneous values.
pub const TOV_INSTANTANEOUS: u8 = 1;
/// Status of fault bit: the record has been transmitted.
pub const SOF_TRANSMITTED: u8 = 0x02;
/// Status of fault bit: the record holds a trip.
pub const SOF_TRIP: u8 = 0x01;

/// Disturbance values per ASDU 30 (2 octets each, well inside one FT1.2 frame).
const VALUES_PER_ASDU: usize = 100;
/// Tags per ASDU 29 (3 octets each).
const TAGS_PER_ASDU: usize = 60;

/// One analog channel of a record.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordChannel {
    /// Actual channel number (ACC: 1 IL1, 2 IL2, 3 IL3, 4 IN, 5 UL1E, 6 UL2E, 7 UL3E,
    /// 8 UEN by the standard).
    pub acc: u8,
    /// Rated primary value.
    pub rpv: f32,
    /// Rated secondary value.
    pub rsv: f32,
    /// Reference factor: a single disturbance value SDV stands for SDV / RFA in
    /// secondary units, so the primary value is `SDV / RFA * RPV / RSV`.
    pub rfa: f32,
    /// The single disturbance values.
    pub samples: Vec<i16>,
}

impl RecordChannel {
    /// The primary value of a sample.
    pub fn primary(&self, sdv: i16) -> f64 {
        if self.rfa == 0.0 || self.rsv == 0.0 {
            return 0.0;
        }
        f64::from(sdv) / f64::from(self.rfa) * f64::from(self.rpv) / f64::from(self.rsv)
    }

    /// The standard's name of the channel number.
    pub fn name(&self) -> String {
        match self.acc {
            1 => "IL1".to_owned(),
            2 => "IL2".to_owned(),
            3 => "IL3".to_owned(),
            4 => "IN".to_owned(),
            5 => "UL1E".to_owned(),
            6 => "UL2E".to_owned(),
            7 => "UL3E".to_owned(),
            8 => "UEN".to_owned(),
            other => format!("ACC{other}"),
        }
    }

    /// Current (A) or voltage (V), by the standard's channel numbers.
    pub fn unit(&self) -> &'static str {
        match self.acc {
            1..=4 => "A",
            5..=8 => "V",
            _ => "",
        }
    }
}

/// A binary signal's state from a sample position on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RecordTag {
    /// The element number (tag position) it applies from.
    pub position: u16,
    /// The signal and its double point.
    pub tag: DisturbanceTag,
}

/// A disturbance record.
#[derive(Debug, Clone, PartialEq)]
pub struct DisturbanceRecord {
    /// Fault number.
    pub fan: u16,
    /// Status of fault.
    pub sof: u8,
    /// When the fault was recorded (ASDU 23).
    pub recorded_at: NaiveDateTime,
    /// Time of the first element (ASDU 26; the date is the recording's).
    pub first_sample: NaiveDateTime,
    /// Interval between elements in microseconds.
    pub interval_us: u16,
    /// The channels.
    pub channels: Vec<RecordChannel>,
    /// The tags.
    pub tags: Vec<RecordTag>,
}

impl DisturbanceRecord {
    /// Elements per channel (the longest channel's).
    pub fn elements(&self) -> usize {
        self.channels
            .iter()
            .map(|channel| channel.samples.len())
            .max()
            .unwrap_or(0)
    }

    fn list_entry(&self) -> Option<RecordedDisturbance> {
        Some(RecordedDisturbance {
            fan: self.fan,
            sof: self.sof,
            time: Cp56Time2a::from_naive(self.recorded_at).ok()?,
        })
    }
}

fn message(address: u8, fun: u8, type_id: u8, body: Body) -> Asdu {
    Asdu::new(type_id, Cause::DISTURBANCE_DATA, address, fun, 0, body)
}

/// The device's half: answers orders from the records it holds.
#[derive(Debug, Clone, Default)]
pub struct DisturbanceSender {
    records: Vec<DisturbanceRecord>,
    selected: Option<usize>,
    /// The channel being offered or sent (index into the record's channels).
    channel: usize,
}

impl DisturbanceSender {
    /// Records kept at most; the oldest goes.
    pub const CAPACITY: usize = 8;

    /// Keeps a new record; returns the list of recorded disturbances to announce it.
    pub fn record(&mut self, record: DisturbanceRecord, address: u8, fun: u8) -> Asdu {
        if self.records.len() >= Self::CAPACITY {
            self.records.remove(0);
            self.selected = None;
        }
        self.records.push(record);
        self.list(address, fun)
    }

    /// The records held.
    pub fn records(&self) -> &[DisturbanceRecord] {
        &self.records
    }

    fn list(&self, address: u8, fun: u8) -> Asdu {
        let entries = self
            .records
            .iter()
            .filter_map(DisturbanceRecord::list_entry)
            .collect();
        message(address, fun, 23, Body::DisturbanceList(entries))
    }

    /// An order (ASDU 24) or acknowledgement (ASDU 25) from the master; returns the
    /// device's answers, in order.
    pub fn handle(&mut self, asdu: &Asdu, address: u8) -> Vec<Asdu> {
        let fun = asdu.header.fun;
        let (too, fan, acc) = match asdu.body {
            Body::DisturbanceOrder { too, fan, acc, .. }
            | Body::DisturbanceAck { too, fan, acc, .. } => (too, fan, acc),
            _ => return Vec::new(),
        };
        let end = |too: u8, acc: u8| {
            message(
                address,
                fun,
                31,
                Body::EndOfTransmission {
                    too,
                    tov: TOV_INSTANTANEOUS,
                    fan,
                    acc,
                },
            )
        };
        match too {
            TOO_REQUEST_LIST => vec![self.list(address, fun)],
            TOO_SELECT_FAULT => {
                self.selected = self.records.iter().position(|record| record.fan == fan);
                self.channel = 0;
                let Some(record) = self.selected.and_then(|index| self.records.get(index)) else {
                    return vec![end(34, 0)];
                };
                vec![message(
                    address,
                    fun,
                    26,
                    Body::DisturbanceReady {
                        tov: TOV_INSTANTANEOUS,
                        fan,
                        nof: fan,
                        noc: u8::try_from(record.channels.len()).unwrap_or(u8::MAX),
                        noe: u16::try_from(record.elements()).unwrap_or(u16::MAX),
                        int: record.interval_us,
                        time: Cp32Time2a::from_naive(record.first_sample),
                    },
                )]
            }
            TOO_REQUEST_DATA => match self.current() {
                Some(record) if !record.tags.is_empty() => {
                    vec![message(address, fun, 28, Body::TagsReady { fan })]
                }
                Some(_) => self.offer_channel(address, fun, fan),
                None => vec![end(34, 0)],
            },
            TOO_REQUEST_TAGS => {
                let Some(record) = self.current() else {
                    return vec![end(40, 0)];
                };
                // One ASDU 29 per tag position (TAP applies to all its tags), at most
                // TAGS_PER_ASDU tags each.
                let mut answers: Vec<Asdu> = Vec::new();
                let mut tags = record.tags.clone();
                tags.sort_by_key(|tag| tag.position);
                for group in tags.chunk_by(|a, b| a.position == b.position) {
                    for chunk in group.chunks(TAGS_PER_ASDU) {
                        answers.push(message(
                            address,
                            fun,
                            29,
                            Body::Tags {
                                fan,
                                tap: chunk.first().map(|tag| tag.position).unwrap_or(0),
                                tags: chunk.iter().map(|tag| tag.tag).collect(),
                            },
                        ));
                    }
                }
                answers.push(end(TOO_END_OF_TAGS, 0));
                answers
            }
            TOO_TAGS_RECEIVED => self.offer_channel(address, fun, fan),
            TOO_REQUEST_CHANNEL => {
                let Some(channel) = self
                    .current()
                    .and_then(|record| record.channels.iter().find(|channel| channel.acc == acc))
                else {
                    return vec![end(37, acc)];
                };
                let mut answers: Vec<Asdu> = channel
                    .samples
                    .chunks(VALUES_PER_ASDU)
                    .enumerate()
                    .map(|(index, chunk)| {
                        message(
                            address,
                            fun,
                            30,
                            Body::DisturbanceValues {
                                tov: TOV_INSTANTANEOUS,
                                fan,
                                acc,
                                nfe: u16::try_from(index * VALUES_PER_ASDU).unwrap_or(u16::MAX),
                                values: chunk.to_vec(),
                            },
                        )
                    })
                    .collect();
                answers.push(end(TOO_END_OF_CHANNEL, acc));
                answers
            }
            TOO_CHANNEL_RECEIVED => {
                self.channel += 1;
                self.offer_channel(address, fun, fan)
            }
            TOO_DATA_RECEIVED => {
                if let Some(record) = self.selected.and_then(|index| self.records.get_mut(index)) {
                    record.sof |= SOF_TRANSMITTED;
                }
                self.selected = None;
                Vec::new()
            }
            TOO_ABORT_DATA => {
                self.selected = None;
                vec![end(33, 0)]
            }
            _ => Vec::new(),
        }
    }

    fn current(&self) -> Option<&DisturbanceRecord> {
        self.selected.and_then(|index| self.records.get(index))
    }

    /// The next channel's "ready", or the end of the data after the last.
    fn offer_channel(&self, address: u8, fun: u8, fan: u16) -> Vec<Asdu> {
        match self
            .current()
            .and_then(|record| record.channels.get(self.channel))
        {
            Some(channel) => vec![message(
                address,
                fun,
                27,
                Body::ChannelReady {
                    tov: TOV_INSTANTANEOUS,
                    fan,
                    acc: channel.acc,
                    rpv: channel.rpv,
                    rsv: channel.rsv,
                    rfa: channel.rfa,
                },
            )],
            None => vec![message(
                address,
                fun,
                31,
                Body::EndOfTransmission {
                    too: TOO_END_OF_DATA,
                    tov: TOV_INSTANTANEOUS,
                    fan,
                    acc: 0,
                },
            )],
        }
    }
}

/// What the master's half wants done after an ASDU.
#[derive(Debug, Clone, PartialEq)]
pub enum ReceiverStep {
    /// Nothing (the ASDU was not about disturbance data, or more is coming).
    Wait,
    /// Send this order or acknowledgement to the device.
    Send(Asdu),
    /// The record is complete (after this acknowledgement to send).
    Complete(Box<DisturbanceRecord>, Asdu),
}

/// The master's half for one device: uploads the records it announces.
#[derive(Debug, Clone, Default)]
pub struct DisturbanceReceiver {
    uploading: Option<DisturbanceRecord>,
    /// Faults announced and not yet uploaded (FAN, recorded at).
    pending: Vec<(u16, NaiveDateTime)>,
    done: Vec<u16>,
}

impl DisturbanceReceiver {
    /// Handles an ASDU from the device; `reference` completes CP32 time tags.
    pub fn handle(&mut self, asdu: &Asdu, reference: NaiveDateTime) -> ReceiverStep {
        let address = asdu.header.common_address;
        let fun = asdu.header.fun;
        let order = |too: u8, fan: u16, acc: u8| {
            Asdu::new(
                24,
                Cause::DISTURBANCE_DATA,
                address,
                fun,
                0,
                Body::DisturbanceOrder {
                    too,
                    tov: TOV_INSTANTANEOUS,
                    fan,
                    acc,
                },
            )
        };
        let ack = |too: u8, fan: u16, acc: u8| {
            Asdu::new(
                25,
                Cause::DISTURBANCE_DATA,
                address,
                fun,
                0,
                Body::DisturbanceAck {
                    too,
                    tov: TOV_INSTANTANEOUS,
                    fan,
                    acc,
                },
            )
        };
        match &asdu.body {
            Body::DisturbanceList(entries) => {
                for entry in entries {
                    let known = self.done.contains(&entry.fan)
                        || self.pending.iter().any(|(fan, _)| *fan == entry.fan);
                    if entry.sof & SOF_TRANSMITTED == 0 && !known {
                        let at = entry.time.to_naive().unwrap_or(reference);
                        self.pending.push((entry.fan, at));
                    }
                }
                self.start_next(order)
            }
            Body::DisturbanceReady {
                fan,
                noc,
                int,
                time,
                ..
            } => {
                let Some(record) = self.uploading.as_mut().filter(|record| record.fan == *fan)
                else {
                    return ReceiverStep::Wait;
                };
                record.interval_us = *int;
                record.first_sample = time
                    .resolve(record.recorded_at)
                    .unwrap_or(record.recorded_at);
                record.channels.reserve(usize::from(*noc));
                ReceiverStep::Send(order(TOO_REQUEST_DATA, *fan, 0))
            }
            Body::TagsReady { fan } => ReceiverStep::Send(order(TOO_REQUEST_TAGS, *fan, 0)),
            Body::Tags { tap, tags, .. } => {
                if let Some(record) = self.uploading.as_mut() {
                    record.tags.extend(tags.iter().map(|tag| RecordTag {
                        position: *tap,
                        tag: *tag,
                    }));
                }
                ReceiverStep::Wait
            }
            Body::ChannelReady {
                fan,
                acc,
                rpv,
                rsv,
                rfa,
                ..
            } => {
                if let Some(record) = self.uploading.as_mut() {
                    record.channels.push(RecordChannel {
                        acc: *acc,
                        rpv: *rpv,
                        rsv: *rsv,
                        rfa: *rfa,
                        samples: Vec::new(),
                    });
                }
                ReceiverStep::Send(order(TOO_REQUEST_CHANNEL, *fan, *acc))
            }
            Body::DisturbanceValues {
                acc, nfe, values, ..
            } => {
                if let Some(channel) = self.uploading.as_mut().and_then(|record| {
                    record
                        .channels
                        .iter_mut()
                        .find(|channel| channel.acc == *acc)
                }) {
                    let start = usize::from(*nfe);
                    if channel.samples.len() < start {
                        channel.samples.resize(start, 0);
                    }
                    channel.samples.truncate(start);
                    channel.samples.extend_from_slice(values);
                }
                ReceiverStep::Wait
            }
            Body::EndOfTransmission { too, fan, acc, .. } => match *too {
                TOO_END_OF_TAGS => ReceiverStep::Send(ack(TOO_TAGS_RECEIVED, *fan, 0)),
                TOO_END_OF_CHANNEL => ReceiverStep::Send(ack(TOO_CHANNEL_RECEIVED, *fan, *acc)),
                TOO_END_OF_DATA => match self.uploading.take() {
                    Some(record) => {
                        self.done.push(record.fan);
                        ReceiverStep::Complete(Box::new(record), ack(TOO_DATA_RECEIVED, *fan, 0))
                    }
                    None => ReceiverStep::Wait,
                },
                _ => {
                    // Aborted by the device: forget this one, go on with the next.
                    if let Some(record) = self.uploading.take() {
                        self.done.push(record.fan);
                    }
                    self.start_next(order)
                }
            },
            _ => ReceiverStep::Wait,
        }
    }

    /// Whether an upload is running.
    pub fn is_busy(&self) -> bool {
        self.uploading.is_some()
    }

    fn start_next(&mut self, order: impl Fn(u8, u16, u8) -> Asdu) -> ReceiverStep {
        if self.uploading.is_some() || self.pending.is_empty() {
            return ReceiverStep::Wait;
        }
        let (fan, recorded_at) = self.pending.remove(0);
        self.uploading = Some(DisturbanceRecord {
            fan,
            sof: 0,
            recorded_at,
            first_sample: recorded_at,
            interval_us: 0,
            channels: Vec::new(),
            tags: Vec::new(),
        });
        ReceiverStep::Send(order(TOO_SELECT_FAULT, fan, 0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::iec103::Direction;

    fn record() -> DisturbanceRecord {
        let at = chrono::NaiveDate::from_ymd_opt(2017, 4, 26)
            .unwrap()
            .and_hms_milli_opt(9, 59, 30, 424)
            .unwrap();
        DisturbanceRecord {
            fan: 7,
            sof: SOF_TRIP,
            recorded_at: at,
            first_sample: at,
            interval_us: 1000,
            channels: (1..=4)
                .map(|acc| RecordChannel {
                    acc,
                    rpv: 100.0,
                    rsv: 1.0,
                    rfa: 1000.0,
                    samples: (0..250)
                        .map(|n| i16::try_from(n * i32::from(acc)).unwrap())
                        .collect(),
                })
                .collect(),
            tags: vec![
                RecordTag {
                    position: 104,
                    tag: DisturbanceTag {
                        fun: 160,
                        inf: 92,
                        dpi: 2,
                    },
                },
                RecordTag {
                    position: 180,
                    tag: DisturbanceTag {
                        fun: 1,
                        inf: 160,
                        dpi: 1,
                    },
                },
                RecordTag {
                    position: 180,
                    tag: DisturbanceTag {
                        fun: 160,
                        inf: 92,
                        dpi: 1,
                    },
                },
            ],
        }
    }

    /// The whole exchange between the two halves, every ASDU through the codec.
    #[test]
    fn a_record_goes_from_device_to_master_unchanged() {
        let mut sender = DisturbanceSender::default();
        let mut receiver = DisturbanceReceiver::default();
        let original = record();
        let reference = original.recorded_at + chrono::Duration::seconds(5);
        let mut to_master = vec![sender.record(original.clone(), 1, 160)];
        let mut uploaded = None;
        for _ in 0..1000 {
            let Some(asdu) = to_master.first().cloned() else {
                break;
            };
            to_master.remove(0);
            let bytes = asdu.to_bytes().unwrap();
            let asdu = Asdu::decode(&bytes, Direction::Monitor).unwrap();
            let reply = match receiver.handle(&asdu, reference) {
                ReceiverStep::Wait => continue,
                ReceiverStep::Send(reply) => reply,
                ReceiverStep::Complete(record, reply) => {
                    uploaded = Some(*record);
                    reply
                }
            };
            let bytes = reply.to_bytes().unwrap();
            let reply = Asdu::decode(&bytes, Direction::Control).unwrap();
            to_master.extend(sender.handle(&reply, 1));
        }
        let uploaded = uploaded.expect("the record arrived");
        assert_eq!(uploaded.fan, 7);
        assert_eq!(uploaded.interval_us, 1000);
        assert_eq!(uploaded.first_sample, original.first_sample);
        assert_eq!(uploaded.channels, original.channels);
        assert_eq!(uploaded.tags, original.tags);
        assert_eq!(sender.records()[0].sof & SOF_TRANSMITTED, SOF_TRANSMITTED);
        assert!((uploaded.channels[0].primary(1000) - 100.0).abs() < 1e-9);
        // Announced again, a transmitted record is not uploaded twice.
        let list = sender.handle(
            &Asdu::new(
                24,
                Cause::DISTURBANCE_DATA,
                1,
                160,
                0,
                Body::DisturbanceOrder {
                    too: TOO_REQUEST_LIST,
                    tov: 0,
                    fan: 0,
                    acc: 0,
                },
            ),
            1,
        );
        assert_eq!(receiver.handle(&list[0], reference), ReceiverStep::Wait);
    }
}
