//! The per-link core of an outstation: everything one link (a TCP connection, a serial
//! link) does with ASDUs, without the link itself.
//!
//! The adapter owns the transport and its link layer (IEC 104's APCI [`Session`], the
//! FT1.2 link layer) and, in its loop:
//!
//! 1. hands every received ASDU to [`LinkCore::handle_asdu`], data transfer starting and
//!    stopping to [`LinkCore::start`] and [`LinkCore::stop`], and the peer's
//!    acknowledgements to [`LinkCore::acknowledged`];
//! 2. lets [`LinkCore::fill`] send what fits the link's window ([`LinkLayer`]):
//!    answers first, then the group's buffered events alternating with the running
//!    interrogation;
//! 3. closes the link when [`LinkCore::close_reason`] says so;
//! 4. waits for its transport, its deadlines, [`LinkCore::poll_commands`] (command
//!    outcomes) and, while started, [`GroupChanges::changed`] (new events, a take-over).
//!
//! [`Session`]: crate::cs104::Session

use std::collections::VecDeque;
use std::future::Future as _;
use std::sync::Arc;
use std::task::{Context, Poll};
use std::time::{Duration, Instant};

use crate::asdu::{
    mirror_with_cause, object_len, pack_objects, Asdu, AsduHeader, AsduParams, Cause,
    CommonAddress, Cot, DoublePointState, Element, InformationObject, Ioa, TimeTag, TypeId,
};

use super::group::{Group, QueuedEvent};
use super::handler::{Command, CommandFuture, CommandOutcome, CommandRefusal, TerminationFuture};
use super::{Outstation, Peer, Selection};

/// Waits for a redundancy group's changes: an event queued, another link taking the group.
#[derive(Debug, Clone)]
pub struct GroupChanges(Arc<Group>);

impl GroupChanges {
    /// The group's change counter. Read it before looking at the core, then wait with
    /// [`changed`](Self::changed): a change in between is not missed.
    pub fn version(&self) -> u64 {
        self.0.version()
    }

    /// Resolves once the group changed since `seen` (a [`version`](Self::version)).
    pub fn changed(&self, seen: u64) -> impl std::future::Future<Output = ()> + '_ {
        self.0.changed(seen)
    }

    /// [`changed`](Self::changed) for a caller that polls by hand (a line endpoint's
    /// wake-up): ready once the group changed since `seen`, otherwise registers the
    /// context's waker with the group.
    pub fn poll_changed(&self, seen: u64, context: &mut Context<'_>) -> Poll<()> {
        let changed = std::pin::pin!(self.0.changed(seen));
        changed.poll(context)
    }
}

/// What the core needs of a link layer: a window to send ASDUs into, and what the peer
/// has not yet confirmed.
pub trait LinkLayer {
    /// Whether one more ASDU may be sent now (data transfer started, window open).
    fn can_send(&self) -> bool;
    /// Sends an ASDU; `false` when the link refused it (it is then kept for later).
    fn send_asdu(&mut self, now: Instant, asdu: &[u8]) -> bool;
    /// ASDUs sent and not yet confirmed by the peer.
    fn unconfirmed(&self) -> usize;
    /// The link lost its redundancy group to another link: it stops carrying data
    /// (silently: a client must never get an unsolicited STOPDT) and forgets the ASDUs
    /// it has in flight, which the group gave to the new link. Returns how many.
    fn hand_over(&mut self) -> usize;
    /// The link that took the group over went away: this one, handed over before and
    /// never stopped by its peer, carries the group's data again.
    fn take_back(&mut self);
}

/// Answers queued for a peer that does not acknowledge them: beyond this the peer is
/// flooding us with requests while its window stays shut, and the link is closed rather
/// than let the queue grow until t1 expires.
const MAX_QUEUED_RESPONSES: usize = 4096;

/// Commands waiting for the application's outcome on one link; further commands are
/// refused with a negative confirmation.
const MAX_PENDING_COMMANDS: usize = 256;

/// Malformed ASDUs tolerated on one link (each is logged and ignored); the next one
/// closes it, so a broken or hostile peer cannot flood the log forever.
const MAX_MALFORMED_ASDUS: u32 = 64;

/// Points an interrogation reads from the image at a time (two full SQ=1 ASDUs of single
/// points; the image's lock is held only while they are copied).
const INTERROGATION_CHUNK: usize = 2 * 127;

/// A command whose outcome the handler has decided.
struct CommandReply {
    request: Vec<u8>,
    select: bool,
    ioa: u32,
    selection: Option<Selection>,
    outcome: CommandOutcome,
}

/// A command termination (ACT_TERM) waiting for its place: after every event its group
/// queued before the command terminated, so that the return information comes between
/// the confirmation and the termination.
struct Termination {
    /// Sent once the group has no event left with a lower sequence number.
    after_seq: u64,
    asdu: Vec<u8>,
}

/// A confirmed command whose application has not yet terminated it.
struct Terminating {
    future: TerminationFuture,
    request: Vec<u8>,
}

/// A command waiting for the handler's outcome. Polled by the link's own loop rather than
/// a spawned task and a channel: an idle link then holds no channel buffers (memory per
/// connection matters with a thousand clients).
struct PendingCommand {
    future: CommandFuture,
    request: Vec<u8>,
    select: bool,
    ioa: u32,
    selection: Option<Selection>,
    /// An execute holds back the group's return information (cause 11) queued from
    /// this sequence number on until its confirmation has gone out.
    holds_return_from: Option<u64>,
}

