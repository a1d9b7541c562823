//! Operations on a running station, typed: what the console, the HMI's and scripts'
//! operations ask for, parsed once ([`Operation::parse`]) and carried out by
//! [`Runtime::perform`](super::Runtime::perform), with a typed error.
//!
//! Before, a line of text was routed in two places (the command line's console and the
//! runtime, the `lift` branch in both) and errors were routed by their wording
//! (`error.contains("has no device")`).
//!
//! | Words | Operation |
//! |---|---|
//! | `link-cut NODE/LINK`, `link-restore NODE/LINK` | [`Operation::Link`] |
//! | `plc-stop NODE`, `plc-start NODE` | [`Operation::Plc`] |
//! | `lift NAME WORDS...` | [`Operation::Lift`]: a simulated EKM66 board's console |
//! | `relay DEVICE WORDS...` | [`Operation::Device`]: a simulated line device's console |
//! | anything else | [`Operation::Plant`]: the plant simulation's console (faults, hand operations) |

/// One operation on a running station.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Operation {
    /// Cut (`cut = true`) or restore a node's client link.
    Link {
        /// The node.
        node: String,
        /// Its link.
        link: String,
        /// Cut rather than restore.
        cut: bool,
    },
    /// Stop or start a node's soft PLC.
    Plc {
        /// The node.
        node: String,
        /// Start rather than stop.
        run: bool,
    },
    /// An operation on a simulated lift board (`fault 3C`, `silent`, `show`).
    Lift {
        /// The lift.
        lift: String,
        /// The board console's words.
        words: Vec<String>,
    },
    /// An operation on a simulated device of a serial line (`local`, `inject 1 1`).
    Device {
        /// The device.
        device: String,
        /// The device console's words.
        words: Vec<String>,
    },
    /// A line of the plant simulation's console (a fault, `clear ...`, a hand operation).
    Plant(String),
}

/// Why an operation could not be carried out.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum OperationError {
    /// The words do not form the operation they start.
    #[error("expected {0}")]
    Usage(&'static str),
    /// No such node runs in this process.
    #[error("no node `{node}` runs here{suggestion}")]
    NoNode {
        /// The name given.
        node: String,
        /// `; did you mean ...?`, or empty.
        suggestion: String,
    },
    /// The node has no such link.
    #[error("no link `{link}` at node `{node}`")]
    NoLink {
        /// The node.
        node: String,
        /// The link given.
        link: String,
    },
    /// The node runs no PLC.
    #[error("node `{0}` has no PLC")]
    NoPlc(String),
    /// No such lift is watched here.
    #[error("no lift `{0}` runs here")]
    NoLift(String),
    /// The lift's board is a real one: the simulator's operations do not apply.
    #[error("lift {0} has a real board")]
    RealBoard(String),
    /// No line has a simulated device of that name.
    #[error("no simulated device `{0}` on any line")]
    NoDevice(String),
    /// The project has no plant simulation for the plant's console.
    #[error("the project has no plant simulation")]
    NoPlant,
    /// The device, board or plant refused the operation, in its own words.
    #[error("{0}")]
    Refused(String),
    /// What would carry it out has stopped (the station is shutting down).
    #[error("{0} has stopped")]
    Stopped(String),
}

impl Operation {
    /// Reads one console line.
    pub fn parse(text: &str) -> Result<Operation, OperationError> {
        let text = text.trim();
        for (prefix, cut) in [("link-cut ", true), ("link-restore ", false)] {
            if let Some(rest) = text.strip_prefix(prefix) {
                let (node, link) = rest.trim().split_once('/').ok_or(OperationError::Usage(
                    "NODE/LINK after link-cut or link-restore",
                ))?;
                return Ok(Operation::Link {
                    node: node.trim().to_owned(),
                    link: link.trim().to_owned(),
                    cut,
                });
            }
        }
        for (prefix, run) in [("plc-stop ", false), ("plc-start ", true)] {
            if let Some(node) = text.strip_prefix(prefix) {
                return Ok(Operation::Plc {
                    node: node.trim().to_owned(),
                    run,
                });
            }
        }
        for (prefix, usage) in [
            ("lift ", "`lift NAME OPERATION`"),
            ("relay ", "`relay DEVICE OPERATION`"),
        ] {
            if let Some(rest) = text.strip_prefix(prefix) {
                let words: Vec<String> = rest.split_whitespace().map(str::to_owned).collect();
                let Some((name, operation)) = words.split_first() else {
                    return Err(OperationError::Usage(usage));
                };
                let (name, words) = (name.clone(), operation.to_vec());
                return Ok(if prefix == "lift " {
                    Operation::Lift { lift: name, words }
                } else {
                    Operation::Device {
                        device: name,
                        words,
                    }
                });
            }
        }
        if text.is_empty() {
            return Err(OperationError::Usage("an operation (`help` lists them)"));
        }
        Ok(Operation::Plant(text.to_owned()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_become_operations() {
        assert_eq!(
            Operation::parse("link-cut RDRT/RH"),
            Ok(Operation::Link {
                node: "RDRT".into(),
                link: "RH".into(),
                cut: true
            })
        );
        assert_eq!(
            Operation::parse("plc-start PLC1"),
            Ok(Operation::Plc {
                node: "PLC1".into(),
                run: true
            })
        );
        assert_eq!(
            Operation::parse("lift L3 fault 3C"),
            Ok(Operation::Lift {
                lift: "L3".into(),
                words: vec!["fault".into(), "3C".into()]
            })
        );
        assert_eq!(
            Operation::parse("relay REF630 inject 1 1"),
            Ok(Operation::Device {
                device: "REF630".into(),
                words: vec!["inject".into(), "1".into(), "1".into()]
            })
        );
        assert_eq!(
            Operation::parse("supply-loss UTILITY"),
            Ok(Operation::Plant("supply-loss UTILITY".into()))
        );
        assert!(matches!(
            Operation::parse("link-cut RDRT"),
            Err(OperationError::Usage(_))
        ));
        assert!(matches!(Operation::parse("lift"), Ok(Operation::Plant(_))));
        assert!(matches!(
            Operation::parse("lift "),
            Err(OperationError::Usage(_)) | Ok(Operation::Plant(_))
        ));
    }
}
