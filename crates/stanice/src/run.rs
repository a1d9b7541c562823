//! `stanice run PROJECT` and `stanice demo`: run a station project.
//!
//! Every node of the project (or those named with `--node`) runs in this process on the
//! simulated clock; `--speed` runs it faster than real time. While it runs, lines typed on
//! standard input inject faults and hand operations (`supply-loss T1`, `selector RH2
//! local`, `link-cut RDRT/RH`, `clear all`, `status`, `help`).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Context as _;
use chrono::{DateTime, Utc};
use clap::Args;
use station::config::{HostsFile, Project};
use station::runtime::{Pacing, Runtime, RuntimeError, RuntimeOptions, StoreChoice};

use crate::interrupt::Interrupt;

/// Arguments of `stanice run`.
#[derive(Args, Debug)]
pub(crate) struct RunArgs {
    /// The project folder (holding station.toml).
    project: PathBuf,
    /// A deployment's hosts file (TOML): the address each node runs at (`[nodes]`: its
    /// server listens there, links to it connect there) and the addresses standing for
    /// the project's client addresses (`[clients]`); see docs/DEPLOYMENT.md.
    #[arg(long, value_name = "FILE")]
    hosts: Option<PathBuf>,
    #[command(flatten)]
    options: RunOptions,
}

/// Options shared by `run` and `demo`.
#[derive(Args, Debug)]
pub(crate) struct RunOptions {
    /// Run only this node (repeatable); links to other nodes then go over the network.
    #[arg(long = "node", value_name = "NAME")]
    nodes: Vec<String>,
    /// Simulated seconds per real second.
    #[arg(long, default_value_t = 1.0)]
    speed: f64,
    /// Event store URL (`sqlite:PATH`, `postgres://...`), or `none`; default: the project's.
    #[arg(long)]
    store: Option<String>,
    /// Moves every server port: the project's port_base becomes this.
    #[arg(long)]
    port_base: Option<u16>,
    /// Simulated start time (RFC 3339, e.g. 2025-01-15T16:00:00Z); default: now.
    #[arg(long)]
    start: Option<DateTime<Utc>>,
    /// Stop after this long in real time (`30s`, `10m`; a plain number is seconds); runs
    /// until Ctrl-C or SIGTERM otherwise.
    #[arg(long, value_name = "TIME", value_parser = crate::duration_arg::seconds)]
    duration: Option<std::time::Duration>,
    /// Also serve the project's web HMI (its `hmi/` folder) on 127.0.0.1:8080 + (port
    /// base - 2404); the demo does by default.
    #[arg(long)]
    hmi: bool,
    /// Where browsers reach the web HMI instead (`127.0.0.1:8080`; port 0: any free
    /// port); the same option as `stanice hmi --hmi-listen`. Implies --hmi.
    #[arg(long, value_name = "ADDR:PORT", conflicts_with = "hmi_port")]
    hmi_listen: Option<std::net::SocketAddr>,
    /// The web HMI's port on 127.0.0.1 instead (0: any free port): short for
    /// `--hmi-listen 127.0.0.1:PORT`.
    #[arg(long, value_name = "PORT")]
    hmi_port: Option<u16>,
    /// Serve the web HMI over HTTPS with this certificate chain (PEM, the server's
    /// certificate first); needs --hmi-tls-key and implies --hmi. Cookies are then Secure.
    #[arg(long, value_name = "FILE", requires = "hmi_tls_key")]
    hmi_tls_cert: Option<PathBuf>,
    /// The private key (PEM: PKCS#8, PKCS#1 or SEC1) of --hmi-tls-cert.
    #[arg(long, value_name = "FILE", requires = "hmi_tls_cert")]
    hmi_tls_key: Option<PathBuf>,
    /// Make every node an MQTT Sparkplug B edge node publishing to this broker
    /// (`mqtt://HOST:PORT`, `mqtts://HOST:PORT`); instead of the url of station.toml's
    /// `[mqtt]`, whose other settings (ca, username, password, primary_host, group) apply.
    #[arg(long, value_name = "URL")]
    mqtt: Option<String>,
}

