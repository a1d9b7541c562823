//! IEC 104 stations.

pub mod config;
pub mod session;

pub use config::{ApciConfig, ConfigError, ConfigWarning};
pub use session::{
    CloseReason, ControlError, Role, SendError, Session, SessionEvent, SessionState, SessionStats,
};
