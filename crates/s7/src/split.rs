//! Cutting a list of reads or writes into jobs that fit the negotiated PDU size.
//!
//! Both the job and its answer must fit: a read job grows by 12 bytes per item and its
//! answer by the data read, a write job by the item and its data and its answer by one
//! byte per item. A job takes at most [`MAX_ITEMS`] items. Items stay whole where a
//! single job can carry them, so that a value is read or written in one piece (a DINT is
//! never half old, half new); only an item larger than a whole job is cut, into
//! consecutive byte runs, starting in a job of its own.
//!
//! ```text
//! read job    10 header + 2 + 12 per item
//! read answer 12 header + 2 + per item: 4 + data (+1 fill if odd, not after the last)
//! write job   10 header + 2 + 12 per item + per item: 4 + data (+1 fill, not last)
//! write answer 12 header + 2 + 1 per item
//! ```

use thiserror::Error;

use crate::address::{Region, RegionError};
use crate::pdu::{
    DataItem, DataTransport, ItemSpec, Pdu, Request, ReturnCode, ACK_HEADER_LEN,
    DATA_ITEM_HEADER_LEN, ITEM_SPEC_LEN, JOB_HEADER_LEN, MAX_ITEMS, VAR_PARAMETER_HEAD_LEN,
};

/// The smallest PDU size a client works with. Real PLCs grant 240 or more; the floor
/// keeps at least a few bytes of data per write job.
pub const MIN_PDU_SIZE: u16 = 64;

/// An item to write: where, and the bytes (one byte, 0 or 1, for a bit).
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct WriteItem {
    /// Where.
    pub region: Region,
    /// What, exactly [`Region::data_len`] bytes.
    pub data: Vec<u8>,
}

/// A part of a caller's item that travels as one protocol item.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Piece {
    /// The index of the caller's item.
    pub item: usize,
    /// Where in the caller's item the piece starts, in bytes.
    pub offset: u32,
    /// What the piece reads or writes.
    pub region: Region,
}

/// The pieces of one job, in order.
#[derive(Debug, Clone, PartialEq, Eq, Hash, Default)]
pub struct Batch {
    /// The pieces.
    pub pieces: Vec<Piece>,
}

/// A read or write no job can carry.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum RequestError {
    /// A region an S7ANY item cannot address.
    #[error("item {item}: {error}")]
    Region {
        /// The item's index.
        item: usize,
        /// What is wrong.
        error: RegionError,
    },
    /// Data of another length than the region.
    #[error("item {item}: {got} bytes of data for a region of {expected}")]
    DataLength {
        /// The item's index.
        item: usize,
        /// The region's length.
        expected: u32,
        /// The data's length.
        got: usize,
    },
    /// A bit written as something other than 0 or 1.
    #[error("item {item}: a bit is written as 0 or 1, not {value}")]
    BitValue {
        /// The item's index.
        item: usize,
        /// The byte given.
        value: u8,
    },
    /// A PDU size below [`MIN_PDU_SIZE`].
    #[error("PDU size {0} is below the minimum of {min}", min = MIN_PDU_SIZE)]
    PduSizeTooSmall(u16),
    /// The connection is closed.
    #[error("the connection is closed")]
    Closed,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Direction {
    Read,
    Write,
}

/// Fills batches piece by piece, tracking both the job's and the answer's length.
struct Packer {
    direction: Direction,
    pdu_size: usize,
    batches: Vec<Batch>,
    current: Batch,
    job_len: usize,
    answer_len: usize,
    last_data_odd: bool,
}

impl Packer {
    const EMPTY_JOB: usize = JOB_HEADER_LEN + VAR_PARAMETER_HEAD_LEN;
    const EMPTY_ANSWER: usize = ACK_HEADER_LEN + VAR_PARAMETER_HEAD_LEN;

    fn new(direction: Direction, pdu_size: u16) -> Packer {
        Packer {
            direction,
            pdu_size: usize::from(pdu_size),
            batches: Vec::new(),
            current: Batch::default(),
            job_len: Self::EMPTY_JOB,
            answer_len: Self::EMPTY_ANSWER,
            last_data_odd: false,
        }
    }

    fn is_empty(&self) -> bool {
        self.current.pieces.is_empty()
    }

    /// The fill byte the previous piece's data gets once another follows it.
    fn fill(&self) -> usize {
        usize::from(self.last_data_odd)
    }

    /// The most data bytes one more piece may carry, 0 if no piece fits.
    fn room(&self) -> usize {
        if self.current.pieces.len() >= MAX_ITEMS {
            return 0;
        }
        let overhead = DATA_ITEM_HEADER_LEN + self.fill();
        match self.direction {
            Direction::Read => {
                if self.job_len + ITEM_SPEC_LEN > self.pdu_size {
                    return 0;
                }
                self.pdu_size.saturating_sub(self.answer_len + overhead)
            }
            Direction::Write => {
                if self.answer_len + 1 > self.pdu_size {
                    return 0;
                }
                self.pdu_size
                    .saturating_sub(self.job_len + ITEM_SPEC_LEN + overhead)
            }
        }
    }

    fn push(&mut self, piece: Piece) {
        let data_len = piece.region.data_len() as usize;
        let data_cost = self.fill() + DATA_ITEM_HEADER_LEN + data_len;
        match self.direction {
            Direction::Read => {
                self.job_len += ITEM_SPEC_LEN;
                self.answer_len += data_cost;
            }
            Direction::Write => {
                self.job_len += ITEM_SPEC_LEN + data_cost;
                self.answer_len += 1;
            }
        }
        self.last_data_odd = data_len % 2 == 1;
        self.current.pieces.push(piece);
    }

