//! `stanice sorting`: the remote sorting lab without the hardware. `run` puts a student's
//! sorting program (or the reference one) behind the built-in supervisor and lets it sort
//! the simulated mechanism's eight balls, with faults if asked; `reliability` measures
//! the reference program over many seeded mechanisms (the sorting-lab thesis, sections
//! 5, 8 and 13; the `sorting` crate's rig).

use std::io::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use clap::{Args, Subcommand};
use lab::program::Program;
use plant::sorter::SorterConfig;
use plant::Plant as _;
use serde::Serialize;
use sorting::classify::Colour;
use sorting::rig::{mechanism_reliability, Rig, RigSettings, SortingOutcome};

use crate::duration_arg::seconds;

/// Sorting-lab subcommands.
#[derive(Debug, Subcommand)]
pub(crate) enum SortingCommand {
    /// Run a sorting program behind the supervisor against the simulated mechanism:
    /// where every ball ended, and every refusal and lock-out of the supervisor; exit 0
    /// when every sorting finished with every ball in its colour's shaft and the
    /// supervisor never had to step in.
    Run(RunArgs),
    /// The reference program's reliability over many seeded sortings: the confusion
    /// matrix per colour.
    Reliability(ReliabilityArgs),
}

/// `stanice sorting run`
#[derive(Debug, Args)]
pub(crate) struct RunArgs {
    /// The sorting program's ST files (compiled together with the lab's interface.st, the
    /// globals the HMI reads and writes; default: the reference program of
    /// examples/sorting-lab/plc/sorter.st, built in).
    #[arg(long = "program", value_name = "FILE.st", num_args = 1..)]
    program: Vec<PathBuf>,
    /// The PROGRAM to run when the files hold several.
    #[arg(long, value_name = "NAME")]
    main: Option<String>,
    /// The mechanism's seed: the balls' order, the deflectors at power-on, the balance's
    /// errors.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Sortings to run one after another (the balls stay where the last left them).
    #[arg(long, default_value_t = 1)]
    sortings: u32,
    /// The colours of shafts 1-4 (red, yellow, blue, green or 1-4), all different.
    #[arg(long, value_name = "C1,C2,C3,C4", default_value = "red,yellow,blue,green", value_parser = parse_colours)]
    colours: [u8; 4],
    /// The longest a sorting may take (simulated).
    #[arg(long, value_name = "DURATION", default_value = "10m", value_parser = seconds)]
    limit: Duration,
    /// A fault of the mechanism's console at the start (`miss Sn5`, `double-dose`,
    /// `stuck D2`, `balance-link-loss`, `dust 0.01`); repeatable.
    #[arg(long, value_name = "LINE")]
    fault: Vec<String>,
    /// Lose the next command pulse of this actuator before the supervisor (S1-S9, SL1,
    /// SL2, Blower, Tare, Light); repeatable.
    #[arg(long, value_name = "ACTUATOR")]
    lose_pulse: Vec<String>,
    /// Print the outcome as JSON.
    #[arg(long)]
    json: bool,
}

/// `stanice sorting reliability`
#[derive(Debug, Args)]
pub(crate) struct ReliabilityArgs {
    /// Sortings, each on a mechanism seeded anew.
    #[arg(long, default_value_t = 1000)]
    sortings: u64,
    /// The first seed (then seed + 1, ...).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Print the outcome as JSON.
    #[arg(long)]
    json: bool,
}

fn parse_colours(text: &str) -> Result<[u8; 4], String> {
    let colours: Vec<u8> = text
        .split(',')
        .map(|word| {
            let word = word.trim();
            Colour::ALL
                .iter()
                .find(|c| c.name().eq_ignore_ascii_case(word) || c.code().to_string() == word)
                .map(|c| c.code())
                .ok_or_else(|| format!("`{word}` is no colour: red, yellow, blue, green or 1-4"))
        })
        .collect::<Result<_, _>>()?;
    let array: [u8; 4] = colours
        .clone()
        .try_into()
        .map_err(|_| format!("four colours, one a shaft, not {}", colours.len()))?;
    let mut sorted = array;
    sorted.sort_unstable();
    if sorted != [1, 2, 3, 4] {
        return Err("forbidden colour combination: each shaft needs a colour of its own".into());
    }
    Ok(array)
}

pub(crate) fn run(command: SortingCommand) -> anyhow::Result<ExitCode> {
    match command {
        SortingCommand::Run(args) => run_sortings(args),
        SortingCommand::Reliability(args) => reliability(args),
    }
}

#[derive(Serialize)]
struct RunReport {
    seed: u64,
    colours: [u8; 4],
    sortings: Vec<SortingOutcome>,
    passed: bool,
}

fn colour_name(code: u8) -> &'static str {
    Colour::ALL
        .iter()
        .find(|c| c.code() == code)
        .map_or("none", |c| c.name())
}

fn right(outcome: &SortingOutcome, colours: [u8; 4]) -> usize {
    outcome
        .shafts
        .iter()
        .filter(|(ball, shaft)| {
            let shaft_colour = usize::from(*shaft)
                .checked_sub(1)
                .and_then(|k| colours.get(k))
                .copied();
            Colour::of_ball(ball).map(Colour::code) == shaft_colour
        })
        .count()
}