/// An interrogation being streamed to the client, a chunk at a time as the window allows.
struct Interrogation {
    request: Vec<u8>,
    qualifier: u8,
    cause: Cause,
    after: Option<Ioa>,
    /// ASDUs of the current chunk not yet sent.
    pending: VecDeque<Vec<u8>>,
    finished: bool,
}

/// The outstation's side of one link: answers, interrogation, commands and the group's
/// events, for whatever link layer carries them (see the module's documentation).
pub struct LinkCore {
    outstation: Arc<Outstation>,
    id: u64,
    group: Arc<Group>,
    peer: Peer,
    /// Confirmations and other answers: sent before anything else.
    responses: VecDeque<Vec<u8>>,
    interrogation: Option<Interrogation>,
    /// For each sent and unconfirmed ASDU, whether it came from the group's buffer.
    sent_from_group: VecDeque<bool>,
    /// Whether this link is its group's started link.
    active: bool,
    /// Started, but its group's data went to another connection (take-over): it takes
    /// the data back when that connection stops.
    standing_by: bool,
    /// Alternates group events and interrogation chunks so neither starves the other.
    prefer_interrogation: bool,
    pending_commands: Vec<PendingCommand>,
    /// Confirmed commands waiting for their application to terminate them.
    terminating: Vec<Terminating>,
    /// Terminations waiting for the events queued before them, oldest first.
    terminations: VecDeque<Termination>,
    /// Malformed ASDUs received so far (see [`MAX_MALFORMED_ASDUS`]).
    malformed_asdus: u32,
}

impl std::fmt::Debug for LinkCore {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LinkCore")
            .field("id", &self.id)
            .field("peer", &self.peer)
            .field("group", &self.group.config.name)
            .field("active", &self.active)
            .finish_non_exhaustive()
    }
}

impl LinkCore {
    pub(super) fn new(outstation: Arc<Outstation>, id: u64, group: Arc<Group>, peer: Peer) -> Self {
        outstation.handler.connection_changed(&peer, true, false);
        Self {
            outstation,
            id,
            group,
            peer,
            responses: VecDeque::new(),
            interrogation: None,
            sent_from_group: VecDeque::new(),
            active: false,
            standing_by: false,
            prefer_interrogation: false,
            pending_commands: Vec::new(),
            terminating: Vec::new(),
            terminations: VecDeque::new(),
            malformed_asdus: 0,
        }
    }

    /// The link's peer.
    pub fn peer(&self) -> &Peer {
        &self.peer
    }

    /// The name of the link's redundancy group.
    pub fn group_name(&self) -> &str {
        &self.group.config.name
    }

    /// Whether this link is its group's started link.
    pub fn is_active(&self) -> bool {
        self.active
    }

    /// Whether the group's changes concern this link: it is the started link, or a
    /// standby one that takes the data back when the started link goes.
    pub fn follows_group(&self) -> bool {
        self.active || self.standing_by
    }

    /// A handle to wait for the group's changes (new events, another link taking the
    /// group) while the core is borrowed elsewhere.
    pub fn changes(&self) -> GroupChanges {
        GroupChanges(Arc::clone(&self.group))
    }

    /// Why the link must be closed now, if it must: a peer sending malformed ASDUs or
    /// requests without acknowledging the answers.
    pub fn close_reason(&self) -> Option<String> {
        if self.malformed_asdus > MAX_MALFORMED_ASDUS {
            return Some(format!(
                "{} malformed ASDUs received: more than the {MAX_MALFORMED_ASDUS} tolerated",
                self.malformed_asdus
            ));
        }
        if self.responses.len() > MAX_QUEUED_RESPONSES {
            return Some(format!(
                "{} answers queued: the client sends requests without acknowledging the answers",
                self.responses.len()
            ));
        }
        None
    }

    /// Whether a command outcome or termination is awaited (see
    /// [`poll_commands`](Self::poll_commands)).
    pub fn awaits_commands(&self) -> bool {
        !self.pending_commands.is_empty() || !self.terminating.is_empty()
    }

    /// Takes the outcomes and terminations the application has decided; `Ready` when it
    /// took at least one (the adapter then fills the window again), `Pending` with the
    /// context's waker registered otherwise.
    pub fn poll_commands(&mut self, context: &mut Context<'_>) -> Poll<()> {
        let mut progressed = false;
        let mut index = 0;
        while let Some(command) = self.pending_commands.get_mut(index) {
            match command.future.as_mut().poll(context) {
                Poll::Ready(outcome) => {
                    let command = self.pending_commands.swap_remove(index);
                    self.finish_command(CommandReply {
                        request: command.request,
                        select: command.select,
                        ioa: command.ioa,
                        selection: command.selection,
                        outcome,
                    });
                    progressed = true;
                }
                Poll::Pending => index += 1,
            }
        }
        let mut index = 0;
        while let Some(command) = self.terminating.get_mut(index) {
            if command.future.as_mut().poll(context).is_ready() {
                let request = self.terminating.swap_remove(index).request;
                self.terminate(&request);
                progressed = true;
            } else {
                index += 1;
            }
        }
        if progressed {
            Poll::Ready(())
        } else {
            Poll::Pending
        }
    }

