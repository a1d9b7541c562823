//! The policy, sans-IO: which rules a notice matches, and for each of their channels
//! whether to send or why not (quiet period, rate limit). No clock: time is a parameter.

use std::collections::{HashMap, VecDeque};

use chrono::{DateTime, TimeDelta, Utc};
use serde::{Deserialize, Serialize};

use crate::config::{RateLimit, RuleConfig};
use crate::notice::Notice;
use crate::pattern::{any_matches, Pattern};

/// How many quiet-period keys are kept before expired ones are swept.
const SWEEP_THRESHOLD: usize = 1024;

/// What to do for one (rule, channel) of a notice.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Decision {
    /// The rule's name.
    pub rule: String,
    /// The channel's name.
    pub channel: String,
    /// Send, or why not.
    pub verdict: Verdict,
}

/// Send or suppress.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub enum Verdict {
    /// Deliver on the channel.
    Send,
    /// Do not; recorded as suppressed.
    Suppressed(SuppressReason),
}

/// Why a notification was not sent.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[non_exhaustive]
pub enum SuppressReason {
    /// The rule notified for this source and class less than its quiet period ago.
    QuietPeriod {
        /// When the quiet period ends.
        until: DateTime<Utc>,
    },
    /// The rule reached its rate limit.
    RateLimit {
        /// When the oldest notification of the window leaves it.
        until: DateTime<Utc>,
    },
    /// The notifier's queue was full (the background form only).
    QueueFull,
}

impl std::fmt::Display for SuppressReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SuppressReason::QuietPeriod { until } => {
                write!(
                    f,
                    "quiet period until {}",
                    until.to_rfc3339_opts(chrono::SecondsFormat::AutoSi, true)
                )
            }
            SuppressReason::RateLimit { until } => {
                write!(
                    f,
                    "rate limit until {}",
                    until.to_rfc3339_opts(chrono::SecondsFormat::AutoSi, true)
                )
            }
            SuppressReason::QueueFull => f.write_str("queue full"),
        }
    }
}

/// A rule ready for matching.
#[derive(Debug, Clone)]
struct Rule {
    name: String,
    sources: Vec<Pattern>,
    classes: Vec<Pattern>,
    channels: Vec<String>,
    quiet: TimeDelta,
    rate: Option<(usize, TimeDelta)>,
    /// Times of this rule's notifications within the rate window, oldest first.
    sent: VecDeque<DateTime<Utc>>,
}

/// The state of all rules: when each (rule, source, class) last notified, and the
/// recent notifications of each rule.
///
/// Quiet period: after a notice of (rule, source, class) is sent, further notices of the
/// same key are suppressed until `quiet_period_s` has passed. Suppressed notices do not
/// extend it. Rate limit: at most `max` sent notices per rule within any `per_s` seconds
/// (a sliding window); a notice counts once however many channels the rule has. A notice
/// suppressed by either does not count.
///
/// Time going backwards (a clock step) ends quiet periods and rate windows early rather
/// than stretching them: a notification too many beats a silent day.
#[derive(Debug, Clone)]
pub struct Policy {
    rules: Vec<Rule>,
    /// (rule index, source, class) -> last sent.
    last: HashMap<(usize, String, String), DateTime<Utc>>,
}

impl Policy {
    /// A policy for `rules` (already validated: see [`crate::NotifyConfig::validate`]).
    pub fn new(rules: &[RuleConfig]) -> Policy {
        let rules = rules
            .iter()
            .map(|rule| Rule {
                name: rule.name.clone(),
                sources: rule.sources.clone(),
                classes: rule.classes.clone(),
                channels: rule.channels.clone(),
                quiet: seconds(rule.quiet_period_s),
                rate: rule.rate_limit.map(|RateLimit { max, per_s }| {
                    (usize::try_from(max).unwrap_or(usize::MAX), seconds(per_s))
                }),
                sent: VecDeque::new(),
            })
            .collect();
        Policy {
            rules,
            last: HashMap::new(),
        }
    }

    /// The decisions for `notice` at `now`: one per channel of every matching rule, in
    /// rule order then channel order. Empty when no rule matches. Records the sends.
    pub fn decide(&mut self, notice: &Notice, now: DateTime<Utc>) -> Vec<Decision> {
        if self.last.len() > SWEEP_THRESHOLD {
            self.sweep(now);
        }
        let mut decisions = Vec::new();
        for (index, rule) in self.rules.iter_mut().enumerate() {
            if !any_matches(&rule.sources, &notice.source)
                || !any_matches(&rule.classes, &notice.class)
            {
                continue;
            }
            let verdict = judge(rule, index, &mut self.last, notice, now);
            decisions.extend(rule.channels.iter().map(|channel| Decision {
                rule: rule.name.clone(),
                channel: channel.clone(),
                verdict: verdict.clone(),
            }));
        }
        decisions
    }

