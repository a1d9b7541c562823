//! The teaching plot: each ball's weighings as a normal density (X̄, S) in its colour
//! (a colour's second ball dashed), the colours' unions as bars beneath, the decision
//! and outer limits as vertical lines, an axis in grams and a legend of the balls.
//!
//! Written by hand as SVG text: it is a few paths, lines and labels. A plotting crate
//! (plotters and the like) would bring a font and raster stack to draw what a browser
//! draws from text anyway, and a hand-written file stays readable, diffable and testable
//! as text.

use std::fmt::Write as _;

use super::limits::Thresholds;
use super::Interval;

const WIDTH: f64 = 1060.0;
const HEIGHT: f64 = 420.0;
const LEFT: f64 = 40.0;
/// The right margin holds the legend.
const RIGHT: f64 = 130.0;
const TOP: f64 = 50.0;
/// The plot area's bottom; below it the union bars, the axis and its labels.
const BOTTOM: f64 = 340.0;
/// Points of each density curve.
const CURVE_POINTS: usize = 240;

/// The SVG stroke colour of a colour name; unknown names get a grey.
fn stroke(colour: &str) -> &'static str {
    match colour {
        "red" => "#d62728",
        "yellow" => "#d4a017",
        "blue" => "#1f77b4",
        "green" => "#2ca02c",
        "orange" => "#ff7f0e",
        "purple" | "violet" => "#9467bd",
        "black" => "#222222",
        "pink" => "#e377c2",
        "brown" => "#8c564b",
        _ => "#7f7f7f",
    }
}

/// Text for SVG: `&`, `<`, `>` and quotes escaped.
fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
        .replace('\'', "&#39;")
}

/// The standard normal density at z.
fn density(z: f64) -> f64 {
    (-0.5 * z * z).exp() / (2.0 * std::f64::consts::PI).sqrt()
}