fn run_sortings(args: RunArgs) -> anyhow::Result<ExitCode> {
    let program = if args.program.is_empty() {
        sorting::programs::reference_sorter()
    } else {
        lab::program::read_files(&args.program)
            .and_then(|files| sorting::programs::sorting_program(files, args.main.as_deref()))
    };
    let program = match program {
        Ok(program) => program,
        Err(error) => {
            // Diagnostics as every other tool prints them, `file:line:col: error: ...`.
            eprintln!("{error}");
            return Ok(ExitCode::from(2));
        }
    };
    for warning in &program.warnings {
        eprintln!("{warning}");
    }
    let settings = RigSettings {
        mechanism: SorterConfig {
            seed: args.seed,
            ..SorterConfig::default()
        },
        ..RigSettings::default()
    };
    let mut rig = Rig::new(program, sorting::programs::supervisor()?, settings)?;
    for line in &args.fault {
        rig.plant_mut()
            .console(line)
            .map_err(|e| anyhow::anyhow!("--fault {line:?}: {e}"))?;
    }
    for actuator in &args.lose_pulse {
        rig.lose_next_pulse(actuator)?;
    }
    let mut sortings = Vec::new();
    for _ in 0..args.sortings.max(1) {
        sortings.push(rig.automatic_sorting(args.colours, args.limit)?);
    }
    let passed = sortings
        .iter()
        .all(|s| s.finished && s.events.is_empty() && right(s, args.colours) == s.shafts.len());
    let report = RunReport {
        seed: args.seed,
        colours: args.colours,
        sortings,
        passed,
    };
    let text = if args.json {
        serde_json::to_string_pretty(&report)? + "\n"
    } else {
        text(&report)
    };
    // a closed pipe (`| head`) is not an error
    let _ = std::io::stdout().lock().write_all(text.as_bytes());
    Ok(if passed {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

fn text(report: &RunReport) -> String {
    let mut out = format!(
        "mechanism seed {}; shafts 1-4: {}\n",
        report.seed,
        report
            .colours
            .iter()
            .map(|c| colour_name(*c))
            .collect::<Vec<_>>()
            .join(", ")
    );
    for (n, sorting) in report.sortings.iter().enumerate() {
        out.push_str(&format!(
            "sorting {}: {} in {:.1} s (simulated); {} of {} balls in their colour's shaft\n",
            n + 1,
            if sorting.finished {
                "finished"
            } else {
                "NOT finished"
            },
            sorting.took.as_secs_f64(),
            right(sorting, report.colours),
            sorting.shafts.len()
        ));
        for (ball, shaft) in &sorting.shafts {
            let place = match shaft {
                0 => "in no shaft".to_owned(),
                k => format!(
                    "shaft {k} ({})",
                    colour_name(
                        report
                            .colours
                            .get(usize::from(*k) - 1)
                            .copied()
                            .unwrap_or(0)
                    )
                ),
            };
            out.push_str(&format!("  {ball:<9} {place}\n"));
        }
        for event in &sorting.events {
            out.push_str(&format!(
                "  {:>9.3} s  supervisor: {} {}: {}\n",
                event.at.as_secs_f64(),
                event.actuator,
                match event.action {
                    sorting::rig::SupervisorAction::Refused => "refused",
                    sorting::rig::SupervisorAction::LockedOut => "locked out",
                },
                event.rule
            ));
        }
    }
    out.push_str(if report.passed {
        "PASSED\n"
    } else {
        "FAILED: a ball astray, a sorting unfinished or the supervisor stepped in\n"
    });
    out
}

fn reliability(args: ReliabilityArgs) -> anyhow::Result<ExitCode> {
    let build = || {
        let compile = |result: Result<Program, lab::program::ProgramError>| {
            result.map_err(|e| sorting::rig::RigError::Plc {
                plc: "built-in program",
                message: e.to_string(),
            })
        };
        Ok((
            compile(sorting::programs::reference_sorter())?,
            compile(sorting::programs::supervisor())?,
        ))
    };
    let report = mechanism_reliability(args.sortings, args.seed, build)?;
    let text = if args.json {
        serde_json::to_string_pretty(&report)? + "\n"
    } else {
        format!(
            "{} automatic sortings of the eight balls (reference program, seeds {}..{}):\n{}\
             all eight right: {} ({:.2} %); unfinished: {}; supervisor refusals and lock-outs: {}; \
             mean sorting {:.1} s simulated\n",
            report.sortings,
            args.seed,
            args.seed + args.sortings.saturating_sub(1),
            report.confusion.table(),
            report.all_right,
            100.0 * report.all_right as f64 / report.sortings.max(1) as f64,
            report.unfinished,
            report.supervisor_events,
            report.mean_time.as_secs_f64()
        )
    };
    let _ = std::io::stdout().lock().write_all(text.as_bytes());
    Ok(ExitCode::SUCCESS)
}
