//! Time tags.