/// The web HMI that `run` (with `--hmi`) or `demo` serves next to the station.
struct HmiPlan {
    /// Asked for (`--hmi`, or its certificate): an HMI that cannot start is an error. The
    /// demo serves one by default and, as before, runs the station without it then.
    required: bool,
    /// The event store is in memory (`--store none`).
    memory_store: bool,
    /// Where browsers reach it; `None`: 127.0.0.1 at 8080 + (port base - 2404).
    listen: Option<std::net::SocketAddr>,
    tls: Option<hmi::tls::TlsFiles>,
}

pub(crate) async fn run(args: RunArgs) -> anyhow::Result<ExitCode> {
    run_project(&args.project, args.hosts.as_deref(), args.options, false).await
}

/// Loads a project, printing every configuration error as `file:line:col: error: ...`.
pub(crate) fn load_project(folder: &Path) -> anyhow::Result<Project> {
    Project::load(folder).map_err(|errors| {
        // One line per error, then `file: ... and N more error(s)` where some were left out.
        eprintln!("{errors}");
        anyhow::anyhow!(
            "{} error(s) in the project {}",
            errors.total(),
            folder.display()
        )
    })
}

/// Applies the hosts file `file` to `project`, printing every error as
/// `file:line:col: error: ...` as [`load_project`] does.
fn deploy(project: Project, file: &Path) -> anyhow::Result<Project> {
    let report = |errors: station::config::ConfigErrors| {
        eprintln!("{errors}");
        anyhow::anyhow!(
            "{} error(s) in the hosts file {}",
            errors.total(),
            file.display()
        )
    };
    let hosts = HostsFile::load(file).map_err(report)?;
    project.with_hosts(&hosts).map_err(report)
}

/// Runs the project in `folder` (deployed as the hosts file `hosts` says, if given).
pub(crate) async fn run_project(
    folder: &Path,
    hosts: Option<&Path>,
    options: RunOptions,
    demo: bool,
) -> anyhow::Result<ExitCode> {
    // From the start: a Ctrl-C while the station starts stops it once started, cleanly.
    let mut interrupt = Interrupt::listen();
    let mut project = load_project(folder)?;
    if let Some(file) = hosts {
        project = deploy(project, file)?;
    }
    if demo {
        // The demo's links between controllers go over mutually authenticated TLS.
        project = crate::demo::secure_links(project)?;
    }
    let tls = match (&options.hmi_tls_cert, &options.hmi_tls_key) {
        (Some(certificate), Some(key)) => Some(hmi::tls::TlsFiles {
            certificate: certificate.clone(),
            key: key.clone(),
        }),
        // clap requires both or neither.
        _ => None,
    };
    let asked = options.hmi || tls.is_some() || options.hmi_listen.is_some();
    let plan = (asked || demo).then(|| HmiPlan {
        required: asked,
        memory_store: options.store.as_deref() == Some("none"),
        listen: options.hmi_listen.or_else(|| {
            options
                .hmi_port
                .map(|port| std::net::SocketAddr::from(([127, 0, 0, 1], port)))
        }),
        tls,
    });
    if let Some(plan) = plan.as_ref().filter(|plan| plan.required) {
        // A broken hmi.toml (or certificate) fails the command before the station starts,
        // with the file:line:col of the mistake, rather than a station without its HMI.
        check_hmi(&project.folder, plan)?;
    }
    if let Some(base) = options.port_base {
        project = project.with_port_base(base);
    }
    if !(options.speed.is_finite() && options.speed > 0.0) {
        anyhow::bail!("--speed must be a positive number");
    }
    let store = match options.store.as_deref() {
        None => StoreChoice::Project,
        Some("none") => StoreChoice::Disabled,
        Some(url) => StoreChoice::Url(url.to_owned()),
    };
    // The lift screens read the station's own store (fault archive, point history); an
    // in-memory store is private to the station, so the HMI gets none then.
    let store_shown = match &store {
        StoreChoice::Project => project.station.store.clone(),
        StoreChoice::Url(url) => url.clone(),
        StoreChoice::Disabled => "none".to_owned(),
    };
    let shown_project = project.clone();
    let runtime = match Runtime::start(
        project,
        RuntimeOptions {
            nodes: options.nodes.clone(),
            pacing: Pacing::RealTime {
                speed: options.speed,
            },
            start: options.start.unwrap_or_else(Utc::now),
            store,
            device_kinds: station::device::DeviceKinds::builtin(),
        },
    )
    .await
    {
        Ok(runtime) => runtime,
        Err(RuntimeError::PortInUse { node, address }) => anyhow::bail!(
            "the station does not start: {}",
            crate::port_in_use::explain(&shown_project, &node, address)
        ),
        Err(error) => return Err(anyhow::Error::new(error).context("the station does not start")),
    };
    print_banner(&runtime, &store_shown, options.speed, demo);
    // Kept for the run: dropping them closes the connections (the broker then publishes
    // each node's NDEATH, its will).
    let _edge_nodes = match start_mqtt(&runtime, options.mqtt.as_deref()) {
        Ok(nodes) => nodes,
        Err(error) => {
            runtime.shutdown().await;
            return Err(anyhow::Error::new(error).context("the station does not start"));
        }
    };
    let archive =
        (store_shown != "none" && !store_shown.contains(":memory:")).then(|| store_shown.clone());
    let hmi = match &plan {
        Some(plan) => match start_hmi(&runtime, plan, archive).await {
            Ok(hmi) => hmi,
            Err(error) => {
                runtime.shutdown().await;
                return Err(error);
            }
        },
        None => None,
    };
    println!("Type a fault or operation here (`help` lists them); Ctrl-C stops (SIGTERM too).");
    let stop = async {
        match options.duration {
            Some(duration) => tokio::time::sleep(duration).await,
            None => interrupt.recv().await,
        }
    };
    tokio::select! {
        () = stop => {}
        () = console(&runtime, hmi.as_ref()) => {}
    }
    if let Some(hmi) = hmi {
        hmi.shutdown().await;
    }
    runtime.shutdown().await;
    Ok(ExitCode::SUCCESS)
}

