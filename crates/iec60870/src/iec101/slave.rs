//! The IEC 101 controlled station on an unbalanced line: the outstation core behind an
//! FT1.2 secondary.

use std::collections::VecDeque;
use std::sync::Arc;
use std::task::{Context, Poll};
use std::time::Instant;

use crate::ft12::{
    Balanced, BalancedEvent, LineEndpoint, LineSettings, PrimaryFunction, SecondaryApplication,
    TimedApplication,
};
use crate::outstation::{GroupChanges, LinkCore, LinkLayer, Outstation, Peer};

/// ASDUs the core may hand to the link ahead of the master's class 1 polls. The rest
/// stays in the redundancy group's buffer, where it survives a dead line.
const CLASS1_WINDOW: usize = 4;

/// The link layer as the outstation core sees it: a short queue of class 1 data that
/// the master's polls empty.
#[derive(Debug, Default)]
struct Class1Queue {
    started: bool,
    asdus: VecDeque<Vec<u8>>,
}

impl LinkLayer for Class1Queue {
    fn can_send(&self) -> bool {
        self.started && self.asdus.len() < CLASS1_WINDOW
    }

    fn send_asdu(&mut self, _now: Instant, asdu: &[u8]) -> bool {
        self.asdus.push_back(asdu.to_vec());
        true
    }

    fn unconfirmed(&self) -> usize {
        self.asdus.len()
    }

    fn hand_over(&mut self) -> usize {
        self.started = false;
        let count = self.asdus.len();
        self.asdus.clear();
        count
    }

    fn take_back(&mut self) {
        self.started = true;
    }
}

/// An [`Outstation`]'s link on an unbalanced IEC 101 line.
///
/// The master's reset of the remote link starts data transfer (IEC 101 has no STARTDT);
/// its user data goes to the core (interrogation, clock sync, commands); everything the
/// core sends (answers, events, interrogation replies) is class 1 data, announced to
/// the master with ACD. An ASDU counts as delivered once it has been answered to a
/// poll: the FT1.2 secondary repeats its last answer when the master's next frame
/// repeats the FCB, so a lost answer is not lost.
#[derive(Debug)]
pub struct Slave {
    core: LinkCore,
    queue: Class1Queue,
    changes: GroupChanges,
    seen: u64,
    now: Instant,
}

impl Slave {
    /// The link `id` of `outstation` on a serial line to `peer` (the name its log and
    /// handler see); `None` when no redundancy group takes the peer.
    pub fn new(outstation: &Arc<Outstation>, id: u64, peer: Peer, now: Instant) -> Option<Slave> {
        let core = outstation.open_link(id, peer)?;
        let changes = core.changes();
        Some(Slave {
            seen: changes.version(),
            core,
            queue: Class1Queue::default(),
            changes,
            now,
        })
    }

    /// Why the core wants the link closed (a flood of malformed ASDUs), if it does.
    pub fn close_reason(&self) -> Option<String> {
        self.core.close_reason()
    }

    /// Closes the link: what is in flight goes back to the group's buffer.
    pub fn close(self) {
        self.core.close(&self.queue);
    }

    fn fill(&mut self) {
        self.core.check_still_active(&mut self.queue);
        self.core.fill(self.now, &mut self.queue);
    }
}

impl SecondaryApplication for Slave {
    fn link_reset(&mut self, function: PrimaryFunction) {
        if function == PrimaryFunction::ResetRemoteLink {
            if self.queue.started {
                // A master that resets again lost its state: what it had not polled
                // yet goes back to the group and is sent again.
                self.core.stop(&self.queue);
                self.queue.asdus.clear();
            }
            self.queue.started = true;
            self.core.start();
            self.fill();
        }
    }

    fn user_data(&mut self, asdu: &[u8], _broadcast: bool) -> bool {
        self.core.handle_asdu(self.now, asdu.to_vec());
        self.fill();
        true
    }

    fn has_class1(&self) -> bool {
        !self.queue.asdus.is_empty()
    }

    fn class1(&mut self) -> Option<Vec<u8>> {
        let asdu = self.queue.asdus.pop_front();
        if asdu.is_some() {
            self.core.acknowledged(&self.queue);
        }
        self.fill();
        asdu
    }

