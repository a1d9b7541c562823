//! The Rekoba EKM66 lift controller board over RS-232 (spec `elevator-ekm66.md`).
//!
//! Choices for the spec's ambiguities (EKM-A1..A9), also in `docs/LIFT.md`:
//!
//! - A1: line 9600 Bd 8E1 by default, every setting configurable.
//! - A2: the status offsets are a [`codec::StatusLayout`] table; the adopted 20-octet
//!   layout (L = 0x0E) and the alternative 21-octet reading (L = 0x0F) are both accepted
//!   by default, each selected by the length octet; either can be switched off.
//! - A3: counter replies of any L ≥ 3; L − 3 octets of counters, 1, 2 or 4 octets each
//!   (little-endian for 2 and 4), default 1.
//! - A4: fault records are 23 octets.
//! - A5: the colour classes of spec §5, overridable per code.
//! - A6: floors are raw numbers; direction 0 stopped, 1 up, 2 down (configurable);
//!   binary time (BCD selectable); year = 2000 + value (base configurable).
//! - A7: status every 1 s, counters every 60 s, reply time-out 500 ms, 3 retries; the
//!   fault index base is detected by reading index 0, then 1.
//! - A8: undocumented octets and the reply prefix are ignored on receive; the simulator
//!   fills zeros and echoes the prefix and the requested index.
//! - A9: codes 1 and 4 keep their texts; unknown codes are shown generically.

pub mod codec;
pub mod console;
pub mod figures;
#[cfg(feature = "tokio")]
pub mod io;
pub mod poller;
pub mod simulator;
pub mod tables;
