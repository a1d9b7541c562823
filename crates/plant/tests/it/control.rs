//! Closed loop: the Structured Text programs of the Vsetín example project
//! (`examples/vsetin/plc/*.st`) running in the soft PLC drive the station plant.
//!
//! One PLC per controller, as on site: the LOGO!s of RH2, RZZ and RDA, the S7-1200 of each
//! lighting board ROV01..ROV12 and the OŘ-area S7-1500, and the TC700 in RDRT. Each is
//! built from its own `.st` files and bound to plant signals by a table of (plant signal,
//! PLC variable) pairs. A virtual clock steps everything: per step the plant advances to
//! `t`, its readings are copied into the PLC inputs, every PLC runs one cycle at `t`
//! (Europe/Prague local time from `chrono-tz`), and the PLC outputs are copied to the
//! plant. Nothing reads the wall clock.

use std::time::Duration;

use chrono::{Offset, TimeZone};
use chrono_tz::Europe::Prague;
use plant::{lighting_boards, Action, Direction, Fault, Plant, StationConfig, Value, VsetinPlant};
use plc::task::{ClockReading, TaskConfig};
use plc::Plc;

use crate::{ms, s};

/// The example project's programs.
const PLC_DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/vsetin/plc");

/// How a plant signal and a PLC variable are connected.
#[derive(Debug, Clone)]
enum Bind {
    /// Plant input (contact, relay, measurement) -> PLC variable.
    In(String, String),
    /// PLC variable -> plant output (coil, command).
    Out(String, String),
    /// `TRUE` into the PLC variable while the plant signal's module is unavailable.
    Invalid(String, String),
}

fn input(signal: &str, var: &str) -> Bind {
    Bind::In(signal.to_string(), var.to_string())
}

fn output(var: &str, signal: &str) -> Bind {
    Bind::Out(var.to_string(), signal.to_string())
}

/// One controller: a PLC with its bindings.
struct Node {
    name: String,
    plc: Plc,
    binds: Vec<Bind>,
    /// The value last written per binding. Inputs are written when they change: none of
    /// the programs assigns its bound inputs, so this equals copying them every cycle
    /// (and writing by path is most of a step's cost in a debug build).
    last: Vec<Option<String>>,
}

/// Compiles `files` from the example project into a PLC running `program` every cycle.
fn build_plc(files: &[&str], program: &str, cycle: Duration) -> Plc {
    let sources: Vec<(String, String)> = files
        .iter()
        .map(|f| {
            let path = format!("{PLC_DIR}/{f}");
            let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
            (f.to_string(), text)
        })
        .collect();
    let (map, result) = plc::build(&sources);
    let compiled = result.unwrap_or_else(|d| {
        panic!(
            "{}",
            d.iter()
                .map(|d| d.render(&map))
                .collect::<Vec<_>>()
                .join("\n")
        )
    });
    let warnings: Vec<String> = compiled
        .checked
        .warnings
        .iter()
        .map(|d| d.render(&map))
        .collect();
    assert!(warnings.is_empty(), "{}", warnings.join("\n"));
    let mut plc = Plc::try_new(compiled, map).unwrap();
    plc.add_task(TaskConfig::cyclic(
        "main",
        cycle.as_nanos() as i64,
        &[program],
    ))
    .unwrap();
    plc
}

/// Local time offset of Europe/Prague at a UTC instant (ns).
fn prague_offset_ns(utc_ns: i64) -> i64 {
    let utc = chrono::DateTime::from_timestamp_nanos(utc_ns).naive_utc();
    i64::from(
        Prague
            .offset_from_utc_datetime(&utc)
            .fix()
            .local_minus_utc(),
    ) * 1_000_000_000
}

/// UTC seconds of a local (Europe/Prague) wall-clock time.
fn local(y: i32, mo: u32, d: u32, h: u32, mi: u32, sec: u32) -> i64 {
    Prague
        .with_ymd_and_hms(y, mo, d, h, mi, sec)
        .single()
        .unwrap()
        .timestamp()
}

/// The plant and its controllers on one virtual clock.
struct Station {
    plant: VsetinPlant,
    nodes: Vec<Node>,
    cycle: Duration,
    /// Checked after every step: the RDA contactors are never both closed or both commanded.
    watch_rda: bool,
    /// The controllers have scanned at the current time.
    scanned: bool,
}

impl Station {
    fn new(plant: VsetinPlant, cycle: Duration) -> Self {
        Station {
            plant,
            nodes: Vec::new(),
            cycle,
            watch_rda: false,
            scanned: false,
        }
    }

    /// Adds a controller; checks that every bound signal and variable exists.
    fn add(&mut self, name: &str, files: &[&str], program: &str, binds: Vec<Bind>) {
        let plc = build_plc(files, program, self.cycle);
        for b in &binds {
            let (signal, var) = match b {
                Bind::In(sig, var) | Bind::Out(var, sig) | Bind::Invalid(sig, var) => (sig, var),
            };
            self.plant
                .read(signal)
                .unwrap_or_else(|e| panic!("{name}: {e}"));
            plc.read(var)
                .unwrap_or_else(|e| panic!("{name}: {var}: {e}"));
            if let Bind::Out(_, sig) = b {
                let info = self
                    .plant
                    .signals()
                    .iter()
                    .find(|i| &i.name == sig)
                    .unwrap();
                assert_eq!(info.direction, Direction::Output, "{name}: {sig}");
            }
        }
        self.nodes.push(Node {
            name: name.to_string(),
            plc,
            last: vec![None; binds.len()],
            binds,
        });
    }

    fn node(&self, name: &str) -> &Node {
        self.nodes.iter().find(|n| n.name == name).unwrap()
    }

    fn node_mut(&mut self, name: &str) -> &mut Node {
        self.nodes.iter_mut().find(|n| n.name == name).unwrap()
    }

    /// A PLC variable as an IEC literal.
    fn get(&self, node: &str, path: &str) -> String {
        self.node(node)
            .plc
            .read_text(path)
            .unwrap_or_else(|e| panic!("{node}: {path}: {e}"))
    }

    /// A BOOL PLC variable.
    fn flag(&self, node: &str, path: &str) -> bool {
        match self.get(node, path).as_str() {
            "TRUE" => true,
            "FALSE" => false,
            other => panic!("{node}: {path} is {other}, not a BOOL"),
        }
    }

    /// Writes a PLC variable (as the station runtime does for a command or a parameter).
    fn set(&mut self, node: &str, path: &str, text: &str) {
        self.node_mut(node)
            .plc
            .write(path, text)
            .unwrap_or_else(|e| panic!("{node}: {path}: {e}"));
    }

