//! A primary host application's STATE (Sparkplug 3.0: a retained JSON payload
//! `{"online": true, "timestamp": 1668114759262}` on `spBv1.0/STATE/{host}`).

use serde::{Deserialize, Serialize};

/// A host's state message.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct HostState {
    /// Whether the host is online.
    pub online: bool,
    /// When the host said so, in milliseconds since the Unix epoch.
    pub timestamp: u64,
}

/// Why a STATE payload is not one.
#[derive(Debug, thiserror::Error)]
#[error("not a Sparkplug STATE payload: {0}")]
pub struct StateError(#[from] serde_json::Error);

impl HostState {
    /// Parses a STATE payload.
    pub fn parse(payload: &[u8]) -> Result<HostState, StateError> {
        Ok(serde_json::from_slice(payload)?)
    }

    /// The payload's bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        // A struct of a bool and an integer always serializes.
        serde_json::to_vec(self).unwrap_or_default()
    }
}
