//! `stanice plc`: check and run IEC 61131-3 Structured Text.

use anyhow::Context;
use clap::{Args, Subcommand};
use plc::task::{ClockReading, TaskConfig};
use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

/// Soft-PLC subcommands.
#[derive(Debug, Subcommand)]
pub(crate) enum PlcCommand {
    /// Parse and check ST files; print diagnostics as `file:line:col: error: message`.
    Check(CheckArgs),
    /// Run a program on a virtual clock and print its variables.
    Run(RunArgs),
    /// Explain a diagnostic code: what it means, an example of the mistake and its fix.
    Explain(ExplainArgs),
}

/// `stanice plc explain`
#[derive(Debug, Args)]
pub(crate) struct ExplainArgs {
    /// The code as diagnostics print it (`E0201`, any case) or its name (`TypeMismatch`).
    #[arg(required_unless_present = "list", conflicts_with = "list")]
    code: Option<String>,
    /// List every code with its one-line meaning.
    #[arg(long)]
    list: bool,
}

/// Every code with the first sentence of its meaning, one a line.
fn code_list() -> String {
    plc::Code::ALL
        .iter()
        .map(|c| {
            let title = c.page().lines().next().unwrap_or_default();
            let title = title
                .trim_start_matches('#')
                .trim()
                .split_once(": ")
                .map_or(title, |(_, t)| t);
            format!("{}  {title}\n", c.as_str())
        })
        .collect()
}

/// `stanice plc check`
#[derive(Debug, Args)]
pub(crate) struct CheckArgs {
    /// ST source files.
    #[arg(required = true)]
    files: Vec<PathBuf>,
}

/// `stanice plc run`
#[derive(Debug, Args)]
pub(crate) struct RunArgs {
    /// ST source files.
    #[arg(required = true)]
    files: Vec<PathBuf>,
    /// The PROGRAM to run.
    #[arg(long)]
    program: String,
    /// Number of scan cycles.
    #[arg(long, default_value_t = 1)]
    cycles: u64,
    /// Virtual time per cycle in milliseconds.
    #[arg(long = "cycle-ms", default_value_t = 10)]
    cycle_ms: u64,
    /// Set a variable before the first cycle: `PATH=VALUE` (IEC literal), repeatable.
    #[arg(long = "set", value_name = "PATH=VALUE")]
    set: Vec<String>,
    /// Run loops as closures instead of machine code (the reference semantics; also
    /// `STANICE_PLC_JIT=0`).
    #[arg(long = "no-jit")]
    no_jit: bool,
}

fn load(files: &[PathBuf]) -> anyhow::Result<Vec<(String, String)>> {
    files
        .iter()
        .map(|f| {
            let bytes = std::fs::read(f).with_context(|| format!("cannot read {}", f.display()))?;
            // Shown as every other diagnostic, `file:line:col: error: ...`, for editors.
            let text = plc::syntax::decode(&bytes).map_err(|error| {
                eprintln!(
                    "{}:{}:{}: error: {error}",
                    f.display(),
                    error.line,
                    error.col
                );
                anyhow::anyhow!("{} is not UTF-8 text", f.display())
            })?;
            Ok((f.display().to_string(), text.to_owned()))
        })
        .collect()
}

/// Runs a `plc` subcommand.
pub(crate) async fn run(command: PlcCommand) -> anyhow::Result<ExitCode> {
    match command {
        PlcCommand::Check(args) => {
            let files = load(&args.files)?;
            let (sources, result) = plc::build(&files);
            match result {
                Ok(compiled) => {
                    for w in &compiled.checked.warnings {
                        println!("{}", w.render(&sources));
                    }
                    // Say what was checked: silence after a check reads as nothing done.
                    let count = |kind: plc::syntax::PouKind| {
                        compiled
                            .checked
                            .pous
                            .iter()
                            .filter(|p| p.kind == kind && !p.stdlib)
                            .count()
                    };
                    println!(
                        "checked {} file(s): {} program(s), {} function block(s), {} function(s); no errors, {} warning(s)",
                        args.files.len(),
                        count(plc::syntax::PouKind::Program),
                        count(plc::syntax::PouKind::FunctionBlock),
                        count(plc::syntax::PouKind::Function),
                        compiled.checked.warnings.len()
                    );
                    Ok(ExitCode::SUCCESS)
                }
                Err(diags) => {
                    for d in &diags {
                        println!("{}", d.render(&sources));
                    }
                    Ok(ExitCode::FAILURE)
                }
            }
        }
        PlcCommand::Explain(args) => {
            let mut out = std::io::stdout().lock();
            let text = match args.code.as_deref() {
                None => code_list(),
                Some(code) => match plc::Code::parse(code) {
                    Ok(code) => code.page().to_owned(),
                    Err(error) => {
                        eprint!("error: {error}; the codes are:\n{}", code_list());
                        return Ok(ExitCode::from(2));
                    }
                },
            };
            // a closed pipe (`| head`) is not an error
            let _ = out.write_all(text.as_bytes());
            Ok(ExitCode::SUCCESS)
        }
        PlcCommand::Run(args) => {
            let files = load(&args.files)?;
            let mut options = plc::CompileOptions::default();
            options.jit &= !args.no_jit;
            let (sources, result) = plc::build_with(&files, options);
            let compiled = match result {
                Ok(c) => c,
                Err(diags) => {
                    for d in &diags {
                        eprintln!("{}", d.render(&sources));
                    }
                    return Ok(ExitCode::FAILURE);
                }
            };
            let mut plc = plc::Plc::new(compiled, sources);
            let cycle_ns = i64::try_from(args.cycle_ms)
                .unwrap_or(i64::MAX / 1_000_000)
                .saturating_mul(1_000_000);
            plc.add_task(TaskConfig::cyclic("main", cycle_ns, &[&args.program]))?;
            for s in &args.set {
                let (path, value) = s
                    .split_once('=')
                    .with_context(|| format!("--set expects PATH=VALUE, got '{s}'"))?;
                plc.write(path.trim(), value.trim())
                    .with_context(|| format!("--set {s}"))?;
            }
            // The virtual wall clock starts at 2024-01-01 00:00:00 UTC, local time UTC+1.
            let epoch = 1_704_067_200_000_000_000i64;
            let mut failed = false;
            for k in 0..args.cycles {
                let t = i64::try_from(k)
                    .unwrap_or(i64::MAX)
                    .saturating_mul(cycle_ns);
                let now = ClockReading {
                    monotonic_ns: t,
                    utc_ns: epoch.saturating_add(t),
                    utc_offset_ns: 3_600_000_000_000,
                };
                for d in plc.run_cycle(now) {
                    eprintln!("{}", plc.render(&d));
                    failed = true;
                }
                if failed {
                    break;
                }
            }
            let mut out = std::io::stdout().lock();
            for leaf in plc.program_leaves(&args.program)? {
                let value = plc.read_text(&leaf.path)?;
                if writeln!(out, "{} = {value}", leaf.path).is_err() {
                    break; // closed pipe: stop quietly
                }
            }
            Ok(if failed {
                ExitCode::FAILURE
            } else {
                ExitCode::SUCCESS
            })
        }
    }
}
