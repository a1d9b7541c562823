//! IEC 104 framing.
