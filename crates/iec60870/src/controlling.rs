//! The controlling station (master) without a transport: the requests it has open and
//! how received ASDUs finish them, and what it sends when data transfer starts.
//!
//! ```text
//!  request ASDU ──> OpenRequests::open(now, asdu, reply)      (the adapter sends it)
//!  received ASDU ─> OpenRequests::offer(now, asdu) ──> (reply, RequestOutcome) when done
//!  deadline ──────> OpenRequests::expire(now) ───────> (reply, timed out / done)
//!  data transfer starts ─> start_requests(..) ───────> clock sync, interrogation
//! ```
//!
//! `R` is whatever the adapter answers a request through (a oneshot sender in the tokio
//! client, a token in a serial master or a test). Nothing here reads a clock: deadlines
//! are `Instant`s the caller gives. The IEC 104 client (`cs104::client`) is its tokio
//! adapter; the IEC 101 master will be another.

use std::time::{Duration, Instant};

use crate::asdu::{Asdu, Cause, CommonAddress, Cot, Element, InformationObject, Ioa, TypeId};
use crate::time::Cp56Time2a;

/// The confirmation a request received.
#[derive(Debug, Clone, PartialEq)]
pub struct RequestOutcome {
    /// The server confirmed positively (P/N = 0).
    pub positive: bool,
    /// The cause of the confirmation (7 actcon, 9 deactcon, or 44..47 for refusals).
    pub cause: Cause,
    /// An activation termination arrived (commands, interrogations).
    pub terminated: bool,
    /// Every ASDU of the exchange as received (confirmation, termination), in order.
    pub responses: Vec<Asdu>,
}

/// How an open request ended at its deadline.
#[derive(Debug, Clone, PartialEq)]
pub enum Expired {
    /// Confirmed, and the termination the station may leave out did not come: done.
    Done(RequestOutcome),
    /// Nothing came in time; says what was waited for ("the confirmation", "the
    /// activation termination").
    TimedOut(&'static str),
}

/// An open request: what it matches and where its answer goes.
#[derive(Debug)]
struct Open<R> {
    type_id: TypeId,
    ioa: Ioa,
    expects_termination: bool,
    /// The termination may not come: the standard leaves ACT_TERM of a command to the
    /// station (c104 sends none after a direct execute). Interrogations must terminate.
    termination_optional: bool,
    is_read: bool,
    responses: Vec<Asdu>,
    confirmation: Option<(bool, Cause)>,
    deadline: Instant,
    reply: R,
}

impl<R> Open<R> {
    fn outcome(&self) -> RequestOutcome {
        let (positive, cause) = self.confirmation.unwrap_or((false, Cause::ACTIVATION_CON));
        RequestOutcome {
            positive,
            cause,
            terminated: self.expects_termination && positive,
            responses: self.responses.clone(),
        }
    }

    /// Offers a received ASDU; returns whether the request is now finished.
    fn offer(
        &mut self,
        now: Instant,
        asdu: &Asdu,
        timeout: Duration,
        termination_timeout: Duration,
    ) -> bool {
        let Some(first) = asdu.objects.first() else {
            return false;
        };
        if self.is_read {
            if first.ioa != self.ioa {
                return false;
            }
            if asdu.cot.cause == Cause::REQUEST && !asdu.cot.negative {
                self.responses.push(asdu.clone());
                self.confirmation = Some((true, Cause::REQUEST));
                return true;
            }
            if asdu.type_id == self.type_id && asdu.cot.negative {
                self.responses.push(asdu.clone());
                self.confirmation = Some((false, asdu.cot.cause));
                return true;
            }
            return false;
        }
        if asdu.type_id != self.type_id || first.ioa != self.ioa {
            return false;
        }
        let cause = asdu.cot.cause;
        let is_confirmation = cause == Cause::ACTIVATION_CON
            || cause == Cause::DEACTIVATION_CON
            || (44..=47).contains(&cause.value());
        if is_confirmation && self.confirmation.is_none() {
            self.responses.push(asdu.clone());
            let positive = !asdu.cot.negative;
            self.confirmation = Some((positive, cause));
            if !positive || !self.expects_termination {
                return true;
            }
            // The termination has its own time allowance.
            let allowance = if self.termination_optional {
                termination_timeout
            } else {
                timeout
            };
            self.deadline = now + allowance;
            return false;
        }
        if cause == Cause::ACTIVATION_TERMINATION {
            self.responses.push(asdu.clone());
            if self.confirmation.is_none() {
                // Termination without confirmation: some stations skip ACT_CON.
                self.confirmation = Some((true, Cause::ACTIVATION_TERMINATION));
            }
            return true;
        }
        false
    }
}

/// The requests a controlling station has sent and not yet seen finished.
#[derive(Debug)]
pub struct OpenRequests<R> {
    open: Vec<Open<R>>,
    timeout: Duration,
    termination_timeout: Duration,
}

impl<R> OpenRequests<R> {
    /// No open request. A request waits `timeout` for its confirmation (and an
    /// interrogation as long again for its termination); a confirmed command waits
    /// `termination_timeout` for a termination the station may leave out.
    pub fn new(timeout: Duration, termination_timeout: Duration) -> Self {
        Self {
            open: Vec::new(),
            timeout,
            termination_timeout,
        }
    }