    /// The link ended: the group gets back what was in flight, the application hears of it.
    pub fn close(mut self, link: &dyn LinkLayer) {
        self.stop(link);
        self.outstation.release_link_group(&self.group);
        self.outstation
            .handler
            .connection_changed(&self.peer, false, false);
    }

    fn params(&self) -> &AsduParams {
        &self.outstation.config.asdu
    }

    /// Notices that another link of the group was started: this one then stops carrying
    /// data, silently (a client must never get an unsolicited STOPDT). The adapter calls
    /// this each turn, before it hands over what it received.
    pub fn check_still_active(&mut self, link: &mut dyn LinkLayer) {
        if !self.active {
            if self.standing_by && self.group.lock().active == Some(self.id) {
                // The connection that took the group over went away: this one, started
                // all along, carries the group's data again.
                tracing::info!(
                    "the group's started connection went away: this one takes the data back"
                );
                self.standing_by = false;
                self.active = true;
                self.sent_from_group.clear();
                link.take_back();
                self.outstation
                    .handler
                    .connection_changed(&self.peer, true, true);
            }
            return;
        }
        let still = self.group.lock().active == Some(self.id);
        if !still {
            tracing::info!(
                "another connection of the group was started: this one is now on standby"
            );
            self.active = false;
            self.standing_by = true;
            self.interrogation = None;
            self.responses.clear();
            // The group gave what this link had in flight to the new link; t1 must not
            // close this (now standby) link for frames whose delivery is no longer its
            // business. The client may still acknowledge them here.
            let handed_over = link.hand_over();
            if handed_over > 0 {
                tracing::debug!(
                    count = handed_over,
                    "unacknowledged frames handed to the new connection"
                );
            }
            for from_group in self.sent_from_group.iter_mut() {
                *from_group = false;
            }
        }
    }

    /// Data transfer started on this link (STARTDT, or the serial master's first request):
    /// it takes its group's data, from another link of the group if one had it.
    pub fn start(&mut self) {
        let group = Arc::clone(&self.group);
        let mut state = group.lock();
        if let Some(previous) = state.active {
            if previous != self.id {
                // At warn level: with independent masters in one group this is the moment
                // one of them silently stops getting data.
                let previous_peer = state
                    .active_peer
                    .as_ref()
                    .map_or_else(|| "?".to_owned(), |peer| peer.to_string());
                tracing::warn!(
                    group = %group.config.name,
                    previous_connection = previous,
                    "take-over: {} started data transfer and takes the redundancy group's data from {previous_peer}, which goes on standby",
                    self.peer,
                );
                let in_flight = std::mem::take(&mut state.in_flight);
                for asdu in in_flight.into_iter().rev() {
                    state.retransmit.push_front(asdu);
                }
                let previous_peer = state.active_peer.clone();
                if let Some(peer) = previous_peer {
                    state.standby.push((previous, peer));
                }
            }
        }
        let id = self.id;
        state.standby.retain(|(standby, _)| *standby != id);
        self.standing_by = false;
        state.active = Some(self.id);
        state.active_peer = Some(self.peer.clone());
        self.active = true;
        // Wake the link that lost the group (and ourselves).
        Group::wake_all(state);
        self.outstation
            .handler
            .connection_changed(&self.peer, true, true);
        tracing::info!("data transfer started");
    }

    /// Data transfer stopped (STOPDT, or the link ended): the group is given up, and what
    /// this link sent from the group's buffer without confirmation goes back to the front
    /// of the buffer.
    pub fn stop(&mut self, link: &dyn LinkLayer) {
        if self.standing_by {
            // A standby connection stopped (or went away): it no longer waits for data.
            self.standing_by = false;
            let id = self.id;
            self.group
                .lock()
                .standby
                .retain(|(standby, _)| *standby != id);
        }
        if !self.active {
            return;
        }
        self.acknowledged(link);
        self.active = false;
        {
            let group = Arc::clone(&self.group);
            let mut state = group.lock();
            if state.active == Some(self.id) {
                state.active = None;
                state.active_peer = None;
                let in_flight = std::mem::take(&mut state.in_flight);
                if !in_flight.is_empty() {
                    tracing::info!(
                        count = in_flight.len(),
                        "unacknowledged events kept for the next connection"
                    );
                }
                for asdu in in_flight.into_iter().rev() {
                    state.retransmit.push_front(asdu);
                }
                // The connection this one took the data from gets it back.
                if let Some((standby, peer)) = state.standby.pop() {
                    tracing::info!(
                        "{peer}, on standby since this connection took over, takes the group's data back"
                    );
                    state.active = Some(standby);
                    state.active_peer = Some(peer);
                    Group::wake_all(state);
                }
            }
        }
        self.sent_from_group.clear();
    }

    /// The peer confirmed ASDUs: their bookkeeping goes (at once: a STOPDT con or a close
    /// may follow, and what the peer confirmed must not go back to the group's queue).
    pub fn acknowledged(&mut self, link: &dyn LinkLayer) {
        let unacknowledged = link.unconfirmed();
        let mut acknowledged_group_frames = 0;
        while self.sent_from_group.len() > unacknowledged {
            if self.sent_from_group.pop_front() == Some(true) {
                acknowledged_group_frames += 1;
            }
        }
        if acknowledged_group_frames > 0 && self.active {
            let mut state = self.group.lock();
            if state.active == Some(self.id) {
                for _ in 0..acknowledged_group_frames {
                    state.in_flight.pop_front();
                }
            }
        }
    }

