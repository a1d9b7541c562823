//! IEC 104 stations.

#[cfg(feature = "tokio")]
pub mod client;
pub mod config;
#[cfg(feature = "tokio")]
pub mod link;
#[cfg(feature = "tokio")]
mod repeated_warning;
#[cfg(feature = "tokio")]
pub mod server;
pub mod session;
#[cfg(feature = "tokio")]
pub mod tls;

pub use config::{ApciConfig, ConfigError, ConfigWarning};
pub use session::{
    CloseReason, ControlError, Role, SendError, Session, SessionEvent, SessionState, SessionStats,
};
