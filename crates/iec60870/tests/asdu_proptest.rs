//! Property tests of the ASDU codec: every type identification, SQ = 0 and SQ = 1, all
//! field sizes, encode -> decode round trips; and arbitrary or mutated bytes never panic.
#![allow(
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing,
    missing_docs
)]

use iec60870::asdu::*;
use proptest::prelude::*;
use proptest::sample::select;

/// Every combination of field sizes, with the largest ASDU so that most objects fit.
fn all_params() -> Vec<AsduParams> {
    let mut params = Vec::new();
    for cot in 1..=2 {
        for ca in 1..=2 {
            for ioa in 1..=3 {
                params.push(AsduParams::try_new(cot, ca, ioa, 255).unwrap());
            }
        }
    }
    params.push(AsduParams::IEC104);
    params.push(AsduParams::IEC101_DEFAULT);
    params
}

fn cp56() -> impl Strategy<Value = Cp56Time2a> {
    (
        (
            0u8..=99,
            1u8..=12,
            1u8..=31,
            0u8..=23,
            0u8..=59,
            0u16..60_000,
        ),
        (0u8..=7, any::<bool>(), any::<bool>(), any::<bool>()),
    )
        .prop_map(
            |((year, month, day, hour, minute, ms), (dow, iv, su, sub))| {
                Cp56Time2a::new(year, month, day, hour, minute, ms)
                    .unwrap()
                    .with_day_of_week(dow)
                    .unwrap()
                    .with_invalid(iv)
                    .with_summer_time(su)
                    .with_substituted(sub)
            },
        )
}

fn cp24() -> impl Strategy<Value = Cp24Time2a> {
    (0u8..=59, 0u16..60_000, any::<bool>(), any::<bool>()).prop_map(|(minute, ms, iv, sub)| {
        Cp24Time2a::new(minute, ms)
            .unwrap()
            .with_invalid(iv)
            .with_substituted(sub)
    })
}

fn cp16() -> impl Strategy<Value = Cp16Time2a> {
    (0u16..60_000).prop_map(|ms| Cp16Time2a::new(ms).unwrap())
}

/// QDS: all five flags.
fn qds() -> impl Strategy<Value = Quality> {
    any::<u8>().prop_map(Quality::from_qds)
}

/// SIQ/DIQ quality: no OV.
fn status_quality() -> impl Strategy<Value = Quality> {
    any::<u8>().prop_map(Quality::from_status_bits)
}

fn double_state() -> impl Strategy<Value = DoublePointState> {
    (0u8..4).prop_map(DoublePointState::from_bits)
}

fn qoc() -> impl Strategy<Value = CommandQualifier> {
    (0u8..=31, any::<bool>()).prop_map(|(qu, select)| CommandQualifier::new(qu, select).unwrap())
}

fn qos() -> impl Strategy<Value = SetpointQualifier> {
    (0u8..=127, any::<bool>()).prop_map(|(ql, select)| SetpointQualifier::new(ql, select).unwrap())
}

/// Any float but NaN (NaN != NaN would defeat the equality check; the byte-level fuzz
/// below covers NaN payloads).
fn float() -> impl Strategy<Value = f32> {
    any::<u32>()
        .prop_map(f32::from_bits)
        .prop_filter("NaN", |value| !value.is_nan())
}

fn protection_quality() -> impl Strategy<Value = ProtectionQuality> {
    any::<u8>().prop_map(ProtectionQuality::from_bits)
}

fn length24() -> impl Strategy<Value = u32> {
    0u32..=0xFF_FFFF
}

