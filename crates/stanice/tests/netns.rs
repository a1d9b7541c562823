//! The Vsetín station deployed as one process per node, each node in a network namespace
//! of its own (its own address, three subnets joined by a routing namespace), built by
//! `scripts/netns-station.sh` from `scripts/netns-vsetin.hosts.toml` (docs/DEPLOYMENT.md).
//!
//! A controlling station in the `dispatch` namespace watches RDRT (the top node). Once
//! every point RDRT gets over its link to RH1.1 is valid, RH1.1's process is killed (kill
//! -9): dispatch must see all those points invalid (IV) and RDRT's COMM_RH report the link
//! down. While RH1.1 is down, RH2 (below RH1.1) is operated from its console, so its
//! server buffers the events for its client group. RH1.1 is started again: dispatch must
//! see every point valid again, and RH1.1's event store must hold every event that RH2
//! stored in the outage (same point, value and time): the buffer replayed, nothing lost.
//!
//! Needs root (network namespaces) and `ip` (iproute2). Where namespaces cannot be made,
//! the test says SKIPPED and passes, except with `STANICE_REQUIRE_PEERS=1` (CI), where it
//! fails. It is a test binary of its own: cargo runs test binaries one at a time, so the
//! station's 23 processes do not share the machine with other tests of this crate.
//!
//! ```text
//! cargo test -p stanice --test netns
//! ```

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

use std::collections::{BTreeSet, HashMap};
use std::io::{BufRead as _, BufReader};
use std::process::{Command, Output, Stdio};
use std::sync::mpsc::{channel, Receiver};
use std::time::{Duration, Instant};

use chrono::{DateTime, Utc};
use points::PointSource;
use serde_json::Value;
use station::config::Project;
use testkit::process::Background;
use testkit::repository_root;

const HOSTS: &str = "scripts/netns-vsetin.hosts.toml";
const SCRIPT: &str = "scripts/netns-station.sh";
/// The node killed and restarted, the link of RDRT to it, and the node below it.
const KILLED: &str = "RH1.1";
const TOP_LINK: &str = "RH";
const LOWER: &str = "RH2";
/// What RH2's console is told while RH1.1 is down: each changes some of RH2's points.
const OPERATIONS: [&str; 4] = [
    "selector RH2 local",
    "breaker-tripped RH2_FA1.1",
    "clear breaker-tripped RH2_FA1.1",
    "selector RH2 remote",
];

/// Generous bounds for a busy 2-core machine (23 station processes on it).
const STARTED_WITHIN: Duration = Duration::from_secs(90);
const NOTICED_WITHIN: Duration = Duration::from_secs(30);

/// A deployment made by the script, taken down when dropped (a failed test too).
struct Deployment {
    prefix: String,
    dir: tempfile::TempDir,
}

/// The script with `args`, for the deployment of namespace prefix `prefix` and state
/// folder `dir`.
fn script(prefix: &str, dir: &std::path::Path, args: &[&str]) -> Command {
    let mut command = Command::new("bash");
    command
        .arg(repository_root().join(SCRIPT))
        .args(args)
        .env("STN_PREFIX", prefix)
        .env("STN_DIR", dir)
        .env("STN_PROJECT", repository_root().join("examples/vsetin"))
        .env("STANICE", env!("CARGO_BIN_EXE_stanice"))
        .current_dir(repository_root());
    command
}

impl Deployment {
    fn script(&self, args: &[&str]) -> Command {
        script(&self.prefix, self.dir.path(), args)
    }

    /// Runs the script with `args`; fails the test when it fails.
    fn run(&self, args: &[&str]) -> Output {
        let output = testkit::process::run_bounded(self.script(args), 60);
        assert!(
            output.status.success(),
            "netns-station.sh {args:?} failed:\n{}{}",
            String::from_utf8_lossy(&output.stdout),
            String::from_utf8_lossy(&output.stderr)
        );
        output
    }

    fn address(&self, name: &str) -> String {
        String::from_utf8(self.run(&["address", name]).stdout)
            .unwrap()
            .trim()
            .to_owned()
    }

    fn store(&self, node: &str) -> String {
        format!(
            "sqlite:{}",
            self.dir.path().join(format!("{node}.sqlite")).display()
        )
    }

    fn log(&self, node: &str) -> String {
        std::fs::read_to_string(self.dir.path().join(format!("{node}.log"))).unwrap_or_default()
    }
}

impl Drop for Deployment {
    fn drop(&mut self) {
        let (output, _) = testkit::process::run_within(self.script(&["down"]), 60);
        if !output.status.success() {
            eprintln!(
                "netns-station.sh down: {}",
                String::from_utf8_lossy(&output.stderr)
            );
        }
    }
}

