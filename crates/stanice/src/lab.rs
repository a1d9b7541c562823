//! `stanice lab`: the PLC teaching lab — a student's Structured Text program against one
//! of the four lab models (`slide`, `crossroad`, `mixing`, `washing`) on the simulated
//! clock, checked by a scenario; a class's folder graded in one command.

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use anyhow::Context;
use clap::{Args, Subcommand};
use lab::run::{DEFAULT_DURATION, DEFAULT_SCAN};
use lab::{Program, RunSettings, Scenario, Session, Speed};
use plant::lab::{LabOptions, Profile};

/// Teaching-lab subcommands.
#[derive(Debug, Subcommand)]
pub(crate) enum LabCommand {
    /// Run a student's program against a model and report every error with its
    /// simulated time and the program's outputs; exit 0 when the run met its scenario.
    Run(RunArgs),
    /// Run every student program in a folder against a scenario and write the verdicts
    /// as CSV and HTML.
    Grade(GradeArgs),
    /// Serve the model's front panel in the browser with the program running: LEDs,
    /// buttons, speed control and a time-line of every signal.
    Serve(ServeArgs),
    /// List a model's signals with their direct addresses in a profile.
    Signals(SignalsArgs),
}

/// `stanice lab serve`
#[derive(Debug, Args)]
pub(crate) struct ServeArgs {
    /// The model: slide, crossroad, mixing or washing (or --project).
    #[arg(required_unless_present = "project", conflicts_with = "project")]
    model: Option<String>,
    /// The program's ST files (compiled together).
    #[arg(long = "program", value_name = "FILE.st", num_args = 1.., required_unless_present = "project", conflicts_with = "project")]
    program: Vec<PathBuf>,
    /// A lab project (TOML): several models, each with its program, served together at
    /// /m/N/ with an index at /.
    #[arg(long, value_name = "FILE.toml")]
    project: Option<PathBuf>,
    #[command(flatten)]
    model_args: ModelArgs,
    /// Where the mimic listens.
    #[arg(long, default_value = "127.0.0.1:8090")]
    listen: std::net::SocketAddr,
    /// The speed to start at: a factor of real time or `max`.
    #[arg(long, default_value = "1")]
    speed: Speed,
    /// Start paused.
    #[arg(long)]
    paused: bool,
    /// A scenario whose lines and properties the run follows.
    #[arg(long)]
    scenario: Option<PathBuf>,
}

/// What every run shares.
#[derive(Debug, Args)]
pub(crate) struct ModelArgs {
    /// Address profile: `model` (the model documentation's Yb.n = %QXb.n, Xb.n = %IXb.n),
    /// `lab` (the lab wiring, LAB-A8's pattern) or `lab-printed` (the lab's table as
    /// printed). Default: the scenario's, else `model`.
    #[arg(long)]
    profile: Option<Profile>,
    /// A model option `KEY=VALUE` (LAB-A1 `sensors=2,4,7,9`, LAB-A7 `heating=level`,
    /// LAB-A9 `drum=4`, LAB-A11 `program-err=true`); repeatable, after the scenario's.
    #[arg(long = "option", value_name = "KEY=VALUE")]
    options: Vec<String>,
    /// Simulated time to run (`90s`, `10m`); default the scenario's, else 10 minutes.
    #[arg(long, value_parser = lab::scenario::parse_duration)]
    duration: Option<Duration>,
    /// The PLC's cycle (`10ms`); default the scenario's, else 10 ms.
    #[arg(long, value_parser = lab::scenario::parse_duration)]
    scan: Option<Duration>,
    /// The PROGRAM to run when the files hold several.
    #[arg(long = "main", value_name = "NAME")]
    main: Option<String>,
}