    fn class2(&mut self) -> Option<Vec<u8>> {
        None
    }
}

impl TimedApplication for Slave {
    fn handle_timeout(&mut self, now: Instant) {
        self.now = now;
        self.fill();
    }

    fn next_deadline(&self) -> Option<Instant> {
        None
    }

    fn poll_wake(&mut self, context: &mut Context<'_>) -> Poll<()> {
        poll_outstation(&mut self.core, &self.changes, &mut self.seen, context)
    }
}

/// The balanced link as the outstation core sees it: user data it sends as primary,
/// confirmed by the other end one at a time.
impl LinkLayer for Balanced {
    fn can_send(&self) -> bool {
        self.is_up() && self.unconfirmed() < CLASS1_WINDOW
    }

    fn send_asdu(&mut self, _now: Instant, asdu: &[u8]) -> bool {
        Balanced::send(self, asdu.to_vec());
        true
    }

    fn unconfirmed(&self) -> usize {
        Balanced::unconfirmed(self)
    }

    fn hand_over(&mut self) -> usize {
        0
    }

    fn take_back(&mut self) {}
}

/// An [`Outstation`]'s link on a balanced (point-to-point) IEC 101 line: it sends its
/// data as soon as it has it, as a primary station, instead of waiting for polls.
#[derive(Debug)]
pub struct BalancedSlave {
    core: LinkCore,
    link: Balanced,
    changes: GroupChanges,
    seen: u64,
    started: bool,
}

impl BalancedSlave {
    /// The link `id` of `outstation` to `peer` over the balanced link `link`.
    pub fn new(outstation: &Arc<Outstation>, id: u64, peer: Peer, link: Balanced) -> Option<Self> {
        let core = outstation.open_link(id, peer)?;
        let changes = core.changes();
        Some(BalancedSlave {
            seen: changes.version(),
            core,
            link,
            changes,
            started: false,
        })
    }

    /// Closes the link: what is in flight goes back to the group's buffer.
    pub fn close(self) {
        self.core.close(&self.link);
    }

    fn process(&mut self, now: Instant) {
        while let Some(event) = self.link.poll_event() {
            match event {
                BalancedEvent::LinkUp if !self.started => {
                    self.started = true;
                    self.core.start();
                }
                BalancedEvent::LinkDown => {
                    self.started = false;
                    self.core.stop(&self.link);
                }
                BalancedEvent::UserData(asdu) => self.core.handle_asdu(now, asdu),
                BalancedEvent::Confirmed => self.core.acknowledged(&self.link),
                _ => {}
            }
        }
        self.core.check_still_active(&mut self.link);
        self.core.fill(now, &mut self.link);
    }
}

impl LineEndpoint for BalancedSlave {
    fn handle_bytes(&mut self, now: Instant, bytes: &[u8]) {
        self.link.handle_bytes(now, bytes);
        self.process(now);
    }

    fn handle_line_pause(&mut self, now: Instant) {
        self.link.handle_line_pause(now);
        self.process(now);
    }

    fn handle_timeout(&mut self, now: Instant) {
        self.link.handle_timeout(now);
        self.process(now);
    }

    fn poll_transmit(&mut self, now: Instant) -> Option<Vec<u8>> {
        let bytes = self.link.poll_transmit(now);
        self.process(now);
        bytes
    }

    fn next_deadline(&self) -> Option<Instant> {
        self.link.next_deadline()
    }

    fn line(&self) -> LineSettings {
        self.link.line()
    }

    fn poll_wake(&mut self, context: &mut Context<'_>) -> Poll<()> {
        poll_outstation(&mut self.core, &self.changes, &mut self.seen, context)
    }
}

/// Ready when a command's outcome came in or the redundancy group changed (an event
/// queued) since `seen`; registers the context's waker with both otherwise.
fn poll_outstation(
    core: &mut LinkCore,
    changes: &GroupChanges,
    seen: &mut u64,
    context: &mut Context<'_>,
) -> Poll<()> {
    if core.awaits_commands() && core.poll_commands(context).is_ready() {
        return Poll::Ready(());
    }
    let version = changes.version();
    if version != *seen {
        *seen = version;
        return Poll::Ready(());
    }
    changes.poll_changed(*seen, context)
}