/// A valid element for `type_id`, any value its fields can carry.
fn element(type_id: TypeId) -> BoxedStrategy<Element> {
    use TypeId::*;
    match type_id {
        M_SP_NA_1 | M_SP_TA_1 | M_SP_TB_1 => (any::<bool>(), status_quality())
            .prop_map(|(on, quality)| Element::SinglePoint { on, quality })
            .boxed(),
        M_DP_NA_1 | M_DP_TA_1 | M_DP_TB_1 => (double_state(), status_quality())
            .prop_map(|(state, quality)| Element::DoublePoint { state, quality })
            .boxed(),
        M_ST_NA_1 | M_ST_TA_1 | M_ST_TB_1 => (-64i8..=63, any::<bool>(), qds())
            .prop_map(|(value, transient, quality)| Element::StepPosition {
                position: StepPosition::new(value, transient).unwrap(),
                quality,
            })
            .boxed(),
        M_BO_NA_1 | M_BO_TA_1 | M_BO_TB_1 => (any::<u32>(), qds())
            .prop_map(|(bits, quality)| Element::Bitstring { bits, quality })
            .boxed(),
        M_ME_NA_1 | M_ME_TA_1 | M_ME_TD_1 => (any::<i16>(), qds())
            .prop_map(|(raw, quality)| Element::Normalized { raw, quality })
            .boxed(),
        M_ME_ND_1 => any::<i16>()
            .prop_map(|raw| Element::Normalized {
                raw,
                quality: Quality::GOOD,
            })
            .boxed(),
        M_ME_NB_1 | M_ME_TB_1 | M_ME_TE_1 => (any::<i16>(), qds())
            .prop_map(|(value, quality)| Element::Scaled { value, quality })
            .boxed(),
        M_ME_NC_1 | M_ME_TC_1 | M_ME_TF_1 => (float(), qds())
            .prop_map(|(value, quality)| Element::Float { value, quality })
            .boxed(),
        M_IT_NA_1 | M_IT_TA_1 | M_IT_TB_1 => any::<[u8; 5]>()
            .prop_map(|bytes| Element::IntegratedTotal(BinaryCounterReading::from_bytes(bytes)))
            .boxed(),
        M_EP_TA_1 | M_EP_TD_1 => (double_state(), protection_quality(), cp16())
            .prop_map(|(state, quality, elapsed)| Element::ProtectionEvent {
                state,
                quality,
                elapsed,
            })
            .boxed(),
        M_EP_TB_1 | M_EP_TE_1 => (any::<u8>(), protection_quality(), cp16())
            .prop_map(|(spe, quality, duration)| Element::ProtectionStartEvents {
                events: StartEvents::from_bits(spe),
                quality,
                duration,
            })
            .boxed(),
        M_EP_TC_1 | M_EP_TF_1 => (any::<u8>(), protection_quality(), cp16())
            .prop_map(
                |(oci, quality, operating_time)| Element::ProtectionOutputCircuit {
                    circuits: OutputCircuits::from_bits(oci),
                    quality,
                    operating_time,
                },
            )
            .boxed(),
        M_PS_NA_1 => (any::<u16>(), any::<u16>(), qds())
            .prop_map(|(status, change, quality)| Element::PackedSinglePoints {
                status,
                change,
                quality,
            })
            .boxed(),
        C_SC_NA_1 | C_SC_TA_1 => (any::<bool>(), qoc())
            .prop_map(|(on, qualifier)| Element::SingleCommand { on, qualifier })
            .boxed(),
        C_DC_NA_1 | C_DC_TA_1 => (double_state(), qoc())
            .prop_map(|(state, qualifier)| Element::DoubleCommand { state, qualifier })
            .boxed(),
        C_RC_NA_1 | C_RC_TA_1 => (0u8..4, qoc())
            .prop_map(|(rcs, qualifier)| Element::RegulatingStep {
                state: RegulatingStepState::from_bits(rcs),
                qualifier,
            })
            .boxed(),
        C_SE_NA_1 | C_SE_TA_1 => (any::<i16>(), qos())
            .prop_map(|(raw, qualifier)| Element::SetpointNormalized { raw, qualifier })
            .boxed(),
        C_SE_NB_1 | C_SE_TB_1 => (any::<i16>(), qos())
            .prop_map(|(value, qualifier)| Element::SetpointScaled { value, qualifier })
            .boxed(),
        C_SE_NC_1 | C_SE_TC_1 => (float(), qos())
            .prop_map(|(value, qualifier)| Element::SetpointFloat { value, qualifier })
            .boxed(),
        C_BO_NA_1 | C_BO_TA_1 => any::<u32>()
            .prop_map(|bits| Element::BitstringCommand { bits })
            .boxed(),
        M_EI_NA_1 => (0u8..=127, any::<bool>())
            .prop_map(
                |(cause, after_parameter_change)| Element::EndOfInitialisation {
                    cause,
                    after_parameter_change,
                },
            )
            .boxed(),
        C_IC_NA_1 => any::<u8>()
            .prop_map(|qualifier| Element::Interrogation { qualifier })
            .boxed(),
        C_CI_NA_1 => (0u8..=63, 0u8..=3)
            .prop_map(|(request, freeze)| Element::CounterInterrogation { request, freeze })
            .boxed(),
        C_RD_NA_1 => Just(Element::Read).boxed(),
        C_CS_NA_1 => cp56().prop_map(|time| Element::ClockSync { time }).boxed(),
        C_TS_NA_1 => any::<u16>()
            .prop_map(|pattern| Element::Test { pattern })
            .boxed(),
        C_RP_NA_1 => any::<u8>()
            .prop_map(|qualifier| Element::ResetProcess { qualifier })
            .boxed(),
        C_CD_NA_1 => cp16()
            .prop_map(|delay| Element::DelayAcquisition { delay })
            .boxed(),
        C_TS_TA_1 => any::<u16>()
            .prop_map(|counter| Element::TestWithTime { counter })
            .boxed(),
        P_ME_NA_1 => (any::<i16>(), any::<u8>())
            .prop_map(|(raw, qualifier)| Element::ParameterNormalized { raw, qualifier })
            .boxed(),
        P_ME_NB_1 => (any::<i16>(), any::<u8>())
            .prop_map(|(value, qualifier)| Element::ParameterScaled { value, qualifier })
            .boxed(),
        P_ME_NC_1 => (float(), any::<u8>())
            .prop_map(|(value, qualifier)| Element::ParameterFloat { value, qualifier })
            .boxed(),
        P_AC_NA_1 => any::<u8>()
            .prop_map(|qualifier| Element::ParameterActivation { qualifier })
            .boxed(),
        F_FR_NA_1 => (any::<u16>(), length24(), any::<u8>())
            .prop_map(|(file, length, qualifier)| Element::FileReady {
                file,
                length,
                qualifier,
            })
            .boxed(),
        F_SR_NA_1 => (any::<u16>(), any::<u8>(), length24(), any::<u8>())
            .prop_map(|(file, section, length, qualifier)| Element::SectionReady {
                file,
                section,
                length,
                qualifier,
            })
            .boxed(),
        F_SC_NA_1 => (any::<u16>(), any::<u8>(), any::<u8>())
            .prop_map(|(file, section, qualifier)| Element::CallOrSelect {
                file,
                section,
                qualifier,
            })
            .boxed(),
        F_LS_NA_1 => (any::<u16>(), any::<u8>(), any::<u8>(), any::<u8>())
            .prop_map(
                |(file, section, qualifier, checksum)| Element::LastSegmentOrSection {
                    file,
                    section,
                    qualifier,
                    checksum,
                },
            )
            .boxed(),
        F_AF_NA_1 => (any::<u16>(), any::<u8>(), any::<u8>())
            .prop_map(|(file, section, qualifier)| Element::AckFileOrSection {
                file,
                section,
                qualifier,
            })
            .boxed(),
        F_SG_NA_1 => (
            any::<u16>(),
            any::<u8>(),
            proptest::collection::vec(any::<u8>(), 0..=40),
        )
            .prop_map(|(file, section, data)| Element::Segment {
                file,
                section,
                data,
            })
            .boxed(),
        F_DR_TA_1 => (any::<u16>(), length24(), any::<u8>())
            .prop_map(|(file, length, status)| Element::Directory {
                file,
                length,
                status,
            })
            .boxed(),
        F_SC_NB_1 => (any::<u16>(), cp56(), cp56())
            .prop_map(|(file, start, stop)| Element::QueryLog { file, start, stop })
            .boxed(),
    }
}