/// Makes every node an MQTT Sparkplug B edge node when `--mqtt URL` or `[mqtt]` asks for
/// it (the URL of `--mqtt` first, the table's other settings either way).
fn start_mqtt(
    runtime: &Runtime,
    url: Option<&str>,
) -> Result<Vec<sparkplug::mqtt::MqttNode>, sparkplug::mqtt::MqttError> {
    let project = runtime.project();
    let settings = match (url, &project.mqtt) {
        (None, None) => return Ok(Vec::new()),
        (url, Some(table)) => sparkplug::mqtt::MqttConfig {
            url: url.map_or_else(|| table.url.clone(), str::to_owned),
            ..table.clone()
        },
        (Some(url), None) => sparkplug::mqtt::MqttConfig {
            url: url.to_owned(),
            ..sparkplug::mqtt::MqttConfig::default()
        },
    };
    let nodes = sparkplug::mqtt::start(runtime, &settings)?;
    let group = settings.group.as_deref().unwrap_or(&project.station.name);
    let primary = settings
        .primary_host
        .as_deref()
        .map(|host| format!(", publishing while primary host `{host}` is online"))
        .unwrap_or_default();
    println!(
        "  MQTT     Sparkplug B to {}: group `{group}`, {} edge node(s){primary}",
        settings.url,
        nodes.len()
    );
    Ok(nodes)
}

/// The project's web HMI folder: screens, points and users.
fn hmi_folder(project: &Path) -> PathBuf {
    project.join("hmi")
}

/// The users file of the project's web HMI (`stanice user --project` edits it).
pub(crate) fn users_file(project: &Path) -> PathBuf {
    hmi_folder(project).join("users.toml")
}