    /// Sends a response or interrogation ASDU (not from the group's queue).
    fn send(&mut self, now: Instant, link: &mut dyn LinkLayer, asdu: &[u8]) -> bool {
        let sent = link.send_asdu(now, asdu);
        if sent {
            self.sent_from_group.push_back(false);
        }
        sent
    }

    /// Sends what the link's window takes: answers first, then a due command
    /// termination, then the group's events alternating with the running interrogation.
    pub fn fill(&mut self, now: Instant, link: &mut dyn LinkLayer) {
        while link.can_send() {
            if let Some(response) = self.responses.pop_front() {
                if !self.send(now, link, &response) {
                    self.responses.push_front(response);
                    break;
                }
                continue;
            }
            if self.termination_due() {
                if let Some(termination) = self.terminations.pop_front() {
                    if !self.send(now, link, &termination.asdu) {
                        self.terminations.push_front(termination);
                        break;
                    }
                    continue;
                }
            }
            let from_interrogation = if self.prefer_interrogation {
                self.next_interrogation_asdu()
            } else {
                None
            };
            if let Some(asdu) = from_interrogation {
                self.prefer_interrogation = false;
                if !self.send(now, link, &asdu) {
                    break;
                }
                continue;
            }
            if self.active && self.send_group_asdu(now, link) {
                self.prefer_interrogation = true;
                continue;
            }
            match self.next_interrogation_asdu() {
                Some(asdu) => {
                    if !self.send(now, link, &asdu) {
                        break;
                    }
                }
                None => break,
            }
        }
    }

    /// Sends the next ASDU of the group: a retransmission, or the oldest buffered events
    /// of one type and cause packed together. Returns whether one was sent.
    ///
    /// Everything happens under the group's lock, after checking that this connection
    /// still owns the group: another connection may have been started since this one
    /// last looked, and must then get every event.
    fn send_group_asdu(&mut self, now: Instant, link: &mut dyn LinkLayer) -> bool {
        let params = self.outstation.config.asdu;
        let common_address = self.outstation.config.common_address;
        let group = Arc::clone(&self.group);
        let mut state = group.lock();
        if state.active != Some(self.id) {
            return false;
        }
        let gate = self.event_gate();
        let asdu = match state.retransmit.pop_front() {
            Some(asdu) => asdu,
            None => {
                if !state
                    .events
                    .front()
                    .is_some_and(|event| gate.lets_through(event))
                {
                    return false;
                }
                let Some(first) = state.events.pop_front() else {
                    return false;
                };
                let capacity = objects_per_asdu(first.type_id, &params);
                let mut asdu = Asdu::new(first.type_id, Cot::new(first.cause), common_address);
                asdu.objects.push(first.object);
                while asdu.objects.len() < capacity {
                    match state.events.front() {
                        Some(next)
                            if next.type_id == asdu.type_id
                                && next.cause == asdu.cot.cause
                                && gate.lets_through(next) =>
                        {
                            if let Some(next) = state.events.pop_front() {
                                asdu.objects.push(next.object);
                            }
                        }
                        _ => break,
                    }
                }
                match encode(&asdu, &params) {
                    Some(bytes) => bytes,
                    // Logged by encode; the events are lost, but the queue goes on.
                    None => return true,
                }
            }
        };
        if link.send_asdu(now, &asdu) {
            state.in_flight.push_back(asdu);
            self.sent_from_group.push_back(true);
            true
        } else {
            state.retransmit.push_front(asdu);
            false
        }
    }

    /// Which of the group's events may go out now (see [`EventGate`]).
    fn event_gate(&self) -> EventGate {
        EventGate {
            before_termination: self.terminations.front().map(|t| t.after_seq),
            hold_return_from: self
                .pending_commands
                .iter()
                .filter_map(|command| command.holds_return_from)
                .min(),
        }
    }

    /// Whether the oldest waiting termination may go out: the group has sent every event
    /// queued before it (or this connection no longer carries the group's data).
    fn termination_due(&self) -> bool {
        let Some(termination) = self.terminations.front() else {
            return false;
        };
        if !self.active {
            return true;
        }
        let state = self.group.lock();
        if state.active != Some(self.id) {
            return true;
        }
        state.retransmit.is_empty()
            && state
                .events
                .front()
                .is_none_or(|event| event.seq >= termination.after_seq)
    }

    /// Queues the termination of an executed command behind the events queued so far.
    fn terminate(&mut self, request: &[u8]) {
        match mirror_with_cause(request, self.params(), Cause::ACTIVATION_TERMINATION, false) {
            Ok(asdu) => {
                let after_seq = self.group.lock().next_seq;
                self.terminations.push_back(Termination { after_seq, asdu });
            }
            Err(error) => tracing::warn!(%error, "cannot mirror request"),
        }
    }

