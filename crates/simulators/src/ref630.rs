//! A simulated protection relay's IEC 103 side, sans-IO: what a relay answers on its
//! serial port, with its measurands, indications, commands, faults and the relay
//! tester's console ([`Device::operate`]). The relay simulator of `stanice iec103 relay`
//! and the gateway's simulated devices (`simulate = "ref630"`) are this with a
//! [`DeviceProfile`] (the REF630 of the thesis: [`DeviceProfile::ref630`]). It speaks the
//! protocol through the `iec60870` crate (the FT1.2 secondary's `SecondaryApplication`),
//! which holds no simulator.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use chrono::NaiveDateTime;

use iec60870::ft12::{PrimaryFunction, SecondaryApplication, TimedApplication};
use iec60870::iec103::{
    Asdu, Body, Cause, Direction, DisturbanceRecord, DisturbanceSender, Measurand, RecordChannel,
    RecordTag, FUN_GLOBAL, INF_POWER_ON, INF_RESET_CU, INF_RESET_FCB, INF_START_RESTART, SOF_TRIP,
};
use iec60870::time::{Cp32Time2a, Cp56Time2a};

/// Class 1 messages kept at most; beyond, the oldest is dropped (and counted) and DFC
/// is reported from three quarters on.
const CLASS1_CAPACITY: usize = 512;

/// A double-point indication of the device (position, state, protection signal).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Indication {
    /// Function type.
    pub fun: u8,
    /// Information number.
    pub inf: u8,
    /// What it is, for logs.
    pub name: String,
    /// Reported in a general interrogation.
    pub in_gi: bool,
    /// The double point at start: 1 OFF, 2 ON.
    pub initial: u8,
}

/// One value of the cyclic measurand set.
#[derive(Debug, Clone, PartialEq)]
pub struct MeasurandChannel {
    /// What it is (`IL1`, `UL1`, `P`, `f`).
    pub name: String,
    /// The rated value in engineering units.
    pub rated: f64,
    /// The limit as a multiple of the rated value (2.4 currents, 1.2 voltages); the
    /// element carries the value as a fraction of `rated * limit_factor`.
    pub limit_factor: f64,
    /// The unit, for logs.
    pub unit: String,
}

impl MeasurandChannel {
    /// The value at fraction 1.0.
    pub fn limit(&self) -> f64 {
        self.rated * self.limit_factor
    }
}

/// A command the device executes: a general command on (FUN, INF) that moves the
/// indication of the same FUN/INF.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CommandPoint {
    /// Function type.
    pub fun: u8,
    /// Information number (the position indication's too).
    pub inf: u8,
    /// From the command to the new position.
    pub operate_time: Duration,
}

/// What a device is: addresses, identity, signals and their numbers.
#[derive(Debug, Clone, PartialEq)]
pub struct DeviceProfile {
    /// Link address and common address of ASDU.
    pub address: u8,
    /// The device's function type (identification and protection signals).
    pub function_type: u8,
    /// Compatibility level of the identification.
    pub compatibility_level: u8,
    /// Twelve characters: 8 of manufacturer text and 4 of software identification.
    pub identification: [u8; 12],
    /// The indications.
    pub indications: Vec<Indication>,
    /// FUN and INF of the measurand set (ASDU 9).
    pub measurand_fun: u8,
    /// INF of the measurand set.
    pub measurand_inf: u8,
    /// The measurands in the order of the set.
    pub measurands: Vec<MeasurandChannel>,
    /// How often the measurands are reported (CycMeasRepTime).
    pub cycle: Duration,
    /// The commands.
    pub commands: Vec<CommandPoint>,
    /// The indication of the LOCAL/REMOTE switch (ON = LOCAL); commands are refused
    /// while it is ON.
    pub local_remote: Option<(u8, u8)>,
    /// The indication of an earth fault trip, reported with relative time and fault
    /// number on [`Device::earth_fault`].
    pub earth_fault: (u8, u8),
    /// How far the device's clock is off before the first synchronisation (the lab
    /// relay ran 58 minutes behind, spec IEC-A5).
    pub clock_offset: chrono::Duration,
}