    /// Whether a request of this type to this address is open (the standard allows one
    /// at a time: its answers could not be told apart).
    pub fn is_open(&self, type_id: TypeId, ioa: Ioa) -> bool {
        self.open
            .iter()
            .any(|request| request.type_id == type_id && request.ioa == ioa)
    }

    /// Whether any request of this type is open.
    pub fn any_of_type(&self, type_id: TypeId) -> bool {
        self.open.iter().any(|request| request.type_id == type_id)
    }

    /// Opens a request that has just been sent.
    pub fn open(&mut self, now: Instant, asdu: &Asdu, reply: R) {
        self.open.push(Open {
            type_id: asdu.type_id,
            ioa: asdu
                .objects
                .first()
                .map(|object| object.ioa)
                .unwrap_or_default(),
            expects_termination: expects_termination(asdu),
            termination_optional: asdu.type_id.is_command(),
            is_read: asdu.type_id == TypeId::C_RD_NA_1,
            responses: Vec::new(),
            confirmation: None,
            deadline: now + self.timeout,
            reply,
        });
    }

    /// Offers a received ASDU to the open requests (the oldest that takes it); returns
    /// the request it finished, with its outcome.
    pub fn offer(&mut self, now: Instant, asdu: &Asdu) -> Option<(R, RequestOutcome)> {
        let (timeout, termination_timeout) = (self.timeout, self.termination_timeout);
        let index = self
            .open
            .iter_mut()
            .position(|request| request.offer(now, asdu, timeout, termination_timeout))?;
        let request = self.open.swap_remove(index);
        let outcome = request.outcome();
        Some((request.reply, outcome))
    }

    /// Ends the requests whose deadline has come.
    pub fn expire(&mut self, now: Instant) -> Vec<(R, Expired)> {
        let mut ended = Vec::new();
        let mut index = 0;
        while index < self.open.len() {
            if self
                .open
                .get(index)
                .is_some_and(|request| request.deadline <= now)
            {
                let mut request = self.open.swap_remove(index);
                let confirmed = request.confirmation.is_some_and(|(positive, _)| positive);
                let end = if confirmed && request.termination_optional {
                    // Confirmed, and the station sends no termination: done.
                    request.expects_termination = false;
                    Expired::Done(request.outcome())
                } else {
                    let waited_for = if request.confirmation.is_some() {
                        "the activation termination"
                    } else {
                        "the confirmation"
                    };
                    tracing::warn!(type_id = %request.type_id, ioa = %request.ioa, waited_for, "request timed out");
                    Expired::TimedOut(waited_for)
                };
                ended.push((request.reply, end));
            } else {
                index += 1;
            }
        }
        ended
    }

    /// The earliest deadline of an open request.
    pub fn next_deadline(&self) -> Option<Instant> {
        self.open.iter().map(|request| request.deadline).min()
    }

    /// Takes every open request (the link was lost).
    pub fn drain(&mut self) -> impl Iterator<Item = R> + '_ {
        self.open.drain(..).map(|request| request.reply)
    }
}

/// Whether a request is answered by an activation termination after its confirmation:
/// interrogations, and the execute of a command.
pub fn expects_termination(asdu: &Asdu) -> bool {
    match asdu.type_id {
        TypeId::C_IC_NA_1 | TypeId::C_CI_NA_1 => asdu.cot.cause == Cause::ACTIVATION,
        type_id if type_id.is_command() => {
            asdu.cot.cause == Cause::ACTIVATION
                && !asdu
                    .objects
                    .first()
                    .is_some_and(|object| object.element.is_select())
        }
        _ => false,
    }
}

