//! "Did you mean": the known name nearest to a mistyped one, for the diagnostics of
//! Structured Text (undeclared names) and of whoever names a PLC's programs and
//! variables, or a project's nodes, from outside (the station's configuration and the
//! command line).
//!
//! Names compare without case, as Structured Text's do; the distance is Damerau-
//! Levenshtein (a swapped pair of letters counts once) from the `strsim` crate, and a
//! name is suggested only when it is close: at most one edit in four characters, and
//! never when two names are equally close.

/// The name of `known` nearest to `name`, when one is clearly meant.
pub fn closest<'a>(name: &str, known: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    let wanted = name.to_lowercase();
    let limit = (wanted.chars().count() / 4).max(1);
    let mut best: Option<(usize, &'a str)> = None;
    let mut tie = false;
    for candidate in known {
        let distance = strsim::damerau_levenshtein(&wanted, &candidate.to_lowercase());
        if distance == 0 || distance > limit {
            continue;
        }
        match best {
            Some((nearest, _)) if distance > nearest => {}
            Some((nearest, _)) if distance == nearest => tie = true,
            _ => {
                best = Some((distance, candidate));
                tie = false;
            }
        }
    }
    best.filter(|_| !tie).map(|(_, candidate)| candidate)
}

/// `"; did you mean `NAME`?"`, or nothing.
pub fn did_you_mean<'a>(name: &str, known: impl IntoIterator<Item = &'a str>) -> String {
    closest(name, known)
        .map(|candidate| format!("; did you mean `{candidate}`?"))
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn suggests_only_a_clear_neighbour() {
        let known = ["Lamp", "Motor", "RDRT", "RH1.1", "RH2"];
        assert_eq!(closest("lmap", known), Some("Lamp"));
        assert_eq!(closest("Motr", known), Some("Motor"));
        assert_eq!(closest("RDRTX", known), Some("RDRT"));
        assert_eq!(closest("Pump", known), None);
        // RH1 is one edit from both RH2 and RH1.1's neighbours: no guess between ties.
        assert_eq!(closest("RH3", ["RH2", "RH4"]), None);
        assert_eq!(did_you_mean("lmap", known), "; did you mean `Lamp`?");
        assert_eq!(did_you_mean("xyz", known), "");
    }
}