    /// The channels `notice` would go to, without deciding or recording anything: what
    /// the notifier records as suppressed when its queue is full.
    pub fn targets(&self, notice: &Notice) -> Vec<(String, String)> {
        self.rules
            .iter()
            .filter(|rule| {
                any_matches(&rule.sources, &notice.source)
                    && any_matches(&rule.classes, &notice.class)
            })
            .flat_map(|rule| {
                rule.channels
                    .iter()
                    .map(|channel| (rule.name.clone(), channel.clone()))
            })
            .collect()
    }

    /// Forgets quiet-period keys whose period is over.
    fn sweep(&mut self, now: DateTime<Utc>) {
        let rules = &self.rules;
        self.last.retain(|(index, _, _), last| {
            rules
                .get(*index)
                .is_some_and(|rule| *last <= now && now < *last + rule.quiet)
        });
    }
}

/// The verdict of one matching rule; records a send.
fn judge(
    rule: &mut Rule,
    index: usize,
    last: &mut HashMap<(usize, String, String), DateTime<Utc>>,
    notice: &Notice,
    now: DateTime<Utc>,
) -> Verdict {
    let key = (index, notice.source.clone(), notice.class.clone());
    if let Some(previous) = last.get(&key) {
        let until = *previous + rule.quiet;
        if *previous <= now && now < until {
            return Verdict::Suppressed(SuppressReason::QuietPeriod { until });
        }
    }
    if let Some((max, window)) = rule.rate {
        // Keep only the sends of the window ending now (and none "from the future").
        rule.sent
            .retain(|sent| *sent <= now && now < *sent + window);
        if rule.sent.len() >= max {
            let until = rule.sent.front().map_or(now, |oldest| *oldest + window);
            return Verdict::Suppressed(SuppressReason::RateLimit { until });
        }
        rule.sent.push_back(now);
    }
    last.insert(key, now);
    Verdict::Send
}

fn seconds(seconds: u64) -> TimeDelta {
    TimeDelta::try_seconds(i64::try_from(seconds).unwrap_or(i64::MAX)).unwrap_or(TimeDelta::MAX)
}

#[cfg(test)]
mod tests {
    use super::*;
    use chrono::TimeZone;
    use proptest::prelude::*;

    fn notice(source: &str, class: &str) -> Notice {
        Notice {
            source: source.into(),
            class: class.into(),
            code: Some(17),
            title: "Porucha".into(),
            text: "Bezpečnostní okruh rozpojen".into(),
            time: t0(),
            link: None,
        }
    }

    fn t0() -> DateTime<Utc> {
        Utc.with_ymd_and_hms(2026, 3, 1, 8, 0, 0).unwrap()
    }

    fn at(s: i64) -> DateTime<Utc> {
        t0() + TimeDelta::seconds(s)
    }

    fn rule(name: &str, quiet: u64, rate: Option<(u32, u64)>) -> RuleConfig {
        let mut rule = RuleConfig::new(name, vec!["mail".into(), "hook".into()]);
        rule.quiet_period_s = quiet;
        rule.rate_limit = rate.map(|(max, per_s)| RateLimit { max, per_s });
        rule
    }

    fn sends(decisions: &[Decision]) -> usize {
        decisions
            .iter()
            .filter(|d| d.verdict == Verdict::Send)
            .count()
    }

    #[test]
    fn matching_by_source_and_class() {
        let mut lifts = rule("lifts", 0, None);
        lifts.sources = vec![Pattern::new("L*")];
        lifts.classes = vec![Pattern::new("door"), Pattern::new("safety-*")];
        let mut policy = Policy::new(&[lifts]);
        assert_eq!(policy.decide(&notice("L3", "door"), at(0)).len(), 2);
        assert_eq!(
            policy.decide(&notice("L3", "safety-circuit"), at(0)).len(),
            2
        );
        assert!(policy.decide(&notice("L3", "comm-lost"), at(0)).is_empty());
        assert!(policy.decide(&notice("P1", "door"), at(0)).is_empty());
        let decisions = policy.decide(&notice("L1", "door"), at(0));
        assert_eq!(decisions[0].rule, "lifts");
        assert_eq!(decisions[0].channel, "mail");
        assert_eq!(decisions[1].channel, "hook");
    }