/// Namespaces made from the hosts file, or `None` (SKIPPED) where they cannot be made.
fn deploy() -> Option<Deployment> {
    let prefix = format!("stn{}", std::process::id());
    let dir = tempfile::tempdir().unwrap();
    let (check, _) = testkit::process::run_within(script(&prefix, dir.path(), &["check"]), 30);
    if !check.status.success() {
        testkit::peers::skip_or_fail(&format!(
            "network namespaces cannot be made here ({}); the deployment test needs root and iproute2",
            String::from_utf8_lossy(&check.stderr).trim()
        ));
        return None;
    }
    take_down_stale(dir.path());
    let deployment = Deployment { prefix, dir };
    deployment.run(&["up", HOSTS]);
    Some(deployment)
}

/// Takes down the namespaces of earlier runs of this test that were killed before they
/// could (`stnPID-...` of a process that is gone).
fn take_down_stale(dir: &std::path::Path) {
    let Ok(list) = Command::new("ip").args(["netns", "list"]).output() else {
        return;
    };
    let stale: BTreeSet<String> = String::from_utf8_lossy(&list.stdout)
        .lines()
        .filter_map(|line| line.split_whitespace().next()?.split_once('-'))
        .map(|(prefix, _)| prefix.to_owned())
        .filter(|prefix| {
            prefix
                .strip_prefix("stn")
                .and_then(|pid| pid.parse::<u32>().ok())
                .is_some_and(|pid| !std::path::Path::new(&format!("/proc/{pid}")).exists())
        })
        .collect();
    for prefix in stale {
        testkit::process::run_within(script(&prefix, dir, &["down"]), 60);
    }
}

/// What dispatch knows of RDRT's points, from the JSON lines of `stanice iec104 client`.
struct Dispatch {
    lines: Receiver<String>,
    /// IOA -> (value, invalid).
    points: HashMap<u32, (Value, bool)>,
    _client: Background,
}

impl Dispatch {
    fn connect(deployment: &Deployment, top: &str) -> Dispatch {
        let mut command = deployment.script(&[
            "exec",
            "dispatch",
            env!("CARGO_BIN_EXE_stanice"),
            "iec104",
            "client",
            &format!("{top}:2404"),
            "--ca",
            "1",
            "--gi",
            "--json",
        ]);
        let mut child = command
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let stdout = child.stdout.take().unwrap();
        let (sender, lines) = channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines().map_while(Result::ok) {
                if sender.send(line).is_err() {
                    break;
                }
            }
        });
        Dispatch {
            lines,
            points: HashMap::new(),
            _client: Background(child),
        }
    }

    /// Takes what the client printed until now (waiting at most `wait` for a line).
    fn read(&mut self, wait: Duration) {
        let mut next = self.lines.recv_timeout(wait).ok();
        while let Some(line) = next {
            if let Ok(object) = serde_json::from_str::<Value>(&line) {
                if let Some(ioa) = object["ioa"].as_u64() {
                    let invalid = object["quality"]
                        .as_array()
                        .is_some_and(|flags| flags.iter().any(|f| f == "IV"));
                    self.points
                        .insert(ioa as u32, (object["value"].clone(), invalid));
                }
            }
            next = self.lines.try_recv().ok();
        }
    }

    /// Waits until `condition` holds of what dispatch knows; fails the test after
    /// `within`, saying `what`.
    fn wait_until(
        &mut self,
        within: Duration,
        what: &str,
        condition: impl Fn(&HashMap<u32, (Value, bool)>) -> bool,
    ) {
        let deadline = Instant::now() + within;
        loop {
            self.read(Duration::from_millis(200));
            if condition(&self.points) {
                return;
            }
            assert!(
                Instant::now() < deadline,
                "dispatch never saw {what} within {within:?}"
            );
        }
    }
}

/// The points of `node` fed by its link `link`: IOA and name.
fn fed_by(project: &Project, node: &str, link: &str) -> Vec<(u32, String)> {
    project
        .node(node)
        .unwrap()
        .points
        .iter()
        .filter(|point| matches!(&point.source, PointSource::Link { link: l, .. } if l == link))
        .map(|point| (point.ioa.get(), point.name.clone()))
        .collect()
}

/// One stored value change: point, value, event time (ms since the epoch).
type Event = (String, String, i64);