    /// A digital plant signal.
    fn sig(&self, name: &str) -> bool {
        self.plant.bool(name).unwrap()
    }

    fn now(&self) -> Duration {
        self.plant.now()
    }

    fn utc_ns(&self) -> i64 {
        self.plant.config().start_unix_secs * 1_000_000_000 + self.now().as_nanos() as i64
    }

    /// One step: the scan at the current time (unless done already), then the plant
    /// advances by one cycle.
    fn step(&mut self) {
        if !self.scanned {
            self.scan();
        }
        let next = self.now() + self.cycle;
        self.plant.advance_to(next).unwrap();
        self.scanned = false;
        if self.watch_rda {
            self.check_rda();
        }
    }

    /// Every controller's scan at the current time: plant readings into the PLC inputs,
    /// one PLC cycle, PLC outputs to the plant.
    fn scan(&mut self) {
        self.scanned = true;
        let utc_ns = self.utc_ns();
        let clock = ClockReading {
            monotonic_ns: self.now().as_nanos() as i64,
            utc_ns,
            utc_offset_ns: prague_offset_ns(utc_ns),
        };
        let plant = &mut self.plant;
        for node in &mut self.nodes {
            for (b, last) in node.binds.iter().zip(node.last.iter_mut()) {
                let (var, text) = match b {
                    Bind::In(sig, var) => {
                        let text = match plant.read(sig).unwrap().value {
                            Value::Bool(true) => "TRUE".to_string(),
                            Value::Bool(false) => "FALSE".to_string(),
                            Value::Real(r) => format!("{r:.6}"),
                        };
                        (var, text)
                    }
                    Bind::Invalid(sig, var) => {
                        let invalid = !plant.read(sig).unwrap().valid;
                        (var, if invalid { "TRUE" } else { "FALSE" }.to_string())
                    }
                    Bind::Out(..) => continue,
                };
                if last.as_deref() != Some(text.as_str()) {
                    node.plc.write(var, &text).unwrap();
                    *last = Some(text);
                }
            }
            let faults = node.plc.run_cycle(clock);
            assert!(
                faults.is_empty(),
                "{} faulted at {:?}: {}",
                node.name,
                plant.now(),
                faults
                    .iter()
                    .map(|d| node.plc.render(d))
                    .collect::<Vec<_>>()
                    .join("\n")
            );
            for b in &node.binds {
                if let Bind::Out(var, sig) = b {
                    let on = match node.plc.read(var).unwrap() {
                        plc::vm::Val::Int(x) => x != 0,
                        other => panic!("{var}: {other:?}"),
                    };
                    plant.set_output(sig, Value::Bool(on)).unwrap();
                }
            }
        }
        if self.watch_rda {
            self.check_rda();
        }
    }

    /// Rule 1 of spec §5.3 on the commands and on the contactors, and the safety monitor.
    fn check_rda(&self) {
        let t = self.now();
        assert!(
            !(self.sig("RDA_KM1_Zap") && self.sig("RDA_KM2_Zap")),
            "both RDA coils commanded at {t:?}"
        );
        assert!(
            !(self.sig("RDA_KM1_Zapnut") && self.sig("RDA_KM2_Zapnut")),
            "both RDA contactors closed at {t:?}"
        );
        assert!(!self.plant.sources_joined(), "sources joined at {t:?}");
        assert!(
            self.plant.safety_log().is_empty(),
            "at {t:?}: {:?}",
            self.plant.safety_log()
        );
    }

    /// Steps until the plant time reaches `t`.
    fn run_until(&mut self, t: Duration) {
        while self.now() < t {
            self.step();
        }
    }

    /// Steps for `d`.
    fn run_for(&mut self, d: Duration) {
        let t = self.now() + d;
        self.run_until(t);
    }

    /// Steps until `cond` holds right after a scan, at most until `limit`; the time of
    /// that scan (so a PLC output is dated by the cycle that set it).
    fn run_until_true(
        &mut self,
        limit: Duration,
        mut cond: impl FnMut(&Station) -> bool,
    ) -> Option<Duration> {
        loop {
            if !self.scanned {
                self.scan();
            }
            if cond(self) {
                return Some(self.now());
            }
            if self.now() >= limit {
                return None;
            }
            self.step();
        }
    }

    fn inject(&mut self, f: &str) {
        self.plant.inject(f.parse().unwrap()).unwrap();
    }

    fn clear(&mut self, f: &str) {
        let f: Fault = f.parse().unwrap();
        self.plant.clear(&f).unwrap();
    }

    fn selector(&mut self, board: &str, remote: bool) {
        self.plant
            .operate(Action::SetSelector {
                board: board.to_string(),
                remote,
            })
            .unwrap();
    }
}

// ------------------------------------------------------------------------ the controllers

/// RH2 or RZZ (the LOGO! breaker logic, spec §5.1/§5.2): the same variable names, the
/// signal prefix of the board. For RH2 these are the pairs of examples/vsetin/station.toml.
fn board_binds(b: &str, program: &str) -> Vec<Bind> {
    let v = |x: &str| format!("{program}.{x}");
    let mut binds = vec![
        input(&format!("{b}_V1_FA1_Zapnut"), &v("FA1_Zapnut")),
        input(
            &format!("{b}_P1_KHU1_Napeti_na_privodu"),
            &v("KHU1_NapetiNaPrivodu"),
        ),
        input(
            &format!("{b}_P1_KHU3_Napeti_na_pripojeni"),
            &v("KHU3_NapetiNaPripojeni"),
        ),
        input(&format!("{b}_P1_SA1_Mistne"), &v("SA1_Mistne")),
        input(&format!("{b}_P1_SA1_Dalkove"), &v("SA1_Dalkove")),
        input(
            &format!("{b}_P1_FU1_Pretavena_pojistka"),
            &v("FU1_PretavenaPojistka"),
        ),
        input(
            &format!("{b}_P1_FV1_Prepetova_ochrana"),
            &v("FV1_PrepetovaOchrana"),
        ),
        input(
            &format!("{b}_P1_KHV{b}_Havarijni_vypnuti"),
            &v("HavarijniVyp"),
        ),
        input(
            &format!("{b}_P1_FV110_Prepetova_ochrana"),
            &v("FV110_PrepetovaOchrana"),
        ),
        input(
            &format!("{b}_P1_G110.2_Napeti_zdroje"),
            &v("G110_2_NapetiZdroje"),
        ),
        input(&format!("{b}_QF1_Zapnut"), &v("QF1_Zapnut")),
        output(&v("QF1_OFF"), &format!("{b}_QF1_Vyp")),
        output(&v("QF1_ON"), &format!("{b}_QF1_Zap")),
    ];
    for i in 1..=5 {
        binds.push(input(&format!("{b}_V1_FA1.{i}"), &v(&format!("FA1_{i}"))));
    }
    for i in 0..=2 {
        binds.push(input(
            &format!("{b}_P1_FA110.{i}"),
            &v(&format!("FA110_{i}")),
        ));
    }
    binds
}