fn time_tag(type_id: TypeId) -> BoxedStrategy<Option<TimeTag>> {
    match type_id.time_tag() {
        TimeTagKind::None => Just(None).boxed(),
        TimeTagKind::Cp24 => cp24().prop_map(|t| Some(TimeTag::Cp24(t))).boxed(),
        TimeTagKind::Cp56 => cp56().prop_map(|t| Some(TimeTag::Cp56(t))).boxed(),
    }
}

/// How many objects fit, the same way the encoder counts (segments assumed at their
/// 40-octet maximum above).
fn capacity(type_id: TypeId, params: &AsduParams, sequence: bool) -> usize {
    let per_object = match type_id.element_len() {
        Some(_) => object_len(type_id, params, sequence),
        None => object_len(type_id, params, sequence) + 40,
    };
    let room = params.max_asdu_len()
        - params.header_len()
        - if sequence {
            usize::from(params.ioa_size())
        } else {
            0
        };
    (room / per_object.max(1)).clamp(1, 127)
}

fn cot(params: AsduParams) -> impl Strategy<Value = Cot> {
    let max_originator = if params.cot_size() == 2 { 255u8 } else { 0 };
    (0u8..=63, any::<bool>(), any::<bool>(), 0..=max_originator).prop_map(
        |(cause, negative, test, originator)| Cot {
            cause: Cause::new(cause).unwrap(),
            negative,
            test,
            originator,
        },
    )
}

