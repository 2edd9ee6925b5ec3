//! The names of motion: the paper's three classes (Haumann et al. 1991,
//! §4.1: floaters, spinners, lilters, plus undetermined) and the
//! literature's finer regimes, with their text forms.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

/// The paper's three kinds of leaf motion, plus `Undetermined`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MotionClass {
    /// Does not rotate; floats or glides gently down (steady, glide, flutter).
    Floater,
    /// Rotates rapidly as it falls (tumble or autorotation).
    Spinner,
    /// Alternately rocks, then rotates end over end (chaotic).
    Lilter,
    /// Cannot tell, or none of the three (e.g. a dive); see the reason.
    Undetermined,
}

/// The finer regime, in the literature's words.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Regime {
    /// Floater: constant attitude, straight down.
    Steady,
    /// Floater: constant attitude, drifting sideways.
    Glide,
    /// Floater: side-to-side rocking, pitch rate reverses.
    Flutter,
    /// Spinner: end-over-end rotation about a horizontal axis.
    Tumble,
    /// Spinner: rotation about the vertical axis, plate steeply tilted.
    Autorotation,
    /// Lilter: rocks, then flips over, irregularly.
    Chaotic,
    /// Edge-on fall without rotation (docs/design/falling-plates.md, "Folded leaves
    /// under the linear law"); class `Undetermined`.
    Dive,
    /// No regime could be named.
    Undetermined,
}

/// Error of [`MotionClass::from_str`] / [`Regime::from_str`].
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown {what} `{input}` (expected one of: {expected})")]
pub struct ParseNameError {
    what: &'static str,
    input: String,
    expected: &'static str,
}

const CLASS_NAMES: [(MotionClass, &str); 4] = [
    (MotionClass::Floater, "floater"),
    (MotionClass::Spinner, "spinner"),
    (MotionClass::Lilter, "lilter"),
    (MotionClass::Undetermined, "undetermined"),
];

const REGIME_NAMES: [(Regime, &str); 8] = [
    (Regime::Steady, "steady"),
    (Regime::Glide, "glide"),
    (Regime::Flutter, "flutter"),
    (Regime::Tumble, "tumble"),
    (Regime::Autorotation, "autorotation"),
    (Regime::Chaotic, "chaotic"),
    (Regime::Dive, "dive"),
    (Regime::Undetermined, "undetermined"),
];

impl MotionClass {
    /// Lower-case name, as in serde and the CLI.
    pub fn as_str(self) -> &'static str {
        CLASS_NAMES
            .iter()
            .find(|(c, _)| *c == self)
            .map_or("", |p| p.1)
    }
}

impl Regime {
    /// Snake-case name, as in serde and the CLI.
    pub fn as_str(self) -> &'static str {
        REGIME_NAMES
            .iter()
            .find(|(r, _)| *r == self)
            .map_or("", |p| p.1)
    }
}

impl fmt::Display for MotionClass {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl fmt::Display for Regime {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl FromStr for MotionClass {
    type Err = ParseNameError;
    /// Parses `floater`, `spinner`, `lilter`, `undetermined` (any case).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let s = s.trim();
        CLASS_NAMES
            .iter()
            .find(|(_, n)| n.eq_ignore_ascii_case(s))
            .map(|p| p.0)
            .ok_or_else(|| ParseNameError {
                what: "motion class",
                input: s.to_string(),
                expected: "floater, spinner, lilter, undetermined",
            })
    }
}

impl FromStr for Regime {
    type Err = ParseNameError;
    /// Parses the snake-case regime names (any case).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let s = s.trim();
        REGIME_NAMES
            .iter()
            .find(|(_, n)| n.eq_ignore_ascii_case(s))
            .map(|p| p.0)
            .ok_or_else(|| ParseNameError {
                what: "regime",
                input: s.to_string(),
                expected: "steady, glide, flutter, tumble, autorotation, chaotic, dive, undetermined",
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_through_display_fromstr_and_serde() {
        for (c, n) in CLASS_NAMES {
            assert_eq!(c.to_string(), n);
            assert_eq!(n.parse::<MotionClass>().unwrap(), c);
            assert_eq!(serde_json::to_string(&c).unwrap(), format!("\"{n}\""));
        }
        for (r, n) in REGIME_NAMES {
            assert_eq!(r.to_string(), n);
            assert_eq!(n.parse::<Regime>().unwrap(), r);
            assert_eq!(serde_json::to_string(&r).unwrap(), format!("\"{n}\""));
        }
        assert!("Spinner".parse::<MotionClass>().is_ok());
        assert!("twirler".parse::<MotionClass>().is_err());
    }
}
