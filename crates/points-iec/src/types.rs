//! Which monitor types a point can be declared with, and what each one is in the point
//! model: the value family, the time tag (none, CP24Time2a, CP56Time2a) and, for M_ME_ND_1
//! alone, no quality descriptor.
//!
//! The mapping is written once, as [`type_id`] (a total match, so the compiler sees every
//! point type has a monitor type); [`point_type`] is its inverse.

use iec60870::asdu::TypeId;
use points::{PointKind, PointType, TimeStamp};

/// Every point type: each kind with each stamp, and the normalized value without quality.
const ALL: [PointType; 25] = {
    use PointKind::*;
    use TimeStamp::{Full, None, Short};
    let kinds = [
        Single, Double, Step, Bitstring, Normalized, Scaled, Float, Total,
    ];
    let mut all = [PointType {
        kind: Normalized,
        stamp: None,
        with_quality: false,
    }; 25];
    let mut k = 0;
    while k < kinds.len() {
        all[3 * k] = PointType::new(kinds[k], None);
        all[3 * k + 1] = PointType::new(kinds[k], Short);
        all[3 * k + 2] = PointType::new(kinds[k], Full);
        k += 1;
    }
    all
};

/// The point type of a monitor type; `None` for types a point cannot be declared with
/// (protection events and packed single points, which a gateway turns into single
/// points; commands; system types).
pub fn point_type(type_id: TypeId) -> Option<PointType> {
    ALL.into_iter()
        .find(|&candidate| self::type_id(candidate) == type_id)
}

/// The monitor type a point of this type is sent as. A type without quality descriptor
/// other than the normalized value's has none on the wire and is sent with it.
pub fn type_id(point_type: PointType) -> TypeId {
    use PointKind::*;
    use TimeStamp::{Full, None, Short};
    use TypeId::*;
    match (point_type.kind, point_type.stamp, point_type.with_quality) {
        (Single, None, _) => M_SP_NA_1,
        (Single, Short, _) => M_SP_TA_1,
        (Single, Full, _) => M_SP_TB_1,
        (Double, None, _) => M_DP_NA_1,
        (Double, Short, _) => M_DP_TA_1,
        (Double, Full, _) => M_DP_TB_1,
        (Step, None, _) => M_ST_NA_1,
        (Step, Short, _) => M_ST_TA_1,
        (Step, Full, _) => M_ST_TB_1,
        (Bitstring, None, _) => M_BO_NA_1,
        (Bitstring, Short, _) => M_BO_TA_1,
        (Bitstring, Full, _) => M_BO_TB_1,
        (Normalized, None, true) => M_ME_NA_1,
        (Normalized, None, false) => M_ME_ND_1,
        (Normalized, Short, _) => M_ME_TA_1,
        (Normalized, Full, _) => M_ME_TD_1,
        (Scaled, None, _) => M_ME_NB_1,
        (Scaled, Short, _) => M_ME_TB_1,
        (Scaled, Full, _) => M_ME_TE_1,
        (Float, None, _) => M_ME_NC_1,
        (Float, Short, _) => M_ME_TC_1,
        (Float, Full, _) => M_ME_TF_1,
        (Total, None, _) => M_IT_NA_1,
        (Total, Short, _) => M_IT_TA_1,
        (Total, Full, _) => M_IT_TB_1,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_point_type_round_trips_and_nothing_else_maps() {
        for point_type in ALL {
            assert_eq!(super::point_type(type_id(point_type)), Some(point_type));
        }
        let declarable = (0..=255u8)
            .filter_map(|code| TypeId::try_from(code).ok())
            .filter(|&id| super::point_type(id).is_some())
            .count();
        assert_eq!(declarable, ALL.len());
        assert_eq!(super::point_type(TypeId::M_EP_TA_1), None);
        assert_eq!(super::point_type(TypeId::C_SC_NA_1), None);
    }
}