impl DeviceProfile {
    /// The ABB REF630 of the thesis (spec §5.1): address as given, identification
    /// `REF630 11.3.` at compatibility level 2; breaker FUN 1 INF 160, earth switch FUN
    /// 1 INF 168, truck FUN 5 INF 9 (test) / 10 (service), measurands II FUN 1 INF 148
    /// with the I103MEAS limits (240 A, 15.2 kV, 1200 MW, 1200 Mvar, 50 Hz), earth fault
    /// FUN 160 (INF 92, trip IN>), CycMeasRepTime 5 s, the clock 58 minutes behind.
    ///
    /// The thesis gives no number for the LOCAL/REMOTE switch; it is reported at
    /// FUN 1 INF 190 (a user-defined position of I103USRDEF, ON = LOCAL).
    pub fn ref630(address: u8) -> DeviceProfile {
        let indication = |fun, inf, name: &str, initial| Indication {
            fun,
            inf,
            name: name.to_owned(),
            in_gi: true,
            initial,
        };
        let channel = |name: &str, rated, limit_factor, unit: &str| MeasurandChannel {
            name: name.to_owned(),
            rated,
            limit_factor,
            unit: unit.to_owned(),
        };
        let mut identification = [0u8; 12];
        identification.copy_from_slice(b"REF630 11.3.");
        DeviceProfile {
            address,
            function_type: 160,
            compatibility_level: 2,
            identification,
            // In the order the relay reports them in a GI (spec §6, polls 3-6).
            indications: vec![
                indication(5, 9, "truck in TEST position", 1),
                indication(5, 10, "truck in SERVICE position", 2),
                indication(1, 160, "circuit breaker", 2),
                indication(1, 168, "earth switch", 1),
                indication(1, 190, "LOCAL/REMOTE switch (ON = LOCAL)", 1),
                Indication {
                    in_gi: false,
                    ..indication(160, 92, "earth fault trip IN>", 1)
                },
            ],
            measurand_fun: 1,
            measurand_inf: iec60870::iec103::INF_MEASURANDS_II,
            measurands: vec![
                channel("IL1", 100.0, 2.4, "A"),
                channel("IL2", 100.0, 2.4, "A"),
                channel("IL3", 100.0, 2.4, "A"),
                channel("UL1", 15_200.0 / 1.2, 1.2, "V"),
                channel("UL2", 15_200.0 / 1.2, 1.2, "V"),
                channel("UL3", 15_200.0 / 1.2, 1.2, "V"),
                channel("P", 500.0e6, 2.4, "W"),
                channel("Q", 500.0e6, 2.4, "var"),
                channel("f", 50.0 / 1.2, 1.2, "Hz"),
            ],
            cycle: Duration::from_secs(5),
            commands: vec![
                CommandPoint {
                    fun: 1,
                    inf: 160,
                    operate_time: Duration::from_millis(60),
                },
                CommandPoint {
                    fun: 1,
                    inf: 168,
                    operate_time: Duration::from_millis(2000),
                },
            ],
            local_remote: Some((1, 190)),
            earth_fault: (160, 92),
            clock_offset: chrono::Duration::minutes(-58),
        }
    }
}

/// What the device did, for its log.
#[derive(Debug, Clone, PartialEq)]
pub enum DeviceEvent {
    /// The master reset the communication unit or the FCB.
    Reset(PrimaryFunction),
    /// A general interrogation started.
    Interrogated {
        /// Its scan number.
        scn: u8,
    },
    /// The clock was set.
    ClockSynchronised {
        /// The time received.
        time: NaiveDateTime,
    },
    /// A general command was accepted or refused.
    Command {
        /// Function type.
        fun: u8,
        /// Information number.
        inf: u8,
        /// ON (true) or OFF.
        on: bool,
        /// Accepted.
        accepted: bool,
        /// Why not.
        reason: &'static str,
    },
    /// An indication changed.
    Changed {
        /// Function type.
        fun: u8,
        /// Information number.
        inf: u8,
        /// The new double point.
        dpi: u8,
        /// The cause it is reported with.
        cause: Cause,
    },
    /// A message the device does not handle.
    Ignored(Vec<u8>),
}

#[derive(Debug)]
struct PendingOperation {
    at: Instant,
    fun: u8,
    inf: u8,
    dpi: u8,
}

