//! The screen cleaner on hand-written files (what is kept, what is removed, where an error
//! is) and on random input (never a panic; its output is clean already and safe).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use mimic_svg::{clean, is_dangerous_url, tag_is_unsafe, tags};
use proptest::prelude::*;

const SVG: &str = "http://www.w3.org/2000/svg";

fn wrap(body: &str) -> String {
    format!("<svg xmlns=\"{SVG}\" xmlns:xlink=\"http://www.w3.org/1999/xlink\" viewBox=\"0 0 10 10\">{body}</svg>")
}

fn inner(body: &str) -> String {
    let out = clean(&wrap(body)).unwrap();
    let start = out.find('>').unwrap() + 1;
    out[start..out.len() - "</svg>".len()].to_owned()
}

#[test]
fn a_binding_screen_is_kept_as_written() {
    let body =
        "<g class=\"x\"><rect x=\"1\" y=\"2\" width=\"3\" height=\"4\" data-point=\"RH2_QF1\"/>\
                <text x=\"1\" y=\"9\" data-text=\"U\" data-unit=\"V\">0 V</text>\
                <a href=\"#screen/rh2\"><text>RH2</text></a>\
                <linearGradient id=\"g\"><stop offset=\"0\"/></linearGradient>\
                <use xlink:href=\"#g\"/><title>Board &amp; feeder</title></g>";
    assert_eq!(inner(body), body);
}

#[test]
fn the_root_gets_its_namespaces_and_keeps_its_attributes() {
    let out = clean(&format!(
        "<?xml version=\"1.0\"?>\n<!-- drawn by hand -->\n<svg xmlns=\"{SVG}\" viewBox=\"0 0 5 5\" width=\"5\"/>"
    ))
    .unwrap();
    assert_eq!(
        out,
        format!("<svg xmlns=\"{SVG}\" xmlns:xlink=\"http://www.w3.org/1999/xlink\" viewBox=\"0 0 5 5\" width=\"5\"/>")
    );
}

#[test]
fn code_is_removed() {
    let body = "<script>alert(1)</script>\
        <foreignObject><iframe xmlns=\"http://www.w3.org/1999/xhtml\" src=\"javascript:alert(2)\"/></foreignObject>\
        <rect onclick=\"alert(3)\" ONMOUSEOVER=\"alert(4)\" x=\"1\"/>\
        <a href=\"javascript:alert(5)\"><text>a</text></a>\
        <a xlink:href=\" java&#9;script:alert(6)\"><text>b</text></a>\
        <a href=\"data:text/html,x\"><text>c</text></a>\
        <a href=\"https://example.org/\"><text>d</text></a>\
        <set attributeName=\"href\" to=\"javascript:alert(7)\"/>\
        <animate attributeName=\"ONCLICK\" values=\"alert(8)\"/>\
        <animateTransform attributeName=\"xlink:href\" values=\"x\"/>\
        <animate attributeName=\"fill\" values=\"javascript:alert(9)\"/>\
        <animate attributeName=\"opacity\" values=\"1;0\" dur=\"1s\"/>\
        <image href=\"x.png\" onerror=\"alert(10)\"/>\
        <rect style=\"fill:url(javascript:alert(11))\"/>\
        <style>@import url(https://example.org/x.css);</style>\
        <style>rect &gt; text { fill: red }</style>";
    let out = inner(body);
    assert_eq!(
        out,
        "<rect x=\"1\"/>\
         <a><text>a</text></a><a><text>b</text></a><a><text>c</text></a><a><text>d</text></a>\
         <animate attributeName=\"opacity\" values=\"1;0\" dur=\"1s\"/>\
         <image/><rect/><style></style><style>rect &gt; text { fill: red }</style>"
    );
}

#[test]
fn other_vocabularies_and_prefixes_are_dropped_or_written_plainly() {
    let out = clean(
        "<svg:svg xmlns:svg=\"http://www.w3.org/2000/svg\" xmlns:inkscape=\"http://www.inkscape.org/namespaces/inkscape\" \
         xmlns:x=\"http://www.w3.org/1999/xlink\">\
         <inkscape:grid/><svg:g inkscape:label=\"layer\" xml:space=\"preserve\" xml:base=\"http://e/\"><svg:use x:href=\"#a\"/></svg:g>\
         <svg:title>t<svg:tspan>u</svg:tspan></svg:title><span>html</span></svg:svg>",
    )
    .unwrap();
    assert!(
        out.ends_with(
            "><g xml:space=\"preserve\"><use xlink:href=\"#a\"/></g><title>t</title></svg>"
        ),
        "{out}"
    );
}

#[test]
fn text_and_values_are_escaped_for_both_parsers() {
    assert_eq!(
        inner("<text data-map=\"0:a&lt;b;1:&quot;c&quot;\">x &lt; y &amp;&#160;z<![CDATA[ <i> ]]></text>"),
        "<text data-map=\"0:a&lt;b;1:&quot;c&quot;\">x &lt; y &amp;\u{a0}z &lt;i&gt; </text>"
    );
}

#[test]
fn internal_entities_of_drawing_tools_are_expanded() {
    let file = format!(
        "<?xml version=\"1.0\"?><!DOCTYPE svg [<!ENTITY ns_svg \"{SVG}\"><!ENTITY label 'Feeder &#38; bus'>]>\
         <svg xmlns=\"&ns_svg;\"><text>&label;</text></svg>"
    );
    let out = clean(&file).unwrap();
    assert!(
        out.ends_with("<text>Feeder &amp; bus</text></svg>"),
        "{out}"
    );
}