/// A LOGO! power board (RH2, RZZ, RH12, RZS2): each its own PLC running `LogoBoard`.
fn add_logo_board(st: &mut Station, board: &str) {
    st.add(
        board,
        &["logo_board.st"],
        "LogoBoard",
        board_binds(board, "LogoBoard"),
    );
}

fn add_rh2(st: &mut Station) {
    add_logo_board(st, "RH2");
}

fn add_rzz(st: &mut Station) {
    add_logo_board(st, "RZZ");
}

fn add_rda(st: &mut Station) {
    let p = |x: &str| format!("RDATransfer.{x}");
    let binds = vec![
        input("RDA_KHU1_Napeti_sit", &p("KHU1_NapetiSit")),
        input("RDA_KHU2_Napeti_DA", &p("KHU2_NapetiDA")),
        input("RDA_KHU3_Napeti_RZS", &p("KHU3_NapetiRZS")),
        input("RDA_KM1_Zapnut", &p("KM1_Zapnut")),
        input("RDA_KM2_Zapnut", &p("KM2_Zapnut")),
        input("RDA_SA1_Mistne", &p("SA1_Mistne")),
        input("RDA_SA1_Dalkove", &p("SA1_Dalkove")),
        input("RDA_KHVRDA_Havarijni_vypnuti", &p("HavarijniVyp")),
        input("RDA_DA_Bezi", &p("DA_Bezi")),
        input("RDA_DA_Pripraven", &p("DA_Pripraven")),
        input("RDA_DA_Porucha", &p("DA_Porucha")),
        input("RDA_FV1_Prepetova_ochrana", &p("FV1_PrepetovaOchrana")),
        input("RDA_FU1_Pretavena_pojistka", &p("FU1_PretavenaPojistka")),
        output(&p("KM1_Zap"), "RDA_KM1_Zap"),
        output(&p("KM2_Zap"), "RDA_KM2_Zap"),
        output(&p("DA_Start"), "RDA_DA_Start"),
    ];
    st.add("RDA", &["rda_transfer.st"], "RDATransfer", binds);
    st.watch_rda = true;
}

/// Staggered switch-on delay of a lighting board: index x 2 s (RS-A8), ROV01 = 2 s ...
/// ROV12 = 24 s, OR = 26 s.
fn stagger(board: &str) -> Duration {
    let i = lighting_boards().iter().position(|b| b == board).unwrap() as u64;
    s(2 * (i + 1))
}

fn add_lighting(st: &mut Station, board: &str) {
    let p = |x: &str| format!("LightingBoard.{x}");
    let binds = vec![
        input(&format!("{board}_Dalkove"), &p("Dalkove")),
        input(&format!("{board}_Cidlo"), &p("Cidlo")),
        input(&format!("{board}_PrRele"), &p("PrRele")),
        input(&format!("{board}_KM1_Zapnut"), &p("KM1_Zapnut")),
        input(&format!("{board}_Rucne_Zap"), &p("Rucne_Zap")),
        input(&format!("{board}_Dvere"), &p("Dvere")),
        input(&format!("{board}_Termostat_Min"), &p("Termostat_Min")),
        input(&format!("{board}_Termostat_Max"), &p("Termostat_Max")),
        input(
            &format!("{board}_FV1_Prepetova_ochrana"),
            &p("FV1_PrepetovaOchrana"),
        ),
        input(
            &format!("{board}_FU1_Pretavena_pojistka"),
            &p("FU1_PretavenaPojistka"),
        ),
        input(&format!("{board}_Napeti"), &p("Napeti")),
        input(&format!("{board}_P_kW"), &p("P_kW")),
        input(&format!("{board}_Energie_kWh"), &p("Energie_kWh")),
        output(&p("OvladanyQ"), &format!("{board}_OvladanyQ")),
    ];
    st.add(
        board,
        &["osvetleni.st", "lighting_board.st"],
        "LightingBoard",
        binds,
    );
    let delay = format!("T#{}ms", stagger(board).as_millis());
    st.set(board, "LightingBoard.Zpozdeni", &delay);
}

fn add_rdrt(st: &mut Station) {
    let p = |x: &str| format!("RDRTIO.{x}");
    let binds = vec![
        input("RDRT_FV230", &p("DI0_FV230")),
        input("RDRT_FV110", &p("DI1_FV110")),
        input("RDRT_FV24", &p("DI2_FV24")),
        input("RDRT_G230_OK", &p("DI3_G230_OK")),
        input("RDRT_G110_OK", &p("DI4_G110_OK")),
        input("RDRT_G24_OK", &p("DI5_G24_OK")),
        input("RDRT_Rezerva_DI6", &p("DI6_Rezerva")),
        input("RDRT_Switch_ABB_OK", &p("DI7_ABB_OK")),
        input("RDRT_Switch_Korenix_Porucha", &p("DI8_Korenix_Porucha")),
        input("RDRT_Switch_Siemens_Porucha", &p("DI9_Siemens_Porucha")),
        input("RDRT_Dvere_NN", &p("P6_Dvere_NN")),
        input("RDRT_Dvere_VN", &p("P6_Dvere_VN")),
        input("RDRT_Dvere_T1", &p("P6_Dvere_T1")),
        input("RDRT_Dvere_T2", &p("P6_Dvere_T2")),
        Bind::Invalid("RDRT_Dvere_NN".into(), p("PoruchaModul6")),
        Bind::Invalid("RDRT_FV230".into(), p("PoruchaModul9")),
    ];
    st.add("RDRT", &["rdrt_io.st"], "RDRTIO", binds);
}

// ------------------------------------------------------------------------ RDA transfer

const RDA: &str = "RDA";

fn rda_station(cycle: Duration) -> Station {
    let mut st = Station::new(VsetinPlant::new(), cycle);
    add_rda(&mut st);
    st
}

fn rda_state(st: &Station) -> String {
    st.get(RDA, "RDATransfer.Stav")
}