/// A 103 device behind an FT1.2 secondary.
#[derive(Debug)]
pub struct Device {
    profile: DeviceProfile,
    states: Vec<u8>,
    values: Vec<f64>,
    class1: VecDeque<Vec<u8>>,
    class1_dropped: u64,
    class2: Option<Vec<u8>>,
    next_cycle: Option<Instant>,
    now: Instant,
    /// The device clock: its reading at `clock_instant`.
    clock_base: NaiveDateTime,
    clock_instant: Instant,
    synchronised_at: Option<Instant>,
    /// The start-up not yet reported: power on (cold) or start/restart (warm).
    start_up_pending: Option<Cause>,
    fault_number: u16,
    operations: Vec<PendingOperation>,
    disturbances: DisturbanceSender,
    events: VecDeque<DeviceEvent>,
}

impl Device {
    /// A device that has just been powered on, at `now` with the wall-clock time `time`
    /// (its own clock is off by the profile's offset until synchronised).
    pub fn new(profile: DeviceProfile, now: Instant, time: NaiveDateTime) -> Device {
        let states = profile.indications.iter().map(|i| i.initial).collect();
        let values = vec![0.0; profile.measurands.len()];
        let clock_base = time + profile.clock_offset;
        Device {
            profile,
            states,
            values,
            class1: VecDeque::new(),
            class1_dropped: 0,
            class2: None,
            next_cycle: Some(now),
            now,
            clock_base,
            clock_instant: now,
            synchronised_at: None,
            start_up_pending: Some(Cause::POWER_ON),
            fault_number: 0,
            operations: Vec::new(),
            disturbances: DisturbanceSender::default(),
            events: VecDeque::new(),
        }
    }

    /// The profile.
    pub fn profile(&self) -> &DeviceProfile {
        &self.profile
    }

    /// The next event.
    pub fn poll_event(&mut self) -> Option<DeviceEvent> {
        self.events.pop_front()
    }

    /// Class 1 messages dropped because nobody polled them.
    pub fn class1_dropped(&self) -> u64 {
        self.class1_dropped
    }

    /// The device's clock now.
    pub fn clock(&self) -> NaiveDateTime {
        self.clock_base
            + chrono::Duration::from_std(self.now - self.clock_instant).unwrap_or_default()
    }

    /// Whether the clock counts as synchronised (within 23 h of the last sync).
    pub fn is_synchronised(&self) -> bool {
        self.synchronised_at.is_some_and(|at| {
            self.now.saturating_duration_since(at) <= Duration::from_secs(23 * 3600)
        })
    }

    fn time_tag(&self) -> Cp32Time2a {
        Cp32Time2a::from_naive(self.clock()).with_invalid(!self.is_synchronised())
    }

    /// The double point of an indication.
    pub fn indication(&self, fun: u8, inf: u8) -> Option<u8> {
        self.index(fun, inf)
            .and_then(|index| self.states.get(index).copied())
    }

    /// Whether the LOCAL/REMOTE switch is in LOCAL.
    pub fn is_local(&self) -> bool {
        self.profile
            .local_remote
            .and_then(|(fun, inf)| self.indication(fun, inf))
            == Some(2)
    }

    /// Sets an indication and reports it with `cause` (1 spontaneous, 11 local
    /// operation, 12 remote operation) if it changed.
    pub fn set_indication(&mut self, fun: u8, inf: u8, dpi: u8, cause: Cause) -> bool {
        let Some(index) = self.index(fun, inf) else {
            return false;
        };
        let Some(state) = self.states.get_mut(index) else {
            return false;
        };
        if *state == dpi {
            return true;
        }
        *state = dpi;
        let message = Asdu::new(
            1,
            cause,
            self.profile.address,
            fun,
            inf,
            Body::TimeTagged {
                dpi,
                time: self.time_tag(),
                sin: 0,
            },
        );
        self.push_class1(&message);
        self.events.push_back(DeviceEvent::Changed {
            fun,
            inf,
            dpi,
            cause,
        });
        true
    }

    /// Sets the LOCAL/REMOTE switch (a hand on the relay's front panel).
    pub fn set_local(&mut self, local: bool) {
        if let Some((fun, inf)) = self.profile.local_remote {
            self.set_indication(fun, inf, if local { 2 } else { 1 }, Cause::LOCAL_OPERATION);
        }
    }

