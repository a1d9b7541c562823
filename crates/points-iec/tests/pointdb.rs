//! Tests of the point database: type checks, report by exception, deadbands, invalidation,
//! element conversions, the process image, cyclic points and communication status: the
//! point model as a node's IEC 104 server sees it.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

use std::collections::HashMap;
use std::time::Duration;

use chrono::{DateTime, TimeZone, Utc};
use iec60870::asdu::{Element, Ioa, TimeTag, TypeId};
use iec60870::time::TimeZonePolicy;
use points::{
    EventCause, PointChange, PointDb, PointDbError, PointSource, PointSpec, PointValue, Quality,
    SourceTime, Transmission,
};
use points_iec::{
    from_element, point_type, process_image, time_tag, to_element, transmission_cause, type_id,
};
use proptest::prelude::*;

fn ioa(n: u32) -> Ioa {
    Ioa::try_new(n).unwrap()
}

/// The element a change is sent as.
fn element_of(c: &PointChange) -> Element {
    to_element(c.point_type, &c.value, c.quality)
}

fn spec(name: &str, type_id: TypeId, n: u32) -> PointSpec {
    PointSpec {
        name: name.into(),
        point_type: point_type(type_id).unwrap(),
        address: n,
        transmission: Transmission::Spontaneous,
        groups: 1,
        deadband: None,
        source: PointSource::Variable(format!("plc:{name}")),
        storage: points::StorageRule::default(),
        description: String::new(),
    }
}

fn t(s: i64) -> DateTime<Utc> {
    Utc.with_ymd_and_hms(2026, 1, 15, 12, 0, 0).unwrap() + chrono::TimeDelta::seconds(s)
}

fn good(db: &mut PointDb, name: &str, v: PointValue) -> Result<Option<PointChange>, PointDbError> {
    db.update(name, v, Quality::GOOD, None, t(0), EventCause::Spontaneous)
}

fn all_types_db() -> PointDb {
    PointDb::new(
        "N",
        vec![
            spec("sp", TypeId::M_SP_TB_1, 1),
            spec("dp", TypeId::M_DP_TB_1, 2),
            spec("st", TypeId::M_ST_TB_1, 3),
            spec("bo", TypeId::M_BO_TB_1, 4),
            spec("na", TypeId::M_ME_TD_1, 5),
            spec("nb", TypeId::M_ME_TE_1, 6),
            spec("nc", TypeId::M_ME_TF_1, 7),
            spec("it", TypeId::M_IT_TB_1, 8),
        ],
    )
    .unwrap()
}

#[test]
fn construction_refuses_duplicates_and_bad_specs() {
    let dup_name = PointDb::new(
        "N",
        vec![
            spec("a", TypeId::M_SP_NA_1, 1),
            spec("a", TypeId::M_SP_NA_1, 2),
        ],
    );
    assert_eq!(
        dup_name.unwrap_err(),
        PointDbError::DuplicateName("a".into())
    );
    let dup_ioa = PointDb::new(
        "N",
        vec![
            spec("a", TypeId::M_SP_NA_1, 1),
            spec("b", TypeId::M_DP_NA_1, 1),
        ],
    );
    assert!(
        matches!(dup_ioa, Err(PointDbError::DuplicateIoa { ref first, ref second, .. }) if first == "a" && second == "b")
    );
    // Protection events and commands are no point types.
    assert_eq!(point_type(TypeId::M_EP_TD_1), None);
    assert_eq!(point_type(TypeId::C_SC_NA_1), None);
    let mut sp_band = spec("a", TypeId::M_SP_NA_1, 1);
    sp_band.deadband = Some(1.0);
    assert!(matches!(
        PointDb::new("N", vec![sp_band]),
        Err(PointDbError::InvalidDeadband { .. })
    ));
    let mut neg_band = spec("a", TypeId::M_ME_NC_1, 1);
    neg_band.deadband = Some(-1.0);
    assert!(matches!(
        PointDb::new("N", vec![neg_band]),
        Err(PointDbError::InvalidDeadband { .. })
    ));
    let mut zero = spec("a", TypeId::M_ME_NC_1, 1);
    zero.transmission = Transmission::Cyclic(Duration::ZERO);
    assert!(matches!(
        PointDb::new("N", vec![zero]),
        Err(PointDbError::ZeroPeriod(_))
    ));
    assert!(matches!(
        PointDb::new("N", vec![spec("", TypeId::M_SP_NA_1, 1)]),
        Err(PointDbError::EmptyName(_))
    ));
}

