//! Kinds of field device a project can name (`[[node.device]] kind = "..."`): each one a
//! [`DeviceProfile`] (the points a device of the kind brings, as data) and a driver
//! factory, kept in a [`DeviceKinds`] registry.
//!
//! A new kind of device (the sorting lab's balance, an S7 or Modbus device, a teaching
//! lab's model) is one more row: a profile and a [`DeviceDriver`]. The project loader
//! makes the points from the profile and refuses unknown kinds; the runtime runs every
//! driver under the one field-source supervisor (`runtime::field`: open, reopen with
//! back-off, communication status, invalidation of a silent device's points); the
//! point list, the store and the HMI see ordinary points. None of them changes.
//!
//! ```text
//!  DeviceKinds --profile--> config (points DEVICE.SIGNAL at ioa_base + offset)
//!       |
//!       +--driver(config)--> supervisor: open -> run(readings) -> closed -> pause -> open ...
//!                                          |
//!                                          v  Readings::value(signal, value, quality)
//!                                     NodePoints (sinks, recorder)
//! ```
//!
//! Drivers speak plain futures (no async runtime in this interface), so a kind can be
//! declared where only the profile is needed (the project loader, its fuzz target).

pub mod balance;
pub mod image;
pub mod modbus;
pub mod s7;

pub use image::{DeviceItem, ImageValue, IoImage, OutputSchedule};

use std::collections::BTreeMap;
use std::fmt;
use std::future::Future;
use std::pin::Pin;
use std::sync::Arc;

use points::{DeviceProfile, PointValue, Quality};

/// A boxed future a driver returns.
pub type DriverFuture<'a, T> = Pin<Box<dyn Future<Output = T> + Send + 'a>>;

/// Why a device could not be opened or stopped being read.
#[derive(Debug, thiserror::Error)]
pub enum DeviceError {
    /// Its line or connection could not be opened or failed.
    #[error("{0}")]
    Io(#[from] std::io::Error),
    /// Its line closed (the peer hung up, the adapter was unplugged).
    #[error("the line closed")]
    Closed,
    /// The device's settings in the project do not fit the kind.
    #[error("setting `{key}`: {reason}")]
    Setting {
        /// The key under `[node.device.settings]`.
        key: String,
        /// What is wrong with it.
        reason: String,
    },
    /// The device answered something the driver cannot use, and the driver gave up on
    /// the connection (it is opened again).
    #[error("protocol: {0}")]
    Protocol(String),
}

/// Where a driver puts what it read.
pub trait Readings: Send + Sync {
    /// A reading of the profile's signal `signal`. A name the profile does not have is
    /// logged and dropped.
    fn value(&self, signal: &str, value: PointValue, quality: Quality);

    /// Whether the device answers now: `false` turns its points invalid and its status
    /// point TRUE until it answers again (and its inputs in the PLC's image invalid).
    fn answering(&self, answering: bool);

    /// The device's part of its node's PLC I/O image, if the project binds items of it
    /// (`[[node.io]] device = ...`): the driver reads the inputs into it and writes its
    /// outputs to the device.
    fn image(&self) -> Option<&IoImage> {
        None
    }
}

/// One device's driver: opened, run until its line closes, opened again by the
/// supervisor after a pause.
pub trait DeviceDriver: Send {
    /// Opens the device's line or connection.
    fn open(&mut self) -> DriverFuture<'_, Result<(), DeviceError>>;

    /// Reads the device until its line closes or fails, putting each reading into
    /// `readings`; why it ended.
    fn run<'a>(&'a mut self, readings: &'a dyn Readings) -> DriverFuture<'a, DeviceError>;
}

/// A kind of device: its profile and how to make a driver for one device of it.
pub trait DeviceKind: Send + Sync {
    /// The points a device of this kind brings.
    fn profile(&self) -> &DeviceProfile;

    /// Checks a device's settings when the project loads, so that a mistake is an error
    /// with its place in the file rather than a driver failing at run time.
    fn check(&self, _device: &crate::config::FieldDeviceConfig) -> Result<(), DeviceError> {
        Ok(())
    }

    /// Checks an item of the device the project binds to a PLC variable (`[[node.io]]
    /// device = ... item = ...`), when the project loads.
    fn check_item(&self, _item: &DeviceItem) -> Result<(), String> {
        Err(format!(
            "a `{}` device has no I/O items (its readings are points)",
            self.profile().kind
        ))
    }

    /// A driver for the device `device` of the project.
    fn driver(
        &self,
        device: &crate::config::FieldDeviceConfig,
    ) -> Result<Box<dyn DeviceDriver>, DeviceError>;
}

/// The kinds of device a project may name, by name.
#[derive(Clone, Default)]
pub struct DeviceKinds {
    kinds: BTreeMap<String, Arc<dyn DeviceKind>>,
}

impl fmt::Debug for DeviceKinds {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_list().entries(self.kinds.keys()).finish()
    }
}

impl DeviceKinds {
    /// The kinds built into the station: the sorting lab's balance ([`balance`]), a PLC
    /// or LOGO! read and written over S7 ([`s7`]), a Modbus TCP server or RTU slave
    /// ([`modbus`]).
    pub fn builtin() -> DeviceKinds {
        let mut kinds = DeviceKinds::default();
        for kind in [
            Arc::new(balance::BalanceKind::new()) as Arc<dyn DeviceKind>,
            Arc::new(s7::S7Kind::new()),
            Arc::new(modbus::ModbusKind::new()),
        ] {
            // A built-in profile that cannot make points is a bug the tests catch.
            if let Err(error) = kinds.register(kind) {
                tracing::error!(%error, "a built-in device kind is refused");
            }
        }
        kinds
    }

    /// Adds (or replaces) a kind under its profile's name. A profile that cannot make
    /// points is refused.
    pub fn register(&mut self, kind: Arc<dyn DeviceKind>) -> Result<(), points::ProfileError> {
        kind.profile().check()?;
        self.kinds.insert(kind.profile().kind.clone(), kind);
        Ok(())
    }

    /// The kind called `name`.
    pub fn get(&self, name: &str) -> Option<&Arc<dyn DeviceKind>> {
        self.kinds.get(name)
    }

    /// The kinds' names, sorted.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.kinds.keys().map(String::as_str)
    }
}
