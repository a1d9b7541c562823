//! `stanice stats`: statistics for the labs. `stanice stats thresholds` derives the
//! sorting lab's class limits from weighings of its balls (the sorting-lab thesis,
//! section 12; the `sorting` crate's statistics module), as a table, as JSON or as an SVG
//! plot.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context as _;
use clap::{Args, Subcommand};
use sorting::statistics::limits::Reliability;
use sorting::statistics::{
    percent, plot, Confidence, Coverage, Interval, Samples, ThresholdConfig, Thresholds,
};

/// Statistics subcommands.
#[derive(Debug, Subcommand)]
pub(crate) enum StatsCommand {
    /// The sorting lab's class limits from weighings of its balls.
    ///
    /// Per ball: n, the mean, S, the confidence interval of the mean (Student t), the
    /// upper bound of sigma (chi-square) and a coverage interval. Per colour: the union
    /// of its balls' coverage intervals. Then the decision limits midway between
    /// neighbouring colours' unions, overlaps, and the sorting reliability to expect (the
    /// sorting-lab thesis, section 12).
    Thresholds(ThresholdsArgs),
}

/// `stanice stats thresholds`
#[derive(Debug, Args)]
pub(crate) struct ThresholdsArgs {
    /// The weighings: CSV with the header `ball,weight_g`, one row per weighing, balls
    /// named by colour and number (`red 1`, `yellow 2`), at least 2 weighings a ball.
    #[arg(value_name = "FILE.csv")]
    file: PathBuf,
    /// Confidence level of the interval of each ball's mean (Student t) and of the upper
    /// bound of its sigma (chi-square): 0.99 or 99%.
    #[arg(long, value_name = "LEVEL", default_value = "0.99", value_parser = parse_confidence)]
    confidence: Confidence,
    /// Share of a ball's weighings its coverage interval is to hold, 0.99 or 99%
    /// (z = 2.5758; the thesis settled for 0.90, z = 1.65, with --confidence 0.95).
    #[arg(long, value_name = "SHARE", default_value = "0.99", value_parser = parse_coverage)]
    coverage: Coverage,
    /// The lowest and highest class limits in grams, set by hand (below the lightest
    /// colour, above the heaviest).
    #[arg(long, value_name = "LOW,HIGH", default_value = "2.0,4.0", value_parser = parse_outer)]
    outer: Interval,
    /// Print the results as one JSON document instead of tables.
    #[arg(long)]
    json: bool,
    /// Also write a plot: each ball's normal density in its colour, the colours' unions
    /// and the limits (SVG, for a browser).
    #[arg(long, value_name = "FILE.svg")]
    plot: Option<PathBuf>,
}

/// A probability as `0.99`, `99%` or `99 %`.
fn parse_probability(text: &str) -> Result<f64, String> {
    let text = text.trim();
    let (number, scale) = match text.strip_suffix('%') {
        Some(number) => (number.trim(), 100.0),
        None => (text, 1.0),
    };
    number
        .parse::<f64>()
        .map(|value| value / scale)
        .map_err(|_| format!("`{text}` is not a number (e.g. 0.99 or 99%)"))
}

fn parse_confidence(text: &str) -> Result<Confidence, String> {
    Confidence::try_new(parse_probability(text)?).map_err(|error| error.to_string())
}

fn parse_coverage(text: &str) -> Result<Coverage, String> {
    Coverage::try_new(parse_probability(text)?).map_err(|error| error.to_string())
}

fn parse_outer(text: &str) -> Result<Interval, String> {
    let numbers: Vec<f64> = text
        .split(',')
        .map(|part| part.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("`{text}` is not two numbers of grams, e.g. 2.0,4.0"))?;
    match numbers.as_slice() {
        [low, high] if low.is_finite() && high.is_finite() && low < high => {
            Ok(Interval::new(*low, *high))
        }
        _ => Err(format!(
            "`{text}` must be two grams, the lower first, e.g. 2.0,4.0"
        )),
    }
}