    #[test]
    fn quiet_period_per_source_and_class() {
        let mut policy = Policy::new(&[rule("r", 600, None)]);
        assert_eq!(sends(&policy.decide(&notice("L1", "door"), at(0))), 2);
        let quiet = policy.decide(&notice("L1", "door"), at(599));
        assert_eq!(
            quiet[0].verdict,
            Verdict::Suppressed(SuppressReason::QuietPeriod { until: at(600) })
        );
        // Another class and another source are other keys.
        assert_eq!(sends(&policy.decide(&notice("L1", "comm-lost"), at(1))), 2);
        assert_eq!(sends(&policy.decide(&notice("L2", "door"), at(1))), 2);
        // Suppressed notices do not extend the period.
        assert_eq!(sends(&policy.decide(&notice("L1", "door"), at(600))), 2);
    }

    #[test]
    fn rate_limit_sliding_window() {
        let mut policy = Policy::new(&[rule("r", 0, Some((2, 60)))]);
        assert_eq!(sends(&policy.decide(&notice("L1", "a"), at(0))), 2);
        assert_eq!(sends(&policy.decide(&notice("L2", "b"), at(10))), 2);
        let limited = policy.decide(&notice("L3", "c"), at(20));
        assert_eq!(
            limited[0].verdict,
            Verdict::Suppressed(SuppressReason::RateLimit { until: at(60) })
        );
        assert_eq!(sends(&policy.decide(&notice("L3", "c"), at(60))), 2);
        assert_eq!(sends(&policy.decide(&notice("L3", "d"), at(65))), 0);
        assert_eq!(sends(&policy.decide(&notice("L3", "d"), at(70))), 2);
    }

    #[test]
    fn rules_are_independent() {
        let mut policy = Policy::new(&[rule("a", 600, None), rule("b", 0, None)]);
        assert_eq!(sends(&policy.decide(&notice("L1", "door"), at(0))), 4);
        assert_eq!(sends(&policy.decide(&notice("L1", "door"), at(1))), 2);
    }

    #[test]
    fn clock_stepping_back_does_not_silence() {
        let mut policy = Policy::new(&[rule("r", 600, Some((1, 3600)))]);
        assert_eq!(sends(&policy.decide(&notice("L1", "door"), at(10_000))), 2);
        assert_eq!(sends(&policy.decide(&notice("L1", "door"), at(0))), 2);
    }

    #[test]
    fn sweep_keeps_live_keys() {
        let mut policy = Policy::new(&[rule("r", 100, None)]);
        for i in 0..=SWEEP_THRESHOLD {
            policy.decide(&notice(&format!("S{i}"), "x"), at(0));
        }
        policy.decide(&notice("late", "x"), at(50));
        assert_eq!(sends(&policy.decide(&notice("late", "x"), at(60))), 0);
        policy.decide(&notice("later", "x"), at(200));
        assert!(policy.last.len() < 10);
    }

    proptest! {
        /// For any monotonic sequence of notices: sends per rule within any window never
        /// exceed the limit, and no key is sent twice within its quiet period.
        #[test]
        fn limits_hold(
            steps in proptest::collection::vec((0i64..400, 0usize..3, 0usize..3), 1..200),
            max in 1u32..5,
            per_s in 1u64..1000,
            quiet in 0u64..500,
        ) {
            let rules = [rule("a", quiet, Some((max, per_s))), rule("b", quiet / 2, None)];
            let mut policy = Policy::new(&rules);
            let mut now = t0();
            let mut sent: Vec<(String, String, String, DateTime<Utc>)> = Vec::new();
            for (dt, source, class) in steps {
                now += TimeDelta::seconds(dt);
                let n = notice(&format!("L{source}"), &format!("c{class}"));
                let decisions = policy.decide(&n, now);
                prop_assert_eq!(decisions.len(), 4);
                for rule in ["a", "b"] {
                    let verdicts: Vec<_> = decisions.iter().filter(|d| d.rule == rule).collect();
                    // One verdict per rule, the same for each of its channels.
                    prop_assert_eq!(&verdicts[0].verdict, &verdicts[1].verdict);
                    if verdicts[0].verdict == Verdict::Send {
                        sent.push((rule.into(), n.source.clone(), n.class.clone(), now));
                    }
                }
            }
            let window = TimeDelta::seconds(per_s as i64);
            for (i, (rule, _, _, start)) in sent.iter().enumerate() {
                if rule == "a" {
                    let in_window = sent[i..]
                        .iter()
                        .filter(|(r, _, _, t)| r == "a" && *t < *start + window)
                        .count();
                    prop_assert!(in_window <= max as usize, "{} sends in a window", in_window);
                }
                let quiet_of = if rule == "a" { quiet } else { quiet / 2 };
                let again = sent[i + 1..].iter().find(|(r, s, c, _)| {
                    (r, s, c) == (&sent[i].0, &sent[i].1, &sent[i].2)
                });
                if let Some((_, _, _, next)) = again {
                    prop_assert!(*next >= *start + TimeDelta::seconds(quiet_of as i64));
                }
            }
        }
    }
}
