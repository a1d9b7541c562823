//! Runtime API: paths, forcing, retain, watchdog, statistics, I/O image, faults.
