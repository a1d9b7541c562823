//! The scan cycle: which tasks are due, and one cycle of a task (forcing, I/O image,
//! programs, statistics, watchdog); the system flags of `System_S`.

use super::{ClockReading, CycleStats, Plc, StopCause, TaskConfig, TaskState};
use crate::check::Size;
use crate::diagnostics::{Code, Diagnostic};
use std::collections::HashSet;

/// A configured task and its run-time state.
pub(super) struct Task {
    pub(super) config: TaskConfig,
    pub(super) programs: Vec<(usize, Size)>,
    pub(super) next_due: Option<i64>,
    pub(super) stats: CycleStats,
    pub(super) state: TaskState,
    pub(super) consecutive_overruns: u32,
    /// Last whole second and tenth of a second seen (system flags), and whether it ran.
    pub(super) last_tick: Option<(i64, i64)>,
    /// Indexes of the programs it runs.
    pub(super) pous: HashSet<usize>,
    /// Upper-case names its programs mention, transitively (globals it drives).
    pub(super) names: HashSet<String>,
}

impl Plc {
    /// Runs every task that is due at `now`. Returns the diagnostics of tasks that faulted
    /// in this call.
    pub fn run_cycle(&mut self, now: ClockReading) -> Vec<Diagnostic> {
        let mut faults = Vec::new();
        if let Some((d, pending)) = &mut self.init_fault {
            if *pending {
                *pending = false;
                faults.push(d.clone());
            }
        }
        self.vm.now = now.monotonic_ns;
        self.vm.utc = now.utc_ns;
        self.vm.local_offset = now.utc_offset_ns;
        for ti in 0..self.tasks.len() {
            let (due, interval) = match self.tasks.get(ti) {
                Some(t) if t.state == TaskState::Running => {
                    (t.next_due.unwrap_or(now.monotonic_ns), t.config.interval_ns)
                }
                _ => continue,
            };
            if now.monotonic_ns < due {
                continue;
            }
            self.update_system_flags(ti, now.monotonic_ns);
            self.apply_io_forces();
            self.sync_inputs();
            self.apply_forces();
            self.vm.budget = self.loop_budget;
            self.stopwatch.start();
            let programs = self
                .tasks
                .get(ti)
                .map(|t| t.programs.clone())
                .unwrap_or_default();
            let mut result = Ok(());
            for (pid, base) in programs {
                result = self.vm.call(pid, base);
                if result.is_err() {
                    break;
                }
            }
            let elapsed = self.stopwatch.elapsed_ns();
            self.apply_forces();
            self.sync_outputs();
            self.apply_io_forces();
            let Some(t) = self.tasks.get_mut(ti) else {
                continue;
            };
            // schedule
            let mut next = due.saturating_add(interval.max(0));
            if interval > 0 {
                while next <= now.monotonic_ns {
                    next = next.saturating_add(interval);
                }
            }
            t.next_due = Some(if interval > 0 { next } else { now.monotonic_ns });
            t.stats.record(elapsed, (now.monotonic_ns - due).abs());
            if let Err(fault) = result {
                let span = fault.span().unwrap_or_default();
                let d = Diagnostic::error(
                    Code::RuntimeFault,
                    span,
                    format!("task '{}' stopped: {fault}", t.config.name),
                );
                t.state = TaskState::Faulted(d.clone());
                faults.push(d.clone());
                self.stop_task(ti, StopCause::Fault(d), now.monotonic_ns);
                continue;
            }
            if let Some(d) = t.watchdog(elapsed) {
                t.state = TaskState::Faulted(d.clone());
                faults.push(d.clone());
                self.stop_task(ti, StopCause::Watchdog(d), now.monotonic_ns);
            }
        }
        faults
    }

    fn update_system_flags(&mut self, ti: usize, now: i64) {
        let Some([sec, tenth, first]) = self.system_flags else {
            return;
        };
        let Some(t) = self.tasks.get_mut(ti) else {
            return;
        };
        let tick = (now.div_euclid(1_000_000_000), now.div_euclid(100_000_000));
        let (s, h, f) = match t.last_tick {
            None => (true, true, true),
            Some((ls, lh)) => (tick.0 != ls, tick.1 != lh, false),
        };
        t.last_tick = Some(tick);
        let _ = self.vm.seti(sec, i64::from(s));
        let _ = self.vm.seti(tenth, i64::from(h));
        let _ = self.vm.seti(first, i64::from(f));
    }
}
