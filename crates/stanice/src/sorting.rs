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
use sorting::classify::Colour;
use sorting::rig::mechanism_reliability;
use sorting::trial::Trial;

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
    #[arg(long, value_name = "DURATION", default_value = "5m", value_parser = seconds)]
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
    let trial = Trial {
        seed: args.seed,
        sortings: args.sortings,
        colours: args.colours,
        limit: args.limit,
        faults: args.fault.clone(),
        lost_pulses: args.lose_pulse.clone(),
    };
    let report = trial.run(program)?;
    let passed = report.passed;
    let text = if args.json {
        serde_json::to_string_pretty(&report)? + "\n"
    } else {
        report.text()
    };
    // a closed pipe (`| head`) is not an error
    let _ = std::io::stdout().lock().write_all(text.as_bytes());
    Ok(if passed {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
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
