//! The crossroad (the teaching-lab thesis, section 4 of the lab-models spec): a passive
//! model whose eight LEDs follow the PLC's outputs. It has no simulation logic and no ERR
//! logic; the simulator records a conflict of greens (the lower head's green together with
//! the upper head's or the pedestrians') as [`ErrorKind::ConflictingGreens`], cleared when
//! it ends, for scenario tests, while ERR stays dark. The conflict is judged on the
//! commanded lights, so a broken lamp does not hide a program's fault.

use super::engine::{spec, Cmd, ErrorLog, SignalSpec, Sim};
use super::{ErrorKind, LabOptions};
use crate::core::{SimTime, Value};

const ZEL_SPODEK: usize = 2;
const ZEL_VRCH: usize = 5;
const ZEL_CHODCI: usize = 7;

/// The crossroad's lights.
#[derive(Debug, Clone, Default)]
pub(crate) struct Crossroad;

impl Sim for Crossroad {
    const NAME: &'static str = "crossroad";
    const OUTPUTS: &'static [SignalSpec] = &[
        spec("cerv_spodek", "red, lower head (printed \"cerpv_spodek\")"),
        spec("oran_spodek", "amber, lower head"),
        spec("zel_spodek", "green, lower head"),
        spec("cerv_vrch", "red, upper head"),
        spec("oran_vrch", "amber, upper head"),
        spec("zel_vrch", "green, upper head"),
        spec("cerv_chodci", "red, pedestrians"),
        spec("zel_chodci", "green, pedestrians"),
    ];
    const SENSORS: &'static [SignalSpec] = &[];
    const BUTTONS: &'static [SignalSpec] = &[spec(
        "tlacitko_chodci",
        "pedestrian push-button (EDUtech input module; console press/release tlacitko_chodci)",
    )];

    fn new(_options: &LabOptions) -> Self {
        Crossroad
    }

    fn reset(&mut self) {}

    fn apply(&mut self, now: SimTime, cmd: Cmd<'_>, log: &mut ErrorLog) {
        let lower = cmd.commanded(ZEL_SPODEK);
        let upper = cmd.commanded(ZEL_VRCH);
        let walk = cmd.commanded(ZEL_CHODCI);
        if lower && (upper || walk) {
            log.raise(now, ErrorKind::ConflictingGreens, || {
                let with: Vec<&str> = [(upper, "zel_vrch"), (walk, "zel_chodci")]
                    .iter()
                    .filter(|(on, _)| *on)
                    .map(|(_, name)| *name)
                    .collect();
                format!("zel_spodek with {}", with.join(" and "))
            });
        } else {
            log.clear(now, ErrorKind::ConflictingGreens);
        }
    }

    fn sensor(&self, _index: usize) -> bool {
        false
    }

    fn state(&self, _cmd: Cmd<'_>) -> Vec<(&'static str, Value)> {
        Vec::new()
    }

    fn describe(&self, cmd: Cmd<'_>) -> Vec<String> {
        let lit: Vec<String> = Self::OUTPUTS
            .iter()
            .enumerate()
            .filter(|(i, _)| cmd.on(*i))
            .map(|(_, s)| s.name.to_owned())
            .collect();
        if lit.is_empty() {
            vec!["all lights dark".to_owned()]
        } else {
            vec![format!("lit: {}", lit.join(", "))]
        }
    }
}