#[test]
fn lookups_by_name_ioa_source_and_id() {
    let db = all_types_db();
    assert_eq!(db.node(), "N");
    assert_eq!(db.len(), 8);
    assert_eq!(db.get("dp").unwrap().spec.address, 2);
    assert_eq!(db.get(3u32).unwrap().spec.name, "st");
    let id = db.id("nc").unwrap();
    assert_eq!(db.get(id).unwrap().spec.name, "nc");
    assert_eq!(
        db.by_source(&PointSource::Variable("plc:bo".into()))
            .map(|p| p.spec.name.as_str())
            .collect::<Vec<_>>(),
        ["bo"]
    );
    assert!(db.get("nope").is_none());
    assert!(db.get(99u32).is_none());
    assert_eq!(
        db.by_source(&PointSource::Variable("nope".into())).count(),
        0
    );
    // Initially IV with the type's zero.
    let p = db.get("sp").unwrap();
    assert!(!p.has_value());
    assert_eq!(p.quality, Quality::INVALID);
    assert_eq!(p.value, PointValue::Bool(false));
}

#[test]
fn every_type_accepts_and_refuses() {
    use PointValue::*;
    let accept: &[(&str, PointValue)] = &[
        ("sp", Bool(true)),
        ("dp", DoublePoint(0)),
        ("dp", DoublePoint(3)),
        ("st", Int(-64)),
        ("st", Int(63)),
        ("bo", Bits(0xDEAD_BEEF)),
        ("na", Float(-1.0)),
        ("na", Float(1.0)),
        ("na", Float(0.5)),
        ("nb", Int(-32768)),
        ("nb", Int(32767)),
        ("nc", Float(1.5e30)),
        ("nc", Float(-3.25)),
        ("it", Int(i64::from(i32::MIN))),
        ("it", Int(i64::from(i32::MAX))),
    ];
    let refuse: &[(&str, PointValue)] = &[
        ("sp", Int(1)),
        ("sp", Text("x".into())),
        ("dp", DoublePoint(4)),
        ("dp", Bool(true)),
        ("st", Int(64)),
        ("st", Int(-65)),
        ("st", Float(1.0)),
        ("bo", Int(5)),
        ("na", Float(1.0001)),
        ("na", Float(-1.5)),
        ("na", Float(f64::NAN)),
        ("na", Int(0)),
        ("nb", Int(32768)),
        ("nb", Int(-32769)),
        ("nb", Float(1.0)),
        ("nc", Float(f64::NAN)),
        ("nc", Float(f64::INFINITY)),
        ("nc", Float(1e300)),
        ("nc", Int(1)),
        ("it", Int(i64::from(i32::MAX) + 1)),
        ("it", Bits(1)),
    ];
    let mut db = all_types_db();
    for (name, v) in accept {
        assert!(
            good(&mut db, name, v.clone()).is_ok(),
            "{name} should accept {v:?}"
        );
    }
    for (name, v) in refuse {
        let err = good(&mut db, name, v.clone()).unwrap_err();
        assert!(
            matches!(err, PointDbError::ValueRefused { .. }),
            "{name} {v:?}: {err}"
        );
    }
    assert!(matches!(
        good(&mut db, "missing", Bool(true)),
        Err(PointDbError::UnknownPoint(_))
    ));
}

#[test]
fn values_are_quantized_to_the_wire() {
    let mut db = all_types_db();
    good(&mut db, "na", PointValue::Float(0.335_114)).unwrap();
    // round(0.335114 * 32768) = 10981 = 0x2AE5.
    assert_eq!(
        db.get("na").unwrap().value,
        PointValue::Float(10981.0 / 32768.0)
    );
    good(&mut db, "na", PointValue::Float(1.0)).unwrap();
    assert_eq!(
        db.get("na").unwrap().value,
        PointValue::Float(32767.0 / 32768.0)
    );
    good(&mut db, "nc", PointValue::Float(0.1)).unwrap();
    assert_eq!(
        db.get("nc").unwrap().value,
        PointValue::Float(f64::from(0.1_f32))
    );
}