/// Checks the project's web HMI files (hmi.toml, points.csv, the screens, the TLS
/// certificate and key) as the HMI will load them.
fn check_hmi(project: &Path, plan: &HmiPlan) -> anyhow::Result<()> {
    let screens = hmi_folder(project);
    if !screens.join("hmi.toml").is_file() {
        anyhow::bail!("no web HMI to serve: {} has no hmi.toml", screens.display());
    }
    hmi::config::HmiConfig::load(&screens).context("the web HMI does not start")?;
    if let Some(tls) = &plan.tls {
        tls.server_config().context("the web HMI does not start")?;
    }
    Ok(())
}

/// Starts the project's web HMI (`PROJECT/hmi/`) against its top node, when the project
/// has one. It connects from its hmi.toml's `local_address` (127.0.0.2 in the Vsetín
/// project: the TC700's HMI-local mode). Without an HMI to serve, or when it does not start,
/// the station runs on unless the plan requires the HMI (then the error is returned).
async fn start_hmi(
    runtime: &Runtime,
    plan: &HmiPlan,
    archive: Option<String>,
) -> anyhow::Result<Option<hmi::Hmi>> {
    let project = runtime.project();
    let screens = hmi_folder(&project.folder);
    let not_started = |why: String| {
        if plan.required {
            Err(anyhow::anyhow!("the web HMI does not start: {why}"))
        } else {
            println!("  HMI      not started: {why}");
            Ok(None)
        }
    };
    if !screens.join("hmi.toml").is_file() {
        if plan.required {
            anyhow::bail!("no web HMI to serve: {} has no hmi.toml", screens.display());
        }
        println!("  (no web HMI: {} has no hmi.toml)", screens.display());
        return Ok(None);
    }
    let Some((top, server)) = project.top_node().and_then(|config| {
        runtime
            .node(&config.name)
            .and_then(|node| node.server.as_ref())
            .map(|server| (config, server))
    }) else {
        return not_started("the project's top node does not run here (--node)".to_owned());
    };
    let offset = i32::from(project.station.port_base) - 2404;
    let listen = plan.listen.unwrap_or_else(|| {
        std::net::SocketAddr::from(([127, 0, 0, 1], u16::try_from(8080 + offset).unwrap_or(0)))
    });
    let store = if plan.memory_store {
        "sqlite::memory:".to_owned()
    } else {
        format!(
            "sqlite:{}",
            project.folder.join("hmi-events.sqlite").display()
        )
    };
    let mut serve = hmi::ServeConfig::default();
    serve.tls = plan.tls.clone();
    serve.trial = match sorting::hmi_trial::trial_for(&screens, Some(runtime.program_loader())) {
        Ok(trial) => trial,
        Err(error) => return not_started(format!("{error:#}")),
    };
    let scheme = if serve.tls.is_some() { "https" } else { "http" };
    let started = hmi::Hmi::start_with(
        hmi::HmiOptions {
            screens: screens.clone(),
            users: users_file(&project.folder),
            connect: vec![server.local_addr().to_string()],
            common_address: top.common_address,
            listen,
            store: Some(store),
            archive,
            zone: iec60870::time::TimeZonePolicy::Zone(project.station.time_zone),
            // hmi.toml's `local_address`: the project gives its HMI a group by address.
            local_address: None,
        },
        serve,
    )
    .await;
    let hmi = match started {
        Ok(hmi) => hmi,
        Err(error) => return not_started(error.to_string()),
    };
    // The users belong to the project: what its hmi.toml says about signing in.
    let users = hmi::config::HmiConfig::load(&screens)
        .ok()
        .and_then(|config| config.sign_in_note)
        .map(|note| format!(": {note}"))
        .unwrap_or_default();
    println!(
        "  HMI      {scheme}://{}/  (users in {}{users})",
        hmi.address,
        users_file(&project.folder).display()
    );
    Ok(Some(hmi))
}