/// `stanice lab run`
#[derive(Debug, Args)]
pub(crate) struct RunArgs {
    /// The model: slide, crossroad, mixing or washing.
    model: String,
    /// The program's ST files (compiled together).
    #[arg(long = "program", value_name = "FILE.st", required = true, num_args = 1..)]
    program: Vec<PathBuf>,
    #[command(flatten)]
    model_args: ModelArgs,
    /// How fast: a factor of real time (`1`, `10`) or `max`.
    #[arg(long, default_value = "max")]
    speed: Speed,
    /// The scenario (TOML): inputs over time, faults, properties.
    #[arg(long)]
    scenario: Option<PathBuf>,
    /// Print the report as JSON.
    #[arg(long)]
    json: bool,
}

/// `stanice lab grade`
#[derive(Debug, Args)]
pub(crate) struct GradeArgs {
    /// The scenario every program is run against (it names the model).
    #[arg(long, required = true)]
    scenario: PathBuf,
    /// The folder of submissions: each `.st` file one student, each subfolder of `.st`
    /// files one student.
    folder: PathBuf,
    #[command(flatten)]
    model_args: ModelArgs,
    /// Where to write the table: PREFIX.csv and PREFIX.html (default FOLDER/grades).
    #[arg(long, value_name = "PREFIX")]
    out: Option<PathBuf>,
}

/// `stanice lab signals`
#[derive(Debug, Args)]
pub(crate) struct SignalsArgs {
    /// The model: slide, crossroad, mixing or washing.
    model: String,
    /// Address profile (model, lab, lab-printed).
    #[arg(long, default_value = "model")]
    profile: Profile,
    /// A model option `KEY=VALUE`; repeatable.
    #[arg(long = "option", value_name = "KEY=VALUE")]
    options: Vec<String>,
}

/// Runs a `lab` subcommand.
pub(crate) async fn run(command: LabCommand) -> anyhow::Result<ExitCode> {
    match command {
        LabCommand::Run(args) => run_one(args),
        LabCommand::Grade(args) => grade(args),
        LabCommand::Serve(args) => serve(args).await,
        LabCommand::Signals(args) => signals(args),
    }
}

async fn serve(args: ServeArgs) -> anyhow::Result<ExitCode> {
    if let Some(project) = &args.project {
        return serve_project(project, &args).await;
    }
    let model = args.model.clone().unwrap_or_default();
    known_model(&model)?;
    let scenario = args.scenario.as_deref().map(Scenario::load).transpose()?;
    let run = settings(&model, &args.model_args, scenario.as_ref(), args.speed)?;
    let sources = match lab::program::read_files(&args.program) {
        Ok(sources) => sources,
        Err(error) => {
            eprintln!("{error}");
            return Ok(ExitCode::from(2));
        }
    };
    // Compiled here first so that a student sees the diagnostics before a browser.
    if let Err(error) = Program::compile(&sources, args.model_args.main.as_deref()) {
        eprintln!("{error}");
        return Ok(ExitCode::from(2));
    }
    // Listening for Ctrl-C and SIGTERM from here on: one that comes right after the banner
    // stops the mimic cleanly.
    let mut interrupt = crate::interrupt::Interrupt::listen();
    let listener = tokio::net::TcpListener::bind(args.listen)
        .await
        .with_context(|| format!("cannot listen on {}", args.listen))?;
    let address = lab::serve::address(&listener).unwrap_or(args.listen);
    println!("the {model} mimic is at http://{address}/ (Ctrl-C to stop)");
    let settings = lab::serve::ServeSettings {
        run,
        sources,
        main: args.model_args.main.clone(),
        scenario,
        paused: args.paused,
    };
    tokio::select! {
        served = lab::serve::serve(listener, settings) => served?,
        () = interrupt.recv() => {}
    }
    Ok(ExitCode::SUCCESS)
}

fn key_values(options: &[String]) -> anyhow::Result<Vec<(String, String)>> {
    options
        .iter()
        .map(|option| {
            option
                .split_once('=')
                .map(|(key, value)| (key.trim().to_owned(), value.trim().to_owned()))
                .with_context(|| format!("--option expects KEY=VALUE, got {option:?}"))
        })
        .collect()
}