    /// The next ASDU of the running interrogation, reading the image a chunk at a time so
    /// that a large interrogation neither copies the whole image nor blocks updates.
    fn next_interrogation_asdu(&mut self) -> Option<Vec<u8>> {
        let params = self.outstation.config.asdu;
        let common_address = self.outstation.config.common_address;
        loop {
            let interrogation = self.interrogation.as_mut()?;
            if let Some(asdu) = interrogation.pending.pop_front() {
                return Some(asdu);
            }
            if interrogation.finished {
                let termination = mirror_with_cause(
                    &interrogation.request,
                    &params,
                    Cause::ACTIVATION_TERMINATION,
                    false,
                )
                .ok();
                self.interrogation = None;
                return termination;
            }
            // One run of points of the same type, at most CHUNK of them.
            let image = self.outstation.read_image();
            let mut run: Vec<InformationObject> = Vec::new();
            let mut run_type: Option<TypeId> = None;
            let mut scanned = interrogation.after;
            let mut more = false;
            let mut cut = false;
            for point in image.monitor_after(interrogation.after) {
                if !answers(point, interrogation.qualifier) {
                    scanned = Some(point.ioa);
                    continue;
                }
                let gi_type = untagged(point.event_type);
                match run_type {
                    None => run_type = Some(gi_type),
                    Some(current) if current != gi_type => {
                        more = true;
                        break;
                    }
                    Some(_) => {}
                }
                if run.len() >= INTERROGATION_CHUNK {
                    more = true;
                    cut = true;
                    break;
                }
                run.push(point.as_object());
                scanned = Some(point.ioa);
            }
            drop(image);
            let Some(type_id) = run_type else {
                interrogation.finished = true;
                continue;
            };
            let cot = Cot::new(interrogation.cause);
            let mut asdus: Vec<Asdu> =
                pack_objects(type_id, cot, common_address, run, &params, true).collect();
            // A chunk cut by its size ends in an ASDU that may be partly filled: leave its
            // objects to the next chunk, so that only the last ASDU of a run is not full.
            if cut && asdus.len() > 1 {
                asdus.pop();
                if let Some(object) = asdus.last().and_then(|asdu| asdu.objects.last()) {
                    scanned = Some(object.ioa);
                }
            }
            interrogation.after = scanned;
            interrogation.finished = !more;
            for asdu in &asdus {
                if let Some(bytes) = encode(asdu, &params) {
                    interrogation.pending.push_back(bytes);
                }
            }
        }
    }

    fn reply(&mut self, request: &[u8], cause: Cause, negative: bool) {
        match mirror_with_cause(request, self.params(), cause, negative) {
            Ok(asdu) => self.responses.push_back(asdu),
            Err(error) => tracing::warn!(%error, "cannot mirror request"),
        }
    }

    /// A received ASDU: answered, or handed to the application.
    pub fn handle_asdu(&mut self, now: Instant, raw: Vec<u8>) {
        let params = self.outstation.config.asdu;
        let header = match AsduHeader::decode(&raw, &params) {
            Ok(header) => header,
            Err(error) => {
                tracing::warn!(%error, "ASDU too short for its header: ignored");
                self.malformed_asdus += 1;
                return;
            }
        };
        let Some(type_id) = TypeId::from_u8(header.type_byte) else {
            tracing::warn!(type_id = header.type_byte, "unknown type identification");
            self.reply(&raw, Cause::UNKNOWN_TYPE, true);
            return;
        };
        let station = self.outstation.config.common_address;
        let broadcast = header.common_address.is_broadcast(&params);
        let broadcast_allowed = matches!(
            type_id,
            TypeId::C_IC_NA_1 | TypeId::C_CI_NA_1 | TypeId::C_CS_NA_1 | TypeId::C_RP_NA_1
        );
        if header.common_address != station && !(broadcast && broadcast_allowed) {
            tracing::warn!(common_address = %header.common_address, "unknown common address");
            self.reply(&raw, Cause::UNKNOWN_COMMON_ADDRESS, true);
            return;
        }
        let asdu = match Asdu::decode(&raw, &params) {
            Ok(asdu) => asdu,
            Err(error) => {
                // Not answered: a mirror would be just as malformed (the client could not
                // decode it either), and no cause says "malformed". The connection stays.
                tracing::warn!(%error, %type_id, bytes = ?raw, "malformed ASDU ignored");
                self.malformed_asdus += 1;
                return;
            }
        };
        tracing::debug!(%asdu, "request");
        // A request to the broadcast address is answered once, as this station: every
        // confirmation, datum and termination carries the station's own address.
        let raw = if broadcast {
            with_station_address(&raw, &params, station)
        } else {
            raw
        };
        let cause = asdu.cot.cause;
        match type_id {
            TypeId::C_IC_NA_1 => self.handle_interrogation(raw, &asdu),
            TypeId::C_CI_NA_1 => self.handle_counter_interrogation(raw, &asdu),
            TypeId::C_RD_NA_1 => self.handle_read(raw, &asdu),
            TypeId::C_CS_NA_1 => {
                if cause != Cause::ACTIVATION {
                    return self.reply(&raw, Cause::UNKNOWN_CAUSE, true);
                }
                let accepted = match asdu.objects.first().map(|object| &object.element) {
                    Some(Element::ClockSync { time }) => {
                        self.outstation.handler.handle_clock_sync(*time, &self.peer)
                    }
                    _ => false,
                };
                self.reply(&raw, Cause::ACTIVATION_CON, !accepted);
            }
            TypeId::C_TS_TA_1 => {
                if cause != Cause::ACTIVATION {
                    return self.reply(&raw, Cause::UNKNOWN_CAUSE, true);
                }
                self.reply(&raw, Cause::ACTIVATION_CON, false);
            }
            TypeId::C_RP_NA_1 => {
                if cause != Cause::ACTIVATION {
                    return self.reply(&raw, Cause::UNKNOWN_CAUSE, true);
                }
                let accepted = match asdu.objects.first().map(|object| &object.element) {
                    Some(Element::ResetProcess { qualifier }) => self
                        .outstation
                        .handler
                        .handle_reset_process(*qualifier, &self.peer),
                    _ => false,
                };
                self.reply(&raw, Cause::ACTIVATION_CON, !accepted);
            }
            TypeId::C_CD_NA_1 => {
                if cause != Cause::ACTIVATION && cause != Cause::SPONTANEOUS {
                    return self.reply(&raw, Cause::UNKNOWN_CAUSE, true);
                }
                self.reply(&raw, Cause::ACTIVATION_CON, false);
            }
            TypeId::P_ME_NA_1 | TypeId::P_ME_NB_1 | TypeId::P_ME_NC_1 | TypeId::P_AC_NA_1 => {
                if cause != Cause::ACTIVATION {
                    return self.reply(&raw, Cause::UNKNOWN_CAUSE, true);
                }
                let accepted = asdu.objects.first().is_some_and(|object| {
                    self.outstation.handler.handle_parameter(
                        object.ioa,
                        &object.element,
                        &self.peer,
                    )
                });
                self.reply(&raw, Cause::ACTIVATION_CON, !accepted);
            }
            _ if type_id.is_command() => self.handle_command(now, raw, asdu),
            _ => {
                // Monitor-direction types from a client, file transfer (not served by this
                // station), and C_TS_NA_1 (not used in IEC 104).
                tracing::warn!(%type_id, "type not served by this station");
                self.reply(&raw, Cause::UNKNOWN_TYPE, true);
            }
        }
    }

