//! Field device models. Each one is a small state machine with absolute deadlines: it is
//! driven at a time `now`, reports its next deadline and fires when the plant reaches it.

use std::time::Duration;

use crate::core::SimTime;

fn min_opt(a: Option<SimTime>, b: Option<SimTime>) -> Option<SimTime> {
    match (a, b) {
        (Some(x), Some(y)) => Some(x.min(y)),
        (x, None) => x,
        (None, y) => y,
    }
}

/// Earliest of several optional deadlines.
pub(crate) fn earliest(it: impl IntoIterator<Item = Option<SimTime>>) -> Option<SimTime> {
    it.into_iter().fold(None, min_opt)
}

/// A boolean that follows a demanded value after a pick-up (false -> true) or drop-out
/// (true -> false) delay: relays, contactors, lamp feedback.
///
/// A demand that reverts before the delay has elapsed cancels the pending change.
#[derive(Debug, Clone)]
pub(crate) struct Delayed {
    value: bool,
    target: bool,
    due: Option<SimTime>,
    on_delay: Duration,
    off_delay: Duration,
    /// Forced position (stuck device): ignores demands while set.
    stuck: Option<bool>,
}

impl Delayed {
    pub(crate) fn new(value: bool, on_delay: Duration, off_delay: Duration) -> Self {
        Delayed {
            value,
            target: value,
            due: None,
            on_delay,
            off_delay,
            stuck: None,
        }
    }

    pub(crate) fn value(&self) -> bool {
        self.value
    }

    pub(crate) fn next_event(&self) -> Option<SimTime> {
        self.due
    }

    /// Demands `want` at `now`; returns true if the value changed immediately.
    pub(crate) fn drive(&mut self, now: SimTime, want: bool) -> bool {
        if let Some(s) = self.stuck {
            self.target = want;
            self.due = None;
            let changed = self.value != s;
            self.value = s;
            return changed;
        }
        if want == self.target && (self.due.is_some() || want == self.value) {
            return false;
        }
        self.target = want;
        if want == self.value {
            self.due = None;
            return false;
        }
        let d = if want { self.on_delay } else { self.off_delay };
        if d.is_zero() {
            self.value = want;
            self.due = None;
            true
        } else {
            self.due = Some(now.saturating_add(d));
            false
        }
    }

    /// Completes a pending change whose deadline has come; true if the value changed.
    pub(crate) fn fire(&mut self, now: SimTime) -> bool {
        match self.due {
            Some(t) if t <= now => {
                self.due = None;
                let changed = self.value != self.target;
                self.value = self.target;
                changed
            }
            _ => false,
        }
    }

    pub(crate) fn set_stuck(&mut self, stuck: Option<bool>) {
        self.stuck = stuck;
        if let Some(s) = stuck {
            self.value = s;
            self.due = None;
        }
    }

    pub(crate) fn stuck(&self) -> Option<bool> {
        self.stuck
    }

    /// Completes a pending change at once (initial steady state).
    pub(crate) fn complete(&mut self) {
        if self.stuck.is_none() {
            self.value = self.target;
        }
        self.due = None;
    }
}

/// A circuit breaker.
///
/// Motorised breakers (QF) have a close coil and a trip (shunt) coil. Closing starts on the
/// *rising edge* of the close coil (anti-pumping: a held close command does not re-close
/// after a trip) and completes after the close time; the trip coil (or a hard-wired
/// emergency-off release) opens after the open time and is trip-free: it wins over a
/// simultaneous close and aborts a closing operation. Manual breakers (FA) have no coils;
/// they open on a trip fault or by hand and close by hand. The auxiliary contact follows
/// the main contacts exactly.
#[derive(Debug, Clone)]
pub(crate) struct Breaker {
    closed: bool,
    op: Option<(bool, SimTime)>,
    close_coil: bool,
    trip_demand: bool,
    close_time: Duration,
    open_time: Duration,
    stuck: Option<bool>,
}

impl Breaker {
    pub(crate) fn new(closed: bool, close_time: Duration, open_time: Duration) -> Self {
        Breaker {
            closed,
            op: None,
            close_coil: false,
            trip_demand: false,
            close_time,
            open_time,
            stuck: None,
        }
    }

    pub(crate) fn closed(&self) -> bool {
        self.closed
    }

    pub(crate) fn next_event(&self) -> Option<SimTime> {
        self.op.map(|(_, t)| t)
    }