    /// Sets the measured values, in engineering units, in the order of the set;
    /// reported at the next cycle.
    pub fn set_measurands(&mut self, values: &[f64]) {
        for (slot, value) in self.values.iter_mut().zip(values) {
            *slot = *value;
        }
    }

    /// Sets the measured values as multiples of each channel's rated value (what a test
    /// set such as the FREJA300 injects: 1.0 = rated).
    pub fn inject_rated_multiples(&mut self, multiples: &[f64]) {
        let values: Vec<f64> = self
            .profile
            .measurands
            .iter()
            .zip(multiples)
            .map(|(channel, multiple)| channel.rated * multiple)
            .collect();
        self.set_measurands(&values);
    }

    /// The relay was restarted (not powered off): the next reset of the communication
    /// unit reports a start/restart instead of a power on.
    pub fn restart(&mut self) {
        self.start_up_pending = Some(Cause::START_RESTART);
    }

    /// An earth fault: the protection trips (ASDU 2 with relative time and the new
    /// fault number, then back to OFF), the breaker opens, and a disturbance record of
    /// the phase and earth currents is kept and announced (ASDU 23).
    pub fn earth_fault(&mut self) -> u16 {
        self.fault_number = self.fault_number.wrapping_add(1);
        let fan = self.fault_number;
        let (fun, inf) = self.profile.earth_fault;
        for (dpi, ret) in [(2u8, 40u16), (1, 120)] {
            let message = Asdu::new(
                2,
                Cause::SPONTANEOUS,
                self.profile.address,
                fun,
                inf,
                Body::TimeTaggedRelative {
                    dpi,
                    ret,
                    fan,
                    time: self.time_tag(),
                    sin: 0,
                },
            );
            self.push_class1(&message);
            if let Some(index) = self.index(fun, inf) {
                if let Some(state) = self.states.get_mut(index) {
                    *state = dpi;
                }
            }
        }
        self.set_indication(1, 160, 1, Cause::SPONTANEOUS);
        let record = self.fault_record(fan);
        let list =
            self.disturbances
                .record(record, self.profile.address, self.profile.function_type);
        self.push_class1(&list);
        fan
    }

    /// The record of an earth fault on phase L1: 1 kHz for 0.3 s; 0.1 s of load current
    /// before the fault, 0.12 s of fault (five times rated in L1 and the earth current),
    /// then the breaker has opened. Tags: the trip at 40 ms into the fault and its reset,
    /// the breaker's opening.
    fn fault_record(&self, fan: u16) -> DisturbanceRecord {
        const SAMPLES: usize = 300;
        const FAULT_START: usize = 100;
        const BREAKER_OPEN: usize = 220;
        // One secondary ampere is 100 disturbance values (RFA), the CT 100 A / 1 A.
        const RFA: f32 = 100.0;
        let load = self.values.first().copied().unwrap_or(0.0);
        let rated = self
            .profile
            .measurands
            .first()
            .map_or(100.0, |channel| channel.rated);
        let amplitude = |primary: f64| primary / rated * f64::from(RFA) * std::f64::consts::SQRT_2;
        let phase_shift = [0.0, -2.0 / 3.0, 2.0 / 3.0];
        let mut channels: Vec<RecordChannel> = (0..4u8)
            .map(|index| RecordChannel {
                acc: index + 1,
                rpv: rated as f32,
                rsv: 1.0,
                rfa: RFA,
                samples: Vec::with_capacity(SAMPLES),
            })
            .collect();
        for sample in 0..SAMPLES {
            let t = sample as f64 / 1000.0;
            let mut sum = 0.0;
            for (phase, shift) in phase_shift.iter().enumerate() {
                let current = match sample {
                    s if s >= BREAKER_OPEN => 0.0,
                    s if s >= FAULT_START && phase == 0 => 5.0 * rated,
                    _ => load,
                };
                let value = amplitude(current)
                    * (2.0 * std::f64::consts::PI * (50.0 * t + shift / 2.0)).sin();
                sum += value;
                if let Some(channel) = channels.get_mut(phase) {
                    channel
                        .samples
                        .push(value.round().clamp(-32768.0, 32767.0) as i16);
                }
            }
            if let Some(earth) = channels.get_mut(3) {
                earth
                    .samples
                    .push(sum.round().clamp(-32768.0, 32767.0) as i16);
            }
        }
        let tag = |position: usize, fun: u8, inf: u8, dpi: u8| RecordTag {
            position: u16::try_from(position).unwrap_or(u16::MAX),
            tag: iec60870::iec103::DisturbanceTag { fun, inf, dpi },
        };
        let (fun, inf) = self.profile.earth_fault;
        let now = self.clock();
        DisturbanceRecord {
            fan,
            sof: SOF_TRIP,
            recorded_at: now,
            first_sample: now - chrono::Duration::milliseconds(FAULT_START as i64),
            interval_us: 1000,
            channels,
            tags: vec![
                tag(FAULT_START + 40, fun, inf, 2),
                tag(BREAKER_OPEN, 1, 160, 1),
                tag(BREAKER_OPEN + 10, fun, inf, 1),
            ],
        }
    }