/// Runs a `stats` subcommand.
pub(crate) fn run(command: StatsCommand) -> anyhow::Result<ExitCode> {
    match command {
        StatsCommand::Thresholds(args) => thresholds(&args),
    }
}

/// `--json`: the file, its weighings and the confidence, then the thresholds' fields
/// (coverage, outer_g, balls, colours, limits, reliability).
#[derive(serde::Serialize)]
struct JsonReport<'a> {
    file: String,
    weighings: usize,
    confidence: f64,
    #[serde(flatten)]
    thresholds: &'a Thresholds,
}

fn thresholds(args: &ThresholdsArgs) -> anyhow::Result<ExitCode> {
    let file = args.file.display();
    let bytes =
        std::fs::read(&args.file).with_context(|| format!("cannot read the weighings {file}"))?;
    let samples =
        Samples::from_bytes(&bytes).map_err(|error| anyhow::anyhow!("{file}: {error}"))?;
    let mut config = ThresholdConfig::default();
    config.confidence = args.confidence;
    config.coverage = args.coverage;
    config.outer_g = args.outer;
    let thresholds = Thresholds::from_samples(&samples, &config)
        .map_err(|error| anyhow::anyhow!("{file}: {error}"))?;
    if args.json {
        let report = JsonReport {
            file: file.to_string(),
            weighings: samples.weighings(),
            confidence: args.confidence.level(),
            thresholds: &thresholds,
        };
        emit(&format!("{}\n", serde_json::to_string_pretty(&report)?))?;
    } else {
        emit(&report(
            &file.to_string(),
            &samples,
            &thresholds,
            args.confidence,
        ))?;
    }
    if let Some(path) = &args.plot {
        std::fs::write(path, plot::svg(&thresholds))
            .with_context(|| format!("cannot write the plot {}", path.display()))?;
        eprintln!("plot written to {}", path.display());
    }
    Ok(ExitCode::SUCCESS)
}

/// Writes to stdout; a reader that went away (`| head`) is no error.
fn emit(text: &str) -> anyhow::Result<()> {
    use std::io::Write as _;
    let mut stdout = std::io::stdout().lock();
    match stdout
        .write_all(text.as_bytes())
        .and_then(|()| stdout.flush())
    {
        Err(error) if error.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        result => Ok(result?),
    }
}

/// A probability without trailing zeros: 0.995, 0.01.
fn decimal(value: f64) -> String {
    let text = format!("{value:.6}");
    text.trim_end_matches('0').trim_end_matches('.').to_owned()
}

fn reliability_columns(reliability: Reliability) -> String {
    format!(
        "{:>9.2} %  {:>9.2} %",
        reliability.expected * 100.0,
        reliability.with_sigma_upper * 100.0
    )
}