#[test]
fn report_by_exception() {
    let mut db = all_types_db();
    let first = good(&mut db, "sp", PointValue::Bool(false))
        .unwrap()
        .unwrap();
    assert_eq!(first.value, PointValue::Bool(false));
    assert_eq!(first.quality, Quality::GOOD);
    assert!(first.send);
    assert!(good(&mut db, "sp", PointValue::Bool(false))
        .unwrap()
        .is_none());
    assert!(good(&mut db, "sp", PointValue::Bool(true))
        .unwrap()
        .is_some());
    assert!(good(&mut db, "sp", PointValue::Bool(true))
        .unwrap()
        .is_none());
    // A new source time alone is not a change.
    let st = Some(SourceTime {
        time: t(5),
        invalid: false,
    });
    assert!(db
        .update(
            "sp",
            PointValue::Bool(true),
            Quality::GOOD,
            st,
            t(5),
            EventCause::Spontaneous
        )
        .unwrap()
        .is_none());
    assert_eq!(db.get("sp").unwrap().source_time, st);
    // Double points, bitstrings, integers.
    for (name, a, b) in [
        ("dp", PointValue::DoublePoint(1), PointValue::DoublePoint(2)),
        ("bo", PointValue::Bits(1), PointValue::Bits(3)),
        ("it", PointValue::Int(10), PointValue::Int(11)),
        ("st", PointValue::Int(-3), PointValue::Int(4)),
    ] {
        assert!(good(&mut db, name, a.clone()).unwrap().is_some());
        assert!(good(&mut db, name, a).unwrap().is_none());
        assert_eq!(good(&mut db, name, b.clone()).unwrap().unwrap().value, b);
    }
}

#[test]
fn quality_only_changes_are_reported() {
    let mut db = all_types_db();
    good(&mut db, "dp", PointValue::DoublePoint(2)).unwrap();
    let nt = Quality {
        not_topical: true,
        ..Quality::GOOD
    };
    let c = db
        .update(
            "dp",
            PointValue::DoublePoint(2),
            nt,
            None,
            t(1),
            EventCause::Spontaneous,
        )
        .unwrap()
        .unwrap();
    assert_eq!(c.quality, nt);
    assert!(db
        .update(
            "dp",
            PointValue::DoublePoint(2),
            nt,
            None,
            t(2),
            EventCause::Spontaneous
        )
        .unwrap()
        .is_none());
    assert!(good(&mut db, "dp", PointValue::DoublePoint(2))
        .unwrap()
        .is_some());
}

#[test]
fn deadband_uses_the_last_reported_value() {
    let mut s = spec("u", TypeId::M_ME_TF_1, 10);
    s.deadband = Some(1.0);
    let mut nb = spec("i", TypeId::M_ME_TE_1, 11);
    nb.deadband = Some(10.0);
    let mut db = PointDb::new("N", vec![s, nb]).unwrap();
    let f = PointValue::Float;
    assert!(good(&mut db, "u", f(230.0)).unwrap().is_some());
    // Creeping up by 0.5: the second step reaches the deadband from 230 (reported).
    assert!(good(&mut db, "u", f(230.5)).unwrap().is_none());
    assert_eq!(db.get("u").unwrap().value, f(230.5)); // still held
    let c = good(&mut db, "u", f(231.0)).unwrap().unwrap();
    assert_eq!(c.value, f(231.0));
    // Negative changes.
    assert!(good(&mut db, "u", f(230.25)).unwrap().is_none());
    assert!(good(&mut db, "u", f(230.5)).unwrap().is_none());
    assert!(good(&mut db, "u", f(230.125)).unwrap().is_none());
    assert_eq!(
        good(&mut db, "u", f(230.0)).unwrap().unwrap().value,
        f(230.0)
    );
    // Back and forth within the band of the reported 230 never reports.
    for x in [229.25, 230.75, 229.5, 230.5] {
        assert!(good(&mut db, "u", f(x)).unwrap().is_none(), "{x}");
    }
    // A quality change within the band is reported, with the newest value.
    let c = db
        .update(
            "u",
            f(229.6),
            Quality::INVALID,
            None,
            t(1),
            EventCause::Spontaneous,
        )
        .unwrap()
        .unwrap();
    assert_eq!(
        (c.value, c.quality),
        (f(229.6_f32.into()), Quality::INVALID)
    );
    // Scaled with an integer deadband.
    let i = PointValue::Int;
    assert!(good(&mut db, "i", i(100)).unwrap().is_some());
    assert!(good(&mut db, "i", i(109)).unwrap().is_none());
    assert!(good(&mut db, "i", i(91)).unwrap().is_none());
    assert!(good(&mut db, "i", i(90)).unwrap().is_some());
    assert!(good(&mut db, "i", i(81)).unwrap().is_none());
    assert!(good(&mut db, "i", i(100)).unwrap().is_some());
}