    /// The operations of a relay tester at the relay (the simulator's console
    /// language, shared by `stanice iec103 relay` and the station's `relay DEVICE ...`):
    /// `inject I U [P Q F]` (multiples of rated), `local`, `remote`, `open`, `close`,
    /// `earth-switch on|off`, `truck test|service`, `fault`, `restart`, `status`. Returns
    /// what was done, or why not. Positions follow the REF630 profile's numbers.
    pub fn operate(&mut self, words: &[&str]) -> Result<String, String> {
        let word = |index: usize| {
            words
                .get(index)
                .map(|w| w.to_ascii_lowercase())
                .unwrap_or_default()
        };
        match word(0).as_str() {
            "inject" => {
                let values: Result<Vec<f64>, _> = words.iter().skip(1).map(|w| w.parse::<f64>()).collect();
                match values {
                    Ok(values) if !values.is_empty() => {
                        let get = |index: usize| values.get(index).copied().unwrap_or(0.0);
                        let (current, voltage) = (get(0), get(1));
                        self.inject_rated_multiples(&[
                            current, current, current, voltage, voltage, voltage, get(2), get(3), get(4),
                        ]);
                        Ok(format!("injected {values:?} x rated; reported at the next cycle"))
                    }
                    _ => Err("inject: give multiples of rated, e.g. `inject 1 1` or `inject 0.8 0.9`".to_owned()),
                }
            }
            "local" => {
                self.set_local(true);
                Ok("LOCAL: remote commands are refused".to_owned())
            }
            "remote" => {
                self.set_local(false);
                Ok("REMOTE".to_owned())
            }
            "open" | "close" => {
                let dpi = if word(0) == "close" { 2 } else { 1 };
                self.set_indication(1, 160, dpi, Cause::LOCAL_OPERATION);
                Ok(format!("breaker {}", if dpi == 2 { "closed" } else { "open" }))
            }
            "earth-switch" => {
                let dpi = if word(1) == "on" { 2 } else { 1 };
                self.set_indication(1, 168, dpi, Cause::LOCAL_OPERATION);
                Ok(format!("earth switch {}", if dpi == 2 { "on" } else { "off" }))
            }
            "truck" => {
                let service = word(1) == "service";
                self.set_indication(5, 10, if service { 2 } else { 1 }, Cause::LOCAL_OPERATION);
                self.set_indication(5, 9, if service { 1 } else { 2 }, Cause::LOCAL_OPERATION);
                Ok(format!("truck in {}", if service { "SERVICE" } else { "TEST" }))
            }
            "fault" => {
                let fan = self.earth_fault();
                Ok(format!("earth fault number {fan}: trip, breaker open"))
            }
            "restart" => {
                self.restart();
                Ok("warm restart: reported at the next reset of the communication unit".to_owned())
            }
            "status" => {
                let position = |fun, inf| self.indication(fun, inf).map(iec60870::iec103::dpi_text).unwrap_or("?");
                Ok(format!(
                    "breaker {}, earth switch {}, truck TEST {} SERVICE {}, switch {}, clock {} ({})",
                    position(1, 160),
                    position(1, 168),
                    position(5, 9),
                    position(5, 10),
                    if self.is_local() { "LOCAL" } else { "REMOTE" },
                    self.clock().format("%Y-%m-%d %H:%M:%S%.3f"),
                    if self.is_synchronised() { "synchronised" } else { "not synchronised: time tags IV" },
                ))
            }
            other => Err(format!(
                "unknown operation {other:?}: inject, local, remote, open, close, earth-switch, truck, fault, restart, status"
            )),
        }
    }

