//! Packing many objects into as few ASDUs as the link allows.

use std::collections::VecDeque;
use std::iter::Peekable;

use super::{Asdu, AsduParams, CommonAddress, Cot, InformationObject, TypeId};

/// The VSQ count is seven bits.
const MAX_OBJECTS: usize = 127;

/// Packs `objects` into ASDUs of `type_id`, each filled up to
/// [`AsduParams::max_asdu_len`] and 127 objects, in the order given.
///
/// With `allow_sequence` and a type that allows it ([`TypeId::allows_sequence`]), runs of
/// consecutive addresses go into SQ = 1 ASDUs; a run is worth its own ASDU once the
/// addresses it saves outweigh a header (`(len - 1) × IOA size ≥ header length`, i.e. runs
/// of 3 or more on 104), shorter runs and scattered addresses share SQ = 0 ASDUs.
///
/// The iterator is lazy and linear: each object is moved once, nothing is buffered beyond
/// one ASDU's worth, so a general interrogation of 100 000 points can stream. It does not
/// check the objects against the type: [`Asdu::encode`] does. An object too long for an
/// ASDU of its own (a segment longer than the link allows) is still yielded alone, and
/// its encoding fails with [`super::AsduError::TooLong`].
pub fn pack_objects<I>(
    type_id: TypeId,
    cot: Cot,
    common_address: CommonAddress,
    objects: I,
    params: &AsduParams,
    allow_sequence: bool,
) -> Packer<I::IntoIter>
where
    I: IntoIterator<Item = InformationObject>,
{
    Packer {
        objects: objects.into_iter().peekable(),
        run: VecDeque::new(),
        type_id,
        cot,
        common_address,
        params: *params,
        sequence: allow_sequence && type_id.allows_sequence() && type_id.element_len().is_some(),
    }
}

/// The iterator of [`pack_objects`].
#[derive(Debug)]
pub struct Packer<I: Iterator<Item = InformationObject>> {
    objects: Peekable<I>,
    /// Objects pulled ahead with consecutive addresses (only when packing with SQ = 1).
    run: VecDeque<InformationObject>,
    type_id: TypeId,
    cot: Cot,
    common_address: CommonAddress,
    params: AsduParams,
    sequence: bool,
}

/// Octets one object takes in an SQ = 0 ASDU.
fn unsequenced_len(params: &AsduParams, type_id: TypeId, object: &InformationObject) -> usize {
    usize::from(params.ioa_size()) + object.element.wire_len(type_id)
}

impl<I: Iterator<Item = InformationObject>> Packer<I> {
    fn empty_asdu(&self, sequence: bool, capacity: usize) -> Asdu {
        Asdu {
            type_id: self.type_id,
            sequence,
            cot: self.cot,
            common_address: self.common_address,
            objects: Vec::with_capacity(capacity),
        }
    }

    /// Elements that fit one SQ = 1 ASDU.
    fn sequence_capacity(&self) -> usize {
        let element = self.type_id.element_len().unwrap_or(1).max(1);
        let room = self
            .params
            .max_asdu_len()
            .saturating_sub(self.params.header_len() + usize::from(self.params.ioa_size()));
        (room / element).clamp(1, MAX_OBJECTS)
    }

    /// Pulls objects into `run` while their addresses follow on, up to one ASDU's worth.
    fn fill_run(&mut self) {
        if self.run.is_empty() {
            match self.objects.next() {
                Some(object) => self.run.push_back(object),
                None => return,
            }
        }
        let capacity = self.sequence_capacity();
        while self.run.len() < capacity {
            let Some(last) = self.run.back().map(|object| object.ioa) else {
                return;
            };
            match self
                .objects
                .next_if(|next| last.checked_add(1) == Some(next.ioa))
            {
                Some(object) => self.run.push_back(object),
                None => return,
            }
        }
    }

    fn run_deserves_sequence(&self) -> bool {
        let len = self.run.len();
        len >= 2 && (len - 1) * usize::from(self.params.ioa_size()) >= self.params.header_len()
    }

    /// SQ = 0 packing straight from the input.
    fn next_unsequenced(&mut self) -> Option<Asdu> {
        let first = self.objects.next()?;
        let mut used =
            self.params.header_len() + unsequenced_len(&self.params, self.type_id, &first);
        let mut asdu = self.empty_asdu(false, MAX_OBJECTS.min(self.estimate_sq0_count()));
        asdu.objects.push(first);
        while asdu.objects.len() < MAX_OBJECTS {
            let Some(next) = self.objects.peek() else {
                break;
            };
            let len = unsequenced_len(&self.params, self.type_id, next);
            if used + len > self.params.max_asdu_len() {
                break;
            }
            used += len;
            if let Some(object) = self.objects.next() {
                asdu.objects.push(object);
            }
        }
        Some(asdu)
    }

    fn estimate_sq0_count(&self) -> usize {
        let per_object = super::object_len(self.type_id, &self.params, false).max(1);
        self.params
            .max_asdu_len()
            .saturating_sub(self.params.header_len())
            / per_object
    }
}

impl<I: Iterator<Item = InformationObject>> Iterator for Packer<I> {
    type Item = Asdu;

    fn next(&mut self) -> Option<Asdu> {
        if !self.sequence {
            return self.next_unsequenced();
        }
        self.fill_run();
        if self.run.is_empty() {
            return None;
        }
        if self.run_deserves_sequence() {
            let mut asdu = self.empty_asdu(true, self.run.len());
            asdu.objects.extend(self.run.drain(..));
            return Some(asdu);
        }
        // Short runs and single objects share an SQ = 0 ASDU until it is full or a run
        // worth its own SQ = 1 ASDU comes up.
        let mut asdu = self.empty_asdu(false, MAX_OBJECTS.min(self.estimate_sq0_count()));
        let mut used = self.params.header_len();
        loop {
            while let Some(front) = self.run.front() {
                let len = unsequenced_len(&self.params, self.type_id, front);
                let full =
                    asdu.objects.len() >= MAX_OBJECTS || used + len > self.params.max_asdu_len();
                if full && !asdu.objects.is_empty() {
                    return Some(asdu);
                }
                used += len;
                if let Some(object) = self.run.pop_front() {
                    asdu.objects.push(object);
                }
            }
            self.fill_run();
            if self.run.is_empty() || self.run_deserves_sequence() {
                return Some(asdu);
            }
        }
    }
}
