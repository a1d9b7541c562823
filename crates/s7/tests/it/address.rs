//! Addresses as users type them, values as users type them, TSAP pairs.

use s7::{
    Address, AddressErrorKind, Area, Region, Tsap, Tsaps, Value, ValueError, ValueType, Width,
};

fn parse(text: &str) -> Address {
    text.parse()
        .unwrap_or_else(|error| panic!("{text}: {error}"))
}

fn error(text: &str) -> AddressErrorKind {
    text.parse::<Address>().expect_err(text).kind
}

#[test]
fn every_spelling_parses_to_its_region_type_and_canonical_form() {
    let cases: &[(&str, Region, ValueType, &str)] = &[
        (
            "DB1.DBX0.3",
            Region::Bit {
                area: Area::DataBlock(1),
                byte: 0,
                bit: 3,
            },
            ValueType::Bool,
            "DB1.DBX0.3",
        ),
        (
            "DB1.DBB1",
            Region::Bytes {
                area: Area::DataBlock(1),
                start: 1,
                len: 1,
            },
            ValueType::Byte,
            "DB1.DBB1",
        ),
        (
            "DB1.DBW2",
            Region::Bytes {
                area: Area::DataBlock(1),
                start: 2,
                len: 2,
            },
            ValueType::Word,
            "DB1.DBW2",
        ),
        (
            "DB1.DBD4",
            Region::Bytes {
                area: Area::DataBlock(1),
                start: 4,
                len: 4,
            },
            ValueType::DWord,
            "DB1.DBD4",
        ),
        (
            "MB10",
            Region::Bytes {
                area: Area::Markers,
                start: 10,
                len: 1,
            },
            ValueType::Byte,
            "MB10",
        ),
        (
            "MW20",
            Region::Bytes {
                area: Area::Markers,
                start: 20,
                len: 2,
            },
            ValueType::Word,
            "MW20",
        ),
        (
            "MD24",
            Region::Bytes {
                area: Area::Markers,
                start: 24,
                len: 4,
            },
            ValueType::DWord,
            "MD24",
        ),
        (
            "MX10.0",
            Region::Bit {
                area: Area::Markers,
                byte: 10,
                bit: 0,
            },
            ValueType::Bool,
            "M10.0",
        ),
        (
            "M10.0",
            Region::Bit {
                area: Area::Markers,
                byte: 10,
                bit: 0,
            },
            ValueType::Bool,
            "M10.0",
        ),
        (
            "IX0.1",
            Region::Bit {
                area: Area::Inputs,
                byte: 0,
                bit: 1,
            },
            ValueType::Bool,
            "I0.1",
        ),
        (
            "I0.1",
            Region::Bit {
                area: Area::Inputs,
                byte: 0,
                bit: 1,
            },
            ValueType::Bool,
            "I0.1",
        ),
        (
            "IB0",
            Region::Bytes {
                area: Area::Inputs,
                start: 0,
                len: 1,
            },
            ValueType::Byte,
            "IB0",
        ),
        (
            "IW2",
            Region::Bytes {
                area: Area::Inputs,
                start: 2,
                len: 2,
            },
            ValueType::Word,
            "IW2",
        ),
        (
            "ID4",
            Region::Bytes {
                area: Area::Inputs,
                start: 4,
                len: 4,
            },
            ValueType::DWord,
            "ID4",
        ),
        (
            "QX0.2",
            Region::Bit {
                area: Area::Outputs,
                byte: 0,
                bit: 2,
            },
            ValueType::Bool,
            "Q0.2",
        ),
        (
            "Q0.2",
            Region::Bit {
                area: Area::Outputs,
                byte: 0,
                bit: 2,
            },
            ValueType::Bool,
            "Q0.2",
        ),
        (
            "QB0",
            Region::Bytes {
                area: Area::Outputs,
                start: 0,
                len: 1,
            },
            ValueType::Byte,
            "QB0",
        ),
        (
            "QW0",
            Region::Bytes {
                area: Area::Outputs,
                start: 0,
                len: 2,
            },
            ValueType::Word,
            "QW0",
        ),
        (
            "QD8",
            Region::Bytes {
                area: Area::Outputs,
                start: 8,
                len: 4,
            },
            ValueType::DWord,
            "QD8",
        ),
    ];
    for (text, region, value_type, canonical) in cases {
        let address = parse(text);
        assert_eq!(address.region(), *region, "{text}");
        assert_eq!(address.value_type(), *value_type, "{text}");
        assert_eq!(address.to_string(), *canonical, "{text}");
        assert_eq!(parse(canonical), address, "{canonical} parses back");
    }
}

#[test]
fn case_spaces_and_the_tia_percent_sign_are_taken() {
    assert_eq!(parse("db1.dbx0.3"), parse("DB1.DBX0.3"));
    assert_eq!(parse("  %MW20 "), parse("MW20"));
    assert_eq!(parse("%DB10.DBD4:real"), parse("DB10.DBD4:REAL"));
    assert_eq!(parse("mw2 : int").to_string(), "MW2:INT");
}

