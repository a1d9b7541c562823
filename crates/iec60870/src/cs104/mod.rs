//! IEC 104 stations.

pub mod client;
pub mod config;
mod repeated_warning;
pub mod server;
pub mod session;
pub mod tls;

pub use config::{ApciConfig, ConfigError, ConfigWarning};
pub use session::{
    CloseReason, ControlError, Role, SendError, Session, SessionEvent, SessionState, SessionStats,
};
