//! Device profiles: the points a kind of device brings, declared once as data.
//!
//! A project names a device and its kind (`[[node.device]] kind = "..."`); the kind's
//! profile says which points that makes (one per signal, at the device's `ioa_base` plus
//! the signal's offset, named `DEVICE.SIGNAL`), of which type and what each means. The
//! project loader, the runtime (which routes the driver's readings by signal name), the
//! point list of the CLI and the HMI all read the same profile, so a new kind of device
//! is one profile and one driver, with nothing to add to any of them.

use crate::PointType;

/// What one kind of device brings.
#[derive(Debug, Clone, PartialEq)]
pub struct DeviceProfile {
    /// The kind's name as a project writes it (`kind = "toy-counter"`).
    pub kind: String,
    /// What such a device is, for the point list and messages.
    pub description: String,
    /// The offset of the point every device has besides its signals,
    /// `DEVICE.not_answering` (TRUE while the device does not answer: the
    /// communication alarm, as a lift's or a line device's status point).
    pub status_offset: u32,
    /// Its signals, each one point.
    pub signals: Vec<SignalProfile>,
}

/// One signal of a device kind: one point of each device of the kind.
#[derive(Debug, Clone, PartialEq)]
pub struct SignalProfile {
    /// The point name's suffix after `DEVICE.` (`count`, `running`).
    pub name: String,
    /// Its IOA's offset from the device's `ioa_base`.
    pub offset: u32,
    /// The point's type.
    pub point_type: PointType,
    /// What the point shows.
    pub description: String,
    /// Which of its changes the history keeps (a signal that changes on every poll while
    /// something is wrong, such as an error count, is stored at most once a minute).
    pub storage: crate::StorageRule,
}

impl DeviceProfile {
    /// The name of the communication-status point's suffix (`DEVICE.not_answering`).
    pub const STATUS_SIGNAL: &'static str = "not_answering";

    /// The signal called `name`.
    pub fn signal(&self, name: &str) -> Option<&SignalProfile> {
        self.signals.iter().find(|signal| signal.name == name)
    }

    /// Why the profile cannot make points: two signals with one name or offset, or an
    /// empty or dotted name (the point name is `DEVICE.SIGNAL`).
    pub fn check(&self) -> Result<(), ProfileError> {
        for (index, signal) in self.signals.iter().enumerate() {
            if signal.name.is_empty()
                || signal.name.contains(['.', ' '])
                || signal.name == Self::STATUS_SIGNAL
            {
                return Err(ProfileError::BadSignalName(signal.name.clone()));
            }
            if signal.offset == self.status_offset {
                return Err(ProfileError::DuplicateOffset {
                    offset: signal.offset,
                    first: Self::STATUS_SIGNAL.to_owned(),
                    second: signal.name.clone(),
                });
            }
            for other in self.signals.iter().skip(index + 1) {
                if other.name == signal.name {
                    return Err(ProfileError::DuplicateSignal(signal.name.clone()));
                }
                if other.offset == signal.offset {
                    return Err(ProfileError::DuplicateOffset {
                        offset: signal.offset,
                        first: signal.name.clone(),
                        second: other.name.clone(),
                    });
                }
            }
        }
        Ok(())
    }
}

/// A profile that cannot make points.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ProfileError {
    /// An empty name, one with a dot or space, or the status point's.
    #[error("signal name `{0}` is empty, has a dot or space, or is the status point's")]
    BadSignalName(String),
    /// Two signals share a name.
    #[error("two signals are called `{0}`")]
    DuplicateSignal(String),
    /// Two signals share an offset.
    #[error("signals `{first}` and `{second}` share offset {offset}")]
    DuplicateOffset {
        /// The offset.
        offset: u32,
        /// The signal listed first.
        first: String,
        /// The signal listed second.
        second: String,
    },
}