/// The settings of a run: the command line over the scenario over the defaults.
fn settings(
    model: &str,
    args: &ModelArgs,
    scenario: Option<&Scenario>,
    speed: Speed,
) -> anyhow::Result<RunSettings> {
    if let Some(named) = scenario.and_then(|s| s.model.as_deref()) {
        if named != model {
            anyhow::bail!(
                "the scenario {} is for the model `{named}`, not `{model}`",
                scenario.map_or("", |s| s.source.as_str())
            );
        }
    }
    let profile = match (args.profile, scenario.and_then(|s| s.profile.as_deref())) {
        (Some(profile), _) => profile,
        (None, Some(text)) => text
            .parse()
            .map_err(|error| anyhow::anyhow!("the scenario's profile: {error}"))?,
        (None, None) => Profile::default(),
    };
    let mut pairs = scenario.map(|s| s.options.clone()).unwrap_or_default();
    pairs.extend(key_values(&args.options)?);
    let options = LabOptions::parse(&pairs)?;
    Ok(RunSettings {
        model: model.to_owned(),
        profile,
        options,
        duration: args
            .duration
            .or(scenario.and_then(|s| s.duration))
            .unwrap_or(DEFAULT_DURATION),
        scan: args
            .scan
            .or(scenario.and_then(|s| s.scan))
            .unwrap_or(DEFAULT_SCAN),
        speed,
    })
}

fn known_model(model: &str) -> anyhow::Result<()> {
    if plant::lab::MODELS.contains(&model) {
        Ok(())
    } else {
        anyhow::bail!(
            "no lab model `{model}` (the models: {})",
            plant::lab::MODELS.join(", ")
        )
    }
}

