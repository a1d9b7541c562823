//! A field device's part of its node's PLC I/O image: the items a project binds to PLC
//! variables (`[[node.io]] device = "LOGO_RH2" item = "I0.1" direction = "input"`), the
//! way a simulated I/O module is bound to the plant, so that a program runs unchanged on
//! the plant or on real I/O.
//!
//! ```text
//!  driver (tokio task)                    IoImage                 simulation thread
//!  read the device's input items ---> inputs[item] = value  ---> PLC input (valid while
//!                                     answering                   the device answers)
//!  write changed (and every so often  <--- outputs[item] <------ PLC output, on change
//!  all) output items
//! ```
//!
//! Plain `std` locks: the simulation thread and the driver each hold one for a moment.

use std::collections::HashMap;

// `OutputSchedule` takes the time from its caller: the device module reads no clock.
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Mutex;

/// A value in the image: a bit, or a number (bytes, words, integers, reals).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ImageValue {
    /// A bit.
    Bool(bool),
    /// A number.
    Number(f64),
}

/// One item of a device bound in the image.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DeviceItem {
    /// The item as the project writes it (an S7 address `DB1.DBX0.3`, ...).
    pub item: String,
    /// Driven by the PLC (written to the device) rather than read from it.
    pub output: bool,
}

/// The image of one device (see the module's description).
#[derive(Debug, Default)]
pub struct IoImage {
    inputs: Mutex<HashMap<String, ImageValue>>,
    outputs: Mutex<HashMap<String, ImageValue>>,
    /// Bumped at every change of an output, so the driver sees that there is news.
    outputs_changed: AtomicU64,
    answering: AtomicBool,
}

impl IoImage {
    /// An empty image of a device not answering yet.
    pub fn new() -> IoImage {
        IoImage::default()
    }

    /// The driver read `value` from the input `item`.
    pub fn set_input(&self, item: &str, value: ImageValue) {
        self.inputs
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
            .insert(item.to_owned(), value);
    }

    /// The driver could not read the input `item` (the device refused it): the PLC keeps
    /// its last value and the input is invalid.
    pub fn clear_input(&self, item: &str) {
        self.inputs
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
            .remove(item);
    }

    /// The input `item` for the PLC: `None` while the device does not answer or the item
    /// was not read.
    pub fn input(&self, item: &str) -> Option<ImageValue> {
        if !self.answering() {
            return None;
        }
        self.inputs
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
            .get(item)
            .copied()
    }

    /// The PLC drives the output `item` to `value`.
    pub fn set_output(&self, item: &str, value: ImageValue) {
        let mut outputs = self
            .outputs
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        if outputs.insert(item.to_owned(), value) != Some(value) {
            self.outputs_changed.fetch_add(1, Ordering::AcqRel);
        }
    }

    /// Every output the PLC drives, with the count of changes so far (the driver writes
    /// again when it grew).
    pub fn outputs(&self) -> (u64, Vec<(String, ImageValue)>) {
        let outputs = self
            .outputs
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        let changes = self.outputs_changed.load(Ordering::Acquire);
        (
            changes,
            outputs
                .iter()
                .map(|(item, value)| (item.clone(), *value))
                .collect(),
        )
    }

    /// The count of output changes so far.
    pub fn output_changes(&self) -> u64 {
        self.outputs_changed.load(Ordering::Acquire)
    }

    /// Whether the device answers: its inputs are valid only then.
    pub fn answering(&self) -> bool {
        self.answering.load(Ordering::Acquire)
    }

    /// The driver says whether the device answers.
    pub fn set_answering(&self, answering: bool) {
        self.answering.store(answering, Ordering::Release);
    }
}

/// When a driver writes a device's outputs: when the PLC has changed one since the last
/// write, and all of them again every `every` (a device that restarted, or whose output a
/// person changed by hand, gets them back).
#[derive(Debug, Clone)]
pub struct OutputSchedule {
    every: std::time::Duration,
    written: Option<u64>,
    last_full: Option<std::time::Instant>,
}

impl OutputSchedule {
    /// A schedule that writes everything again every `every`.
    pub fn new(every: std::time::Duration) -> OutputSchedule {
        OutputSchedule {
            every,
            written: None,
            last_full: None,
        }
    }

    /// The outputs to write at `now`, if it is time (the first call always is).
    pub fn due(
        &mut self,
        image: &IoImage,
        now: std::time::Instant,
    ) -> Option<Vec<(String, ImageValue)>> {
        let full = self
            .last_full
            .is_none_or(|last| now.saturating_duration_since(last) >= self.every);
        if !full && self.written == Some(image.output_changes()) {
            return None;
        }
        let (changes, outputs) = image.outputs();
        self.written = Some(changes);
        if full {
            self.last_full = Some(now);
        }
        Some(outputs)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inputs_count_only_while_the_device_answers_and_outputs_count_their_changes() {
        let image = IoImage::new();
        image.set_input("I0.1", ImageValue::Bool(true));
        assert_eq!(image.input("I0.1"), None, "not answering yet");
        image.set_answering(true);
        assert_eq!(image.input("I0.1"), Some(ImageValue::Bool(true)));
        image.clear_input("I0.1");
        assert_eq!(image.input("I0.1"), None);
        image.set_output("Q0.0", ImageValue::Bool(true));
        image.set_output("Q0.0", ImageValue::Bool(true));
        assert_eq!(image.output_changes(), 1, "the same value is no change");
        image.set_output("Q0.0", ImageValue::Bool(false));
        let (changes, outputs) = image.outputs();
        assert_eq!(changes, 2);
        assert_eq!(outputs, vec![("Q0.0".to_owned(), ImageValue::Bool(false))]);
    }

    #[test]
    fn outputs_are_written_on_change_and_all_again_every_period() {
        use std::time::{Duration, Instant};
        let image = IoImage::new();
        image.set_output("Q0.0", ImageValue::Bool(true));
        let mut schedule = OutputSchedule::new(Duration::from_secs(1));
        let start = Instant::now();
        assert!(schedule.due(&image, start).is_some(), "the first time");
        assert!(schedule
            .due(&image, start + Duration::from_millis(100))
            .is_none());
        image.set_output("Q0.0", ImageValue::Bool(false));
        let changed = schedule
            .due(&image, start + Duration::from_millis(200))
            .unwrap();
        assert_eq!(changed, vec![("Q0.0".to_owned(), ImageValue::Bool(false))]);
        assert!(schedule
            .due(&image, start + Duration::from_millis(900))
            .is_none());
        assert!(
            schedule
                .due(&image, start + Duration::from_millis(1000))
                .is_some(),
            "all again after the period"
        );
    }
}