fn print_banner(runtime: &Runtime, store: &str, speed: f64, demo: bool) {
    let project = runtime.project();
    let title = if demo { "Stanice demo: " } else { "" };
    println!(
        "{title}station {} ({}), {} node(s), simulated clock x{speed}",
        project.station.name,
        project.folder.display(),
        runtime.nodes().len()
    );
    for node in runtime.nodes() {
        let name = node.points.name();
        let config = project.node(name);
        let ca = config
            .map(|c| c.common_address.to_string())
            .unwrap_or_default();
        let server = node
            .server
            .as_ref()
            .map(|s| format!("IEC 104 server {} (CA {ca})", s.local_addr()))
            .unwrap_or_else(|| "no server".to_owned());
        let links: Vec<&str> = node.links.iter().map(|l| l.name()).collect();
        let links = if links.is_empty() {
            String::new()
        } else {
            format!(", links to {}", links.join(", "))
        };
        let s7 = node
            .s7_server
            .as_ref()
            .map(|s7| format!(", S7 server {}", s7.local_addr()))
            .unwrap_or_default();
        println!(
            "  {name:<8} {} points, {server}{s7}{links}",
            node.points.points().len()
        );
    }
    for port in runtime.plant_ports() {
        println!(
            "  {:<8} on the plant's serial port `{}`: pseudo-terminal {}",
            port.device(),
            port.port(),
            port.pty_path()
        );
    }
    println!("  events and command audit: {store}");
    let top = project
        .top_node()
        .and_then(|config| runtime.node(&config.name).map(|node| (config, node)));
    if let Some((config, server)) =
        top.and_then(|(config, node)| node.server.as_ref().map(|s| (config, s)))
    {
        let ca = config.common_address;
        let program = this_program();
        println!("Look at it from another terminal (the dispatch side, CA {ca}):");
        println!(
            "  {program} iec104 client {} --ca {ca} --gi",
            server.local_addr()
        );
        // A command that a client on this machine (dispatch's group) may send, if any.
        if let Some((command, select)) = dispatch_command(config) {
            let select = if select { " --select" } else { "" };
            println!(
                "  {program} iec104 command {} --ca {ca} --ioa {} --type {} --value ON{select}   # {}",
                server.local_addr(),
                command.ioa,
                command.type_id,
                command.name
            );
        }
        println!("  {program} points {}", project.folder.display());
        println!(
            "  {program} events {} --since 10m   (--commands: the command audit, with the reason of a refusal)",
            project.folder.display()
        );
    }
}

/// How to run this program again from the same place: its name or path as it was
/// started (`stanice` from PATH, `./stanice`, `target/release/stanice` under `cargo
/// run`), so that a suggested command works for whoever reads it.
fn this_program() -> String {
    std::env::args()
        .next()
        .filter(|started| !started.is_empty() && !started.contains(char::is_whitespace))
        .unwrap_or_else(|| "stanice".to_owned())
}

/// The first single or double command of `node` that a client on this machine may send
/// (the group that a client at 127.0.0.1 falls in is not excluded by `from_groups`), and
/// whether it must be selected first.
fn dispatch_command(
    node: &station::config::NodeConfig,
) -> Option<(&station::config::CommandConfig, bool)> {
    use iec60870::asdu::TypeId;
    let server = node.server.as_ref()?;
    let group = station::config::RedundancyGroup::of_client(
        &server.redundancy_groups,
        Some(std::net::IpAddr::from([127, 0, 0, 1])),
    )
    .map(|group| group.name.clone())
    .unwrap_or_default();
    node.commands
        .iter()
        .filter(|command| {
            matches!(
                command.type_id,
                TypeId::C_SC_NA_1 | TypeId::C_DC_NA_1 | TypeId::C_SC_TA_1 | TypeId::C_DC_TA_1
            )
        })
        .find(|command| command.from_groups.is_empty() || command.from_groups.contains(&group))
        .map(|command| (command, command.select_required))
}

/// Console words that are neither faults nor hand operations of the plant.
const CONSOLE_HELP: &str = "\
other:           status (nodes, links, breakers, transfer, faults), help";

/// Lines longer than this are wrapped in help and status (a terminal's 100 columns).
const WIDTH: usize = 100;