/// The value changes `node` stored in `store` since `since`, read with `stanice events`.
fn stored_events(store: &str, node: &str, since: DateTime<Utc>) -> Vec<Event> {
    let mut command = Command::new(env!("CARGO_BIN_EXE_stanice"));
    command
        .arg("events")
        .arg(repository_root().join("examples/vsetin"))
        .args([
            "--store", store, "--node", node, "--json", "--limit", "10000",
        ])
        .args(["--since", &since.to_rfc3339()]);
    let output = testkit::process::run_bounded(command, 60);
    if !output.status.success() {
        // The node's recorder makes the store with its first records: none yet.
        return Vec::new();
    }
    String::from_utf8_lossy(&output.stdout)
        .lines()
        .filter_map(|line| serde_json::from_str::<Value>(line).ok())
        .map(|record| {
            let time = DateTime::parse_from_rfc3339(record["time"].as_str().unwrap())
                .unwrap()
                .timestamp_millis();
            (
                record["point"].as_str().unwrap().to_owned(),
                record["value"].as_str().unwrap().to_owned(),
                time,
            )
        })
        .collect()
}

fn wait_for(within: Duration, what: &str, mut condition: impl FnMut() -> bool) {
    let deadline = Instant::now() + within;
    while !condition() {
        assert!(Instant::now() < deadline, "{what} not within {within:?}");
        std::thread::sleep(Duration::from_millis(250));
    }
}

#[test]
fn a_node_killed_in_its_namespace_loses_no_event_and_dispatch_sees_iv_and_recovery() {
    let Some(deployment) = deploy() else {
        return;
    };
    let started = Instant::now();
    let project = Project::load(&repository_root().join("examples/vsetin")).unwrap();
    let top = project.top_node().unwrap().name.clone();
    // What RDRT gets through RH1.1 (RH1.1's own points, and RH2's and RH1.2's it
    // republishes), and the points RH1.1 gets from RH2.
    let through: Vec<u32> = fed_by(&project, &top, TOP_LINK)
        .into_iter()
        .map(|(ioa, _)| ioa)
        .collect();
    // Indications: every change of them is stored at both ends. (A measurement's storage
    // deadband counts from the last value each store kept, which differ after a restart.)
    let killed = project.node(KILLED).unwrap();
    let from_lower: BTreeSet<String> = fed_by(&project, KILLED, LOWER)
        .into_iter()
        .map(|(_, name)| name)
        .filter(|name| {
            let kind = killed.point(name).unwrap().point_type.kind;
            matches!(kind, points::PointKind::Single | points::PointKind::Double)
        })
        .collect();
    assert!(through.len() > 20 && !from_lower.is_empty());
    let link_status = project
        .node(&top)
        .unwrap()
        .point("COMM_RH")
        .unwrap()
        .ioa
        .get();

    deployment.run(&["start-all"]);
    let mut dispatch = Dispatch::connect(&deployment, &deployment.address(&top));
    let all_valid = |points: &HashMap<u32, (Value, bool)>| {
        through
            .iter()
            .all(|ioa| points.get(ioa).is_some_and(|(_, invalid)| !invalid))
            && points.get(&link_status).map(|(value, _)| value) == Some(&Value::Bool(false))
    };
    dispatch.wait_until(
        STARTED_WITHIN,
        "every point RDRT gets through RH1.1 valid",
        all_valid,
    );
    eprintln!(
        "{} nodes up, {} points through {KILLED} valid at dispatch after {:.1} s",
        project.nodes.len(),
        through.len(),
        started.elapsed().as_secs_f64()
    );

    // RH1.1 crashes.
    deployment.run(&["kill", KILLED]);
    dispatch.wait_until(
        NOTICED_WITHIN,
        "every point through RH1.1 invalid (IV) and COMM_RH on",
        |points| {
            through
                .iter()
                .all(|ioa| points.get(ioa).is_some_and(|(_, invalid)| *invalid))
                && points.get(&link_status).map(|(value, _)| value) == Some(&Value::Bool(true))
        },
    );
    // The outage is told by RH2's own records, not by this test's clock: RH2's time is the
    // one RH1.1 synchronised it to (a node's simulated clock starts when its simulation
    // does, a little after the process). Its indications do not change by themselves
    // once started, so what it stored by now is from before the outage.
    let indications = |events: Vec<Event>| -> BTreeSet<Event> {
        events
            .into_iter()
            .filter(|(point, _, _)| from_lower.contains(point))
            .collect()
    };
    let since = Utc::now() - chrono::Duration::hours(1);
    let before = indications(stored_events(&deployment.store(LOWER), LOWER, since));
    let outage_so_far = || -> Vec<Event> {
        indications(stored_events(&deployment.store(LOWER), LOWER, since))
            .difference(&before)
            .cloned()
            .collect()
    };

    // RH2 changes while nobody takes its events.
    for (i, operation) in OPERATIONS.iter().enumerate() {
        deployment.run(&["console", LOWER, operation]);
        let answered = format!("ok: {operation}");
        wait_for(
            NOTICED_WITHIN,
            &format!("RH2's answer to `{operation}`"),
            || deployment.log(LOWER).contains(&answered),
        );
        // Each operation its own moment: the PLC scans between them.
        wait_for(NOTICED_WITHIN, "RH2 storing the operation's events", || {
            outage_so_far().len() > i
        });
    }
    let outage = outage_so_far();
    assert!(
        outage
            .iter()
            .any(|(point, _, _)| point == "RH2_P1_SA1_Mistne"),
        "RH2 stored no change of its selector: {outage:?}"
    );

    // RH1.1 comes back: its link to RH2 replays RH2's buffer, dispatch sees it all.
    deployment.run(&["start", KILLED]);
    dispatch.wait_until(
        STARTED_WITHIN,
        "every point through RH1.1 valid again and COMM_RH off",
        all_valid,
    );
    let missing = |events: &[Event]| -> Vec<Event> {
        let stored: BTreeSet<&Event> = events.iter().collect();
        outage
            .iter()
            .filter(|event| !stored.contains(event))
            .cloned()
            .collect()
    };
    let deadline = Instant::now() + NOTICED_WITHIN;
    loop {
        let at_killed = stored_events(&deployment.store(KILLED), KILLED, since);
        let lost = missing(&at_killed);
        if lost.is_empty() {
            break;
        }
        assert!(
            Instant::now() < deadline,
            "{} of RH2's {} events of the outage never reached RH1.1's store: {lost:?}\nRH1.1 stored: {at_killed:?}\nRH1.1's log:\n{}",
            lost.len(),
            outage.len(),
            deployment.log(KILLED)
        );
        std::thread::sleep(Duration::from_millis(500));
    }
    eprintln!(
        "{KILLED} killed and restarted: dispatch saw IV and recovery, {} events of {LOWER} from the outage all in {KILLED}'s store; {:.1} s in all",
        outage.len(),
        started.elapsed().as_secs_f64()
    );
}