    fn handle_interrogation(&mut self, raw: Vec<u8>, asdu: &Asdu) {
        let qualifier = match asdu.objects.first().map(|object| &object.element) {
            Some(Element::Interrogation { qualifier }) => *qualifier,
            _ => return self.reply(&raw, Cause::ACTIVATION_CON, true),
        };
        match asdu.cot.cause {
            Cause::ACTIVATION => {}
            Cause::DEACTIVATION => {
                let running = self.interrogation.take().is_some();
                return self.reply(&raw, Cause::DEACTIVATION_CON, !running);
            }
            _ => return self.reply(&raw, Cause::UNKNOWN_CAUSE, true),
        }
        let Some(cause) = (match qualifier {
            20 => Some(Cause::INTERROGATED_BY_STATION),
            21..=36 => Cause::interrogated_by_group(qualifier - 20),
            _ => None,
        }) else {
            return self.reply(&raw, Cause::ACTIVATION_CON, true);
        };
        if self.interrogation.is_some() {
            tracing::warn!("interrogation refused: another one is still running");
            return self.reply(&raw, Cause::ACTIVATION_CON, true);
        }
        self.reply(&raw, Cause::ACTIVATION_CON, false);
        self.interrogation = Some(Interrogation {
            request: raw,
            qualifier,
            cause,
            after: None,
            pending: VecDeque::new(),
            finished: false,
        });
    }

    fn handle_counter_interrogation(&mut self, raw: Vec<u8>, asdu: &Asdu) {
        let (request, freeze) = match asdu.objects.first().map(|object| &object.element) {
            Some(Element::CounterInterrogation { request, freeze }) => (*request, *freeze),
            _ => return self.reply(&raw, Cause::ACTIVATION_CON, true),
        };
        if asdu.cot.cause != Cause::ACTIVATION {
            return self.reply(&raw, Cause::UNKNOWN_CAUSE, true);
        }
        // RQT 1..=4 counter groups, 5 general.
        if !(1..=5).contains(&request) {
            return self.reply(&raw, Cause::ACTIVATION_CON, true);
        }
        self.reply(&raw, Cause::ACTIVATION_CON, false);
        if freeze == 0 {
            let params = self.outstation.config.asdu;
            let cause = Cause::new(
                Cause::REQUESTED_BY_GENERAL_COUNTER.value()
                    + if request == 5 { 0 } else { request },
            )
            .unwrap_or(Cause::REQUESTED_BY_GENERAL_COUNTER);
            let counters: Vec<(TypeId, InformationObject)> = self
                .outstation
                .read_image()
                .monitor_points()
                .filter(|point| matches!(point.element, Element::IntegratedTotal(_)))
                .filter(|point| request == 5 || point.groups & (1 << (request - 1)) != 0)
                .map(|point| (untagged(point.event_type), point.as_object()))
                .collect();
            let common_address = self.outstation.config.common_address;
            let objects = counters.into_iter().map(|(_, object)| object);
            for asdu in pack_objects(
                TypeId::M_IT_NA_1,
                Cot::new(cause),
                common_address,
                objects,
                &params,
                true,
            ) {
                if let Some(bytes) = encode(&asdu, &params) {
                    self.responses.push_back(bytes);
                }
            }
        }
        self.reply(&raw, Cause::ACTIVATION_TERMINATION, false);
    }

