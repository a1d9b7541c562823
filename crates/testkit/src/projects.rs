//! Project folders for tests and benchmarks: the repository's examples, a copy of one to
//! run from a folder of the test's own, a temporary folder of given files, and the lift
//! fleet (one node polling many EKM66 boards) that the station's and the HMI's
//! benchmarks measure.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::repository_root;

/// The example project `examples/NAME` of the repository.
pub fn example(name: &str) -> PathBuf {
    repository_root().join("examples").join(name)
}

/// The Vsetín example project (`examples/vsetin`).
pub fn vsetin() -> PathBuf {
    example("vsetin")
}

/// A copy of the project folder `from` in `parent/name` (replacing what was there),
/// without its event stores (`*.sqlite*`), so that a test runs it from a folder of its
/// own.
pub fn copy_project(from: &Path, parent: &Path, name: &str) -> PathBuf {
    fn copy(from: &Path, to: &Path) {
        std::fs::create_dir_all(to).unwrap();
        for entry in std::fs::read_dir(from).unwrap() {
            let entry = entry.unwrap();
            let file_name = entry.file_name();
            if file_name.to_string_lossy().contains(".sqlite") {
                continue;
            }
            if entry.file_type().unwrap().is_dir() {
                copy(&entry.path(), &to.join(&file_name));
            } else {
                std::fs::copy(entry.path(), to.join(&file_name)).unwrap();
            }
        }
    }
    let project = parent.join(name);
    let _ = std::fs::remove_dir_all(&project);
    copy(from, &project);
    project
}

/// A project folder in a temporary directory with the given files (`station.toml`, ST
/// sources, ...), their folders made as needed.
pub fn folder(files: &[(&str, &str)]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    for (path, text) in files {
        let path = dir.path().join(path);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, text).unwrap();
    }
    dir
}

/// IOAs per lift of a [`LiftFleet`]: the common signals and up to 24 floors' counters.
pub const LIFT_IOA_STRIDE: u32 = 40;

/// How the fleet's node reaches one lift's board.
#[derive(Debug, Clone, Copy)]
pub enum LiftBoard {
    /// A board behind a TCP listener on loopback (an RS-232-to-Ethernet converter).
    Tcp(u16),
    /// A board simulated inside the station (`simulate = "ekm66"`), never faulting by
    /// itself.
    Simulated,
}

/// A station named `fleet` with one node `FLEET` (common address 1, its IEC 104 server on
/// `port_base`) polling a lift `L{i}` per board, archiving to `events.sqlite`: lift `i`
/// has [`LiftFleet::floors`] floors and its points from [`LiftFleet::ioa_base`].
#[derive(Debug, Clone)]
pub struct LiftFleet {
    /// The station's time zone (`UTC`, `Europe/Prague`).
    pub time_zone: String,
    /// The node's IEC 104 server port.
    pub port_base: u16,
    /// The lifts' boards, lift `L{i}` on `boards[i]`.
    pub boards: Vec<LiftBoard>,
}

impl LiftFleet {
    /// The floors of lift `lift`: 3 to 20, varied over the fleet.
    pub fn floors(lift: usize) -> u8 {
        u8::try_from(3 + lift % 18).unwrap()
    }

    /// The first IOA of lift `lift`'s points.
    pub fn ioa_base(lift: usize) -> u32 {
        1 + LIFT_IOA_STRIDE * u32::try_from(lift).unwrap()
    }

    /// The project's `station.toml`.
    pub fn station_toml(&self) -> String {
        let mut toml = format!(
            "[station]\nname = \"fleet\"\ntime_zone = \"{}\"\nstore = \"sqlite:events.sqlite\"\nport_base = {}\n\n[[node]]\nname = \"FLEET\"\ncommon_address = 1\nserver = {{ port_offset = 0 }}\n",
            self.time_zone, self.port_base
        );
        for (lift, board) in self.boards.iter().enumerate() {
            let _ = write!(
                toml,
                "\n[[node.lift]]\nname = \"L{lift}\"\nfloors = {}\nioa_base = {}\n",
                Self::floors(lift),
                Self::ioa_base(lift)
            );
            match board {
                LiftBoard::Tcp(port) => {
                    let _ = writeln!(toml, "tcp = \"127.0.0.1:{port}\"");
                }
                LiftBoard::Simulated => {
                    toml.push_str("simulate = \"ekm66\"\nfault_probability = 0.0\n");
                }
            }
        }
        toml
    }

    /// An HMI's `hmi.toml` titled `title` listing every lift.
    pub fn hmi_toml(&self, title: &str) -> String {
        let mut hmi = format!("title = \"{title}\"\n");
        for lift in 0..self.boards.len() {
            let _ = write!(
                hmi,
                "\n[[lift]]\nname = \"L{lift}\"\ndescription = \"lift {lift}\"\nfloors = {}\n",
                Self::floors(lift)
            );
        }
        hmi
    }

    /// Writes `station.toml` into `dir`.
    pub fn write(&self, dir: &Path) {
        std::fs::write(dir.join("station.toml"), self.station_toml()).unwrap();
    }
}

/// A fresh, empty folder `stanice-NAME-PID` in the temporary directory (what was there
/// removed), for a test that runs a project or writes files from a folder of its own.
pub fn fresh_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("stanice-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}