#[test]
fn type_suffixes_give_typed_values_and_stay_in_the_canonical_form() {
    let cases = [
        ("DB1.DBW2:INT", ValueType::Int, "DB1.DBW2:INT"),
        ("DB1.DBD4:DINT", ValueType::DInt, "DB1.DBD4:DINT"),
        ("DB1.DBD4:REAL", ValueType::Real, "DB1.DBD4:REAL"),
        ("MB0:SINT", ValueType::SInt, "MB0:SINT"),
        ("MW0:WORD", ValueType::Word, "MW0"),
        ("MD0:DWORD", ValueType::DWord, "MD0"),
        ("IB0:BYTE", ValueType::Byte, "IB0"),
        ("Q0.0:BOOL", ValueType::Bool, "Q0.0"),
    ];
    for (text, value_type, canonical) in cases {
        let address = parse(text);
        assert_eq!(address.value_type(), value_type, "{text}");
        assert_eq!(address.to_string(), canonical, "{text}");
    }
}

#[test]
fn bad_spellings_name_what_is_wrong() {
    assert_eq!(error(""), AddressErrorKind::Empty);
    assert_eq!(error("  "), AddressErrorKind::Empty);
    assert_eq!(error("M10.8"), AddressErrorKind::BitOutOfRange(8));
    assert_eq!(error("DB1.DBX0.9"), AddressErrorKind::BitOutOfRange(9));
    assert_eq!(error("M10"), AddressErrorKind::MissingBit);
    assert_eq!(error("DB1.DBX4"), AddressErrorKind::MissingBit);
    assert_eq!(error("M10."), AddressErrorKind::MissingBit);
    assert_eq!(error("DB1.DBW2.1"), AddressErrorKind::UnexpectedBit);
    assert_eq!(error("MB3.0"), AddressErrorKind::UnexpectedBit);
    assert_eq!(
        error("DB1.DBW2:REAL"),
        AddressErrorKind::TypeMismatch {
            width: Width::Word,
            value_type: ValueType::Real
        }
    );
    assert_eq!(
        error("DB1.DBX0.0:INT"),
        AddressErrorKind::TypeMismatch {
            width: Width::Bit(0),
            value_type: ValueType::Int
        }
    );
    assert_eq!(
        error("MB1:BOOL"),
        AddressErrorKind::TypeMismatch {
            width: Width::Byte,
            value_type: ValueType::Bool
        }
    );
    assert_eq!(
        error("MW2:FLOAT"),
        AddressErrorKind::UnknownType("FLOAT".into())
    );
    assert_eq!(error("E0.1"), AddressErrorKind::UnknownArea("E".into()));
    assert_eq!(error("AW2"), AddressErrorKind::UnknownArea("AW".into()));
    assert_eq!(error("DB.DBW2"), AddressErrorKind::MissingDbNumber);
    assert_eq!(error("DB0.DBW2"), AddressErrorKind::DbNumberZero);
    assert_eq!(
        error("DB65536.DBW2"),
        AddressErrorKind::DbNumberTooLarge(65536)
    );
    assert_eq!(error("DB1.W2"), AddressErrorKind::MissingDbField);
    assert_eq!(error("DB1"), AddressErrorKind::MissingDbField);
    assert_eq!(error("DB1.DB2"), AddressErrorKind::MissingDbField);
    assert_eq!(error("DB1.DBQ2"), AddressErrorKind::UnknownWidth('Q'));
    assert_eq!(error("MA2"), AddressErrorKind::UnknownWidth('A'));
    assert_eq!(error("MW"), AddressErrorKind::MissingByte);
    assert_eq!(error("MW2x"), AddressErrorKind::Trailing("X".into()));
    assert_eq!(error("MW-2"), AddressErrorKind::Trailing("-2".into()));
    assert_eq!(
        error("MB99999999999999999999999"),
        AddressErrorKind::ByteTooLarge(u64::MAX)
    );
    // The last byte a bit address reaches is 0x1FFFFF; a double word must end there too.
    assert!("MB2097151".parse::<Address>().is_ok());
    assert_eq!(
        error("MB2097152"),
        AddressErrorKind::ByteTooLarge(2_097_152)
    );
    assert_eq!(
        error("MD2097150"),
        AddressErrorKind::ByteTooLarge(2_097_150)
    );
}

#[test]
fn error_messages_quote_the_input() {
    let message = "M10.8".parse::<Address>().unwrap_err().to_string();
    assert_eq!(message, "address \"M10.8\": bit number 8 is above 7");
    let message = "DB1.DBW2:REAL".parse::<Address>().unwrap_err().to_string();
    assert_eq!(
        message,
        "address \"DB1.DBW2:REAL\": REAL does not fit a word"
    );
}