#[test]
fn rda_steady_state_on_mains() {
    let mut st = rda_station(ms(10));
    st.run_for(s(5));
    assert!(st.sig("RDA_KM1_Zapnut"));
    assert!(!st.sig("RDA_KM2_Zapnut"));
    assert!(!st.sig("RDA_DA_Start"));
    assert!(!st.sig("RDA_DA_Bezi"));
    assert!(st.plant.bus_live("RZS").unwrap());
    assert_eq!(rda_state(&st), "1");
    assert!(st.flag(RDA, "RDATransfer.NaSiti"));
    assert!(!st.flag(RDA, "RDATransfer.NaDA"));
    assert!(!st.flag(RDA, "RDATransfer.Porucha"));
    assert_eq!(st.plant.source_violations(), 0);
}

#[test]
fn rda_mains_loss_transfers_to_diesel_and_back() {
    let mut st = rda_station(ms(10));
    st.run_until(s(60));
    let t_loss = st.now();
    st.inject("supply-loss UTILITY");

    // Confirmation delay T_Ztrata = 1 s after the relay KHU1 dropped (20 ms).
    let t_km1_cmd_off = st
        .run_until_true(s(70), |st| !st.sig("RDA_KM1_Zap"))
        .unwrap();
    assert_eq!(
        t_km1_cmd_off,
        t_loss + ms(1_020),
        "KHU1 20 ms + T_Ztrata 1 s"
    );
    assert!(st.sig("RDA_DA_Start"), "generator started with KM1 opening");
    assert_eq!(rda_state(&st), "2");
    let t_km1_open = st
        .run_until_true(s(70), |st| !st.sig("RDA_KM1_Zapnut"))
        .unwrap();
    assert!(t_km1_open <= t_km1_cmd_off + ms(30));

    // Generator: cranking 5 s, 90 % voltage 1 s later (KHU2 after 20 ms), settled ("ready")
    // 6 s after cranking. KM2 only after ready and 10 s of voltage (T_Ustaleni).
    let t_khu2 = st
        .run_until_true(s(90), |st| st.sig("RDA_KHU2_Napeti_DA"))
        .unwrap();
    assert!(!st.sig("RDA_KM2_Zap"));
    let t_ready = st
        .run_until_true(s(90), |st| st.sig("RDA_DA_Pripraven"))
        .unwrap();
    assert!(!st.sig("RDA_KM2_Zap"), "KM2 commanded before ready");
    let t_km2_cmd = st
        .run_until_true(s(100), |st| st.sig("RDA_KM2_Zap"))
        .unwrap();
    assert!(
        t_km2_cmd > t_ready,
        "KM2 {t_km2_cmd:?} before ready {t_ready:?}"
    );
    assert!(
        t_km2_cmd >= t_khu2 + s(10) && t_km2_cmd <= t_khu2 + s(10) + ms(20),
        "KM2 at {t_km2_cmd:?}, KHU2 at {t_khu2:?}"
    );
    assert_eq!(
        t_ready,
        ms(72_020),
        "start 61.02 + cranking 5 s + settle 6 s"
    );
    assert_eq!(
        t_km2_cmd,
        ms(77_040),
        "start 61.02 + KHU2 6.02 s + T_Ustaleni 10 s"
    );
    let t_km2 = st
        .run_until_true(s(100), |st| st.sig("RDA_KM2_Zapnut"))
        .unwrap();
    assert!(t_km2 <= t_km2_cmd + ms(40));
    st.run_for(ms(100));
    assert!(st.plant.bus_live("RZS").unwrap(), "RZS live again");
    assert_eq!(st.plant.real("RZS1_U").unwrap(), 400.0);
    assert_eq!(rda_state(&st), "4");
    assert!(st.flag(RDA, "RDATransfer.NaDA"));
    assert!(!st.flag(RDA, "RDATransfer.Porucha"));

    // Mains back: 60 s of stable mains (T_Navrat), KM2 opens, then KM1 closes, then the
    // generator is released and cools down by itself.
    st.run_until(s(200));
    let t_back = st.now();
    st.clear("supply-loss UTILITY");
    let t_km2_off = st
        .run_until_true(s(400), |st| !st.sig("RDA_KM2_Zap"))
        .unwrap();
    assert!(
        t_km2_off >= t_back + s(60) && t_km2_off <= t_back + s(60) + ms(40),
        "{t_km2_off:?}"
    );
    let t_km2_open = st
        .run_until_true(s(400), |st| !st.sig("RDA_KM2_Zapnut"))
        .unwrap();
    let t_km1_cmd = st
        .run_until_true(s(400), |st| st.sig("RDA_KM1_Zap"))
        .unwrap();
    assert!(
        t_km1_cmd >= t_km2_open,
        "KM1 commanded before KM2 seen open"
    );
    assert!(st.sig("RDA_DA_Start"), "generator kept until KM1 is closed");
    let t_km1 = st
        .run_until_true(s(400), |st| st.sig("RDA_KM1_Zapnut"))
        .unwrap();
    let t_stop = st
        .run_until_true(s(400), |st| !st.sig("RDA_DA_Start"))
        .unwrap();
    assert!(
        t_stop >= t_km1 && t_stop <= t_km1 + ms(20),
        "stop at {t_stop:?}"
    );
    assert_eq!(rda_state(&st), "1");
    st.run_until(t_stop + s(59));
    assert!(st.sig("RDA_DA_Bezi"), "cooling down unloaded");
    st.run_until(t_stop + s(61));
    assert!(!st.sig("RDA_DA_Bezi"), "stopped after the cool-down");
    assert!(st.plant.bus_live("RZS").unwrap());
    assert!(st.flag(RDA, "RDATransfer.NaSiti"));
    assert_eq!(st.plant.source_violations(), 0);
    assert!(st.plant.safety_log().is_empty());
}

#[test]
fn rda_generator_fail_to_start_reports_a_fault_and_never_closes_km2() {
    let mut st = rda_station(ms(10));
    st.run_until(s(5));
    st.inject("generator-fail-to-start");
    st.inject("supply-loss UTILITY");
    let mut km2_ever = false;
    while st.now() < s(65) {
        st.step();
        km2_ever |= st.sig("RDA_KM2_Zap") || st.sig("RDA_KM2_Zapnut");
    }
    assert!(!km2_ever, "KM2 closed without a generator");
    assert!(st.sig("RDA_DA_Porucha"));
    assert!(st.flag(RDA, "RDATransfer.Porucha_DA"));
    assert!(st.flag(RDA, "RDATransfer.Porucha"));
    assert!(st.flag(RDA, "RDATransfer.BezNapeti"));
    assert!(!st.plant.bus_live("RZS").unwrap());
    assert_eq!(rda_state(&st), "2");

    // The mains comes back while nothing is fed: taken after T_Ztrata, not T_Navrat.
    st.clear("supply-loss UTILITY");
    let t_back = st.now();
    let t_km1 = st
        .run_until_true(s(80), |st| st.sig("RDA_KM1_Zapnut"))
        .unwrap();
    assert!(t_km1 <= t_back + s(2), "{t_km1:?}");
    assert!(!st.sig("RDA_DA_Start"));
    assert!(st.plant.bus_live("RZS").unwrap());

    // The fault clears while the mains is lost again: the held start goes through.
    st.inject("supply-loss UTILITY");
    st.run_for(s(10));
    st.clear("generator-fail-to-start");
    let t_ok = st.now();
    let t_km2 = st
        .run_until_true(t_ok + s(60), |st| st.sig("RDA_KM2_Zapnut"))
        .unwrap();
    assert!(t_km2 >= t_ok + s(16), "{t_km2:?}");
    assert!(!st.flag(RDA, "RDATransfer.Porucha"));
    assert_eq!(st.plant.source_violations(), 0);
}