    fn index(&self, fun: u8, inf: u8) -> Option<usize> {
        self.profile
            .indications
            .iter()
            .position(|indication| indication.fun == fun && indication.inf == inf)
    }

    fn push_class1(&mut self, asdu: &Asdu) {
        let Ok(bytes) = asdu.to_bytes() else {
            return;
        };
        if self.class1.len() >= CLASS1_CAPACITY {
            self.class1.pop_front();
            self.class1_dropped += 1;
        }
        self.class1.push_back(bytes);
    }

    fn identification(&mut self, cause: Cause, inf: u8) {
        let mut text = [0u8; 8];
        let mut software = [0u8; 4];
        let (head, tail) = self.profile.identification.split_at(8);
        text.copy_from_slice(head);
        software.copy_from_slice(tail);
        let message = Asdu::new(
            5,
            cause,
            self.profile.address,
            self.profile.function_type,
            inf,
            Body::Identification {
                col: self.profile.compatibility_level,
                text,
                software,
            },
        );
        self.push_class1(&message);
    }

    fn general_interrogation(&mut self, scn: u8) {
        self.events.push_back(DeviceEvent::Interrogated { scn });
        let time = self.time_tag();
        let answers: Vec<Asdu> = self
            .profile
            .indications
            .iter()
            .zip(&self.states)
            .filter(|(indication, _)| indication.in_gi)
            .map(|(indication, dpi)| {
                Asdu::new(
                    1,
                    Cause::GENERAL_INTERROGATION,
                    self.profile.address,
                    indication.fun,
                    indication.inf,
                    Body::TimeTagged {
                        dpi: *dpi,
                        time,
                        sin: scn,
                    },
                )
            })
            .collect();
        for answer in &answers {
            self.push_class1(answer);
        }
        let end = Asdu::new(
            8,
            Cause::GI_TERMINATION,
            self.profile.address,
            FUN_GLOBAL,
            0,
            Body::GiTermination { scn },
        );
        self.push_class1(&end);
    }

    fn clock_sync(&mut self, time: Cp56Time2a, broadcast: bool) {
        let Ok(set) = time.to_naive() else {
            return;
        };
        self.clock_base = set;
        self.clock_instant = self.now;
        self.synchronised_at = Some(self.now);
        self.events
            .push_back(DeviceEvent::ClockSynchronised { time: set });
        if !broadcast {
            // An addressed synchronisation is confirmed with the time as set.
            let answer = Asdu::new(
                6,
                Cause::TIME_SYNC,
                self.profile.address,
                FUN_GLOBAL,
                0,
                Body::TimeSync { time },
            );
            self.push_class1(&answer);
        }
    }

    fn general_command(&mut self, fun: u8, inf: u8, dco: u8, rii: u8) {
        let on = dco == 2;
        let command = self
            .profile
            .commands
            .iter()
            .find(|command| command.fun == fun && command.inf == inf)
            .cloned();
        let refusal = match (&command, dco) {
            (None, _) => Some("no such command"),
            (Some(_), 1 | 2) if self.is_local() => Some("the relay is in LOCAL"),
            (Some(_), 1 | 2) => None,
            (Some(_), _) => Some("DCO must be 1 (OFF) or 2 (ON)"),
        };
        let ack = Asdu::new(
            1,
            if refusal.is_none() {
                Cause::COMMAND_ACK
            } else {
                Cause::COMMAND_NACK
            },
            self.profile.address,
            fun,
            inf,
            Body::TimeTagged {
                dpi: dco,
                time: self.time_tag(),
                sin: rii,
            },
        );
        self.push_class1(&ack);
        self.events.push_back(DeviceEvent::Command {
            fun,
            inf,
            on,
            accepted: refusal.is_none(),
            reason: refusal.unwrap_or("executed"),
        });
        if let (None, Some(command)) = (refusal, command) {
            self.operations.push(PendingOperation {
                at: self.now + command.operate_time,
                fun,
                inf,
                dpi: dco,
            });
        }
    }

