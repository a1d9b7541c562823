//! The SVG plot: well formed, one path per ball, one line per limit.

use sorting::statistics::plot::svg;
use sorting::statistics::{BallSamples, Samples, ThresholdConfig, Thresholds};

use crate::thesis_samples;

/// Checks that every element opened is closed in order (self-closing ones aside) and
/// returns the element names in document order.
fn elements(svg: &str) -> Vec<String> {
    let mut stack: Vec<String> = Vec::new();
    let mut names = Vec::new();
    let mut rest = svg;
    while let Some(start) = rest.find('<') {
        let end = rest[start..].find('>').expect("a tag closes") + start;
        let tag = &rest[start + 1..end];
        assert!(!tag.contains('<'), "a `<` inside a tag: {tag}");
        if let Some(name) = tag.strip_prefix('/') {
            assert_eq!(stack.pop().as_deref(), Some(name), "closing {name}");
        } else {
            let name: String = tag
                .chars()
                .take_while(|c| !c.is_whitespace() && *c != '/')
                .collect();
            names.push(name.clone());
            if !tag.ends_with('/') {
                stack.push(name);
            }
        }
        rest = &rest[end + 1..];
    }
    assert!(stack.is_empty(), "unclosed: {stack:?}");
    names
}

#[test]
fn the_plot_has_a_density_per_ball_and_a_line_per_limit() {
    let thresholds =
        Thresholds::from_samples(&thesis_samples(), &ThresholdConfig::default()).unwrap();
    let svg = svg(&thresholds);
    assert!(svg.starts_with("<svg "), "{}", &svg[..40]);
    assert!(svg.trim_end().ends_with("</svg>"));
    let names = elements(&svg);
    assert_eq!(names.first().map(String::as_str), Some("svg"));
    assert_eq!(svg.matches("<path class=\"ball\"").count(), 8);
    assert_eq!(names.iter().filter(|name| *name == "path").count(), 8);
    assert_eq!(svg.matches("<line class=\"limit\"").count(), 3);
    assert_eq!(svg.matches("<line class=\"limit outer\"").count(), 2);
    assert_eq!(svg.matches("<rect class=\"union\"").count(), 4);
    // coloured by colour; a colour's second ball dashed
    let red: Vec<&str> = svg
        .lines()
        .filter(|line| line.starts_with("<path class=\"ball\"") && line.contains("#d62728"))
        .collect();
    assert_eq!(red.len(), 2);
    assert!(!red[0].contains("stroke-dasharray") && red[1].contains("stroke-dasharray"));
    assert_eq!(svg.matches("<g class=\"legend\">").count(), 8);
    assert!(svg.contains("<title>blue 2: X̄ 3.105 g, S 0.048 g, n 16</title>"));
    assert!(svg.contains(">weight [g]<"));
}

#[test]
fn names_are_escaped() {
    let samples = Samples::new(vec![
        BallSamples::new("red <1>", vec![2.28, 2.30, 2.29]),
        BallSamples::new("blue & co", vec![3.08, 3.10, 3.09]),
    ]);
    let thresholds = Thresholds::from_samples(&samples, &ThresholdConfig::default()).unwrap();
    let svg = svg(&thresholds);
    elements(&svg);
    assert!(svg.contains("red &lt;1&gt;") && svg.contains("blue &amp; co"));
}
