//! A PLC's memory as a server serves it: process inputs, process outputs, markers and
//! data blocks, all zeroed at the start, all readable and writable by any client.

use std::collections::BTreeMap;

use thiserror::Error;

use crate::address::{Address, Area, Region, MAX_BYTE};
use crate::pdu::ReturnCode;
use crate::value::Value;

/// A data block that cannot be added.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
pub enum MemoryError {
    /// Data block 0.
    #[error("data block 0 does not exist on a PLC")]
    DbNumberZero,
    /// A data block already there.
    #[error("data block {0} exists already")]
    Exists(u16),
    /// Larger than an S7ANY item can address.
    #[error("a data block of {0} bytes is larger than the address space")]
    TooLarge(usize),
}

/// The memory image of a simulated PLC.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Memory {
    inputs: Vec<u8>,
    outputs: Vec<u8>,
    markers: Vec<u8>,
    data_blocks: BTreeMap<u16, Vec<u8>>,
}

impl Memory {
    /// The size of each of I, Q and M by default.
    pub const DEFAULT_AREA_SIZE: usize = 1024;

    /// Zeroed inputs, outputs and markers of these sizes (capped at the address
    /// space), no data blocks.
    pub fn new(inputs: usize, outputs: usize, markers: usize) -> Memory {
        let cap = |size: usize| size.min(MAX_BYTE as usize + 1);
        Memory {
            inputs: vec![0; cap(inputs)],
            outputs: vec![0; cap(outputs)],
            markers: vec![0; cap(markers)],
            data_blocks: BTreeMap::new(),
        }
    }

    /// Adds data block `number` of `size` bytes, zeroed.
    pub fn add_data_block(&mut self, number: u16, size: usize) -> Result<(), MemoryError> {
        if number == 0 {
            return Err(MemoryError::DbNumberZero);
        }
        if size > MAX_BYTE as usize + 1 {
            return Err(MemoryError::TooLarge(size));
        }
        if self.data_blocks.contains_key(&number) {
            return Err(MemoryError::Exists(number));
        }
        self.data_blocks.insert(number, vec![0; size]);
        Ok(())
    }

    /// The numbers of the data blocks, ascending.
    pub fn data_block_numbers(&self) -> impl Iterator<Item = u16> + '_ {
        self.data_blocks.keys().copied()
    }

    /// An area's bytes; `None` for a data block not added.
    pub fn area(&self, area: Area) -> Option<&[u8]> {
        match area {
            Area::Inputs => Some(&self.inputs),
            Area::Outputs => Some(&self.outputs),
            Area::Markers => Some(&self.markers),
            Area::DataBlock(number) => self.data_blocks.get(&number).map(Vec::as_slice),
        }
    }

    /// An area's bytes to change; `None` for a data block not added.
    pub fn area_mut(&mut self, area: Area) -> Option<&mut [u8]> {
        match area {
            Area::Inputs => Some(&mut self.inputs),
            Area::Outputs => Some(&mut self.outputs),
            Area::Markers => Some(&mut self.markers),
            Area::DataBlock(number) => self.data_blocks.get_mut(&number).map(Vec::as_mut_slice),
        }
    }

    /// The bytes of a region (one byte, 0 or 1, for a bit), or the return code a PLC
    /// answers: 0x0A for a data block that does not exist, 0x05 past the area's end.
    pub fn read(&self, region: &Region) -> Result<Vec<u8>, ReturnCode> {
        let bytes = self
            .area(region.area())
            .ok_or(ReturnCode::ObjectDoesNotExist)?;
        match *region {
            Region::Bit { byte, bit, .. } => {
                let value = bytes
                    .get(byte as usize)
                    .ok_or(ReturnCode::AddressOutOfRange)?;
                Ok(vec![(value >> (bit & 7)) & 1])
            }
            Region::Bytes { start, len, .. } => {
                let start = start as usize;
                bytes
                    .get(start..start.saturating_add(len as usize))
                    .map(<[u8]>::to_vec)
                    .ok_or(ReturnCode::AddressOutOfRange)
            }
        }
    }

    /// Writes a region: a bit alone (data one byte, non-zero sets it), bytes exactly
    /// (data of the region's length, else 0x07).
    pub fn write(&mut self, region: &Region, data: &[u8]) -> Result<(), ReturnCode> {
        let bytes = self
            .area_mut(region.area())
            .ok_or(ReturnCode::ObjectDoesNotExist)?;
        match *region {
            Region::Bit { byte, bit, .. } => {
                let &[value] = data else {
                    return Err(ReturnCode::TypeInconsistent);
                };
                let target = bytes
                    .get_mut(byte as usize)
                    .ok_or(ReturnCode::AddressOutOfRange)?;
                let mask = 1u8 << (bit & 7);
                if value != 0 {
                    *target |= mask;
                } else {
                    *target &= !mask;
                }
                Ok(())
            }
            Region::Bytes { start, len, .. } => {
                if data.len() != len as usize {
                    return Err(ReturnCode::TypeInconsistent);
                }
                let start = start as usize;
                let target = bytes
                    .get_mut(start..start.saturating_add(data.len()))
                    .ok_or(ReturnCode::AddressOutOfRange)?;
                target.copy_from_slice(data);
                Ok(())
            }
        }
    }

    /// The value at an address.
    pub fn get(&self, address: &Address) -> Result<Value, ReturnCode> {
        let bytes = self.read(&address.region())?;
        address
            .decode(&bytes)
            .map_err(|_| ReturnCode::TypeInconsistent)
    }

    /// Sets the value at an address (of the address's size).
    pub fn set(&mut self, address: &Address, value: &Value) -> Result<(), ReturnCode> {
        let bytes = address
            .encode(value)
            .map_err(|_| ReturnCode::TypeInconsistent)?;
        self.write(&address.region(), &bytes)
    }
}

/// 1024 bytes each of inputs, outputs and markers; no data blocks.
impl Default for Memory {
    fn default() -> Self {
        Memory::new(
            Self::DEFAULT_AREA_SIZE,
            Self::DEFAULT_AREA_SIZE,
            Self::DEFAULT_AREA_SIZE,
        )
    }
}