    fn flush(&mut self) {
        if !self.is_empty() {
            self.batches.push(std::mem::take(&mut self.current));
        }
        self.job_len = Self::EMPTY_JOB;
        self.answer_len = Self::EMPTY_ANSWER;
        self.last_data_odd = false;
    }

    fn add(&mut self, item: usize, region: Region) {
        match region {
            Region::Bit { .. } => {
                if self.room() < 1 {
                    self.flush();
                }
                self.push(Piece {
                    item,
                    offset: 0,
                    region,
                });
            }
            Region::Bytes { area, start, len } => {
                let mut offset = 0u32;
                while offset < len {
                    let remaining = len - offset;
                    let room = u32::try_from(self.room()).unwrap_or(u32::MAX);
                    let take = if remaining <= room {
                        remaining
                    } else if !self.is_empty() {
                        // Too big for what is left: a fresh job, where it either fits
                        // whole or is cut into as few pieces as possible.
                        self.flush();
                        continue;
                    } else {
                        room
                    };
                    self.push(Piece {
                        item,
                        offset,
                        region: Region::Bytes {
                            area,
                            start: start + offset,
                            len: take,
                        },
                    });
                    offset += take;
                    if offset < len {
                        self.flush();
                    }
                }
            }
        }
    }

    fn finish(mut self) -> Vec<Batch> {
        self.flush();
        self.batches
    }
}

fn check_pdu_size(pdu_size: u16) -> Result<(), RequestError> {
    if pdu_size < MIN_PDU_SIZE {
        Err(RequestError::PduSizeTooSmall(pdu_size))
    } else {
        Ok(())
    }
}

/// Checks every region of a read.
pub fn validate_reads(regions: &[Region]) -> Result<(), RequestError> {
    for (item, region) in regions.iter().enumerate() {
        region
            .validate()
            .map_err(|error| RequestError::Region { item, error })?;
    }
    Ok(())
}

/// Checks every region and its data of a write.
pub fn validate_writes(items: &[WriteItem]) -> Result<(), RequestError> {
    for (index, item) in items.iter().enumerate() {
        item.region
            .validate()
            .map_err(|error| RequestError::Region { item: index, error })?;
        let expected = item.region.data_len();
        if item.data.len() as u64 != u64::from(expected) {
            return Err(RequestError::DataLength {
                item: index,
                expected,
                got: item.data.len(),
            });
        }
        if let (Region::Bit { .. }, [value]) = (item.region, item.data.as_slice()) {
            if *value > 1 {
                return Err(RequestError::BitValue {
                    item: index,
                    value: *value,
                });
            }
        }
    }
    Ok(())
}

/// The read jobs for `regions` at `pdu_size`, pieces in the regions' order.
pub fn split_reads(regions: &[Region], pdu_size: u16) -> Result<Vec<Batch>, RequestError> {
    check_pdu_size(pdu_size)?;
    validate_reads(regions)?;
    let mut packer = Packer::new(Direction::Read, pdu_size);
    for (item, region) in regions.iter().enumerate() {
        packer.add(item, *region);
    }
    Ok(packer.finish())
}

/// The write jobs for `items` at `pdu_size`, pieces in the items' order.
pub fn split_writes(items: &[WriteItem], pdu_size: u16) -> Result<Vec<Batch>, RequestError> {
    check_pdu_size(pdu_size)?;
    validate_writes(items)?;
    let mut packer = Packer::new(Direction::Write, pdu_size);
    for (index, item) in items.iter().enumerate() {
        packer.add(index, item.region);
    }
    Ok(packer.finish())
}

/// The read var job for a batch.
pub fn read_job(batch: &Batch, pdu_ref: u16) -> Pdu {
    Pdu::Job {
        pdu_ref,
        request: read_request(batch),
    }
}

/// The read var request for a batch.
pub fn read_request(batch: &Batch) -> Request {
    Request::ReadVar(
        batch
            .pieces
            .iter()
            .map(|piece| ItemSpec::for_piece(&piece.region))
            .collect(),
    )
}

/// The write var job for a batch of `items` (those [`split_writes`] cut it from).
pub fn write_job(batch: &Batch, items: &[WriteItem], pdu_ref: u16) -> Pdu {
    Pdu::Job {
        pdu_ref,
        request: write_request(batch, items),
    }
}

/// The write var request for a batch of `items`.
pub fn write_request(batch: &Batch, items: &[WriteItem]) -> Request {
    let pieces = batch.pieces.iter().map(|piece| {
        let start = piece.offset as usize;
        let len = piece.region.data_len() as usize;
        let data = items
            .get(piece.item)
            .and_then(|item| item.data.get(start..start + len))
            .unwrap_or_default()
            .to_vec();
        let transport = match piece.region {
            Region::Bit { .. } => DataTransport::Bit,
            Region::Bytes { .. } => DataTransport::Bytes,
        };
        (
            ItemSpec::for_piece(&piece.region),
            DataItem {
                return_code: ReturnCode::Reserved,
                transport,
                data,
            },
        )
    });
    Request::WriteVar(pieces.collect())
}

/// The length of the answer to a read batch when every piece succeeds: what
/// [`split_reads`] keeps within the PDU size.
pub fn read_answer_len(batch: &Batch) -> usize {
    let mut len = Packer::EMPTY_ANSWER;
    let count = batch.pieces.len();
    for (index, piece) in batch.pieces.iter().enumerate() {
        let data_len = piece.region.data_len() as usize;
        len += DATA_ITEM_HEADER_LEN + data_len;
        if index + 1 < count && data_len % 2 == 1 {
            len += 1;
        }
    }
    len
}

/// The length of the answer to a write batch.
pub fn write_answer_len(batch: &Batch) -> usize {
    Packer::EMPTY_ANSWER + batch.pieces.len()
}
