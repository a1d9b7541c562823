//! `pack_objects`: information objects packed into ASDUs within the length limits, with
//! SQ=1 only for runs of consecutive addresses.

use iec60870::asdu::*;

use crate::support::*;

fn float_points(addresses: impl IntoIterator<Item = u32>) -> Vec<InformationObject> {
    addresses
        .into_iter()
        .map(|address| {
            InformationObject::new(
                ioa(address),
                Element::Float {
                    value: address as f32,
                    quality: Quality::GOOD,
                },
            )
        })
        .collect()
}

fn unpack(asdus: &[Asdu], params: &AsduParams) -> Vec<InformationObject> {
    let mut objects = Vec::new();
    for asdu in asdus {
        let bytes = asdu.to_bytes(params).unwrap();
        assert!(bytes.len() <= params.max_asdu_len());
        objects.extend(Asdu::decode(&bytes, params).unwrap().objects);
    }
    objects
}

#[test]
fn packing_a_large_interrogation() {
    let gi = Cot::new(Cause::INTERROGATED_BY_STATION);
    let points: Vec<InformationObject> = (1..=100_000u32)
        .map(|n| {
            InformationObject::new(
                ioa(n),
                Element::SinglePoint {
                    on: n % 3 == 0,
                    quality: Quality::GOOD,
                },
            )
        })
        .collect();
    let started = std::time::Instant::now();
    let asdus: Vec<Asdu> =
        pack_objects(TypeId::M_SP_NA_1, gi, ca1(), points.clone(), &P104, true).collect();
    let elapsed = started.elapsed();
    assert_eq!(asdus.len(), 100_000usize.div_ceil(127));
    assert!(asdus.iter().all(|asdu| asdu.sequence));
    assert!(asdus[..asdus.len() - 1]
        .iter()
        .all(|a| a.objects.len() == 127));
    assert_eq!(unpack(&asdus, &P104), points);
    assert!(elapsed.as_secs() < 5, "packing took {elapsed:?}");

    // Without SQ: 60 per ASDU.
    let asdus: Vec<Asdu> =
        pack_objects(TypeId::M_SP_NA_1, gi, ca1(), points.clone(), &P104, false).collect();
    assert_eq!(asdus.len(), 100_000usize.div_ceil(60));
    assert!(asdus.iter().all(|asdu| !asdu.sequence));
    assert_eq!(unpack(&asdus, &P104), points);
}

#[test]
fn packing_mixed_runs() {
    let gi = Cot::new(Cause::INTERROGATED_BY_STATION);
    // Scattered addresses, a pair, a long run, more scatter, a run of 3.
    let mut addresses: Vec<u32> = vec![5, 9, 20, 21];
    addresses.extend(100..200);
    addresses.extend([300, 302, 304, 400, 401, 402]);
    let points = float_points(addresses.iter().copied());
    let asdus: Vec<Asdu> =
        pack_objects(TypeId::M_ME_NC_1, gi, ca1(), points.clone(), &P104, true).collect();
    assert_eq!(unpack(&asdus, &P104), points);
    let shapes: Vec<(bool, usize)> = asdus
        .iter()
        .map(|a| (a.sequence, a.objects.len()))
        .collect();
    assert_eq!(
        shapes,
        [
            (false, 4), // 5, 9, 20, 21: scattered and a pair
            (true, 48), // 100..=147
            (true, 48), // 148..=195
            (true, 4),  // 196..=199
            (false, 3), // 300, 302, 304
            (true, 3),  // 400..=402
        ]
    );
    // Every ASDU respects the limits and SQ=1 only holds consecutive runs.
    for asdu in &asdus {
        assert!(asdu.encoded_len(&P104) <= 249);
        assert!(asdu.objects.len() <= 127);
    }
    // Time-tagged types never use SQ=1.
    let tagged: Vec<InformationObject> = (1..=50)
        .map(|n| {
            InformationObject::with_time(
                ioa(n),
                Element::SinglePoint {
                    on: true,
                    quality: Quality::GOOD,
                },
                cp56(T),
            )
        })
        .collect();
    let asdus: Vec<Asdu> =
        pack_objects(TypeId::M_SP_TB_1, gi, ca1(), tagged.clone(), &P104, true).collect();
    assert!(asdus.iter().all(|a| !a.sequence));
    assert_eq!(
        asdus.iter().map(|a| a.objects.len()).collect::<Vec<_>>(),
        [22, 22, 6]
    );
    assert_eq!(unpack(&asdus, &P104), tagged);
    // Nothing in, nothing out.
    assert_eq!(
        pack_objects(TypeId::M_SP_NA_1, gi, ca1(), Vec::new(), &P104, true).count(),
        0
    );
}
