//! Cycle statistics of a task: execution times, jitter, watchdog overruns.

use super::Plc;

/// Cycle statistics of a task (times in ns).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CycleStats {
    /// Cycles run.
    pub cycles: u64,
    /// Last execution time.
    pub last_ns: i64,
    /// Minimum execution time.
    pub min_ns: i64,
    /// Maximum execution time.
    pub max_ns: i64,
    /// Average execution time.
    pub avg_ns: f64,
    /// Largest deviation of a cycle start from its due time.
    pub jitter_ns: i64,
    /// Cycles whose execution exceeded the watchdog time.
    pub overruns: u64,
}

impl CycleStats {
    /// Counts a cycle that ran `elapsed` ns and started `jitter` ns off its due time.
    pub(super) fn record(&mut self, elapsed: i64, jitter: i64) {
        let s = self;
        s.cycles += 1;
        s.last_ns = elapsed;
        s.min_ns = if s.cycles == 1 {
            elapsed
        } else {
            s.min_ns.min(elapsed)
        };
        s.max_ns = s.max_ns.max(elapsed);
        s.avg_ns += (elapsed as f64 - s.avg_ns) / s.cycles as f64;
        s.jitter_ns = s.jitter_ns.max(jitter);
    }
}

impl Plc {
    /// Statistics of a task.
    pub fn stats(&self, task: &str) -> Option<CycleStats> {
        self.tasks
            .iter()
            .find(|t| t.config.name == task)
            .map(|t| t.stats)
    }
}