/// The plot of `thresholds` as an SVG document: one `<path class="ball">` per ball, one
/// `<line class="limit">` per decision limit and one `<line class="limit outer">` per
/// outer limit, a `<rect class="union">` per colour, a `<g class="legend">` per ball.
#[must_use]
pub fn svg(thresholds: &Thresholds) -> String {
    let range = x_range(thresholds);
    let x = |grams: f64| LEFT + (grams - range.lower) / range.width() * (WIDTH - LEFT - RIGHT);
    // A zero S would be an infinitely thin spike: drawn as a narrow one.
    let floor = range.width() / 500.0;
    let peak = thresholds
        .balls
        .iter()
        .map(|ball| density(0.0) / ball.statistics.sd_g.max(floor))
        .fold(0.0_f64, f64::max)
        * 1.05;
    let y = |value: f64| BOTTOM - value / peak * (BOTTOM - TOP);
    let mut out = String::new();
    let _ = writeln!(
        out,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{HEIGHT}" viewBox="0 0 {WIDTH} {HEIGHT}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(
        out,
        r#"<text x="{LEFT}" y="20" font-size="14">Weighings as normal densities (X̄, S); coverage {}; limits midway between the colours' unions</text>"#,
        escape(&thresholds.coverage.to_string())
    );
    // the colours' unions, as bars under the curves
    for (index, colour) in thresholds.colours.iter().enumerate() {
        #[allow(clippy::cast_precision_loss)] // a handful of colours
        let top = BOTTOM + 6.0 + (index % 2) as f64 * 8.0;
        let _ = writeln!(
            out,
            r#"<rect class="union" x="{:.1}" y="{top:.1}" width="{:.1}" height="6" fill="{}" fill-opacity="0.5"><title>{} union {}</title></rect>"#,
            x(colour.union_g.lower),
            (x(colour.union_g.upper) - x(colour.union_g.lower)).max(0.5),
            stroke(&colour.colour),
            escape(&colour.colour),
            colour.union_g
        );
    }
    let _ = writeln!(
        out,
        r##"<line class="baseline" x1="{LEFT}" y1="{BOTTOM}" x2="{:.1}" y2="{BOTTOM}" stroke="#bbb"/>"##,
        WIDTH - RIGHT
    );
    // one density per ball over X̄ ± 5 S; a colour's second and later balls dashed
    for (index, ball) in thresholds.balls.iter().enumerate() {
        let statistics = &ball.statistics;
        let sd = statistics.sd_g.max(floor);
        let dashed = thresholds
            .balls
            .iter()
            .take(index)
            .any(|other| other.statistics.colour == statistics.colour);
        let dash = if dashed {
            r#" stroke-dasharray="6 3""#
        } else {
            ""
        };
        let from = (statistics.mean_g - 5.0 * sd).max(range.lower);
        let to = (statistics.mean_g + 5.0 * sd).min(range.upper);
        let mut path = String::new();
        for step in 0..=CURVE_POINTS {
            #[allow(clippy::cast_precision_loss)] // a few hundred points
            let grams = from + (to - from) * step as f64 / CURVE_POINTS as f64;
            let value = density((grams - statistics.mean_g) / sd) / sd;
            let command = if step == 0 { 'M' } else { 'L' };
            let _ = write!(path, "{command}{:.1} {:.1} ", x(grams), y(value));
        }
        let colour = stroke(&statistics.colour);
        let name = escape(&statistics.ball);
        let _ = writeln!(
            out,
            r#"<path class="ball" d="{}" fill="none" stroke="{colour}" stroke-width="1.6"{dash}><title>{name}: X̄ {:.3} g, S {:.3} g, n {}</title></path>"#,
            path.trim_end(),
            statistics.mean_g,
            statistics.sd_g,
            statistics.n
        );
        // the legend, in the right margin
        #[allow(clippy::cast_precision_loss)] // a handful of balls
        let legend_y = TOP + 10.0 + index as f64 * 18.0;
        let legend_x = WIDTH - RIGHT + 16.0;
        let _ = writeln!(
            out,
            r#"<g class="legend"><line x1="{legend_x}" y1="{legend_y}" x2="{}" y2="{legend_y}" stroke="{colour}" stroke-width="1.6"{dash}/><text x="{}" y="{}">{name}</text></g>"#,
            legend_x + 24.0,
            legend_x + 30.0,
            legend_y + 4.0
        );
    }
    #[allow(clippy::cast_precision_loss)] // a handful of balls
    let notes_y = TOP + 10.0 + thresholds.balls.len() as f64 * 18.0 + 12.0;
    for (line, note) in [
        "bars: colour unions",
        "- - decision limits",
        "··· outer limits",
    ]
    .iter()
    .enumerate()
    {
        #[allow(clippy::cast_precision_loss)] // three lines
        let note_y = notes_y + line as f64 * 16.0;
        let _ = writeln!(
            out,
            r##"<text class="note" x="{}" y="{note_y}" fill="#555">{note}</text>"##,
            WIDTH - RIGHT + 16.0
        );
    }
    // the limits
    let outer = [thresholds.outer_g.lower, thresholds.outer_g.upper];
    let decision = thresholds.limits.iter().map(|limit| limit.limit_g);
    for (grams, class) in decision
        .map(|grams| (grams, "limit"))
        .chain(outer.into_iter().map(|grams| (grams, "limit outer")))
    {
        let _ = writeln!(
            out,
            r##"<line class="{class}" x1="{0:.1}" y1="{TOP}" x2="{0:.1}" y2="{BOTTOM}" stroke="#333" stroke-width="1" stroke-dasharray="{1}"/>"##,
            x(grams),
            if class == "limit" { "5 4" } else { "2 3" },
        );
        let _ = writeln!(
            out,
            r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{grams:.3}</text>"#,
            x(grams),
            TOP - 4.0
        );
    }
    axis(&mut out, range, x);
    out.push_str("</svg>\n");
    out
}

/// The grams shown: the outer limits and every ball's X̄ ± 4 S, widened to tenths.
fn x_range(thresholds: &Thresholds) -> Interval {
    let mut range = thresholds.outer_g;
    for ball in &thresholds.balls {
        let statistics = &ball.statistics;
        range = range.hull(Interval::new(
            statistics.mean_g - 4.0 * statistics.sd_g,
            statistics.mean_g + 4.0 * statistics.sd_g,
        ));
    }
    for colour in &thresholds.colours {
        range = range.hull(colour.union_g);
    }
    Interval::new(
        (range.lower * 10.0).floor() / 10.0 - 0.05,
        (range.upper * 10.0).ceil() / 10.0 + 0.05,
    )
}

/// The axis with a tick every 0.1 g, labelled every 0.1 g or, over more than 3 g, 0.5 g.
fn axis(out: &mut String, range: Interval, x: impl Fn(f64) -> f64) {
    let axis_y = BOTTOM + 24.0;
    let _ = writeln!(
        out,
        r##"<line class="axis" x1="{LEFT}" y1="{axis_y}" x2="{:.1}" y2="{axis_y}" stroke="#000"/>"##,
        WIDTH - RIGHT
    );
    #[allow(clippy::cast_possible_truncation)] // tenths of a few grams
    let (first, last) = (
        (range.lower * 10.0).ceil() as i64,
        (range.upper * 10.0).floor() as i64,
    );
    let every = if range.width() > 3.0 { 5 } else { 1 };
    for tenth in first..=last {
        #[allow(clippy::cast_precision_loss)] // tenths of a few grams
        let grams = tenth as f64 / 10.0;
        let _ = writeln!(
            out,
            r##"<line class="tick" x1="{0:.1}" y1="{axis_y}" x2="{0:.1}" y2="{1}" stroke="#000"/>"##,
            x(grams),
            axis_y + 5.0
        );
        if tenth % every == 0 {
            let _ = writeln!(
                out,
                r#"<text x="{:.1}" y="{}" text-anchor="middle">{grams:.1}</text>"#,
                x(grams),
                axis_y + 18.0
            );
        }
    }
    let _ = writeln!(
        out,
        r#"<text x="{:.1}" y="{}" text-anchor="middle">weight [g]</text>"#,
        f64::midpoint(LEFT, WIDTH - RIGHT),
        axis_y + 36.0
    );
}