/// `items` joined by `separator` after `head`, wrapped at [`WIDTH`] with continuation
/// lines indented under the first item.
fn wrapped(head: &str, items: &[String], separator: &str) -> String {
    let indent = " ".repeat(head.chars().count());
    let mut out = head.to_owned();
    let mut line_length = out.chars().count();
    for (i, item) in items.iter().enumerate() {
        let piece = if i + 1 < items.len() {
            format!("{item}{separator}")
        } else {
            item.clone()
        };
        let length = piece.chars().count();
        if i > 0 && line_length + length > WIDTH {
            out.truncate(out.trim_end().len());
            out.push('\n');
            out.push_str(&indent);
            line_length = indent.len();
        }
        out.push_str(&piece);
        line_length += length;
    }
    out
}

/// The console's help: every fault and hand operation of the plant with the device names
/// it takes (from the plant itself), the links of the running nodes, the console's own words.
async fn help_text(runtime: &Runtime) -> String {
    let operations = runtime
        .with_simulation(|sim| sim.plant().map(|plant| plant.console_operations()))
        .await
        .ok()
        .flatten();
    let mut out = Vec::new();
    match operations {
        Some(operations) => {
            for fault in [true, false] {
                out.push(if fault {
                    "faults (each stays until `clear FAULT` or `clear all`):".to_owned()
                } else {
                    "hand operations:".to_owned()
                });
                for operation in operations.iter().filter(|o| o.fault == fault) {
                    out.push(format!("  {}", operation.usage));
                    if let Some(kind) = &operation.names_kind {
                        let placeholder =
                            operation.usage.split_whitespace().nth(1).unwrap_or("NAME");
                        out.push(wrapped(
                            &format!("      {placeholder} ({kind}): "),
                            &operation.names,
                            " ",
                        ));
                    }
                }
            }
            out.push(
                "  NAME, BOARD and MODULE may be shortened to their first or last `_`-separated \
                 words,\n  in any case, when only one device fits."
                    .to_owned(),
            );
        }
        None => out.push(
            "(this project has no plant simulation: no faults or hand operations)".to_owned(),
        ),
    }
    let links: Vec<String> = runtime
        .nodes()
        .iter()
        .flat_map(|node| {
            node.links
                .iter()
                .map(move |link| format!("{}/{}", node.points.name(), link.name()))
        })
        .collect();
    out.push("links:           link-cut NODE/LINK, link-restore NODE/LINK; hmi-link-cut, hmi-link-restore".to_owned());
    let plcs: Vec<String> = runtime
        .project()
        .nodes
        .iter()
        .filter(|node| !node.tasks.is_empty())
        .filter(|node| runtime.node(&node.name).is_some())
        .map(|node| node.name.clone())
        .collect();
    if !plcs.is_empty() {
        out.push(
            "PLCs:            plc-stop NODE (outputs to their safe values), plc-start NODE"
                .to_owned(),
        );
        out.push(wrapped("      NODE: ", &plcs, " "));
    }
    if !links.is_empty() {
        out.push(wrapped("      NODE/LINK: ", &links, " "));
    }
    let lifts: Vec<String> = runtime
        .nodes()
        .iter()
        .flat_map(|node| &node.lifts)
        .filter(|lift| lift.is_simulated())
        .map(|lift| lift.name().to_owned())
        .collect();
    if let (false, Some(board)) = (lifts.is_empty(), simulators::registry::find("ekm66")) {
        out.push("simulated lift boards: lift NAME OPERATION, the operations:".to_owned());
        out.push(board.console_help.to_owned());
        out.push(wrapped("      NAME: ", &lifts, " "));
    }
    let relays: Vec<String> = runtime
        .nodes()
        .iter()
        .flat_map(|node| &node.lines)
        .flat_map(|line| line.simulated_devices())
        .map(str::to_owned)
        .collect();
    if let (false, Some(relay)) = (relays.is_empty(), simulators::registry::find("ref630")) {
        out.push("simulated relays: relay DEVICE OPERATION, the operations:".to_owned());
        out.push(relay.console_help.trim_end().to_owned());
        out.push(wrapped("      DEVICE: ", &relays, " "));
    }
    out.push(CONSOLE_HELP.to_owned());
    out.join("\n")
}