#[test]
fn bulk_invalidation_of_a_link_and_recovery() {
    let mut specs = Vec::new();
    for n in 281..=284 {
        let mut s = spec(&format!("RH2_{n}"), TypeId::M_SP_TB_1, n);
        s.source = PointSource::Link {
            link: "RH2".into(),
            ioa: n,
        };
        specs.push(s);
    }
    let mut other = spec("RZS_1", TypeId::M_SP_TB_1, 400);
    other.source = PointSource::Link {
        link: "RZS".into(),
        ioa: 1,
    };
    specs.push(other);
    let mut db = PointDb::new("RDRT", specs).unwrap();
    for n in 281..=283 {
        good(&mut db, &format!("RH2_{n}"), PointValue::Bool(n % 2 == 0)).unwrap();
    }
    good(&mut db, "RZS_1", PointValue::Bool(true)).unwrap();
    let changes = db.invalidate_link("RH2", t(10));
    // 284 never had a value: it is IV already.
    let names: Vec<_> = changes.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["RH2_281", "RH2_282", "RH2_283"]);
    for c in &changes {
        assert!(c.quality.invalid);
        assert_eq!(c.received, t(10));
        assert_eq!(
            c.source_time,
            Some(SourceTime {
                time: t(10),
                invalid: false
            })
        );
    }
    assert_eq!(changes[1].value, PointValue::Bool(true)); // last value kept
    assert!(!db.get("RZS_1").unwrap().quality.invalid);
    // Twice: nothing new.
    assert!(db.invalidate_link("RH2", t(11)).is_empty());
    // Recovery: the same value with good quality is reported; a later repeat is not.
    let back = good(&mut db, "RH2_282", PointValue::Bool(true))
        .unwrap()
        .unwrap();
    assert_eq!(back.quality, Quality::GOOD);
    assert!(good(&mut db, "RH2_282", PointValue::Bool(true))
        .unwrap()
        .is_none());
    // Predicate form (a module's points by IOA range, spec §7.2), other flags kept.
    let sb = Quality {
        substituted: true,
        ..Quality::GOOD
    };
    db.update(
        "RZS_1",
        PointValue::Bool(true),
        sb,
        None,
        t(12),
        EventCause::Spontaneous,
    )
    .unwrap();
    let changes = db.invalidate_where(|s| s.address >= 400, t(13));
    assert_eq!(changes.len(), 1);
    assert_eq!(
        changes[0].quality,
        Quality {
            invalid: true,
            substituted: true,
            ..Quality::GOOD
        }
    );
}

#[test]
fn link_status_points_are_true_on_failure() {
    let mut db = PointDb::new(
        "RDRT",
        vec![
            spec("PorKom_RH", TypeId::M_SP_TB_1, 32),
            spec("m", TypeId::M_ME_NC_1, 33),
        ],
    )
    .unwrap();
    let c = db
        .set_link_status("PorKom_RH", false, t(1))
        .unwrap()
        .unwrap();
    assert_eq!(c.value, PointValue::Bool(true));
    assert_eq!(c.quality, Quality::GOOD);
    assert_eq!(c.source_time.unwrap().time, t(1));
    assert!(db
        .set_link_status("PorKom_RH", false, t(2))
        .unwrap()
        .is_none());
    let c = db.set_link_status(32u32, true, t(3)).unwrap().unwrap();
    assert_eq!(c.value, PointValue::Bool(false));
    assert!(db.set_link_status("m", true, t(3)).is_err());
}