    /// Applies the coil states at `now`; returns true if the contacts changed at once.
    pub(crate) fn drive(&mut self, now: SimTime, close_coil: bool, trip: bool) -> bool {
        let rising = close_coil && !self.close_coil;
        self.close_coil = close_coil;
        self.trip_demand = trip;
        if self.stuck.is_some() {
            self.op = None;
            return false;
        }
        if trip {
            match self.op {
                Some((false, _)) => {}
                Some((true, _)) => self.op = None, // trip-free: closing aborted
                None if self.closed => self.op = Some((false, now.saturating_add(self.open_time))),
                None => {}
            }
            if self.open_time.is_zero() {
                return self.fire(now);
            }
            return false;
        }
        if rising && !self.closed && self.op.is_none() {
            self.op = Some((true, now.saturating_add(self.close_time)));
            if self.close_time.is_zero() {
                return self.fire(now);
            }
        }
        false
    }

    /// Completes an operation whose time has come.
    pub(crate) fn fire(&mut self, now: SimTime) -> bool {
        match self.op {
            Some((target, t)) if t <= now => {
                self.op = None;
                let changed = self.closed != target;
                self.closed = target;
                changed
            }
            _ => false,
        }
    }

    /// Opens or closes by hand (manual breakers, or a QF operated mechanically): immediate.
    pub(crate) fn hand(&mut self, closed: bool) -> bool {
        if self.stuck.is_some() || (closed && self.trip_demand) {
            return false;
        }
        self.op = None;
        let changed = self.closed != closed;
        self.closed = closed;
        changed
    }

    /// Starts a closing operation as the close coil would (local pushbutton).
    pub(crate) fn start_close(&mut self, now: SimTime) {
        if self.stuck.is_none() && !self.trip_demand && !self.closed && self.op.is_none() {
            self.op = Some((true, now.saturating_add(self.close_time)));
        }
    }

    /// Starts an opening operation as the trip coil would (local pushbutton).
    pub(crate) fn start_open(&mut self, now: SimTime) {
        if self.stuck.is_none() && (self.closed || self.op.is_some()) {
            if self.closed {
                self.op = Some((false, now.saturating_add(self.open_time)));
            } else {
                self.op = None;
            }
        }
    }

    pub(crate) fn set_stuck(&mut self, stuck: Option<bool>) {
        self.stuck = stuck;
        if let Some(s) = stuck {
            self.closed = s;
            self.op = None;
        }
    }

    pub(crate) fn stuck(&self) -> Option<bool> {
        self.stuck
    }
}

/// Timing and ratings of the diesel generator set.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct GeneratorConfig {
    /// Start command to end of cranking (engine running, excitation begins).
    pub start_delay: Duration,
    /// End of cranking to the voltage reaching 90 % of nominal (voltage relay picks up).
    pub voltage_build: Duration,
    /// End of cranking to the voltage settled at nominal (the controller's "ready to load").
    /// Between `voltage_build` and `settle` the voltage overshoots to 106 % at mid-way
    /// and comes back to nominal.
    pub settle: Duration,
    /// Start command removed to engine stop (runs unloaded at nominal voltage meanwhile).
    pub cool_down: Duration,
    /// Nominal line-to-line voltage, volts.
    pub nominal_voltage: f64,
}

impl Default for GeneratorConfig {
    fn default() -> Self {
        GeneratorConfig {
            start_delay: Duration::from_secs(5),
            voltage_build: Duration::from_secs(1),
            settle: Duration::from_secs(6),
            cool_down: Duration::from_secs(60),
            nominal_voltage: 400.0,
        }
    }
}

/// State of the generator set.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GeneratorState {
    /// At rest.
    Stopped,
    /// Starter engaged since the given time.
    Cranking {
        /// When cranking began.
        since: SimTime,
    },
    /// Engine running; voltage building or settling since `since` (end of cranking).
    Running {
        /// End of cranking.
        since: SimTime,
    },
    /// Start command removed: running unloaded until `until`, then stops.
    CoolDown {
        /// End of cranking of this run (voltage shape continues from it).
        since: SimTime,
        /// When the engine stops.
        until: SimTime,
    },
    /// Failed to start (injected fault); waits until the fault is cleared.
    Failed,
}

/// Diesel generator set with a start/run command (level), a fail-to-start fault and a
/// deterministic piecewise-linear voltage shape.
#[derive(Debug, Clone)]
pub(crate) struct Generator {
    pub(crate) cfg: GeneratorConfig,
    pub(crate) state: GeneratorState,
    start_cmd: bool,
    pub(crate) fail_to_start: bool,
}

impl Generator {
    pub(crate) fn new(cfg: GeneratorConfig) -> Self {
        Generator {
            cfg,
            state: GeneratorState::Stopped,
            start_cmd: false,
            fail_to_start: false,
        }
    }