#[test]
fn rda_start_supervision_without_a_fault_contact() {
    // A generator that cranks for 40 s without reporting a fault: T_StartDA (30 s) does.
    let mut cfg = StationConfig::default();
    cfg.generator.start_delay = s(40);
    let mut st = Station::new(VsetinPlant::with_config(cfg), ms(10));
    add_rda(&mut st);
    st.run_until(s(1));
    st.inject("supply-loss UTILITY");
    let t_fault = st
        .run_until_true(s(60), |st| st.flag(RDA, "RDATransfer.Porucha_DA"))
        .unwrap();
    // start at 2.02 s (1 s + 20 ms relay + 1 s), fault 30 s later
    assert_eq!(t_fault, ms(32_020));
    assert!(!st.sig("RDA_DA_Porucha"));
    // It eventually starts: the fault clears once it is ready.
    st.run_until_true(s(120), |st| st.sig("RDA_KM2_Zapnut"))
        .unwrap();
    assert!(!st.flag(RDA, "RDATransfer.Porucha_DA"));
}

#[test]
fn rda_welded_km1_keeps_km2_open() {
    let mut st = rda_station(ms(10));
    st.run_until(s(5));
    st.inject("stuck-closed RDA_KM1");
    st.inject("supply-loss UTILITY");
    let mut km2_ever = false;
    while st.now() < s(60) {
        st.step();
        km2_ever |= st.sig("RDA_KM2_Zap") || st.sig("RDA_KM2_Zapnut");
    }
    assert!(!km2_ever, "KM2 closed while KM1's contact shows it closed");
    assert!(
        st.sig("RDA_DA_Pripraven"),
        "the generator is ready all the same"
    );
    assert_eq!(rda_state(&st), "3");
    assert!(st.flag(RDA, "RDATransfer.Porucha_KM1"));
    assert!(st.flag(RDA, "RDATransfer.Porucha"));
    // The mains returns onto the welded contactor: nothing was paralleled.
    st.clear("supply-loss UTILITY");
    st.run_for(s(5));
    assert!(st.plant.bus_live("RZS").unwrap());
    assert_eq!(st.plant.source_violations(), 0);

    // The same with KM2 welded while on the generator: KM1 never closes on the return.
    let mut st = rda_station(ms(10));
    st.run_until(s(5));
    st.inject("supply-loss UTILITY");
    st.run_until_true(s(60), |st| st.sig("RDA_KM2_Zapnut"))
        .unwrap();
    st.inject("stuck-closed RDA_KM2");
    st.clear("supply-loss UTILITY");
    let mut km1_ever = false;
    while st.now() < s(150) {
        st.step();
        km1_ever |= st.sig("RDA_KM1_Zap") || st.sig("RDA_KM1_Zapnut");
    }
    assert!(!km1_ever);
    assert!(st.flag(RDA, "RDATransfer.Porucha_KM2"));
    assert!(st.sig("RDA_DA_Start"), "the generator keeps feeding RZS");
    assert!(st.plant.bus_live("RZS").unwrap());
    assert_eq!(st.plant.source_violations(), 0);
}

#[test]
fn rda_emergency_off_opens_both_and_restarts_when_released() {
    let mut st = rda_station(ms(10));
    st.run_until(s(2));
    st.inject("supply-loss UTILITY");
    st.run_until_true(s(60), |st| st.sig("RDA_KM2_Zapnut"))
        .unwrap();
    st.inject("emergency-off RDA");
    st.run_for(ms(100));
    assert_eq!(rda_state(&st), "9");
    assert!(!st.sig("RDA_KM1_Zap") && !st.sig("RDA_KM2_Zap"));
    assert!(!st.sig("RDA_KM1_Zapnut") && !st.sig("RDA_KM2_Zapnut"));
    assert!(!st.sig("RDA_DA_Start"));
    assert!(!st.plant.bus_live("RZS").unwrap());
    st.run_for(s(10));
    assert!(!st.sig("RDA_KM1_Zapnut") && !st.sig("RDA_KM2_Zapnut"));
    // Released with the mains back: the sequence restarts and takes the mains at once.
    st.clear("supply-loss UTILITY");
    st.run_for(s(1));
    st.clear("emergency-off RDA");
    st.run_for(ms(200));
    assert_eq!(rda_state(&st), "1");
    assert!(st.sig("RDA_KM1_Zapnut"));
    assert_eq!(st.plant.source_violations(), 0);
}

#[test]
fn rda_remote_generator_run_only_in_remote() {
    let mut st = rda_station(ms(10));
    // Past T_Navrat, so the mains counts as stable when the request is withdrawn.
    st.run_until(s(61));
    // Local: the remote request does nothing.
    st.selector(RDA, false);
    st.set(RDA, "RDATransfer.Cmd_ProvozDA", "TRUE");
    st.run_for(s(30));
    assert_eq!(rda_state(&st), "1");
    assert!(!st.sig("RDA_DA_Start"));
    // Remote: transfer with the mains healthy, no confirmation delay, settle as usual.
    st.selector(RDA, true);
    let t0 = st.now();
    let t_start = st
        .run_until_true(s(120), |st| st.sig("RDA_DA_Start"))
        .unwrap();
    assert!(t_start <= t0 + ms(20));
    st.run_until_true(s(120), |st| st.sig("RDA_KM2_Zapnut"))
        .unwrap();
    st.run_for(ms(100));
    assert!(st.flag(RDA, "RDATransfer.NaDA"), "fed from the generator");
    assert!(!st.flag(RDA, "RDATransfer.NaSiti"));
    // Request withdrawn: the mains has been stable for long, so the load goes back.
    st.set(RDA, "RDATransfer.Cmd_ProvozDA", "FALSE");
    let t1 = st.now();
    let t_km1 = st
        .run_until_true(s(200), |st| st.sig("RDA_KM1_Zapnut"))
        .unwrap();
    assert!(t_km1 <= t1 + ms(100), "{t_km1:?}");
    assert_eq!(st.plant.source_violations(), 0);
}