/// Reads operations from standard input until it closes.
async fn console(runtime: &Runtime, hmi: Option<&hmi::Hmi>) {
    let mut lines = crate::console::stdin_lines();
    while let Some(line) = lines.recv().await {
        let line = line.trim();
        match line {
            "" => {}
            "help" => println!("{}", help_text(runtime).await),
            "status" => print_status(runtime).await,
            "hmi-link-cut" | "hmi-link-restore" => match hmi {
                Some(hmi) => {
                    hmi.station.set_link(line == "hmi-link-restore");
                    println!("ok: {line}");
                }
                None => println!("error: no web HMI runs here"),
            },
            // A simulated board's or device's answer (`lift L1 show`) is worth printing.
            _ => match runtime.operate(line).await {
                Ok(answer) if answer.is_empty() => println!("ok: {line}"),
                Ok(answer) => println!("ok: {answer}"),
                Err(error) => println!("error: {error}"),
            },
        }
    }
    // Standard input closed (e.g. run from a script): keep running until stopped.
    std::future::pending::<()>().await;
}

async fn print_status(runtime: &Runtime) {
    let clock = runtime.clock();
    println!(
        "simulated time {} ({} s since start)",
        clock.utc_at(clock.now()).format("%Y-%m-%d %H:%M:%S UTC"),
        clock.now().as_secs()
    );
    for node in runtime.nodes() {
        let invalid = node
            .points
            .points()
            .iter()
            .filter(|p| p.quality.invalid)
            .count();
        let links: Vec<String> = node
            .links
            .iter()
            .map(|l| format!("{} {}", l.name(), if l.is_up() { "up" } else { "DOWN" }))
            .collect();
        let clients = node
            .server
            .as_ref()
            .map(|s| s.stats().connections)
            .unwrap_or(0);
        println!(
            "  {:<8} {invalid} invalid point(s), {clients} client(s), links: {}",
            node.points.name(),
            if links.is_empty() {
                "-".to_owned()
            } else {
                links.join(", ")
            }
        );
        for lift in &node.lifts {
            println!("    {}", lift_status(&node.points, lift.name()));
        }
    }
    print_plant_status(runtime).await;
}

/// One lift's line of `status`: its status text, floor and direction, or the
/// communication alarm, from its points.
fn lift_status(points: &station::runtime::NodePoints, lift: &str) -> String {
    use points::{LiftSignal, PointValue};
    let value = |signal: LiftSignal| {
        points
            .point(signal.point_name(lift).as_str())
            .filter(|point| point.has_value() && !point.quality.invalid)
            .map(|point| point.value)
    };
    let number = |signal: LiftSignal| match value(signal) {
        Some(PointValue::Int(n)) => Some(n),
        _ => None,
    };
    if value(LiftSignal::NotAnswering) == Some(PointValue::Bool(true)) {
        return format!("lift {lift}: NOT ANSWERING");
    }
    let Some(status) = number(LiftSignal::Status).and_then(|code| u8::try_from(code).ok()) else {
        return format!("lift {lift}: no status yet");
    };
    let direction = match number(LiftSignal::Direction) {
        Some(1) => "up",
        Some(2) => "down",
        _ => "stopped",
    };
    format!(
        "lift {lift}: {} ({status}), floor {}, {direction}, {} fault(s) archived, last 0x{:02X}",
        devices::ekm66::tables::status_text(status),
        number(LiftSignal::Position).unwrap_or_default(),
        number(LiftSignal::Faults).unwrap_or_default(),
        number(LiftSignal::LastFault).unwrap_or_default()
    )
}

/// The plant's part of `status`, as the plant reports it.
async fn print_plant_status(runtime: &Runtime) {
    let lines = runtime
        .with_simulation(|sim| sim.plant().map(|plant| plant.status()))
        .await
        .ok()
        .flatten();
    for line in lines.unwrap_or_default() {
        let label = format!("  {:<10} ", format!("{}:", line.label));
        println!("{}", wrapped(&label, &line.items, ", "));
    }
}
