//! `stanice hmi`: the web HMI for a station (docs/HMI.md), and `stanice user`: its users.

use std::io::BufRead as _;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context as _;
use clap::{Args, Subcommand};
use hmi::{Hmi, HmiOptions, ServeConfig};
use iec60870::asdu::CommonAddress;
use iec60870::time::TimeZonePolicy;

/// Arguments of `stanice hmi`.
#[derive(Args, Debug)]
pub(crate) struct HmiArgs {
    /// The station: HOST:PORT, alternates after commas.
    #[arg(long, value_delimiter = ',', required = true)]
    connect: Vec<String>,
    /// The station's common address.
    #[arg(long, default_value_t = 1)]
    ca: u16,
    /// The screens folder (hmi.toml, points.csv, SVG mimics).
    #[arg(long)]
    screens: PathBuf,
    /// The users file; default: users.toml in the screens folder.
    #[arg(long)]
    users: Option<PathBuf>,
    /// Where browsers connect (also spelt `--hmi-listen`, as `stanice run` spells it).
    #[arg(long, alias = "hmi-listen", default_value = "127.0.0.1:8080")]
    listen: SocketAddr,
    /// The HMI's event store (`sqlite:PATH`, `postgres://...`, `none`).
    #[arg(long, default_value = "sqlite:hmi-events.sqlite")]
    store: String,
    /// The station's event store (`sqlite:PATH`, `postgres://...`), read for the lift
    /// screens' fault archive and service figures; without it they show live values only.
    #[arg(long)]
    archive: Option<String>,
    /// The zone of the station's time tags (IANA name, `UTC` or `local`); default: the
    /// screens folder's hmi.toml `time_zone` (its project's), else UTC, as the test
    /// servers stamp.
    #[arg(long, value_name = "ZONE")]
    time_zone: Option<TimeZonePolicy>,
    /// Serve HTTPS with this certificate chain (PEM); needs --tls-key. Cookies are then
    /// Secure. Behind a reverse proxy that terminates TLS, leave it out (docs/HMI.md).
    #[arg(long, requires = "tls_key")]
    tls_cert: Option<PathBuf>,
    /// The private key (PEM) of --tls-cert.
    #[arg(long, requires = "tls_cert")]
    tls_key: Option<PathBuf>,
    /// Connect to the station from this local address; default: the screens folder's
    /// hmi.toml `local_address` (the address the project gives its HMI's group).
    #[arg(long)]
    local_address: Option<std::net::IpAddr>,
    /// Stop after this long (`30s`, `10m`; a plain number is seconds); runs until Ctrl-C
    /// or SIGTERM otherwise.
    #[arg(long, value_name = "TIME", value_parser = crate::duration_arg::seconds)]
    duration: Option<std::time::Duration>,
}

pub(crate) async fn run(args: HmiArgs) -> anyhow::Result<ExitCode> {
    let mut interrupt = crate::interrupt::Interrupt::listen();
    let zone = match args.time_zone {
        Some(zone) => zone,
        None => hmi::config::HmiConfig::load(&args.screens)
            .context("the HMI does not start")?
            .time_zone
            .unwrap_or_default(),
    };
    let users = args
        .users
        .clone()
        .unwrap_or_else(|| args.screens.join("users.toml"));
    let mut serve = ServeConfig::default();
    serve.trial =
        sorting::hmi_trial::trial_for(&args.screens, None).context("the HMI does not start")?;
    if let (Some(certificate), Some(key)) = (&args.tls_cert, &args.tls_key) {
        serve.tls = Some(hmi::tls::TlsFiles {
            certificate: certificate.clone(),
            key: key.clone(),
        });
    }
    let scheme = if serve.tls.is_some() { "https" } else { "http" };
    let hmi = Hmi::start_with(
        HmiOptions {
            screens: args.screens.clone(),
            users: users.clone(),
            connect: args.connect.clone(),
            common_address: CommonAddress::new(args.ca),
            listen: args.listen,
            store: (args.store != "none").then(|| args.store.clone()),
            archive: args.archive.clone(),
            zone,
            local_address: args.local_address,
        },
        serve,
    )
    .await
    .context("the HMI does not start")?;
    println!(
        "Stanice HMI on {scheme}://{} for the station at {} (CA {})",
        hmi.address,
        args.connect.join(","),
        args.ca
    );
    println!(
        "  users: {} (stanice user add NAME --level N --users FILE)",
        users.display()
    );
    match args.duration {
        Some(duration) => tokio::time::sleep(duration).await,
        None => interrupt.recv().await,
    }
    hmi.shutdown().await;
    Ok(ExitCode::SUCCESS)
}