/// The tables and findings as text.
fn report(
    file: &str,
    samples: &Samples,
    thresholds: &Thresholds,
    confidence: Confidence,
) -> String {
    let mut out = String::new();
    let level = percent(confidence.level());
    let coverage = percent(thresholds.coverage.probability());
    let _ = writeln!(
        out,
        "{file}: {} balls, {} weighings",
        thresholds.balls.len(),
        samples.weighings()
    );
    let mut sizes: Vec<_> = thresholds
        .balls
        .iter()
        .map(|ball| ball.statistics.factors)
        .collect();
    sizes.sort_by_key(|factors| factors.n);
    sizes.dedup_by_key(|factors| factors.n);
    for factors in sizes {
        let freedom = factors.n.saturating_sub(1);
        let _ = writeln!(
            out,
            "{level} confidence, n = {}: t({}; {freedom}) = {:.4}, chi2({}; {freedom}) = {:.4}, sigma upper = {:.4} S",
            factors.n,
            decimal(1.0 - confidence.alpha() / 2.0),
            factors.t,
            decimal(confidence.alpha()),
            factors.chi_square,
            factors.sigma_factor
        );
    }
    let _ = writeln!(
        out,
        "coverage {}: each ball's ⟨mu lower − z·sigma upper, mu upper + z·sigma upper⟩",
        thresholds.coverage
    );
    let width = thresholds
        .balls
        .iter()
        .map(|ball| ball.statistics.ball.chars().count())
        .chain(
            thresholds
                .colours
                .iter()
                .map(|colour| colour.colour.chars().count()),
        )
        .max()
        .unwrap_or(4)
        .max(6);
    let _ = writeln!(
        out,
        "\n{:width$}  {:>3}  {:>8}  {:>6}  {:>16}  {:>11}  {:>20}",
        "ball",
        "n",
        "mean [g]",
        "S [g]",
        format!("mu {level} [g]"),
        "sigma upper",
        format!("coverage {coverage} [g]"),
    );
    for ball in &thresholds.balls {
        let statistics = &ball.statistics;
        let _ = writeln!(
            out,
            "{:width$}  {:>3}  {:>8.3}  {:>6.3}  {:>16}  {:>11.3}  {:>20}",
            statistics.ball,
            statistics.n,
            statistics.mean_g,
            statistics.sd_g,
            statistics.mean_interval_g.to_string(),
            statistics.sigma_upper_g,
            ball.coverage_g.to_string(),
        );
    }
    let _ = writeln!(
        out,
        "\n{:width$}  {:>16}  {:>16}  {:>11}  {:>11}",
        "colour", "union [g]", "decision [g]", "expected", "pessimistic"
    );
    for colour in &thresholds.colours {
        let _ = writeln!(
            out,
            "{:width$}  {:>16}  {:>16}  {}",
            colour.colour,
            colour.union_g.to_string(),
            colour.decision_g.to_string(),
            reliability_columns(colour.reliability),
        );
    }
    let _ = writeln!(
        out,
        "{:width$}  {:>16}  {:>16}  {}",
        "all",
        "",
        "",
        reliability_columns(thresholds.reliability)
    );
    let limits: Vec<String> = thresholds
        .limits
        .iter()
        .map(|limit| format!("{:.3} ({} | {})", limit.limit_g, limit.below, limit.above))
        .collect();
    let _ = writeln!(
        out,
        "\ndecision limits: {}; outer limits {:.3} and {:.3} g",
        if limits.is_empty() {
            "none (one colour)".to_owned()
        } else {
            limits.join(", ")
        },
        thresholds.outer_g.lower,
        thresholds.outer_g.upper
    );
    let overlaps: Vec<String> = thresholds
        .overlaps()
        .map(|limit| {
            format!(
                "{} and {} by {:.3} g",
                limit.below, limit.above, -limit.gap_g
            )
        })
        .collect();
    if overlaps.is_empty() {
        let _ = writeln!(
            out,
            "no colours overlap: each ball's {coverage} coverage interval lies within its colour's decision interval"
        );
    } else {
        let _ = writeln!(
            out,
            "overlapping unions: {}: a {coverage} coverage is not achievable with these balls (they would need larger weight differences)",
            overlaps.join(", ")
        );
    }
    let _ = writeln!(
        out,
        "reliability: {:.2} % expected (weighings normal with each ball's mean and S, averaged over the balls); {:.2} % with sigma upper in place of S (pessimistic)",
        thresholds.reliability.expected * 100.0,
        thresholds.reliability.with_sigma_upper * 100.0
    );
    out
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn levels_and_outer_limits_parse() {
        assert_eq!(parse_confidence("0.95").unwrap().level(), 0.95);
        assert!((parse_confidence("99%").unwrap().level() - 0.99).abs() < 1e-12);
        assert!((parse_coverage("90 %").unwrap().z() - 1.6449).abs() < 1e-4);
        assert!(parse_confidence("99")
            .unwrap_err()
            .contains("between 0 and 1"));
        assert!(parse_coverage("x").is_err());
        assert_eq!(parse_outer("2.0, 4.0").unwrap(), Interval::new(2.0, 4.0));
        assert!(parse_outer("4,2").is_err());
        assert!(parse_outer("2").is_err());
        assert!(parse_outer("2,x").is_err());
    }
}