    fn handle_read(&mut self, raw: Vec<u8>, asdu: &Asdu) {
        if asdu.cot.cause != Cause::REQUEST {
            return self.reply(&raw, Cause::UNKNOWN_CAUSE, true);
        }
        let Some(object) = asdu.objects.first() else {
            return self.reply(&raw, Cause::UNKNOWN_OBJECT_ADDRESS, true);
        };
        let point = self.outstation.read_image().monitor(object.ioa).cloned();
        let Some(point) = point else {
            return self.reply(&raw, Cause::UNKNOWN_OBJECT_ADDRESS, true);
        };
        // The event type with the value's time tag when it has one of the type's kind,
        // else the type without time tag (a value set without time, or with a tag of
        // another kind through `ServerHandle::set`, must still be answered).
        let (type_id, time) = match point.time {
            Some(time) if time.kind() == point.event_type.time_tag() => {
                (point.event_type, Some(time))
            }
            _ => (untagged(point.event_type), None),
        };
        if time.is_none() && type_id.time_tag() != crate::asdu::TimeTagKind::None {
            // A type that exists only with a time tag and has none: nothing to answer with.
            tracing::warn!(ioa = %point.ioa, %type_id, "read of a point without a time tag");
            return self.reply(&raw, Cause::UNKNOWN_OBJECT_ADDRESS, true);
        }
        let mut answer = Asdu::new(
            type_id,
            Cot::new(Cause::REQUEST),
            self.outstation.config.common_address,
        );
        answer.objects.push(InformationObject {
            ioa: point.ioa,
            element: point.element,
            time,
        });
        if let Some(bytes) = encode(&answer, self.params()) {
            self.responses.push_back(bytes);
        }
    }

    fn handle_command(&mut self, now: Instant, raw: Vec<u8>, asdu: Asdu) {
        let mut cause = asdu.cot.cause;
        if cause == Cause::REQUEST && self.outstation.config.accept_request_as_activation {
            cause = Cause::ACTIVATION;
        }
        if cause != Cause::ACTIVATION && cause != Cause::DEACTIVATION {
            tracing::warn!(%cause, "command with a cause other than activation or deactivation");
            return self.reply(&raw, Cause::UNKNOWN_CAUSE, true);
        }
        let [object] = asdu.objects.as_slice() else {
            tracing::warn!(
                count = asdu.objects.len(),
                "a command must carry exactly one object"
            );
            return self.reply(&raw, Cause::ACTIVATION_CON, true);
        };
        let select = object.element.is_select();
        let key = object.ioa.get();
        let command = Command {
            type_id: asdu.type_id,
            common_address: asdu.common_address,
            ioa: object.ioa,
            element: object.element.clone(),
            time: object.time,
            originator: asdu.cot.originator,
            select,
            peer: self.peer.clone(),
        };
        let point = self.outstation.read_image().command(object.ioa).cloned();
        let Some(point) = point else {
            return self.refuse(&raw, &command, CommandRefusal::UnknownAddress);
        };
        if base_command_type(point.command_type) != base_command_type(asdu.type_id) {
            let expected = point.command_type;
            return self.refuse(&raw, &command, CommandRefusal::WrongType { expected });
        }
        if let Element::DoubleCommand { state, .. } = &object.element {
            if !matches!(state, DoublePointState::On | DoublePointState::Off) {
                return self.refuse(&raw, &command, CommandRefusal::StateNotPermitted);
            }
        }
        if cause == Cause::DEACTIVATION {
            let mut selections = self.outstation.lock_selections();
            let ours = selections
                .get(&key)
                .is_some_and(|selection| selection.link == self.id);
            if ours {
                selections.remove(&key);
            }
            drop(selections);
            return self.reply(&raw, Cause::DEACTIVATION_CON, !ours);
        }
        if let Some(limit) = point.max_age.or(self.outstation.config.max_command_age) {
            if let Err(refusal) = self.check_age(&command, limit) {
                return self.refuse(&raw, &command, refusal);
            }
        }
        let originator = asdu.cot.originator;
        let mut pending_selection = None;
        if select {
            pending_selection = Some(Selection {
                link: self.id,
                originator,
                type_id: asdu.type_id,
                element: object.element.as_execute(),
                deadline: now + self.outstation.config.select_timeout,
            });
        } else if point.select_required {
            let mut selections = self.outstation.lock_selections();
            let matches = selections.get(&key).is_some_and(|selection| {
                selection.link == self.id
                    && selection.originator == originator
                    && selection.type_id == asdu.type_id
                    && selection.element == object.element.as_execute()
                    && selection.deadline >= now
            });
            // A selection is used once, matched or not, but only by the connection that
            // made it: another connection's attempt must not cancel it.
            if selections
                .get(&key)
                .is_some_and(|selection| selection.link == self.id)
            {
                selections.remove(&key);
            }
            drop(selections);
            if !matches {
                return self.refuse(&raw, &command, CommandRefusal::NoSelection);
            }
        }
        tracing::info!(%command.type_id, ioa = %command.ioa, element = %command.element, select, "command");
        if self.pending_commands.len() >= MAX_PENDING_COMMANDS {
            return self.refuse(&raw, &command, CommandRefusal::TooManyPending);
        }
        // Return information of an execute that the application queues before it decides
        // (or while it does) must still follow the confirmation.
        let holds_return_from = (!select).then(|| self.group.lock().next_seq);
        let future = self.outstation.handler.handle_command(command);
        self.pending_commands.push(PendingCommand {
            future,
            request: raw,
            select,
            ioa: key,
            selection: pending_selection,
            holds_return_from,
        });
    }