    fn measurand_message(&self) -> Option<Vec<u8>> {
        if self.profile.measurands.is_empty() {
            return None;
        }
        let values = self
            .profile
            .measurands
            .iter()
            .zip(&self.values)
            .map(|(channel, value)| Measurand::from_physical(*value, channel.limit()))
            .collect();
        let message = Asdu::new(
            9,
            Cause::CYCLIC,
            self.profile.address,
            self.profile.measurand_fun,
            self.profile.measurand_inf,
            Body::Measurands(values),
        );
        message.to_bytes().ok()
    }
}

impl SecondaryApplication for Device {
    fn link_reset(&mut self, function: PrimaryFunction) {
        self.events.push_back(DeviceEvent::Reset(function));
        match function {
            PrimaryFunction::ResetRemoteLink => {
                // Reset of the communication unit: the events go, the identification
                // (and a start-up not yet reported) comes; the last measurands stay
                // valid until the next cycle.
                self.class1.clear();
                self.identification(Cause::RESET_CU, INF_RESET_CU);
                match self.start_up_pending.take() {
                    Some(Cause::POWER_ON) => self.identification(Cause::POWER_ON, INF_POWER_ON),
                    Some(cause) => self.identification(cause, INF_START_RESTART),
                    None => {}
                }
            }
            PrimaryFunction::ResetFcb => self.identification(Cause::RESET_FCB, INF_RESET_FCB),
            _ => {}
        }
    }

    fn user_data(&mut self, bytes: &[u8], broadcast: bool) -> bool {
        let Ok(asdu) = Asdu::decode(bytes, Direction::Control) else {
            self.events.push_back(DeviceEvent::Ignored(bytes.to_vec()));
            return true;
        };
        let addressed = asdu.header.common_address == self.profile.address
            || asdu.header.common_address == 0xFF;
        if !addressed {
            self.events.push_back(DeviceEvent::Ignored(bytes.to_vec()));
            return true;
        }
        match asdu.body {
            Body::TimeSync { time } => {
                self.clock_sync(time, broadcast || asdu.header.common_address == 0xFF)
            }
            Body::GiInitiation { scn } if !broadcast => self.general_interrogation(scn),
            Body::GeneralCommand { dco, rii } if !broadcast => {
                self.general_command(asdu.header.fun, asdu.header.inf, dco, rii)
            }
            Body::DisturbanceOrder { .. } | Body::DisturbanceAck { .. } if !broadcast => {
                for answer in self.disturbances.handle(&asdu, self.profile.address) {
                    self.push_class1(&answer);
                }
            }
            _ => self.events.push_back(DeviceEvent::Ignored(bytes.to_vec())),
        }
        true
    }

    fn has_class1(&self) -> bool {
        !self.class1.is_empty()
    }

    fn class1(&mut self) -> Option<Vec<u8>> {
        self.class1.pop_front()
    }

    fn class2(&mut self) -> Option<Vec<u8>> {
        self.class2.take()
    }

    fn data_flow_stopped(&self) -> bool {
        self.class1.len() >= CLASS1_CAPACITY * 3 / 4
    }
}

impl TimedApplication for Device {
    fn handle_timeout(&mut self, now: Instant) {
        self.now = now;
        let due: Vec<PendingOperation> = {
            let (due, pending): (Vec<_>, Vec<_>) = self
                .operations
                .drain(..)
                .partition(|operation| operation.at <= now);
            self.operations = pending;
            due
        };
        for operation in due {
            self.set_indication(
                operation.fun,
                operation.inf,
                operation.dpi,
                Cause::REMOTE_OPERATION,
            );
        }
        if self.next_cycle.is_some_and(|at| at <= now) {
            self.class2 = self.measurand_message();
            let mut next = self.next_cycle.unwrap_or(now) + self.profile.cycle;
            if next <= now {
                next = now + self.profile.cycle;
            }
            self.next_cycle = Some(next);
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        self.operations
            .iter()
            .map(|operation| operation.at)
            .chain(self.next_cycle)
            .min()
    }
}