fn run_one(args: RunArgs) -> anyhow::Result<ExitCode> {
    known_model(&args.model)?;
    let scenario = args.scenario.as_deref().map(Scenario::load).transpose()?;
    let settings = settings(&args.model, &args.model_args, scenario.as_ref(), args.speed)?;
    let program = match Program::load(&args.program, args.model_args.main.as_deref()) {
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
    let report = Session::new(program, settings, scenario.as_ref())?.run()?;
    let mut out = std::io::stdout().lock();
    let text = if args.json {
        serde_json::to_string_pretty(&report)? + "\n"
    } else {
        report.text()
    };
    // a closed pipe (`| head`) is not an error
    let _ = out.write_all(text.as_bytes());
    Ok(if report.passed {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

fn grade(args: GradeArgs) -> anyhow::Result<ExitCode> {
    let scenario = Scenario::load(&args.scenario)?;
    let Some(model) = scenario.model.clone() else {
        anyhow::bail!(
            "the scenario {} names no model (`model = \"slide\"`)",
            args.scenario.display()
        );
    };
    known_model(&model)?;
    let settings = settings(&model, &args.model_args, Some(&scenario), Speed::Max)?;
    let grades = lab::grade::grade(
        &args.folder,
        &scenario,
        &settings,
        args.model_args.main.as_deref(),
    )
    .with_context(|| format!("cannot read the folder {}", args.folder.display()))?;
    if grades.is_empty() {
        anyhow::bail!(
            "no submissions in {}: each .st file is one student, each subfolder of .st files one student",
            args.folder.display()
        );
    }
    let prefix = args.out.unwrap_or_else(|| args.folder.join("grades"));
    let csv_path = prefix.with_extension("csv");
    let html_path = prefix.with_extension("html");
    std::fs::write(&csv_path, lab::grade::csv(&grades)?)
        .with_context(|| format!("cannot write {}", csv_path.display()))?;
    let title = format!(
        "{} on {} ({})",
        args.scenario.display(),
        model,
        settings.profile
    );
    std::fs::write(&html_path, lab::grade::html(&title, &grades))
        .with_context(|| format!("cannot write {}", html_path.display()))?;
    let mut out = std::io::stdout().lock();
    for grade in &grades {
        let detail = if grade.first_violation.is_empty() {
            grade.diagnostics.lines().next().unwrap_or("").to_owned()
        } else {
            grade.first_violation.clone()
        };
        let _ = writeln!(
            out,
            "{:<20} {:<16} {:>4}  {detail}",
            grade.student,
            grade.verdict.text(),
            grade.violations
        );
    }
    let passed = grades
        .iter()
        .filter(|g| g.verdict == lab::grade::Verdict::Passed)
        .count();
    let _ = writeln!(
        out,
        "{passed} of {} passed; the table is in {} and {}",
        grades.len(),
        csv_path.display(),
        html_path.display()
    );
    Ok(ExitCode::SUCCESS)
}

/// Serves every model of a lab project, each with its program.
async fn serve_project(path: &std::path::Path, args: &ServeArgs) -> anyhow::Result<ExitCode> {
    let project = lab::project::LabProject::load(path)?;
    let mut mimics = Vec::new();
    for entry in &project.models {
        known_model(&entry.model)?;
        let scenario = entry.scenario.as_deref().map(Scenario::load).transpose()?;
        let mut model_args = ModelArgs {
            profile: args.model_args.profile,
            options: entry
                .options
                .iter()
                .map(|(key, value)| format!("{key}={value}"))
                .chain(args.model_args.options.iter().cloned())
                .collect(),
            duration: args.model_args.duration,
            scan: args.model_args.scan,
            main: entry.main.clone(),
        };
        if model_args.profile.is_none() {
            model_args.profile = entry
                .profile
                .as_deref()
                .map(str::parse)
                .transpose()
                .map_err(|error| anyhow::anyhow!("{}: {error}", entry.title))?;
        }
        let run = settings(&entry.model, &model_args, scenario.as_ref(), args.speed)?;
        let sources = match lab::program::read_files(&entry.program) {
            Ok(sources) => sources,
            Err(error) => {
                eprintln!("{error}");
                return Ok(ExitCode::from(2));
            }
        };
        if let Err(error) = Program::compile(&sources, entry.main.as_deref()) {
            eprintln!("{}: {error}", entry.title);
            return Ok(ExitCode::from(2));
        }
        mimics.push((
            entry.title.clone(),
            lab::serve::ServeSettings {
                run,
                sources,
                main: entry.main.clone(),
                scenario,
                paused: args.paused,
            },
        ));
    }
    let mut interrupt = crate::interrupt::Interrupt::listen();
    let listener = tokio::net::TcpListener::bind(args.listen)
        .await
        .with_context(|| format!("cannot listen on {}", args.listen))?;
    let address = lab::serve::address(&listener).unwrap_or(args.listen);
    println!(
        "the lab's {} mimics are at http://{address}/ (Ctrl-C to stop)",
        mimics.len()
    );
    tokio::select! {
        served = lab::serve::serve_many(listener, mimics) => served?,
        () = interrupt.recv() => {}
    }
    Ok(ExitCode::SUCCESS)
}

fn signals(args: SignalsArgs) -> anyhow::Result<ExitCode> {
    known_model(&args.model)?;
    let options = LabOptions::parse(&key_values(&args.options)?)?;
    let model = plant::lab::open(&args.model, &options)?;
    let bindings = plant::lab::bindings(&args.model, args.profile, &options)?;
    let mut out = std::io::stdout().lock();
    let _ = writeln!(out, "signal,address,direction,description");
    for binding in bindings {
        let info = model.signals().iter().find(|s| s.name == binding.signal);
        let (direction, description) = info.map_or(("", String::new()), |info| {
            let direction = match info.direction {
                plant::Direction::Input => "PLC input",
                plant::Direction::Output => "PLC output",
            };
            (direction, info.description.clone())
        });
        let _ = writeln!(
            out,
            "{},%{},{direction},\"{}\"",
            binding.signal,
            binding.address,
            description.replace('"', "\"\"")
        );
    }
    Ok(ExitCode::SUCCESS)
}
