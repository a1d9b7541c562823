//! A cursor over received bytes: every read is checked, none can panic, so the decoders
//! stay total over whatever a peer or a fuzzer sends.

/// Reads big-endian fields from the front of a byte slice.
#[derive(Debug, Clone)]
pub(crate) struct Reader<'a> {
    bytes: &'a [u8],
}

impl<'a> Reader<'a> {
    pub(crate) fn new(bytes: &'a [u8]) -> Self {
        Self { bytes }
    }

    pub(crate) fn u8(&mut self) -> Option<u8> {
        let (&first, rest) = self.bytes.split_first()?;
        self.bytes = rest;
        Some(first)
    }

    pub(crate) fn u16(&mut self) -> Option<u16> {
        let bytes = self.take(2)?;
        let array: [u8; 2] = bytes.try_into().ok()?;
        Some(u16::from_be_bytes(array))
    }

    /// The 24-bit bit addresses of S7ANY items.
    pub(crate) fn u24(&mut self) -> Option<u32> {
        let bytes = self.take(3)?;
        let array: [u8; 3] = bytes.try_into().ok()?;
        let [high, middle, low] = array;
        Some(u32::from_be_bytes([0, high, middle, low]))
    }

    pub(crate) fn take(&mut self, len: usize) -> Option<&'a [u8]> {
        let (taken, rest) = self.bytes.split_at_checked(len)?;
        self.bytes = rest;
        Some(taken)
    }

    pub(crate) fn rest(&self) -> &'a [u8] {
        self.bytes
    }

    pub(crate) fn is_empty(&self) -> bool {
        self.bytes.is_empty()
    }
}

/// Appends a 24-bit big-endian value (the upper byte of `value` is dropped: callers
/// check the range first).
pub(crate) fn put_u24(out: &mut Vec<u8>, value: u32) {
    let [_, high, middle, low] = value.to_be_bytes();
    out.extend_from_slice(&[high, middle, low]);
}

/// Lowercase hex of bytes, for logs and JSON.
pub(crate) fn hex(bytes: &[u8]) -> String {
    use std::fmt::Write;
    let mut text = String::with_capacity(bytes.len() * 2);
    for byte in bytes {
        // Writing to a String cannot fail.
        let _ = write!(text, "{byte:02x}");
    }
    text
}
