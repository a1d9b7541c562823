//! Field sizes of a link: the "application layer parameters" of 101/104.

use super::AsduError;

/// The largest fixed-size element (F_SC_NB_1, 16 octets): every link must fit one object
/// of every fixed-size type into an ASDU.
const LARGEST_FIXED_ELEMENT: usize = 16;

/// Field sizes of a link and its maximum ASDU length.
///
/// IEC 104 fixes COT 2, common address 2, IOA 3 and 249 octets ([`AsduParams::IEC104`]);
/// on IEC 101 links all of them are per-link settings, and a mismatch between the two
/// ends yields garbage silently, so they are validated here and carried explicitly.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct AsduParams {
    cot_size: u8,
    common_address_size: u8,
    ioa_size: u8,
    max_asdu_len: usize,
}

impl AsduParams {
    /// IEC 104: COT 2 octets, common address 2, IOA 3, ASDU at most 249 octets (253 APDU
    /// length minus the 4 control octets).
    pub const IEC104: AsduParams = AsduParams {
        cot_size: 2,
        common_address_size: 2,
        ioa_size: 3,
        max_asdu_len: 249,
    };

    /// A common IEC 101 setting: COT 1 octet, common address 1, IOA 2, ASDU at most 253
    /// octets (an FT1.2 frame carries 255 octets of control field, link address and ASDU;
    /// this leaves one octet of link address). Links differ: use [`AsduParams::try_new`]
    /// with the values of the device.
    pub const IEC101_DEFAULT: AsduParams = AsduParams {
        cot_size: 1,
        common_address_size: 1,
        ioa_size: 2,
        max_asdu_len: 253,
    };

    /// Parameters with COT 1 or 2 octets, common address 1 or 2, IOA 1, 2 or 3, and a
    /// maximum ASDU length that holds one object of every fixed-size type (header + IOA +
    /// 16) and at most 255 (no 101/104 frame carries more).
    pub fn try_new(
        cot_size: u8,
        common_address_size: u8,
        ioa_size: u8,
        max_asdu_len: usize,
    ) -> Result<AsduParams, AsduError> {
        let invalid = |field: &'static str, value: usize| AsduError::InvalidParams { field, value };
        if !(1..=2).contains(&cot_size) {
            return Err(invalid("cot_size", cot_size.into()));
        }
        if !(1..=2).contains(&common_address_size) {
            return Err(invalid("common_address_size", common_address_size.into()));
        }
        if !(1..=3).contains(&ioa_size) {
            return Err(invalid("ioa_size", ioa_size.into()));
        }
        let params = AsduParams {
            cot_size,
            common_address_size,
            ioa_size,
            max_asdu_len,
        };
        let smallest = params.header_len() + usize::from(ioa_size) + LARGEST_FIXED_ELEMENT;
        if !(smallest..=255).contains(&max_asdu_len) {
            return Err(invalid("max_asdu_len", max_asdu_len));
        }
        Ok(params)
    }

    /// Octets of the cause of transmission: 1 (cause only) or 2 (with originator).
    pub fn cot_size(&self) -> u8 {
        self.cot_size
    }

    /// Octets of the common address: 1 or 2.
    pub fn common_address_size(&self) -> u8 {
        self.common_address_size
    }

    /// Octets of an information object address: 1, 2 or 3.
    pub fn ioa_size(&self) -> u8 {
        self.ioa_size
    }

    /// Maximum octets of one ASDU.
    pub fn max_asdu_len(&self) -> usize {
        self.max_asdu_len
    }

    /// Octets before the first object: type, VSQ, COT and common address (6 on 104).
    pub fn header_len(&self) -> usize {
        2 + usize::from(self.cot_size) + usize::from(self.common_address_size)
    }

    /// The largest information object address the IOA field can carry.
    pub fn max_ioa(&self) -> u32 {
        match self.ioa_size {
            1 => 0xFF,
            2 => 0xFFFF,
            _ => 0xFF_FFFF,
        }
    }

    /// The largest common address the field can carry (also the broadcast address).
    pub fn max_common_address(&self) -> u16 {
        if self.common_address_size == 1 {
            0xFF
        } else {
            0xFFFF
        }
    }
}

impl Default for AsduParams {
    /// [`AsduParams::IEC104`].
    fn default() -> AsduParams {
        AsduParams::IEC104
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]
mod tests {
    use super::*;

    #[test]
    fn validation() {
        assert_eq!(
            AsduParams::try_new(2, 2, 3, 249).unwrap(),
            AsduParams::IEC104
        );
        assert_eq!(
            AsduParams::try_new(1, 1, 2, 253).unwrap(),
            AsduParams::IEC101_DEFAULT
        );
        assert!(AsduParams::try_new(0, 2, 3, 249).is_err());
        assert!(AsduParams::try_new(2, 3, 3, 249).is_err());
        assert!(AsduParams::try_new(2, 2, 4, 249).is_err());
        assert!(AsduParams::try_new(2, 2, 3, 256).is_err());
        assert!(AsduParams::try_new(2, 2, 3, 24).is_err());
        assert!(AsduParams::try_new(2, 2, 3, 25).is_ok());
        assert_eq!(AsduParams::IEC104.header_len(), 6);
        assert_eq!(AsduParams::IEC101_DEFAULT.header_len(), 4);
    }
}
