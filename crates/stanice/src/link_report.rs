//! How the serial masters (`iec101 master`, `iec103 master`) speak of their link layer:
//! its events in words, and the stations a master never reached.
//!
//! A master whose station never answers (a wrong `--address`, a cable on the wrong port)
//! used to print its banner and exit 0, and `--verbose` showed Rust structures. It now
//! says which station does not answer to what, once, when the first request has used up
//! its repeats, and ends with exit code 2 naming the stations never reached.

use std::collections::BTreeSet;
use std::process::ExitCode;

use iec60870::ft12::{Answer, PrimaryEvent, PrimaryFunction};

/// Exit code of a master that never reached one of its stations (as `iec104 command`
/// for no connection).
pub(crate) const NOT_REACHED: u8 = 2;

/// A link function's name in the words of IEC 60870-5-2.
pub(crate) fn function_name(function: PrimaryFunction) -> String {
    match function {
        PrimaryFunction::ResetRemoteLink => "reset of remote link".to_owned(),
        PrimaryFunction::ResetUserProcess => "reset of user process".to_owned(),
        PrimaryFunction::TestLink => "test function for link".to_owned(),
        PrimaryFunction::UserDataConfirmed => "user data (send/confirm)".to_owned(),
        PrimaryFunction::UserDataNoReply => "user data (send/no reply)".to_owned(),
        PrimaryFunction::ResetFcb => "reset of frame count bit".to_owned(),
        PrimaryFunction::RequestAccessDemand => "request for access demand".to_owned(),
        PrimaryFunction::RequestLinkStatus => "request status of link".to_owned(),
        PrimaryFunction::RequestClass1 => "request user data class 1".to_owned(),
        PrimaryFunction::RequestClass2 => "request user data class 2".to_owned(),
        PrimaryFunction::Other(code) => format!("function code {code}"),
    }
}

/// An answer's name.
pub(crate) fn answer_name(answer: &Answer) -> String {
    match answer {
        Answer::Ack => "ACK".to_owned(),
        Answer::Busy => "NACK (busy)".to_owned(),
        Answer::UserData(asdu) => format!("user data ({} octets)", asdu.len()),
        Answer::NoData => "NACK (no data)".to_owned(),
        Answer::LinkStatus => "status of link".to_owned(),
        Answer::NotFunctioning => "link service not functioning".to_owned(),
        Answer::NotImplemented => "link service not implemented".to_owned(),
    }
}

/// A link-layer event of an unbalanced master in words (for `--verbose`).
pub(crate) fn primary_event_text(event: &PrimaryEvent) -> String {
    match event {
        PrimaryEvent::Exchange {
            address,
            request,
            answer,
            acd,
            dfc,
        } => {
            let mut text = format!(
                "station {address}: {} answered with {}",
                function_name(*request),
                answer_name(answer)
            );
            if *acd {
                text.push_str(", class 1 data waiting (ACD)");
            }
            if *dfc {
                text.push_str(", busy (DFC)");
            }
            text
        }
        PrimaryEvent::Broadcast { function } => {
            format!("broadcast: {}", function_name(*function))
        }
        PrimaryEvent::Timeout {
            address,
            request,
            attempt,
        } => format!(
            "station {address}: no answer to {} (attempt {attempt})",
            function_name(*request)
        ),
        PrimaryEvent::LinkUp { address } => format!("station {address}: link up"),
        PrimaryEvent::LinkDown { address } => format!("station {address}: link down"),
        PrimaryEvent::Undelivered { address, asdu } => format!(
            "station {address}: user data not delivered ({} octets), the station failed",
            asdu.len()
        ),
        PrimaryEvent::LineError(error) => format!("line error: {error}"),
    }
}

/// Which of a master's stations answered.
#[derive(Debug)]
pub(crate) struct Reach {
    /// The link addresses the master polls.
    expected: Vec<u16>,
    /// The attempts of a request (1 + repeats): its last timeout means no answer at all.
    attempts: u8,
    /// Stations whose link came up at least once.
    reached: BTreeSet<u16>,
    /// Stations already said not to answer.
    told: BTreeSet<u16>,
}

impl Reach {
    /// A master polling `expected`, each request sent `1 + retries` times.
    pub(crate) fn new(expected: &[u16], retries: u8) -> Reach {
        Reach {
            expected: expected.to_vec(),
            attempts: retries.saturating_add(1),
            reached: BTreeSet::new(),
            told: BTreeSet::new(),
        }
    }

    /// A station's link came up.
    pub(crate) fn link_up(&mut self, address: u16) {
        self.reached.insert(address);
    }

    /// A request to a station timed out; the first time a station never reached has used
    /// up a request's repeats, the sentence that says so.
    pub(crate) fn timed_out(
        &mut self,
        address: u16,
        request: PrimaryFunction,
        attempt: u8,
    ) -> Option<String> {
        if attempt < self.attempts || self.reached.contains(&address) || !self.told.insert(address)
        {
            return None;
        }
        Some(format!(
            "station {address} does not answer: no reply to {} after {} attempt(s) (is its \
             link address {address}, and the line's speed and parity its own?)",
            function_name(request),
            self.attempts
        ))
    }

    /// Follows an unbalanced master's link event: a link up, or the sentence for a
    /// station that does not answer ([`Reach::timed_out`]).
    pub(crate) fn observe(&mut self, event: &PrimaryEvent) -> Option<String> {
        match event {
            PrimaryEvent::LinkUp { address } => {
                self.link_up(*address);
                None
            }
            PrimaryEvent::Timeout {
                address,
                request,
                attempt,
            } => self.timed_out(*address, *request, *attempt),
            _ => None,
        }
    }

    /// The command's exit: success when every station was reached, else [`NOT_REACHED`]
    /// after saying which were not.
    pub(crate) fn verdict(&self, line: &str) -> ExitCode {
        let missing: Vec<String> = self
            .expected
            .iter()
            .filter(|address| !self.reached.contains(address))
            .map(u16::to_string)
            .collect();
        if missing.is_empty() {
            return ExitCode::SUCCESS;
        }
        eprintln!(
            "never reached station(s) {} on {line}: no answer",
            missing.join(", ")
        );
        ExitCode::from(NOT_REACHED)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_station_that_never_answers_is_told_once_and_fails_the_command() {
        let mut reach = Reach::new(&[3, 4], 2);
        reach.link_up(3);
        assert_eq!(
            reach.timed_out(4, PrimaryFunction::RequestLinkStatus, 1),
            None
        );
        let told = reach.timed_out(4, PrimaryFunction::RequestLinkStatus, 3);
        assert!(
            told.as_deref()
                .is_some_and(|text| text.contains("station 4 does not answer")
                    && text.contains("request status of link")),
            "{told:?}"
        );
        assert_eq!(
            reach.timed_out(4, PrimaryFunction::RequestLinkStatus, 3),
            None
        );
        // A reached station's later silence is the link-down news, not this.
        assert_eq!(reach.timed_out(3, PrimaryFunction::RequestClass2, 3), None);
        assert_eq!(reach.verdict("test"), ExitCode::from(NOT_REACHED));
        reach.link_up(4);
        assert_eq!(reach.verdict("test"), ExitCode::SUCCESS);
    }

    #[test]
    fn events_are_words_not_structures() {
        let text = primary_event_text(&PrimaryEvent::Timeout {
            address: 4,
            request: PrimaryFunction::RequestLinkStatus,
            attempt: 1,
        });
        assert_eq!(
            text,
            "station 4: no answer to request status of link (attempt 1)"
        );
        assert!(!text.contains('{'));
    }
}