/// A valid ASDU of `type_id` under `params`, with SQ = 1 whenever `sequence` and the type
/// has fixed-size elements.
fn asdu_of(type_id: TypeId, params: AsduParams, sequence: bool) -> BoxedStrategy<Asdu> {
    let sequence = sequence && type_id.element_len().is_some();
    let max_count = capacity(type_id, &params, sequence);
    let max_ioa = params.max_ioa();
    let object = (element(type_id), time_tag(type_id));
    (
        cot(params),
        0..=params.max_common_address(),
        proptest::collection::vec((0..=max_ioa, object), 1..=max_count),
    )
        .prop_flat_map(move |(cot, ca, objects)| {
            let count = u32::try_from(objects.len()).unwrap();
            // A base address such that base + count - 1 still fits the field.
            (Just((cot, ca, objects)), 0..=max_ioa - (count - 1))
        })
        .prop_map(move |((cot, ca, objects), base)| {
            let objects = objects
                .into_iter()
                .enumerate()
                .map(|(index, (address, (element, time)))| {
                    let address = if sequence {
                        base + u32::try_from(index).unwrap()
                    } else {
                        address
                    };
                    InformationObject {
                        ioa: Ioa::try_new(address).unwrap(),
                        element,
                        time,
                    }
                })
                .collect();
            Asdu {
                type_id,
                sequence,
                cot,
                common_address: CommonAddress::new(ca),
                objects,
            }
        })
        .boxed()
}

fn any_asdu() -> impl Strategy<Value = (AsduParams, Asdu)> {
    (
        select(all_params()),
        select(TypeId::ALL.to_vec()),
        any::<bool>(),
    )
        .prop_flat_map(|(params, type_id, sequence)| {
            (Just(params), asdu_of(type_id, params, sequence))
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn encode_then_decode_is_identity((params, asdu) in any_asdu()) {
        let mut bytes = Vec::new();
        asdu.encode(&params, &mut bytes).unwrap();
        prop_assert_eq!(bytes.len(), asdu.encoded_len(&params));
        prop_assert!(bytes.len() <= params.max_asdu_len());
        let decoded = Asdu::decode(&bytes, &params).unwrap();
        prop_assert_eq!(&decoded, &asdu);
        // The header alone decodes to the same fields.
        let header = AsduHeader::decode(&bytes, &params).unwrap();
        prop_assert_eq!(header, asdu.header());
        // Display never fails.
        prop_assert!(!asdu.to_string().is_empty());
    }

    #[test]
    fn arbitrary_bytes_never_panic(
        params in select(all_params()),
        bytes in proptest::collection::vec(any::<u8>(), 0..300),
    ) {
        check_no_panic(&bytes, &params);
    }

    #[test]
    fn every_type_with_plausible_header_never_panics(
        params in select(all_params()),
        type_id in select(TypeId::ALL.to_vec()),
        vsq in any::<u8>(),
        rest in proptest::collection::vec(any::<u8>(), 0..260),
    ) {
        let mut bytes = vec![type_id.value(), vsq];
        bytes.extend_from_slice(&rest);
        check_no_panic(&bytes, &params);
    }

    #[test]
    fn packing_preserves_objects(
        params in select(all_params()),
        type_id in select(vec![TypeId::M_SP_NA_1, TypeId::M_ME_NC_1, TypeId::M_DP_TB_1, TypeId::M_IT_NA_1]),
        gaps in proptest::collection::vec(prop_oneof![4 => Just(1u32), 1 => 2u32..5], 1..600),
        allow_sequence in any::<bool>(),
    ) {
        let max_ioa = params.max_ioa();
        let mut address = 0u32;
        let mut objects = Vec::new();
        for gap in gaps {
            address += gap;
            if address > max_ioa {
                break;
            }
            let element = match type_id {
                TypeId::M_SP_NA_1 => Element::SinglePoint { on: address % 2 == 0, quality: Quality::GOOD },
                TypeId::M_ME_NC_1 => Element::Float { value: address as f32, quality: Quality::GOOD },
                TypeId::M_DP_TB_1 => Element::DoublePoint { state: DoublePointState::On, quality: Quality::GOOD },
                _ => Element::IntegratedTotal(BinaryCounterReading::new(i32::try_from(address).unwrap(), 0).unwrap()),
            };
            let time = (type_id == TypeId::M_DP_TB_1)
                .then(|| TimeTag::Cp56(Cp56Time2a::new(17, 4, 26, 9, 59, 30_424).unwrap()));
            objects.push(InformationObject { ioa: Ioa::try_new(address).unwrap(), element, time });
        }
        let cot = Cot::new(Cause::INTERROGATED_BY_STATION);
        let ca = CommonAddress::new(1);
        let mut unpacked = Vec::new();
        for asdu in pack_objects(type_id, cot, ca, objects.clone(), &params, allow_sequence) {
            let bytes = asdu.to_bytes(&params).unwrap();
            prop_assert!(bytes.len() <= params.max_asdu_len());
            if asdu.sequence {
                prop_assert!(allow_sequence && type_id.allows_sequence());
            }
            unpacked.extend(Asdu::decode(&bytes, &params).unwrap().objects);
        }
        prop_assert_eq!(unpacked, objects);
    }
}

/// Decoding must return, not panic; what decodes must re-encode to the same length and
/// decode again to the same ASDU (compared through its bytes, as NaN != NaN).
fn check_no_panic(bytes: &[u8], params: &AsduParams) {
    let _ = AsduHeader::decode(bytes, params);
    let _ = mirror_with_cause(bytes, params, Cause::UNKNOWN_TYPE, true);
    let Ok(asdu) = Asdu::decode(bytes, params) else {
        return;
    };
    let _ = asdu.to_string();
    if bytes.len() > params.max_asdu_len() {
        // Decoding is lenient about the link's maximum, encoding is not.
        assert!(matches!(
            asdu.to_bytes(params),
            Err(AsduError::TooLong { .. })
        ));
        return;
    }
    let first = asdu.to_bytes(params).unwrap();
    assert_eq!(first.len(), bytes.len());
    let again = Asdu::decode(&first, params).unwrap();
    assert_eq!(again.to_bytes(params).unwrap(), first);
    assert_eq!(format!("{again:?}"), format!("{asdu:?}"));
}

/// A small deterministic generator (xorshift64*), so the stable mutation test needs no
/// extra dependency and reproduces exactly.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    fn below(&mut self, bound: usize) -> usize {
        (self.next() % bound as u64) as usize
    }

    fn byte(&mut self) -> u8 {
        self.next().to_le_bytes()[0]
    }
}