/// A small deterministic generator (xorshift64*), so the sequence is fixed by the seed.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    /// A duration between `lo` and `hi` in 10 ms steps.
    fn between(&mut self, lo: Duration, hi: Duration) -> Duration {
        let steps = (hi - lo).as_millis() as u64 / 10;
        lo + ms(10 * (self.next() % (steps + 1)))
    }
}

#[test]
fn rda_random_loss_and_restore_never_joins_sources() {
    let mut st = rda_station(ms(50));
    let mut rng = Rng(0x5653_4554_494e_2024);
    st.run_until(s(2));
    let mut on_da = 0;
    for _ in 0..50 {
        // Losses from a flicker (shorter than T_Ztrata) to a long outage, returns from a
        // blip to well past T_Navrat; now and then a generator that will not start.
        let fail = rng.next() % 8 == 0;
        if fail {
            st.inject("generator-fail-to-start");
        }
        st.inject("supply-loss UTILITY");
        let d = rng.between(ms(50), s(40));
        st.run_for(d);
        on_da += usize::from(st.sig("RDA_KM2_Zapnut"));
        if fail {
            st.clear("generator-fail-to-start");
        }
        st.clear("supply-loss UTILITY");
        let d = rng.between(ms(50), s(90));
        st.run_for(d);
    }
    assert!(
        on_da >= 5,
        "the sequence should reach the generator sometimes: {on_da}"
    );
    // Finally back on the mains with the generator stopped.
    st.run_for(s(200));
    assert_eq!(rda_state(&st), "1");
    assert!(st.sig("RDA_KM1_Zapnut"));
    assert!(!st.sig("RDA_DA_Bezi"));
    assert_eq!(st.plant.source_violations(), 0);
    assert!(st.plant.safety_log().is_empty());
}

// ------------------------------------------------------------------------ RH2 and RZZ

/// Holds a command for 200 ms, then releases it (the runtime writes the state of a single
/// command; the breaker closes on the close coil's rising edge).
fn pulse(st: &mut Station, node: &str, cmd: &str) {
    st.set(node, cmd, "TRUE");
    st.run_for(ms(200));
    st.set(node, cmd, "FALSE");
    st.run_for(ms(100));
}

#[test]
fn rh2_and_rzz_remote_commands_operate_qf1_only_in_remote() {
    for (board, program) in [("RH2", "LogoBoard"), ("RZZ", "LogoBoard")] {
        let mut st = Station::new(VsetinPlant::new(), ms(10));
        add_rh2(&mut st);
        add_rzz(&mut st);
        let qf1 = format!("{board}_QF1_Zapnut");
        let bus = format!("{board}_P1_KHU3_Napeti_na_pripojeni");
        let off = format!("{program}.Cmd_VypnoutQF1");
        let on = format!("{program}.Cmd_ZapnoutQF1");
        st.run_for(s(1));
        assert!(st.sig(&qf1));

        pulse(&mut st, board, &off);
        assert!(!st.sig(&qf1), "{board}: remote open");
        assert!(!st.sig(&bus), "{board}: busbar dead");
        pulse(&mut st, board, &on);
        assert!(st.sig(&qf1), "{board}: remote close");
        assert!(st.sig(&bus));

        // Local: remote commands do nothing, the door pushbuttons work.
        st.selector(board, false);
        pulse(&mut st, board, &off);
        assert!(st.sig(&qf1), "{board}: open ignored in local");
        st.plant
            .operate(Action::Open(format!("{board}_QF1")))
            .unwrap();
        st.run_for(ms(100));
        assert!(!st.sig(&qf1));
        pulse(&mut st, board, &on);
        assert!(!st.sig(&qf1), "{board}: close ignored in local");
        st.selector(board, true);
        pulse(&mut st, board, &on);
        assert!(st.sig(&qf1));
        // The other board was never touched.
        let other = if board == "RH2" { "RZZ" } else { "RH2" };
        assert!(st.sig(&format!("{other}_QF1_Zapnut")));
        assert!(
            st.plant.safety_log().is_empty(),
            "{:?}",
            st.plant.safety_log()
        );
    }
}

#[test]
fn rh2_and_rzz_emergency_off_trips_through_the_logo() {
    // Without the hard-wired release, only the LOGO! program opens the feeder.
    let mut cfg = StationConfig::default();
    cfg.estop_trips_feeder = false;
    for (board, program) in [("RH2", "LogoBoard"), ("RZZ", "LogoBoard")] {
        let mut st = Station::new(VsetinPlant::with_config(cfg.clone()), ms(10));
        add_rh2(&mut st);
        add_rzz(&mut st);
        let qf1 = format!("{board}_QF1_Zapnut");
        st.run_for(s(1));
        st.selector(board, false);
        st.inject(&format!("emergency-off {board}"));
        st.run_for(ms(100));
        assert!(st.flag(board, &format!("{program}.QF1_OFF")));
        assert!(!st.sig(&qf1), "{board}: tripped in local too");
        // A close command while the button is latched does nothing, nor any coil pair.
        st.selector(board, true);
        pulse(&mut st, board, &format!("{program}.Cmd_ZapnoutQF1"));
        assert!(!st.sig(&qf1));
        st.clear(&format!("emergency-off {board}"));
        st.run_for(ms(50));
        pulse(&mut st, board, &format!("{program}.Cmd_ZapnoutQF1"));
        assert!(st.sig(&qf1), "{board}: closes after the release");
        assert!(
            st.plant.safety_log().is_empty(),
            "{:?}",
            st.plant.safety_log()
        );
    }
}

// ------------------------------------------------------------------------ lighting

/// A station whose simulated time zero is the given local time, with the given lighting
/// boards in astronomical mode.
fn lighting_station(start_utc_secs: i64, boards: &[&str], cycle: Duration) -> Station {
    let mut cfg = StationConfig::default();
    cfg.start_unix_secs = start_utc_secs;
    let mut st = Station::new(VsetinPlant::with_config(cfg), cycle);
    for b in boards {
        add_lighting(&mut st, b);
        st.set(b, "LightingBoard.Vstupy.W_Astral", "TRUE");
    }
    st
}

/// Simulated time of a local wall-clock instant.
fn sim_at(st: &Station, utc_secs: i64) -> Duration {
    s((utc_secs - st.plant.config().start_unix_secs) as u64)
}

