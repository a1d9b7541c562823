//! A task's configuration: name, interval, priority, programs and watchdog.

use super::Watchdog;

/// Configuration of a task.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct TaskConfig {
    /// Name.
    pub name: String,
    /// Cycle interval (ns); 0 = every `run_cycle`.
    pub interval_ns: i64,
    /// Priority: 0 is the highest; equal priorities run in configuration order.
    pub priority: u8,
    /// Programs, run in order.
    pub programs: Vec<String>,
    /// Watchdog.
    pub watchdog: Option<Watchdog>,
}

impl TaskConfig {
    /// A cyclic task running `programs` every `interval_ns`.
    pub fn cyclic(name: impl Into<String>, interval_ns: i64, programs: &[&str]) -> Self {
        TaskConfig {
            name: name.into(),
            interval_ns,
            priority: 10,
            programs: programs.iter().map(|s| s.to_string()).collect(),
            watchdog: None,
        }
    }
    /// With a priority.
    #[must_use]
    pub fn with_priority(mut self, priority: u8) -> Self {
        self.priority = priority;
        self
    }
    /// With a watchdog.
    #[must_use]
    pub fn with_watchdog(mut self, time_ns: i64, sensitivity: u32) -> Self {
        self.watchdog = Some(Watchdog {
            time_ns,
            sensitivity: sensitivity.max(1),
        });
        self
    }
}