#[test]
fn errors_say_line_and_column() {
    let error = clean(&format!(
        "<svg xmlns=\"{SVG}\">\n  <g>\n    <rect/>\n  </h>\n</svg>"
    ))
    .unwrap_err();
    assert_eq!(error.line, 4, "{error}");
    let error = clean("<html><body/></html>").unwrap_err();
    assert_eq!((error.line, error.column), (1, 1), "{error}");
    assert!(error.message.contains("root element is <html>"), "{error}");
    let error = clean(&format!("<svg xmlns=\"{SVG}\">\n<text>&nbsp;</text></svg>")).unwrap_err();
    assert!(error.message.contains("nbsp"), "{error}");
    assert_eq!(error.line, 2, "{error}");
    let error = clean(&format!("<svg xmlns=\"{SVG}\"><g>")).unwrap_err();
    assert!(error.to_string().contains("ends inside <g>"), "{error}");
    assert!(clean("").is_err());
    assert!(clean(&format!("<svg xmlns=\"{SVG}\"/><svg xmlns=\"{SVG}\"/>")).is_err());
    let deep = format!(
        "<svg xmlns=\"{SVG}\">{}{}</svg>",
        "<g>".repeat(300),
        "</g>".repeat(300)
    );
    assert!(clean(&deep).unwrap_err().message.contains("deeper"));
}

#[test]
fn the_output_check_finds_what_it_looks_for() {
    for tag in [
        "script",
        "/foreignObject",
        "rect x=\"1\" onclick=\"x\"",
        "a href=\"javascript:x\"",
    ] {
        assert!(tag_is_unsafe(tag), "{tag}");
    }
    for tag in [
        "rect x=\"1\"",
        "text data-on=\"ON\"",
        "a href=\"#screen/x\"",
    ] {
        assert!(!tag_is_unsafe(tag), "{tag}");
    }
    assert_eq!(
        tags("<g a=\"1\">x &lt; y<rect/></g>").collect::<Vec<_>>(),
        ["g a=\"1\"", "rect/", "/g"]
    );
}

#[test]
fn dangerous_urls_are_found_through_spacing_and_case() {
    for url in [
        "javascript:x",
        " JavaScript:x",
        "java\tscript:x",
        "java\u{0}script:x",
        "data:image/png,x",
        "VBScript:x",
        "#x javascript:y",
    ] {
        assert!(is_dangerous_url(url), "{url:?}");
    }
    for url in [
        "#screen/rh2",
        "https://example.org/",
        "0:off;1:on",
        "RH2_QF1",
    ] {
        assert!(!is_dangerous_url(url), "{url:?}");
    }
}

/// Every example project's screens are well-formed and lose nothing a screen uses.
#[test]
fn the_example_screens_pass_unchanged_in_substance() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    let mut checked = 0;
    for project in std::fs::read_dir(&root).unwrap() {
        let hmi = project.unwrap().path().join("hmi");
        let Ok(files) = std::fs::read_dir(&hmi) else {
            continue;
        };
        for file in files {
            let path = file.unwrap().path();
            if path.extension().is_none_or(|e| e != "svg") {
                continue;
            }
            let text = std::fs::read_to_string(&path).unwrap();
            let out = clean(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            for needle in [
                "data-point=",
                "data-text=",
                "data-command=",
                "<text",
                "href=\"#screen/",
            ] {
                assert_eq!(
                    text.matches(needle).count(),
                    out.matches(needle).count(),
                    "{}: {needle}",
                    path.display()
                );
            }
            checked += 1;
        }
    }
    assert!(checked >= 10, "{checked} screens");
}

/// Markup made of the pieces a hostile or careless file would use.
fn hostile_markup() -> impl Strategy<Value = String> {
    let piece = prop_oneof![
        Just("<g>".to_owned()),
        Just("</g>".to_owned()),
        Just("<rect x=\"1\"/>".to_owned()),
        Just("<script>alert(1)</script>".to_owned()),
        Just("<a href=\"javascript:x\">".to_owned()),
        Just("</a>".to_owned()),
        Just("<set attributeName=\"href\" to=\"javascript:x\"/>".to_owned()),
        Just("<rect onload=\"x\"/>".to_owned()),
        Just("<title>".to_owned()),
        Just("</title>".to_owned()),
        Just("<style>".to_owned()),
        Just("</style>".to_owned()),
        Just("<foreignObject>".to_owned()),
        Just("</foreignObject>".to_owned()),
        Just("<![CDATA[<script>]]>".to_owned()),
        Just("&amp;".to_owned()),
        Just("&#x3c;".to_owned()),
        "[a-z<>&\"' ]{0,8}",
    ];
    proptest::collection::vec(piece, 0..30).prop_map(|pieces| wrap(&pieces.concat()))
}

proptest! {
    #[test]
    fn any_text_is_an_answer_never_a_panic(text in "\\PC{0,200}") {
        let _ = clean(&text);
    }

    #[test]
    fn the_output_is_clean_stable_and_safe(text in hostile_markup()) {
        if let Ok(out) = clean(&text) {
            // Cleaning again changes nothing: the output is in the form the page reads.
            let again = clean(&out);
            prop_assert_eq!(again.as_ref(), Ok(&out));
            for tag in mimic_svg::tags(&out) {
                prop_assert!(!mimic_svg::tag_is_unsafe(tag), "{}", tag);
            }
        }
    }
}