#[test]
fn lighting_board_switches_on_at_the_table_sunset_plus_its_delay() {
    // Winter: 2024-01-03 is week 0 of the table, sunset 15:20 UTC = 16:20 CET.
    let start = local(2024, 1, 3, 16, 19, 0);
    let mut st = lighting_station(start, &["ROV03"], ms(50));
    st.run_for(s(1));
    assert_eq!(
        st.get("ROV03", "LightingBoard.Osvetleni.TODSunset"),
        "TOD#16:20:00"
    );
    assert!(!st.flag("ROV03", "LightingBoard.Vystupy.Osv_Zap"));
    let sunset = sim_at(&st, local(2024, 1, 3, 16, 20, 0));
    let t_astral = st
        .run_until_true(s(300), |st| {
            st.flag("ROV03", "LightingBoard.Vystupy.Zap_Astral")
        })
        .unwrap();
    assert_eq!(t_astral, sunset, "the table's sunset, local time");
    let t_on = st
        .run_until_true(s(300), |st| st.sig("ROV03_OvladanyQ"))
        .unwrap();
    let expected = sunset + stagger("ROV03");
    assert_eq!(stagger("ROV03"), s(6));
    assert_eq!(t_on, expected, "sunset + the staggered delay");
    let t_km1 = st
        .run_until_true(s(300), |st| st.sig("ROV03_KM1_Zapnut"))
        .unwrap();
    assert!(t_km1 <= t_on + ms(50));
    st.run_for(s(5));
    assert!(st.sig("ROV03_PrRele"));
    assert_eq!(st.plant.real("ROV03_Svit_pct").unwrap(), 100.0);
    assert!(!st.flag("ROV03", "LightingBoard.Vystupy.Osv_Por"));
    assert!(!st.flag("ROV03", "LightingBoard.Porucha_KM1"));
    assert!(!st.flag("ROV03", "LightingBoard.Vystupy.Zap_Z_Rozvadece"));
}

#[test]
fn lighting_summer_sunset_is_in_local_summer_time() {
    // 2024-07-15 is week 28: table sunset 18:00 UTC = 20:00 CEST (offset from chrono-tz).
    let start = local(2024, 7, 15, 19, 59, 30);
    let mut st = lighting_station(start, &["OR"], ms(50));
    st.run_for(s(1));
    assert_eq!(st.get("OR", "LightingBoard.Osvetleni.TimeZone"), "2");
    assert_eq!(
        st.get("OR", "LightingBoard.Osvetleni.TODSunset"),
        "TOD#20:00:00"
    );
    let t_on = st
        .run_until_true(s(120), |st| st.sig("OR_OvladanyQ"))
        .unwrap();
    let expected = sim_at(&st, local(2024, 7, 15, 20, 0, 0)) + stagger("OR");
    assert_eq!(t_on, expected);
}

#[test]
fn lighting_boards_stagger_their_switch_on() {
    let start = local(2024, 1, 3, 16, 19, 55);
    let boards = lighting_boards();
    let names: Vec<&str> = boards.iter().map(String::as_str).collect();
    let mut st = lighting_station(start, &names, ms(50));
    let sunset = sim_at(&st, local(2024, 1, 3, 16, 20, 0));
    let mut on: Vec<Option<Duration>> = vec![None; names.len()];
    while st.now() < sunset + s(30) {
        st.step();
        for (i, b) in names.iter().enumerate() {
            if on[i].is_none() && st.sig(&format!("{b}_KM1_Zapnut")) {
                on[i] = Some(st.now());
            }
        }
    }
    for (i, b) in names.iter().enumerate() {
        let t = on[i].unwrap_or_else(|| panic!("{b} never switched on"));
        let expected = sunset + stagger(b);
        // command in the first cycle after the delay, contactor 30 ms later
        assert!(
            t > expected && t <= expected + ms(100),
            "{b}: {t:?} vs {expected:?}"
        );
        if i > 0 {
            assert!(t > on[i - 1].unwrap(), "{b} after its predecessor");
        }
    }
}

#[test]
fn lighting_lamp_failure_sets_osv_por_after_the_fault_delay() {
    let start = local(2024, 1, 3, 18, 0, 0);
    let mut st = lighting_station(start, &["ROV05"], ms(50));
    st.run_for(s(15));
    assert!(st.sig("ROV05_PrRele"));
    let t_fail = st.now();
    st.inject("lamp-failure ROV05");
    let t_por = st
        .run_until_true(s(60), |st| {
            st.flag("ROV05", "LightingBoard.Vystupy.Osv_Por")
        })
        .unwrap();
    // Osv_PorTON 5 s: the PLC sees PrRele drop in its next cycle.
    assert!(
        t_por >= t_fail + s(5) && t_por <= t_fail + s(5) + ms(100),
        "{t_por:?}"
    );
    assert!(st.sig("ROV05_OvladanyQ"), "the command stays on");
    assert!(
        !st.flag("ROV05", "LightingBoard.Porucha_KM1"),
        "the contactor is fine"
    );
    st.clear("lamp-failure ROV05");
    st.run_for(ms(200));
    assert!(!st.flag("ROV05", "LightingBoard.Vystupy.Osv_Por"));

    // A contactor that does not pull in: Osv_Por and the contactor supervision.
    st.inject("stuck-open ROV05_KM1");
    st.run_for(s(6));
    assert!(st.flag("ROV05", "LightingBoard.Vystupy.Osv_Por"));
    assert!(st.flag("ROV05", "LightingBoard.Porucha_KM1"));
}