fn prague() -> TimeZonePolicy {
    TimeZonePolicy::Zone(chrono_tz::Europe::Prague)
}

fn change(
    type_id: TypeId,
    value: PointValue,
    quality: Quality,
    time: DateTime<Utc>,
) -> PointChange {
    PointChange {
        name: "p".into(),
        address: 1,
        point_type: point_type(type_id).unwrap(),
        value,
        quality,
        source_time: Some(SourceTime {
            time,
            invalid: false,
        }),
        received: time,
        cause: EventCause::Spontaneous,
        send: true,
    }
}

#[test]
fn element_round_trips_for_every_family() {
    use PointValue::*;
    let flags = Quality {
        not_topical: true,
        substituted: true,
        blocked: true,
        ..Quality::GOOD
    };
    let ov = Quality {
        overflow: true,
        ..Quality::GOOD
    };
    let cases: Vec<(TypeId, PointValue, Quality)> = vec![
        (TypeId::M_SP_TB_1, Bool(true), flags),
        (TypeId::M_SP_TB_1, Bool(false), Quality::INVALID),
        (TypeId::M_DP_TB_1, DoublePoint(2), flags),
        (TypeId::M_DP_TB_1, DoublePoint(3), Quality::GOOD),
        (TypeId::M_ST_TB_1, Int(-64), ov),
        (TypeId::M_ST_TB_1, Int(63), flags),
        (TypeId::M_BO_TB_1, Bits(0x8000_0001), ov),
        (TypeId::M_ME_TD_1, Float(10981.0 / 32768.0), ov),
        (TypeId::M_ME_TD_1, Float(-1.0), Quality::INVALID),
        (TypeId::M_ME_TE_1, Int(-32768), flags),
        (TypeId::M_ME_TF_1, Float(231.5), ov),
        (
            TypeId::M_IT_TB_1,
            Int(-5),
            Quality {
                invalid: true,
                overflow: true,
                ..Quality::GOOD
            },
        ),
        (TypeId::M_IT_TB_1, Int(123_456), Quality::GOOD),
    ];
    let winter =
        Utc.with_ymd_and_hms(2026, 1, 15, 11, 0, 0).unwrap() + chrono::TimeDelta::milliseconds(424);
    let summer = Utc.with_ymd_and_hms(2026, 7, 15, 11, 0, 0).unwrap();
    for (type_id, value, quality) in cases {
        for (zone, time, hour, su) in [
            (TimeZonePolicy::Utc, winter, 11, false),
            (TimeZonePolicy::Utc, summer, 11, false),
            (prague(), winter, 12, false),
            (prague(), summer, 13, true),
        ] {
            let c = change(type_id, value.clone(), quality, time);
            let element = element_of(&c);
            assert!(element.family_matches(type_id));
            let tag = time_tag(&c, zone).unwrap();
            assert_eq!(tag.hour(), hour);
            assert_eq!(tag.is_summer_time(), su);
            assert!(!tag.is_invalid());
            let (v, q, st) =
                from_element(type_id, &element, Some(&TimeTag::Cp56(tag)), zone).unwrap();
            assert_eq!((v, q), (value.clone(), quality), "{type_id}");
            assert_eq!(
                st,
                Some(SourceTime {
                    time,
                    invalid: false
                })
            );
        }
    }
    // Untagged type, CP24 tag and a wrong element.
    let e = Element::SinglePoint {
        on: true,
        quality: Default::default(),
    };
    assert_eq!(
        from_element(TypeId::M_SP_NA_1, &e, None, TimeZonePolicy::Utc).unwrap(),
        (Bool(true), Quality::GOOD, None)
    );
    assert!(from_element(TypeId::M_DP_NA_1, &e, None, TimeZonePolicy::Utc).is_err());
    assert!(from_element(TypeId::M_EP_TD_1, &e, None, TimeZonePolicy::Utc).is_err());
}