    fn breakpoints(&self, since: SimTime) -> [SimTime; 3] {
        let b = since.saturating_add(self.cfg.voltage_build);
        let s = since.saturating_add(self.cfg.settle.max(self.cfg.voltage_build));
        let mid = b.saturating_add(s.saturating_sub(b) / 2);
        [b, mid, s]
    }

    pub(crate) fn next_event(&self, now: SimTime) -> Option<SimTime> {
        match self.state {
            GeneratorState::Stopped | GeneratorState::Failed => None,
            GeneratorState::Cranking { since } => Some(since.saturating_add(self.cfg.start_delay)),
            GeneratorState::Running { since } => {
                self.breakpoints(since).into_iter().find(|t| *t > now)
            }
            GeneratorState::CoolDown { since, until } => self
                .breakpoints(since)
                .into_iter()
                .find(|t| *t > now && *t < until)
                .or(Some(until)),
        }
    }

    /// Applies the start command at `now`; true if the state changed.
    pub(crate) fn drive(&mut self, now: SimTime, start: bool) -> bool {
        self.start_cmd = start;
        let before = self.state;
        self.state = match (self.state, start) {
            (GeneratorState::Stopped, true) => GeneratorState::Cranking { since: now },
            (GeneratorState::Cranking { .. }, false) => GeneratorState::Stopped,
            (GeneratorState::Running { since }, false) => GeneratorState::CoolDown {
                since,
                until: now.saturating_add(self.cfg.cool_down),
            },
            (GeneratorState::CoolDown { since, .. }, true) => GeneratorState::Running { since },
            (s, _) => s,
        };
        self.fire(now) || before != self.state
    }

    /// Processes due transitions; true if the state changed.
    pub(crate) fn fire(&mut self, now: SimTime) -> bool {
        let mut changed = false;
        loop {
            let next = match self.state {
                GeneratorState::Cranking { since }
                    if since.saturating_add(self.cfg.start_delay) <= now =>
                {
                    let end = since.saturating_add(self.cfg.start_delay);
                    if self.fail_to_start {
                        GeneratorState::Failed
                    } else {
                        GeneratorState::Running { since: end }
                    }
                }
                GeneratorState::CoolDown { until, .. } if until <= now => GeneratorState::Stopped,
                GeneratorState::Stopped if self.start_cmd => {
                    GeneratorState::Cranking { since: now }
                }
                _ => return changed,
            };
            changed = true;
            self.state = next;
        }
    }

    /// Clears the fail-to-start fault; a held start command restarts the engine.
    pub(crate) fn clear_failure(&mut self, now: SimTime) {
        self.fail_to_start = false;
        if self.state == GeneratorState::Failed {
            self.state = GeneratorState::Stopped;
            self.fire(now);
        }
    }

    /// Terminal voltage at `now` (volts).
    pub(crate) fn voltage(&self, now: SimTime) -> f64 {
        let since = match self.state {
            GeneratorState::Running { since } | GeneratorState::CoolDown { since, .. } => since,
            _ => return 0.0,
        };
        let un = self.cfg.nominal_voltage;
        let [b, mid, s] = self.breakpoints(since);
        let lerp = |t0: SimTime, v0: f64, t1: SimTime, v1: f64| {
            let span = t1.saturating_sub(t0).as_secs_f64();
            if span <= 0.0 {
                return v1;
            }
            let x = now.saturating_sub(t0).as_secs_f64() / span;
            v0 + (v1 - v0) * x.clamp(0.0, 1.0)
        };
        if now < b {
            lerp(since, 0.0, b, 0.9 * un)
        } else if now < mid {
            lerp(b, 0.9 * un, mid, 1.06 * un)
        } else if now < s {
            lerp(mid, 1.06 * un, s, un)
        } else {
            un
        }
    }

    /// Output voltage present (the terminals are a live source).
    pub(crate) fn live(&self) -> bool {
        matches!(
            self.state,
            GeneratorState::Running { .. } | GeneratorState::CoolDown { .. }
        )
    }

    /// Voltage at or above 90 % of nominal (exact at the build breakpoint).
    pub(crate) fn voltage_ok(&self, now: SimTime) -> bool {
        match self.state {
            GeneratorState::Running { since } | GeneratorState::CoolDown { since, .. } => {
                now >= self.breakpoints(since)[0]
            }
            _ => false,
        }
    }

    /// Voltage settled: the controller's "ready to load" output.
    pub(crate) fn ready(&self, now: SimTime) -> bool {
        match self.state {
            GeneratorState::Running { since } | GeneratorState::CoolDown { since, .. } => {
                now >= self.breakpoints(since)[2]
            }
            _ => false,
        }
    }

    pub(crate) fn running(&self) -> bool {
        self.live()
    }

    pub(crate) fn failed(&self) -> bool {
        self.state == GeneratorState::Failed
    }
}