/// What a controlling station sends each time data transfer starts, in order: a clock
/// synchronisation to `clock` (when given), then a station interrogation (when asked).
pub fn start_requests(
    common_address: CommonAddress,
    originator: u8,
    clock: Option<Cp56Time2a>,
    interrogate: bool,
) -> Vec<Asdu> {
    let request = |type_id: TypeId, element: Element| {
        let mut asdu = Asdu::new(type_id, Cot::new(Cause::ACTIVATION), common_address);
        asdu.cot.originator = originator;
        asdu.objects.push(InformationObject {
            ioa: Ioa::default(),
            element,
            time: None,
        });
        asdu
    };
    let mut requests = Vec::new();
    if let Some(time) = clock {
        requests.push(request(TypeId::C_CS_NA_1, Element::ClockSync { time }));
    }
    if interrogate {
        requests.push(request(
            TypeId::C_IC_NA_1,
            Element::Interrogation { qualifier: 20 },
        ));
    }
    requests
}

#[cfg(test)]
#[allow(clippy::disallowed_methods)] // Instant::now as the base of the tests' own clock
mod tests {
    use super::*;
    use crate::asdu::CommandQualifier;

    fn command(select: bool) -> Asdu {
        let mut asdu = Asdu::new(TypeId::C_SC_NA_1, Cause::ACTIVATION, CommonAddress::new(1));
        let qualifier = if select {
            CommandQualifier::SELECT
        } else {
            CommandQualifier::EXECUTE
        };
        asdu.objects.push(InformationObject::new(
            Ioa::try_new(5).unwrap(),
            Element::SingleCommand {
                on: true,
                qualifier,
            },
        ));
        asdu
    }

    fn answer(request: &Asdu, cause: Cause, negative: bool) -> Asdu {
        let mut asdu = request.clone();
        asdu.cot = Cot::new(cause);
        asdu.cot.negative = negative;
        asdu
    }

    #[test]
    fn an_execute_finishes_at_its_termination_and_a_select_at_its_confirmation() {
        let t0 = Instant::now();
        let mut open = OpenRequests::new(Duration::from_secs(5), Duration::from_secs(1));
        let execute = command(false);
        open.open(t0, &execute, "execute");
        assert!(open.is_open(TypeId::C_SC_NA_1, Ioa::try_new(5).unwrap()));
        assert!(open
            .offer(t0, &answer(&execute, Cause::ACTIVATION_CON, false))
            .is_none());
        let (reply, outcome) = open
            .offer(t0, &answer(&execute, Cause::ACTIVATION_TERMINATION, false))
            .unwrap();
        assert_eq!(reply, "execute");
        assert!(outcome.positive && outcome.terminated);
        assert_eq!(outcome.responses.len(), 2);

        let select = command(true);
        open.open(t0, &select, "select");
        let (reply, outcome) = open
            .offer(t0, &answer(&select, Cause::ACTIVATION_CON, false))
            .unwrap();
        assert_eq!(reply, "select");
        assert!(outcome.positive && !outcome.terminated);
    }

    #[test]
    fn a_confirmed_command_without_termination_is_done_at_the_termination_allowance() {
        let t0 = Instant::now();
        let mut open = OpenRequests::new(Duration::from_secs(5), Duration::from_secs(1));
        let execute = command(false);
        open.open(t0, &execute, 1);
        open.offer(t0, &answer(&execute, Cause::ACTIVATION_CON, false));
        assert_eq!(open.next_deadline(), Some(t0 + Duration::from_secs(1)));
        assert!(open.expire(t0 + Duration::from_millis(999)).is_empty());
        let ended = open.expire(t0 + Duration::from_secs(1));
        assert!(matches!(
            ended.as_slice(),
            [(
                1,
                Expired::Done(RequestOutcome {
                    positive: true,
                    terminated: false,
                    ..
                })
            )]
        ));
    }

    #[test]
    fn an_unanswered_request_times_out_waiting_for_its_confirmation() {
        let t0 = Instant::now();
        let mut open = OpenRequests::new(Duration::from_secs(5), Duration::from_secs(1));
        open.open(t0, &command(false), ());
        let ended = open.expire(t0 + Duration::from_secs(5));
        assert_eq!(ended, [((), Expired::TimedOut("the confirmation"))]);
        assert_eq!(open.next_deadline(), None);
    }

    #[test]
    fn start_requests_are_the_clock_then_the_interrogation() {
        let requests = start_requests(CommonAddress::new(7), 3, Some(Cp56Time2a::default()), true);
        let kinds: Vec<TypeId> = requests.iter().map(|asdu| asdu.type_id).collect();
        assert_eq!(kinds, [TypeId::C_CS_NA_1, TypeId::C_IC_NA_1]);
        assert!(requests.iter().all(|asdu| asdu.cot.originator == 3));
        assert!(start_requests(CommonAddress::new(7), 0, None, false).is_empty());
    }
}