#[test]
fn time_tag_iv_and_dst_edges() {
    let mut c = change(
        TypeId::M_SP_TB_1,
        PointValue::Bool(true),
        Quality::GOOD,
        t(0),
    );
    c.source_time = Some(SourceTime {
        time: t(0),
        invalid: true,
    });
    let tag = time_tag(&c, TimeZonePolicy::Utc).unwrap();
    assert!(tag.is_invalid());
    let (_, _, st) = from_element(
        type_id(c.point_type),
        &element_of(&c),
        Some(&TimeTag::Cp56(tag)),
        TimeZonePolicy::Utc,
    )
    .unwrap();
    assert_eq!(
        st,
        Some(SourceTime {
            time: t(0),
            invalid: true
        })
    );
    c.source_time = None;
    assert!(time_tag(&c, TimeZonePolicy::Utc).is_none());
    // The repeated hour of 2026-10-25 in Prague: 00:30 UTC (summer, 02:30 CEST) and
    // 01:30 UTC (winter, 02:30 CET) read back apart thanks to the SU bit.
    for (utc_hour, su) in [(0, true), (1, false)] {
        let time = Utc.with_ymd_and_hms(2026, 10, 25, utc_hour, 30, 0).unwrap();
        let tag = prague().to_cp56(time);
        assert_eq!((tag.hour(), tag.is_summer_time()), (2, su));
        assert_eq!(
            prague().from_cp56(&tag),
            Some(SourceTime {
                time,
                invalid: false
            })
        );
    }
}

#[test]
fn a_change_keeps_its_cause_for_the_wire() {
    let mut db = all_types_db();
    let st = Some(SourceTime {
        time: t(1),
        invalid: false,
    });
    let c = db
        .update(
            "nb",
            PointValue::Int(7),
            Quality::GOOD,
            st,
            t(2),
            EventCause::ReturnRemote,
        )
        .unwrap()
        .unwrap();
    assert_eq!(
        transmission_cause(c.cause),
        iec60870::asdu::Cause::RETURN_REMOTE
    );
    assert_eq!(c.address, 6);
    assert_eq!(c.source_time, st);
}

#[test]
fn process_image_matches_the_database() {
    let mut specs = vec![
        spec("sp", TypeId::M_SP_TB_1, 281),
        spec("nc", TypeId::M_ME_NC_1, 300),
    ];
    specs[1].groups = 0b101;
    let mut db = PointDb::new("N", specs).unwrap();
    let st = Some(SourceTime {
        time: t(0),
        invalid: false,
    });
    db.update(
        "sp",
        PointValue::Bool(true),
        Quality::GOOD,
        st,
        t(0),
        EventCause::Spontaneous,
    )
    .unwrap();
    let image = process_image(&db, TimeZonePolicy::Utc).unwrap();
    assert_eq!(image.monitor_len(), 2);
    let sp = image.monitor(ioa(281)).unwrap();
    assert_eq!(sp.event_type, TypeId::M_SP_TB_1);
    assert_eq!(sp.groups, 1);
    assert_eq!(
        sp.element,
        Element::SinglePoint {
            on: true,
            quality: Default::default()
        }
    );
    assert_eq!(sp.time.unwrap().as_cp56().unwrap().hour(), 12);
    let nc = image.monitor(ioa(300)).unwrap();
    assert_eq!(nc.groups, 0b101);
    assert!(nc.answers_interrogation(23) && !nc.answers_interrogation(22));
    // Never updated: zero with IV.
    assert_eq!(
        nc.element.quality().unwrap(),
        iec60870::asdu::Quality::INVALID
    );
    assert_eq!(nc.time, None);
    // An untagged type carries no time in the image, even with a source time.
    db.update(
        "nc",
        PointValue::Float(1.5),
        Quality::GOOD,
        st,
        t(0),
        EventCause::Spontaneous,
    )
    .unwrap();
    let image = process_image(&db, TimeZonePolicy::Utc).unwrap();
    let nc = image.monitor(ioa(300)).unwrap();
    assert_eq!(
        nc.element,
        Element::Float {
            value: 1.5,
            quality: Default::default()
        }
    );
    assert_eq!(nc.time, None);
}

