//! Time as the caller passes it: the reading of a cycle's clocks and the stopwatch that
//! measures a cycle's work. A [`Plc`](super::Plc) never reads a clock itself.

/// The time of one cycle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ClockReading {
    /// Monotonic time since the PLC started (ns). Drives timers.
    pub monotonic_ns: i64,
    /// Wall-clock UTC (ns since 1970-01-01).
    pub utc_ns: i64,
    /// Local time offset from UTC (ns), e.g. 3 600 000 000 000 for CET.
    pub utc_offset_ns: i64,
}

/// A virtual clock: starts at a given UTC time and advances only when told.
#[derive(Debug, Clone, Copy)]
pub struct VirtualClock {
    reading: ClockReading,
}

impl VirtualClock {
    /// A clock at `utc_ns` with a fixed local offset.
    pub fn new(utc_ns: i64, utc_offset_ns: i64) -> Self {
        VirtualClock {
            reading: ClockReading {
                monotonic_ns: 0,
                utc_ns,
                utc_offset_ns,
            },
        }
    }
    /// The current reading.
    pub fn now(&self) -> ClockReading {
        self.reading
    }
    /// Advances by `ns`.
    pub fn advance(&mut self, ns: i64) {
        self.reading.monotonic_ns = self.reading.monotonic_ns.saturating_add(ns);
        self.reading.utc_ns = self.reading.utc_ns.saturating_add(ns);
    }
    /// Sets the local offset (daylight-saving changes).
    pub fn set_offset(&mut self, utc_offset_ns: i64) {
        self.reading.utc_offset_ns = utc_offset_ns;
    }
}

/// Measures how long a cycle's work took (ns). Production uses a monotonic system timer;
/// tests script it to exercise the watchdog deterministically.
pub trait Stopwatch {
    /// Starts a measurement.
    fn start(&mut self);
    /// Nanoseconds since `start`.
    fn elapsed_ns(&mut self) -> i64;
}

/// A stopwatch that always reports zero (virtual-time runs).
#[derive(Debug, Default, Clone, Copy)]
pub struct NoStopwatch;

impl Stopwatch for NoStopwatch {
    fn start(&mut self) {}
    fn elapsed_ns(&mut self) -> i64 {
        0
    }
}