/// The deployment's hosts file fits the project: every node at an address of its own, and
/// RDRT's link to RH1.1 crosses the router (another subnet).
#[test]
fn the_hosts_file_fits_the_project() {
    let root = repository_root();
    let project = Project::load(&root.join("examples/vsetin")).unwrap();
    let hosts = station::config::HostsFile::load(&root.join(HOSTS)).unwrap();
    let deployed = project.clone().with_hosts(&hosts).unwrap();
    let addresses: BTreeSet<_> = deployed
        .nodes
        .iter()
        .map(|node| node.server_address(&deployed.station).unwrap().ip())
        .collect();
    assert_eq!(addresses.len(), project.nodes.len());
    let top = deployed.top_node().unwrap();
    let to_killed = deployed.link_address(top.link(TOP_LINK).unwrap()).unwrap();
    let top_ip = top.server_address(&deployed.station).unwrap().ip();
    let subnet = |ip: std::net::IpAddr| ip.to_string().rsplit_once('.').unwrap().0.to_owned();
    assert_ne!(subnet(to_killed.ip()), subnet(top_ip));
}

/// `stanice run --hosts` with a hosts file that does not fit the project stops before the
/// station starts, with the mistake at its file:line:col.
#[test]
fn run_refuses_a_hosts_file_that_does_not_fit() {
    let folder = tempfile::tempdir().unwrap();
    let file = folder.path().join("hosts.toml");
    std::fs::write(
        &file,
        "[nodes]\nRDRT = \"10.77.0.10\"\nRH9 = \"10.77.0.9\"\n",
    )
    .unwrap();
    let mut command = Command::new(env!("CARGO_BIN_EXE_stanice"));
    command
        .arg("run")
        .arg(repository_root().join("examples/vsetin"))
        .args([
            "--node",
            "RH2",
            "--store",
            "none",
            "--duration",
            "1s",
            "--hosts",
        ])
        .arg(&file);
    let output = testkit::process::run_bounded(command, 60);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success(), "{stderr}");
    let shown = file.display();
    assert!(
        stderr.contains(&format!(
            "{shown}:3:1: error: nodes.RH9: no node `RH9` in the project"
        )),
        "{stderr}"
    );
    assert!(
        stderr.contains(&format!(
            "{shown}:1:2: error: nodes: no address for `RH1.1`, `RH2`, `RH1.2`"
        )),
        "{stderr}"
    );
}