#[test]
fn cyclic_points_and_their_due_times() {
    let mut a = spec("a", TypeId::M_ME_NC_1, 1);
    a.transmission = Transmission::Cyclic(Duration::from_secs(10));
    let mut b = spec("b", TypeId::M_ME_NC_1, 2);
    b.transmission = Transmission::Cyclic(Duration::from_secs(25));
    let mut gi = spec("gi", TypeId::M_ME_NC_1, 3);
    gi.transmission = Transmission::InterrogationOnly;
    let mut db = PointDb::new("N", vec![a, b, gi, spec("s", TypeId::M_SP_NA_1, 4)]).unwrap();
    assert_eq!(db.next_cyclic_due(t(0)), Some(t(0)));
    // Changes of cyclic and interrogation-only points are not sent spontaneously.
    let c = good(&mut db, "a", PointValue::Float(1.0)).unwrap().unwrap();
    assert!(!c.send);
    assert!(
        !good(&mut db, "gi", PointValue::Float(1.0))
            .unwrap()
            .unwrap()
            .send
    );
    // First call: every cyclic point with a value is due ("b" has none yet).
    let due = db.due_cyclic(t(0));
    assert_eq!(
        due.iter().map(|c| c.name.as_str()).collect::<Vec<_>>(),
        ["a"]
    );
    assert!(due[0].send);
    assert_eq!(due[0].cause, EventCause::Cyclic);
    assert_eq!(
        transmission_cause(due[0].cause),
        iec60870::asdu::Cause::PERIODIC
    );
    assert_eq!(db.next_cyclic_due(t(0)), Some(t(10)));
    good(&mut db, "b", PointValue::Float(2.0)).unwrap();
    assert!(db.due_cyclic(t(9)).is_empty());
    assert_eq!(db.due_cyclic(t(10)).len(), 1);
    assert!(db.due_cyclic(t(19)).is_empty());
    // Late by 1 s: the next due time stays on the grid (30).
    assert_eq!(db.due_cyclic(t(21)).len(), 1);
    assert_eq!(db.next_cyclic_due(t(21)), Some(t(25)));
    let due = db.due_cyclic(t(25));
    assert_eq!(
        due.iter().map(|c| c.name.as_str()).collect::<Vec<_>>(),
        ["b"]
    );
    assert_eq!(due[0].value, PointValue::Float(2.0));
    assert_eq!(db.due_cyclic(t(30)).len(), 1);
    // Missed many periods: one transmission, then rescheduled from now.
    assert_eq!(db.due_cyclic(t(1000)).len(), 2);
    assert_eq!(db.next_cyclic_due(t(1000)), Some(t(1010)));
}

fn arb_value() -> impl Strategy<Value = PointValue> {
    prop_oneof![
        any::<bool>().prop_map(PointValue::Bool),
        (0u8..6).prop_map(PointValue::DoublePoint),
        prop_oneof![-70i64..70, -40000i64..40000, any::<i64>()].prop_map(PointValue::Int),
        prop_oneof![-1.2f64..1.2, -1e6f64..1e6, any::<f64>()].prop_map(PointValue::Float),
        any::<u32>().prop_map(PointValue::Bits),
        "[a-z]{0,3}".prop_map(PointValue::Text),
    ]
}

fn arb_quality() -> impl Strategy<Value = Quality> {
    (
        any::<bool>(),
        any::<bool>(),
        any::<bool>(),
        any::<bool>(),
        any::<bool>(),
    )
        .prop_map(
            |(invalid, not_topical, substituted, blocked, overflow)| Quality {
                invalid,
                not_topical,
                substituted,
                blocked,
                overflow,
            },
        )
}