#[test]
fn values_parse_per_type_with_range_checks() {
    let ok = |value_type, text: &str| Value::parse(value_type, text).unwrap();
    assert_eq!(ok(ValueType::Bool, "true"), Value::Bool(true));
    assert_eq!(ok(ValueType::Bool, "FALSE"), Value::Bool(false));
    assert_eq!(ok(ValueType::Bool, "1"), Value::Bool(true));
    assert_eq!(ok(ValueType::Bool, "0"), Value::Bool(false));
    assert_eq!(ok(ValueType::Byte, "255"), Value::Byte(255));
    assert_eq!(ok(ValueType::Byte, "0xff"), Value::Byte(255));
    assert_eq!(ok(ValueType::Word, "16#BEEF"), Value::Word(0xBEEF));
    assert_eq!(ok(ValueType::SInt, "-128"), Value::SInt(-128));
    assert_eq!(ok(ValueType::Int, "-32768"), Value::Int(-32768));
    assert_eq!(ok(ValueType::DWord, "4294967295"), Value::DWord(u32::MAX));
    assert_eq!(ok(ValueType::DInt, "-2147483648"), Value::DInt(i32::MIN));
    assert_eq!(ok(ValueType::Real, "-1.5"), Value::Real(-1.5));
    assert_eq!(ok(ValueType::Real, "2.5e3"), Value::Real(2500.0));

    let out_of_range = |value_type, text: &str| {
        assert!(
            matches!(
                Value::parse(value_type, text),
                Err(ValueError::OutOfRange { .. })
            ),
            "{value_type} {text}"
        );
    };
    out_of_range(ValueType::Byte, "256");
    out_of_range(ValueType::Byte, "-1");
    out_of_range(ValueType::Word, "65536");
    out_of_range(ValueType::Int, "32768");
    out_of_range(ValueType::SInt, "128");
    out_of_range(ValueType::DWord, "-1");
    out_of_range(ValueType::DInt, "2147483648");
    out_of_range(ValueType::DInt, "99999999999999999999999");
    out_of_range(ValueType::Real, "1e39");

    assert!(matches!(
        Value::parse(ValueType::Bool, "yes"),
        Err(ValueError::NotABool(_))
    ));
    for (value_type, text) in [
        (ValueType::Int, "ten"),
        (ValueType::Int, "0x10"),
        (ValueType::Word, "1.5"),
        (ValueType::Real, "NaN"),
        (ValueType::Real, "inf"),
        (ValueType::Real, ""),
    ] {
        assert!(
            matches!(
                Value::parse(value_type, text),
                Err(ValueError::NotANumber { .. })
            ),
            "{value_type} {text:?}"
        );
    }
}

#[test]
fn values_display_as_json() {
    assert_eq!(Value::Bool(true).to_string(), "true");
    assert_eq!(Value::Word(65535).to_string(), "65535");
    assert_eq!(Value::Int(-2).to_string(), "-2");
    assert_eq!(Value::Real(1.5).to_string(), "1.5");
    assert_eq!(Value::Real(1.0e-7).to_string(), "0.0000001");
    assert_eq!(Value::Real(f32::NAN).to_string(), "null");
    assert_eq!(Value::Real(f32::INFINITY).to_string(), "null");
}

#[test]
fn values_travel_big_endian() {
    assert_eq!(Value::Int(-2).to_bytes(), [0xFF, 0xFE]);
    assert_eq!(Value::DWord(0x0102_0304).to_bytes(), [1, 2, 3, 4]);
    assert_eq!(Value::Real(1.0).to_bytes(), [0x3F, 0x80, 0, 0]);
    assert_eq!(Value::Bool(true).to_bytes(), [1]);
    assert_eq!(
        Value::from_bytes(ValueType::Int, &[0x80, 0x00]).unwrap(),
        Value::Int(i16::MIN)
    );
    assert_eq!(
        Value::from_bytes(ValueType::Word, &[0x80]),
        Err(ValueError::WrongLength {
            value_type: ValueType::Word,
            expected: 2,
            got: 1
        })
    );
    // An INT may go to a WORD address; a REAL may not.
    let word = parse("MW0");
    assert_eq!(word.encode(&Value::Int(-1)).unwrap(), [0xFF, 0xFF]);
    assert!(word.encode(&Value::Real(1.0)).is_err());
}

#[test]
fn tsap_pairs_parse_in_four_hex_digits_each() {
    let tsaps: Tsaps = "0100:0301".parse().unwrap();
    assert_eq!(tsaps, Tsaps::rack_slot(0, 1));
    assert_eq!(tsaps, Tsaps::default());
    assert_eq!(tsaps.to_string(), "0100:0301");
    let logo: Tsaps = "0200:4D57".parse().unwrap();
    assert_eq!(logo.local, Tsap::new(0x0200));
    assert_eq!(logo.remote.as_u16(), Some(0x4D57));
    assert_eq!(Tsaps::rack_slot(1, 2).remote, Tsap::new(0x0322));
    for bad in [
        "0100",
        "100:301",
        "0100:03011",
        "01.00:03.01",
        "zz00:0301",
        "",
    ] {
        assert!(bad.parse::<Tsaps>().is_err(), "{bad}");
    }
}