/// Valid encodings of every type under `params`, to mutate.
fn seeds(params: &AsduParams, rng: &mut Rng) -> Vec<Vec<u8>> {
    let mut seeds = Vec::new();
    let mut runner = proptest::test_runner::TestRunner::deterministic();
    for &type_id in TypeId::ALL {
        for sequence in [false, true] {
            let strategy = asdu_of(type_id, *params, sequence);
            for _ in 0..2 {
                let asdu = strategy.new_tree(&mut runner).unwrap().current();
                seeds.push(asdu.to_bytes(params).unwrap());
            }
        }
    }
    // A few of pure noise too.
    for _ in 0..8 {
        let len = rng.below(64);
        seeds.push((0..len).map(|_| rng.byte()).collect());
    }
    seeds
}

fn mutate(seed: &[u8], rng: &mut Rng) -> Vec<u8> {
    let mut bytes = seed.to_vec();
    for _ in 0..=rng.below(4) {
        match rng.below(8) {
            0 if !bytes.is_empty() => {
                let at = rng.below(bytes.len());
                bytes[at] ^= 1 << rng.below(8);
            }
            1 if !bytes.is_empty() => {
                let at = rng.below(bytes.len());
                bytes[at] = rng.byte();
            }
            2 => {
                let len = rng.below(bytes.len() + 1);
                bytes.truncate(len);
            }
            3 => {
                for _ in 0..=rng.below(8) {
                    bytes.push(rng.byte());
                }
            }
            4 if bytes.len() > 1 => bytes[1] = rng.byte(), // VSQ: count and SQ
            5 if !bytes.is_empty() => bytes[0] = rng.byte(), // type identification
            6 if !bytes.is_empty() => {
                let at = rng.below(bytes.len());
                bytes.remove(at);
            }
            _ => {
                let at = rng.below(bytes.len() + 1);
                bytes.insert(at, rng.byte());
            }
        }
    }
    bytes
}

#[test]
fn two_hundred_thousand_mutated_inputs_never_panic() {
    let mut rng = Rng(0x5EED_60870);
    let params = all_params();
    let corpus: Vec<(AsduParams, Vec<Vec<u8>>)> =
        params.iter().map(|p| (*p, seeds(p, &mut rng))).collect();
    let mut decoded = 0usize;
    for round in 0..200_000 {
        let (params, seeds) = &corpus[round % corpus.len()];
        let seed = &seeds[rng.below(seeds.len())];
        let input = if round % 10 == 0 {
            let len = rng.below(300);
            (0..len).map(|_| rng.byte()).collect()
        } else {
            mutate(seed, &mut rng)
        };
        check_no_panic(&input, params);
        if Asdu::decode(&input, params).is_ok() {
            decoded += 1;
        }
    }
    // The mutations must still reach the element decoders, not only the header checks.
    assert!(decoded > 10_000, "only {decoded} inputs decoded");
}