    /// Checks a time-tagged command's age against the maximum command delay, on the
    /// station's clock with the tag read in the server's zone.
    fn check_age(&self, command: &Command, limit: Duration) -> Result<(), CommandRefusal> {
        let Some(TimeTag::Cp56(tag)) = command.time else {
            return Ok(());
        };
        let Some(sent) = self.outstation.config.time_zone.from_cp56(&tag) else {
            return Err(CommandRefusal::TimeUnusable);
        };
        if sent.invalid {
            return Err(CommandRefusal::TimeUnusable);
        }
        let now = self.outstation.handler.now();
        let age = now.signed_duration_since(sent.time);
        match age.to_std() {
            Ok(age) if age > limit => Err(CommandRefusal::Stale { age, limit }),
            Ok(_) => Ok(()),
            // Negative: the tag is ahead of the station's clock.
            Err(_) => match (-age).to_std() {
                Ok(ahead) if ahead > limit => Err(CommandRefusal::FromTheFuture { ahead, limit }),
                _ => Ok(()),
            },
        }
    }

    /// Refuses a command the server itself finds wrong: a negative confirmation (cause 47
    /// for an unknown address, else ACT_CON), a warning naming the peer, and the
    /// application told so that it can audit it.
    fn refuse(&mut self, raw: &[u8], command: &Command, refusal: CommandRefusal) {
        tracing::warn!(
            type_id = %command.type_id,
            ioa = %command.ioa,
            element = %command.element,
            select = command.select,
            reason = %refusal,
            "command refused"
        );
        self.outstation.handler.command_refused(command, &refusal);
        let cause = match refusal {
            CommandRefusal::UnknownAddress => Cause::UNKNOWN_OBJECT_ADDRESS,
            _ => Cause::ACTIVATION_CON,
        };
        self.reply(raw, cause, true);
    }

    fn finish_command(&mut self, reply: CommandReply) {
        let positive = reply.outcome.is_positive();
        tracing::info!(ioa = reply.ioa, select = reply.select, outcome = ?reply.outcome, "command outcome");
        if positive {
            if let Some(selection) = reply.selection {
                self.outstation
                    .lock_selections()
                    .insert(reply.ioa, selection);
            }
        }
        self.reply(&reply.request, Cause::ACTIVATION_CON, !positive);
        if reply.select {
            return;
        }
        match reply.outcome {
            CommandOutcome::Executed => self.terminate(&reply.request),
            CommandOutcome::Confirmed(future) => self.terminating.push(Terminating {
                future,
                request: reply.request,
            }),
            CommandOutcome::Refused => {}
        }
    }
}

/// Which of the group's events a connection may send now, keeping the command sequence:
/// nothing queued at or after a waiting termination's place, and no return information
/// (cause 11) queued since an execute arrived whose confirmation has not gone out yet.
struct EventGate {
    before_termination: Option<u64>,
    hold_return_from: Option<u64>,
}

impl EventGate {
    fn lets_through(&self, event: &QueuedEvent) -> bool {
        let after_termination = self
            .before_termination
            .is_some_and(|place| event.seq >= place);
        let held_return = self
            .hold_return_from
            .is_some_and(|from| event.seq >= from && event.cause == Cause::RETURN_REMOTE);
        !after_termination && !held_return
    }
}

/// Whether a point answers a (station or group) interrogation. Integrated totals answer
/// counter interrogation instead, and types that exist only with a time tag (protection
/// events) cannot be sent without one, as an interrogation must.
fn answers(point: &super::MonitorPoint, qualifier: u8) -> bool {
    !matches!(point.element, Element::IntegratedTotal(_))
        && untagged(point.event_type).time_tag() == crate::asdu::TimeTagKind::None
        && point.answers_interrogation(qualifier)
}

/// The type without time tag (`M_SP_TB_1` -> `M_SP_NA_1`); a type that has no such
/// twin stays as it is.
fn untagged(type_id: TypeId) -> TypeId {
    type_id.without_time().unwrap_or(type_id)
}

/// The untagged command type: `C_SC_TA_1` (58) -> `C_SC_NA_1` (45), and so on.
fn base_command_type(type_id: TypeId) -> u8 {
    let value = type_id as u8;
    if (58..=64).contains(&value) {
        value - 13
    } else {
        value
    }
}

fn objects_per_asdu(type_id: TypeId, params: &AsduParams) -> usize {
    let header = AsduHeader::header_len(params);
    let per_object = object_len(type_id, params, false).max(1);
    (params.max_asdu_len().saturating_sub(header) / per_object).clamp(1, 127)
}

fn encode(asdu: &Asdu, params: &AsduParams) -> Option<Vec<u8>> {
    let mut bytes = Vec::with_capacity(params.max_asdu_len());
    match asdu.encode(params, &mut bytes) {
        Ok(()) => Some(bytes),
        Err(error) => {
            tracing::error!(%error, type_id = %asdu.type_id, "cannot encode ASDU: dropped");
            None
        }
    }
}

/// A copy of a request with the common address replaced (a broadcast interrogation is
/// terminated with the station's own address).
fn with_station_address(raw: &[u8], params: &AsduParams, station: CommonAddress) -> Vec<u8> {
    let mut copy = raw.to_vec();
    let offset = 2 + usize::from(params.cot_size());
    let address = station.get().to_le_bytes();
    for (index, byte) in address
        .iter()
        .take(usize::from(params.common_address_size()))
        .enumerate()
    {
        if let Some(slot) = copy.get_mut(offset + index) {
            *slot = *byte;
        }
    }
    copy
}