/// `stanice user ...`.
#[derive(Subcommand, Debug)]
pub(crate) enum UserCommand {
    /// Adds a user; the password is typed twice without echo on a terminal, or read
    /// from standard input (one line) when it is a pipe or file.
    Add {
        /// User name.
        name: String,
        /// Permission level 0..=9 (0 = read-only).
        #[arg(long)]
        level: u8,
        /// The screen the browser opens after login: a screen id of hmi.toml or a page
        /// (`lifts`, `faults`, `mobile`, `events`, `alarms`, `trends`).
        #[arg(long)]
        start: Option<String>,
        #[command(flatten)]
        file: UsersFileArgs,
    },
    /// Removes a user.
    Remove {
        /// User name.
        name: String,
        #[command(flatten)]
        file: UsersFileArgs,
    },
    /// Sets a user's password (typed twice without echo, or one line of standard input)
    /// and optionally level.
    Passwd {
        /// User name.
        name: String,
        /// New permission level.
        #[arg(long)]
        level: Option<u8>,
        #[command(flatten)]
        file: UsersFileArgs,
    },
    /// Lists the users and their levels.
    List {
        #[command(flatten)]
        file: UsersFileArgs,
    },
}

/// Which users file a `stanice user` command edits. There is no default: a users file
/// quietly created in the current directory is one no HMI reads.
#[derive(Args, Debug)]
#[group(required = true, multiple = false)]
pub(crate) struct UsersFileArgs {
    /// The users file.
    #[arg(long)]
    users: Option<PathBuf>,
    /// A project folder: its web HMI's users file (`PROJECT/hmi/users.toml`), the one
    /// `stanice run --hmi` and `stanice demo` read.
    #[arg(long)]
    project: Option<PathBuf>,
}

impl UsersFileArgs {
    fn path(&self) -> anyhow::Result<PathBuf> {
        match (&self.users, &self.project) {
            (Some(users), _) => Ok(users.clone()),
            (None, Some(project)) => {
                if !project.join(station::config::PROJECT_FILE).is_file() {
                    anyhow::bail!(
                        "{} is not a project folder (no {})",
                        project.display(),
                        station::config::PROJECT_FILE
                    );
                }
                Ok(crate::run::users_file(project))
            }
            // clap requires one of the two; kept as an error rather than a panic.
            (None, None) => anyhow::bail!("give the users file: --users FILE or --project FOLDER"),
        }
    }
}

/// The new password: on a terminal typed twice without echo (the two must agree), from
/// a pipe or file its first line (for scripts).
fn read_password() -> anyhow::Result<String> {
    if std::io::IsTerminal::is_terminal(&std::io::stdin()) {
        let first = rpassword::prompt_password("password: ")?;
        let again = rpassword::prompt_password("password again: ")?;
        if first != again {
            anyhow::bail!("the two passwords differ; nothing was changed");
        }
        return Ok(first);
    }
    let mut line = String::new();
    std::io::stdin().lock().read_line(&mut line)?;
    Ok(line.trim_end_matches(['\r', '\n']).to_owned())
}

pub(crate) fn user(command: UserCommand) -> anyhow::Result<ExitCode> {
    match command {
        UserCommand::Add {
            name,
            level,
            start,
            file,
        } => {
            let users = file.path()?;
            let mut file = hmi::users::Users::load(&users)?;
            if let Some(start) = &start {
                if !hmi::users::valid_start(start) {
                    anyhow::bail!(
                        "`{start}`: a start screen is 1-64 letters, digits, '-', '_', '/'"
                    );
                }
            }
            let password = read_password()?;
            file.add(&name, level, &password)?;
            if let Some(start) = &start {
                file.set_start(&name, Some(start))?;
            }
            println!(
                "user {name} added with level {level} to {}",
                users.display()
            );
        }
        UserCommand::Remove { name, file } => {
            let users = file.path()?;
            hmi::users::Users::load(&users)?.remove(&name)?;
            println!("user {name} removed from {}", users.display());
        }
        UserCommand::Passwd { name, level, file } => {
            let users = file.path()?;
            let mut file = hmi::users::Users::load(&users)?;
            let password = read_password()?;
            file.passwd(&name, &password, level)?;
            println!("password of {name} changed in {}", users.display());
        }
        UserCommand::List { file } => {
            for (name, level) in hmi::users::Users::load(&file.path()?)?.list() {
                println!("{name}\t{level}");
            }
        }
    }
    Ok(ExitCode::SUCCESS)
}