#[test]
fn lighting_manual_mode_and_local_control() {
    // Noon: the astronomical mode keeps the lights off.
    let start = local(2024, 1, 3, 12, 0, 0);
    let mut st = lighting_station(start, &["ROV12"], ms(50));
    st.run_for(s(1));
    assert!(!st.sig("ROV12_OvladanyQ"));
    st.set("ROV12", "LightingBoard.Vstupy.W_Rucne", "TRUE");
    st.set("ROV12", "LightingBoard.Vstupy.W_ZapRucne", "TRUE");
    let t0 = st.now();
    let t_on = st
        .run_until_true(s(10), |st| st.sig("ROV12_KM1_Zapnut"))
        .unwrap();
    // No staggering delay (24 s for ROV12) in manual mode.
    assert!(t_on <= t0 + ms(100), "{t_on:?}");
    assert!(st.flag("ROV12", "LightingBoard.Vystupy.Zap_Rucne"));
    assert!(st.flag("ROV12", "LightingBoard.Vystupy.Osv_Rucne"));
    st.set("ROV12", "LightingBoard.Vstupy.W_ZapRucne", "FALSE");
    st.run_for(ms(100));
    assert!(!st.sig("ROV12_KM1_Zapnut"));
    // Leaving manual mode discards a pending manual-on request (spec 4.3 step 3).
    st.set("ROV12", "LightingBoard.Vstupy.W_ZapRucne", "TRUE");
    st.set("ROV12", "LightingBoard.Vstupy.W_Rucne", "FALSE");
    st.run_for(ms(100));
    assert!(!st.sig("ROV12_OvladanyQ"));
    assert!(!st.flag("ROV12", "LightingBoard.Vstupy.W_ZapRucne"));

    // Local control (the cabinet's remote-enable switch off): remote requests are not
    // adopted, the block reports local control and keeps its last settings.
    st.selector("ROV12", false);
    st.set("ROV12", "LightingBoard.Vstupy.W_Rucne", "TRUE");
    st.set("ROV12", "LightingBoard.Vstupy.W_ZapRucne", "TRUE");
    st.run_for(ms(200));
    assert!(st.flag("ROV12", "LightingBoard.Vystupy.Zap_Z_Rozvadece"));
    assert!(!st.flag("ROV12", "LightingBoard.Vystupy.Osv_Rucne"));
    assert!(!st.sig("ROV12_OvladanyQ"));
    // The hard-wired 0/1 switch lights the tower without the PLC.
    st.plant
        .operate(Action::SetManualSwitch {
            board: "ROV12".into(),
            on: true,
        })
        .unwrap();
    st.run_for(ms(200));
    assert!(st.sig("ROV12_PrRele"));
    assert!(st.flag("ROV12", "LightingBoard.Rucne_Zap"));
    assert!(!st.flag("ROV12", "LightingBoard.Porucha_KM1"));
}

// ------------------------------------------------------------------------ RDRT

#[test]
fn rdrt_inputs_map_to_single_points_with_the_spec_polarity() {
    let mut st = Station::new(VsetinPlant::new(), ms(50));
    add_rdrt(&mut st);
    let points = [
        "SP1_FV230",
        "SP2_FV110",
        "SP3_FV24",
        "SP4_G230",
        "SP5_G110",
        "SP6_G24",
        "SP7_Rezerva",
        "SP8_Korenix",
        "SP9_ABB",
        "SP10_Siemens",
        "SP24_PoruchaModul6",
        "SP25_PoruchaModul9",
        "SP26_Dvere_NN",
        "SP27_Dvere_VN",
        "SP28_Dvere_T1",
        "SP29_Dvere_T2",
    ];
    let active = |st: &Station| -> Vec<&str> {
        points
            .iter()
            .copied()
            .filter(|p| st.flag("RDRT", &format!("RDRTIO.{p}")))
            .collect()
    };
    st.run_for(ms(100));
    // Healthy station: the supply-healthy contacts are closed, every point reads FALSE.
    assert!(st.sig("RDRT_G230_OK") && st.sig("RDRT_Switch_ABB_OK"));
    assert_eq!(active(&st), Vec::<&str>::new());
    let cases = [
        ("surge-arrester RDRT_FV230", "SP1_FV230"),
        ("surge-arrester RDRT_FV110", "SP2_FV110"),
        ("surge-arrester RDRT_FV24", "SP3_FV24"),
        ("supply-unit-fault RDRT_G230", "SP4_G230"),
        ("supply-unit-fault RDRT_G110", "SP5_G110"),
        ("supply-unit-fault RDRT_G24", "SP6_G24"),
        ("network-switch-fault RDRT_KORENIX", "SP8_Korenix"),
        ("network-switch-fault RDRT_ABB", "SP9_ABB"),
        ("network-switch-fault RDRT_SIEMENS", "SP10_Siemens"),
        ("door-open RDRT_NN", "SP26_Dvere_NN"),
        ("door-open RDRT_VN", "SP27_Dvere_VN"),
        ("door-open RDRT_T1", "SP28_Dvere_T1"),
        ("door-open RDRT_T2", "SP29_Dvere_T2"),
        ("module-pulled RDRT_P6", "SP24_PoruchaModul6"),
        ("module-pulled RDRT_P9", "SP25_PoruchaModul9"),
    ];
    for (fault, point) in cases {
        st.inject(fault);
        st.run_for(ms(100));
        assert_eq!(active(&st), vec![point], "{fault}");
        st.clear(fault);
        st.run_for(ms(100));
        assert_eq!(active(&st), Vec::<&str>::new(), "{fault} cleared");
    }
}

// ------------------------------------------------------------------------ whole station

#[test]
fn whole_station_every_plant_output_is_driven_by_one_controller() {
    let mut st = Station::new(VsetinPlant::new(), ms(50));
    add_rh2(&mut st);
    add_rzz(&mut st);
    add_rda(&mut st);
    add_logo_board(&mut st, "RH12");
    add_logo_board(&mut st, "RZS2");
    for b in lighting_boards() {
        add_lighting(&mut st, &b);
    }
    add_rdrt(&mut st);
    assert_eq!(st.nodes.len(), 19);
    let mut driven: Vec<String> = st
        .nodes
        .iter()
        .flat_map(|n| n.binds.iter())
        .filter_map(|b| match b {
            Bind::Out(_, sig) => Some(sig.clone()),
            _ => None,
        })
        .collect();
    driven.sort();
    let mut outputs: Vec<String> = st
        .plant
        .signals()
        .iter()
        .filter(|i| i.direction == Direction::Output)
        .map(|i| i.name.clone())
        .collect();
    outputs.sort();
    assert_eq!(driven, outputs);
    // Midnight of 2024-01-01 (plant time zero): everything steady, RZS on the mains,
    // the towers lit (astronomical mode) once their staggered delays ran out.
    for b in lighting_boards() {
        st.set(&b, "LightingBoard.Vstupy.W_Astral", "TRUE");
    }
    st.run_for(s(30));
    assert!(st.sig("RDA_KM1_Zapnut"));
    assert!(st.sig("RH2_QF1_Zapnut") && st.sig("RZZ_QF1_Zapnut"));
    assert!(st.sig("RH12_QF1_Zapnut") && st.sig("RZS2_QF1_Zapnut"));
    assert!(st.sig("UZ_K1_Zapnut") && !st.sig("UZ_K2_Zapnut") && st.sig("UZ_Vystup"));
    for b in lighting_boards() {
        assert!(st.sig(&format!("{b}_PrRele")), "{b}");
    }
    assert_eq!(st.plant.source_violations(), 0);
    assert!(st.plant.safety_log().is_empty());
}
