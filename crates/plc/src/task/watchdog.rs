//! The watchdog: the longest a cycle may run and how many overruns in a row stop the task.

use super::cycle::Task;
use crate::diagnostics::{Code, Diagnostic};

/// Watchdog settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Watchdog {
    /// Maximum execution time of one cycle (ns).
    pub time_ns: i64,
    /// Consecutive overruns that make a fault (1 = the first).
    pub sensitivity: u32,
}

impl Task {
    /// Counts the cycle against the watchdog (an overrun when it ran longer than the
    /// watchdog time); the diagnostic when the task must stop.
    pub(super) fn watchdog(&mut self, elapsed: i64) -> Option<Diagnostic> {
        let w = self.config.watchdog?;
        if elapsed > w.time_ns {
            self.stats.overruns += 1;
            self.consecutive_overruns += 1;
            if self.consecutive_overruns >= w.sensitivity {
                return Some(Diagnostic::error(
                    Code::RuntimeFault,
                    crate::syntax::Span::default(),
                    format!(
                        "task '{}' stopped by the watchdog: {} consecutive cycle(s) over {} ns (last {} ns)",
                        self.config.name, self.consecutive_overruns, w.time_ns, elapsed
                    ),
                ));
            }
        } else {
            self.consecutive_overruns = 0;
        }
        None
    }
}