proptest! {
    #[test]
    fn random_updates_never_panic_nor_report_unchanged(
        ops in prop::collection::vec((0usize..9, arb_value(), arb_quality()), 1..200)
    ) {
        let mut specs: Vec<PointSpec> = all_types_db().points().map(|p| p.spec.clone()).collect();
        specs[4].deadband = Some(0.01);
        specs[6].deadband = Some(5.0);
        let mut db = PointDb::new("N", specs).unwrap();
        let names = ["sp", "dp", "st", "bo", "na", "nb", "nc", "it", "missing"];
        // Before any update each point shows its initial state (zero, IV): that counts as
        // reported, so an update leaving it so is silent.
        let mut last: HashMap<String, (PointValue, Quality)> = db
            .points()
            .map(|p| (p.spec.name.clone(), (p.value.clone(), p.quality)))
            .collect();
        for (i, (n, value, quality)) in ops.into_iter().enumerate() {
            let name = names[n];
            let time = t(i64::try_from(i).unwrap());
            if name == "missing" && quality.invalid {
                // A link failure: bulk invalidation of everything.
                for c in db.invalidate_where(|_| true, time) {
                    prop_assert_ne!(last.get(&c.name), Some(&(c.value.clone(), c.quality)));
                    let _ = element_of(&c);
                    last.insert(c.name.clone(), (c.value, c.quality));
                }
                continue;
            }
            match db.update(name, value, quality, None, time, EventCause::Spontaneous) {
                Ok(Some(c)) => {
                    prop_assert_ne!(last.get(name), Some(&(c.value.clone(), c.quality)));
                    let element = element_of(&c);
                    let (v, q, _) =
                        from_element(type_id(c.point_type), &element, None, TimeZonePolicy::Utc).unwrap();
                    prop_assert_eq!(&v, &c.value);
                    if type_id(c.point_type) != TypeId::M_IT_TB_1 {
                        let mut expect = c.quality;
                        if matches!(type_id(c.point_type), TypeId::M_SP_TB_1 | TypeId::M_DP_TB_1) {
                            expect.overflow = false;
                        }
                        prop_assert_eq!(q, expect);
                    }
                    last.insert(name.to_owned(), (c.value, c.quality));
                }
                Ok(None) => {
                    // Without deadband, silence means nothing changed.
                    let point = db.get(name).unwrap();
                    if point.spec.deadband.is_none() {
                        prop_assert_eq!(
                            last.get(name),
                            Some(&(point.value.clone(), point.quality))
                        );
                    }
                }
                Err(_) => {}
            }
        }
        prop_assert!(process_image(&db, prague()).is_ok());
        let _ = db.due_cyclic(t(10_000));
    }
}

#[tokio::test]
async fn changes_publish_to_a_server() {
    use iec60870::asdu::CommonAddress;
    use iec60870::cs104::server::{spawn_server, ReadOnlyStation, ServerConfig};
    let mut gi = spec("gi", TypeId::M_ME_NB_1, 2);
    gi.transmission = Transmission::InterrogationOnly;
    let mut db = PointDb::new("N", vec![spec("sp", TypeId::M_SP_TB_1, 1), gi]).unwrap();
    let image = process_image(&db, prague()).unwrap();
    let config = ServerConfig::new("127.0.0.1:0".parse().unwrap(), CommonAddress::new(1));
    let server = spawn_server(config, image, std::sync::Arc::new(ReadOnlyStation))
        .await
        .unwrap();
    let st = Some(SourceTime {
        time: t(0),
        invalid: false,
    });
    let c = db
        .update(
            "sp",
            PointValue::Bool(true),
            Quality::GOOD,
            st,
            t(0),
            EventCause::Spontaneous,
        )
        .unwrap()
        .unwrap();
    let queued = server.stats().groups[0].queued;
    points_iec::publish(&c, &server, prague()).unwrap();
    let p = server.get(ioa(1)).unwrap();
    assert_eq!(p.element, element_of(&c));
    assert_eq!(p.time.unwrap().as_cp56().unwrap().hour(), 13);
    assert_eq!(server.stats().groups[0].queued, queued + 1);
    let c = good(&mut db, "gi", PointValue::Int(-7)).unwrap().unwrap();
    points_iec::publish(&c, &server, prague()).unwrap();
    assert_eq!(server.get(ioa(2)).unwrap().element, element_of(&c));
    assert_eq!(server.stats().groups[0].queued, queued + 1);
    server.shutdown();
}
