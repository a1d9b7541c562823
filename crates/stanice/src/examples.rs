//! The Examples section of every `--help`, kept in one table.
//!
//! One table rather than an attribute on each argument struct: some of those structs live
//! in modules owned by other areas (the HMI, the test tool's server), and a table lets a
//! test check that every subcommand has examples and that every example parses.

use clap::Command;

/// The quality notation of the test tool's analyser lines, explained where it is used.
pub(crate) const QUALITY_LEGEND: &str = "\
Quality: each value is followed by its flags, [iv nt sb bl] ([iv nt sb bl ov] for measured
values); lower case = clear, UPPER CASE = set, e.g. [IV nt sb bl] is an invalid value.
  IV invalid       the value cannot be trusted (source failed, module pulled, link lost)
  NT not topical   not updated within its expected time (e.g. after a restart)
  SB substituted   entered by an operator or a substitution, not measured
  BL blocked       blocked for transmission; the value is the last one before blocking
  OV overflow      a measured value beyond its range";

/// (subcommand path, examples); the path is the words after `stanice`, "" for the top.
const EXAMPLES: &[(&str, &str)] = &[
    (
        "",
        "  stanice demo                                   # the Vsetín railway station, HMI included
  stanice run examples/vsetin --speed 60         # a project, one simulated minute per second
  stanice iec104 client 127.0.0.1:2404 --ca 1 --gi
  stanice help run                               # the help of one subcommand",
    ),
    (
        "iec104",
        "  stanice iec104 server --points points.csv --simulate
  stanice iec104 client 127.0.0.1:2404 --ca 1 --gi
  stanice iec104 command 127.0.0.1:2404 --ca 1 --ioa 2021 --type C_SC_NA_1 --value 1
  stanice iec104 decode 68 04 07 00 00 00",
    ),
    (
        "iec104 server",
        "  stanice iec104 server --points points.csv      # CSV header: ioa,type,value[,name]
  stanice iec104 server --points points.csv --listen 0.0.0.0:2404 --ca 7 --simulate
  stanice iec104 server --points points.csv --mode groups-by-address --group scada=10.0.0.5,10.0.0.6",
    ),
    (
        "iec104 client",
        "  stanice iec104 client 127.0.0.1:2404 --ca 1 --gi          # analyser lines until Ctrl-C
  stanice iec104 client 127.0.0.1:2404 --gi --exit-after-gi --json
  stanice iec104 client 10.0.0.1:2404,10.0.0.2:2404 --clock-sync --duration 60s",
    ),
    (
        "iec104 command",
        "  stanice iec104 command 127.0.0.1:2404 --ca 1 --ioa 2021 --type C_SC_NA_1 --value 1
  stanice iec104 command 127.0.0.1:2404 --ca 1 --ioa 2100 --type C_DC_NA_1 --value ON --select
  stanice iec104 command 127.0.0.1:2404 --ca 1 --ioa 3000 --type C_SE_NC_1 --value 12.5
The exit code is 0 on a positive confirmation and termination, non-zero otherwise.",
    ),
    (
        "iec104 decode",
        "  stanice iec104 decode 68 04 07 00 00 00         # STARTDT act
  stanice iec104 decode 680E0000000001010300010001000001
  stanice iec104 decode --asdu 01 01 03 00 01 00 01 00 00 01",
    ),
    (
        "iec101",
        "  stanice iec101 slave --pty --points points.csv --address 3 --simulate
  stanice iec101 master --serial /dev/pts/4 --address 3 --gi
  stanice iec101 master --tcp 10.0.0.9:2401 --address 1,2,3 --gi --clock-sync --json",
    ),
    (
        "iec101 master",
        "  stanice iec101 master --serial /dev/ttyUSB0 --baud 9600 --address 3 --ca 7 --gi
  stanice iec101 master --serial /dev/ttyUSB0 --address 1,2,3 --timeout 300ms --retries 3 --verbose
  stanice iec101 master --tcp 10.0.0.9:2401 --balanced --link-address-size 0 --address 0 --gi
  stanice iec101 master --serial /dev/pts/4 --cot-size 2 --ca-size 2 --ioa-size 3 --gi --exit-after-gi --json
The field sizes (--link-address-size, --cot-size, --ca-size, --ioa-size) must match the outstation's.",
    ),
    (
        "iec101 slave",
        "  stanice iec101 slave --pty --points points.csv --address 3   # prints `pty: /dev/pts/N`
  stanice iec101 slave --serial /dev/ttyS0 --baud 19200 --points points.csv --simulate
  stanice iec101 slave --listen 0.0.0.0:2401 --points points.csv --balanced --link-address-size 0 --address 0",
    ),
    (
        "iec103",
        "  stanice iec103 relay --pty --inject 1,1             # prints `pty: /dev/pts/N`
  stanice iec103 master --serial /dev/pts/4 --gi --clock-sync
  stanice iec103 master --serial /dev/pts/4 --telegrams reset-link,class2,class1",
    ),
    (
        "iec103 master",
        "  stanice iec103 master --serial /dev/ttyUSB0 --baud 9600 --address 1 --gi --clock-sync
  stanice iec103 master --serial /dev/ttyUSB0 --gi --command 1:160:OFF --exit-after-commands
  stanice iec103 master --serial /dev/ttyUSB0 --address 3 --timeout 500ms --telegrams time,reset-link,class2,class1
  stanice iec103 master --tcp 10.0.0.20:4001 --address 1,2,3 --gi --json
Single telegrams (--telegrams) are PCVDEW6's menu: reset-link (r), link-status (s), reset-fcb (f),
class1 (1), class2 (2), gi (g), time (i, broadcast). Measurands II (INF 148) are shown as
multiples of rated (2.4 x for currents and powers, 1.2 x for voltages and frequency).",
    ),
    (
        "iec103 relay",
        "  stanice iec103 relay --pty --address 1 --cycle 5s
  stanice iec103 relay --serial /dev/ttyS0 --baud 19200 --inject 0.8,0.9
  stanice iec103 relay --listen 0.0.0.0:4001
While it runs, type `help` for its console: inject, local/remote, open/close, fault, restart.",
    ),
    (
        "lift",
        "  stanice lift simulate --pty --floors 6 --speed 10      # prints `pty: /dev/pts/N`
  stanice lift poll --serial /dev/pts/4 --json",
    ),
    (
        "lift simulate",
        "  stanice lift simulate --pty --floors 6 --seed 7 --speed 10
  stanice lift simulate --serial /dev/ttyS0 --stack-size 32 --fault-probability 0
  stanice lift simulate --listen 0.0.0.0:4001 --status-layout alternative --counter-width 2
While it runs, type `help` for its console: fault 3C, status 18, status auto, trip 3, silent, answer, clear.",
    ),
    (
        "lift poll",
        "  stanice lift poll --serial /dev/ttyUSB0                 # 9600 8E1, status every second
  stanice lift poll --serial /dev/ttyUSB0 --baud 19200 --parity none --json --duration 60s
  stanice lift poll --tcp 10.0.0.30:4001 --archive lift1.cursor --json
JSON lines carry kind (status, counters, fault, comm) and status, status_text, position,
target, direction, time, counters, fault_code, fault_text, index. With --archive a restarted
monitor reads the fault log on where it stopped: no record twice, none missed.",
    ),
    (
        "demo",
        "  stanice demo                                   # web HMI on http://127.0.0.1:8080/
  stanice demo --speed 60 --store none           # fast, without writing events
  stanice demo --start 2025-01-15T16:00:00Z      # at dusk: the lighting switches on
While it runs, type `help` for the faults and hand operations of the console.",
    ),
    (
        "run",
        "  stanice run examples/vsetin
  stanice run examples/vsetin --node RH2 --port-base 12404   # one node, other ports
  stanice run examples/vsetin --speed 60 --duration 30s --store none
  stanice run examples/vsetin --node RH1.1 --hosts scripts/netns-vsetin.hosts.toml   # on its own host
While it runs, type `help` for the faults and hand operations of the console.",
    ),
    (
        "points",
        "  stanice points examples/vsetin                 # what the top node serves to dispatch
  stanice points examples/vsetin --node RH2",
    ),
    (
        "events",
        "  stanice events examples/vsetin --since 10m
  stanice events examples/vsetin --point 'RH2_*' --node RDRT --since 2h
  stanice events examples/vsetin --commands --limit 20",
    ),
    (
        "hmi",
        "  stanice hmi --connect 127.0.0.1:2404 --ca 1 --screens examples/vsetin/hmi
  stanice hmi --connect 127.0.0.1:2404 --screens examples/vsetin/hmi --listen 0.0.0.0:8080 --store none",
    ),
    (
        "user",
        "  stanice user add alice --level 5 --project examples/vsetin    # password on stdin
  stanice user list --project examples/vsetin",
    ),
    (
        "user add",
        "  stanice user add alice --level 5 --project examples/vsetin    # password on stdin
  stanice user add bob --level 0 --users users.toml             # read-only",
    ),
    (
        "user remove",
        "  stanice user remove alice --project examples/vsetin",
    ),
    (
        "user passwd",
        "  stanice user passwd alice --project examples/vsetin            # new password on stdin
  stanice user passwd alice --level 7 --users users.toml",
    ),
    (
        "user list",
        "  stanice user list --project examples/vsetin
  stanice user list --users users.toml",
    ),
    (
        "balance",
        "  stanice balance simulate --pty --ball 'red 1'           # prints pty: /dev/pts/N
  stanice balance read --serial /dev/pts/N --json
  stanice balance read --serial /dev/ttyUSB0                # a real balance at 1200 Bd, no parity",
    ),
    (
        "balance read",
        "  stanice balance read --serial /dev/ttyUSB0
  stanice balance read --serial /dev/pts/3 --json --duration 10s
  stanice balance read --tcp 10.0.0.7:4001                  # behind a terminal server
The exit code is 0 when at least one legal record arrived.",
    ),
    (
        "balance simulate",
        "  stanice balance simulate --pty
  stanice balance simulate --pty --ball 'green 2' --seed 7
  stanice balance simulate --listen 127.0.0.1:4002 --rate 4
Console: ball red 1, ball 2.5, remove, blower, tare, dust 0.001, status, help.",
    ),
    (
        "stats",
        "  stanice stats thresholds examples/sorting-lab/weighings.csv
  stanice stats thresholds examples/sorting-lab/weighings.csv --confidence 0.95 --coverage 0.90 --plot limits.svg",
    ),
    (
        "stats thresholds",
        "  stanice stats thresholds examples/sorting-lab/weighings.csv     # table 5.1 at 99 %, 99 % coverage
  stanice stats thresholds examples/sorting-lab/weighings.csv --confidence 0.95 --coverage 0.90
  stanice stats thresholds weighings.csv --outer 1.9,4.1 --json
  stanice stats thresholds weighings.csv --plot limits.svg           # densities and limits for a browser
The CSV has the header ball,weight_g and a row per weighing (`red 1,2.29105`), at least 2 a ball;
the colour is the ball name's first word. Reliability is the share of a ball's weighings (normal
with its mean and S) that falls within its colour's decision interval, `expected`; `pessimistic`
repeats it with the upper bound of sigma in place of S.",
    ),
    (
        "sorting",
        "  stanice sorting run                                   # the reference program, seed 1
  stanice sorting run --program my_sorter.st --fault double-dose
  stanice sorting reliability --sortings 1000",
    ),
    (
        "sorting run",
        "  stanice sorting run                                   # the reference program, seed 1
  stanice sorting run --program my_sorter.st --seed 7 --sortings 3
  stanice sorting run --colours green,blue,yellow,red --fault double-dose --lose-pulse S4
  stanice sorting run --program my_sorter.st --json
The program reaches the actuators only through the built-in supervisor (section 5's rules):
sensors %IX0.0-%IX0.4, weight in micrograms %ID4, commands %QX0.0-%QX1.5, and the HMI's
globals of examples/sorting-lab/plc/interface.st (compiled with it); see docs/SORTING.md.",
    ),
    (
        "sorting reliability",
        "  stanice sorting reliability                           # 1,000 sortings, seeds 1..1000
  stanice sorting reliability --sortings 100 --seed 500 --json",
    ),
    (
        "lab",
        "  stanice lab run slide --program examples/lab/slide.st --duration 2m
  stanice lab run mixing --program examples/lab/mixing.st --scenario examples/lab/scenarios/mixing.toml
  stanice lab grade --scenario examples/lab/scenarios/slide.toml submissions/
  stanice lab serve slide --program examples/lab/slide.st     # the front panel in a browser
  stanice lab signals washing --profile lab",
    ),
    (
        "lab run",
        "  stanice lab run slide --program examples/lab/slide.st --duration 2m
  stanice lab run slide --program examples/lab/slide.st --scenario examples/lab/scenarios/slide.toml
  stanice lab run washing --program main.st lib.st --main Washing --profile lab --json
  stanice lab run slide --program slide.st --option sensors=2,4,7,9 --speed 10
The exit code is 0 when the run met its scenario (no model error, every property held),
1 when it did not, 2 when the program does not compile.",
    ),
    (
        "lab grade",
        "  stanice lab grade --scenario examples/lab/scenarios/slide.toml submissions/
  stanice lab grade --scenario crossroad.toml class-2b/ --profile lab --out results/crossroad
Each .st file in the folder is one student, each subfolder of .st files one student;
the table goes to FOLDER/grades.csv and FOLDER/grades.html unless --out says otherwise.",
    ),
    (
        "lab serve",
        "  stanice lab serve slide --program examples/lab/slide.st     # then open http://127.0.0.1:8090/
  stanice lab serve mixing --program mixing.st --listen 127.0.0.1:8091 --paused
  stanice lab serve slide --program examples/lab/class/boris.st --speed 10
  stanice lab serve --project examples/lab/lab.toml          # the four models, an index at /",
    ),
    (
        "lab signals",
        "  stanice lab signals slide
  stanice lab signals mixing --profile lab
  stanice lab signals slide --option program-err=true     # with ERR and RESET for the program",
    ),
    (
        "plc",
        "  stanice plc check examples/vsetin/plc/logo_board.st
  stanice plc run counter.st --program Main --cycles 10",
    ),
    (
        "plc check",
        "  stanice plc check examples/vsetin/plc/logo_board.st
  stanice plc check lib.st main.st               # several files form one program",
    ),
    (
        "plc run",
        "  stanice plc run counter.st --program Main --cycles 10 --cycle-ms 100
  stanice plc run logic.st --program Main --set Main.Start=TRUE --set Main.Limit=5",
    ),
    (
        "plc explain",
        "  stanice plc explain E0201                     # what a code means, a wrong example, the fix
  stanice plc explain --list",
    ),
    ("modbus", crate::modbus::EXAMPLES),
    ("modbus read", crate::modbus::READ_EXAMPLES),
    ("modbus write", crate::modbus::WRITE_EXAMPLES),
    ("modbus serve", crate::modbus::SERVE_EXAMPLES),
    ("s7", crate::s7::EXAMPLES),
    ("s7 read", crate::s7::READ_EXAMPLES),
    ("s7 write", crate::s7::WRITE_EXAMPLES),
    ("s7 serve", crate::s7::SERVE_EXAMPLES),
];

/// The `after_help` of the subcommand at `path`: its examples, and for the client the
/// quality legend.
fn after_help(path: &str, examples: &str) -> String {
    let mut text = format!("Examples:\n{examples}");
    if path == "iec104 client" {
        text.push_str("\n\n");
        text.push_str(QUALITY_LEGEND);
    }
    text
}

/// `command` with the Examples section of every subcommand that has one in the table.
pub(crate) fn with_examples(command: Command) -> Command {
    let mut command = command;
    for (path, examples) in EXAMPLES {
        let text = after_help(path, examples);
        command = apply(
            command,
            path.split_whitespace().collect::<Vec<_>>().as_slice(),
            text,
        );
    }
    command
}

fn apply(command: Command, path: &[&str], text: String) -> Command {
    match path.split_first() {
        None => command.after_help(text),
        Some((first, rest)) => {
            let rest: Vec<&str> = rest.to_vec();
            command.mut_subcommand(*first, move |sub| apply(sub, &rest, text))
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]

    use clap::CommandFactory as _;

    use super::*;
    use crate::Cli;

    /// Every subcommand path of `command`, "" for itself, leaving out clap's `help`.
    fn paths(command: &Command, prefix: &str, out: &mut Vec<String>) {
        out.push(prefix.to_owned());
        for sub in command.get_subcommands() {
            if sub.get_name() == "help" {
                continue;
            }
            let path = format!("{prefix} {}", sub.get_name());
            paths(sub, path.trim(), out);
        }
    }

    #[test]
    fn every_subcommand_has_examples_and_no_example_names_an_unknown_one() {
        let mut all = Vec::new();
        paths(&Cli::command(), "", &mut all);
        for path in &all {
            assert!(
                EXAMPLES.iter().any(|(p, _)| p == path),
                "`stanice {path}` has no examples"
            );
        }
        for (path, _) in EXAMPLES {
            assert!(all.iter().any(|p| p == path), "no subcommand `{path}`");
        }
    }

    /// The words of a command line as a shell splits them: at spaces, except inside
    /// single quotes (`--ball 'red 1'` is two words).
    fn shell_words(line: &str) -> Vec<String> {
        let mut words = Vec::new();
        let mut word: Option<String> = None;
        let mut quoted = false;
        for c in line.chars() {
            match c {
                '\'' => {
                    quoted = !quoted;
                    word.get_or_insert_with(String::new);
                }
                c if c.is_whitespace() && !quoted => words.extend(word.take()),
                c => word.get_or_insert_with(String::new).push(c),
            }
        }
        words.extend(word);
        words
    }

    #[test]
    fn example_lines_split_as_a_shell_splits_them() {
        assert_eq!(
            shell_words("  stanice balance simulate --ball 'red 1'  --json"),
            ["stanice", "balance", "simulate", "--ball", "red 1", "--json"]
        );
        assert_eq!(shell_words("a '' b"), ["a", "", "b"]);
    }

    /// Each example line is a command line the parser accepts.
    #[test]
    fn every_example_parses() {
        for (path, examples) in EXAMPLES {
            for line in examples.lines().filter(|l| l.starts_with("  stanice ")) {
                let words = shell_words(line.split(" #").next().unwrap());
                let parsed = with_examples(Cli::command()).try_get_matches_from(&words);
                if let Err(error) = parsed {
                    // `stanice help run` prints help by design
                    assert!(
                        words.get(1).map(String::as_str) == Some("help"),
                        "`{line}` (examples of `{path}`): {error}"
                    );
                }
            }
        }
    }
}
