//! Motion descriptors of a fall and the distance between two falls: what
//! `breed --like`, `breed --target-features` and `compare` steer by.
//!
//! A fall is described by the classifier's class and regime and by ten
//! numbers from its features ([`crate::motion::classify::Features`]), each over the
//! classifier's analysis window (the start-up transient discarded):
//!
//! | name | descriptor | unit |
//! |---|---|---|
//! | `descent` | mean descent speed | m/s |
//! | `spin` | \|mean rotation rate about the vertical\| | rad/s |
//! | `tumble` | net rotation rate about the dominant horizontal axis | rad/s |
//! | `flips` | normal flips per second | 1/s |
//! | `reversals` | pitch-rate reversals per second | 1/s |
//! | `drift` | horizontal travel / descent | — |
//! | `period` | oscillation period (none without ≥ 3 turning points) | s |
//! | `descent_cv` | spread of the descent speed (std / mean) | — |
//! | `tilt` | mean tilt of the plate from horizontal | degrees |
//! | `tilt_std` | spread of that tilt | degrees |
//!
//! # Distance
//!
//! d(a, b) = √( Σᵢ ((aᵢ − bᵢ) / sᵢ)² / n ) over the n descriptors the target
//! sets, with sᵢ the descriptor's [`SCALES`]: its standard deviation across a
//! reference population (200 variants each of prototypes A and B at
//! variation scale 1, 10 s drops, of which 391 are described; `cargo run --release --example
//! descriptor_scales` recomputes them). So d = 1 means "as far apart, on
//! average, as two random members of that population". A period that only
//! one fall has counts as one scale apart. The distance is dimensionless.
//!
//! **Class gate.** Falls of different classes are never close: their
//! distance is infinite, whatever the numbers (a floater that descends like
//! a spinner is not like it). An undetermined fall has no descriptors.

use crate::motion::classify::{Classification, MotionClass, Regime};
use crate::util::setting::Setting;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;

/// The descriptor names, in vector order.
pub const NAMES: [&str; 10] = [
    "descent",
    "spin",
    "tumble",
    "flips",
    "reversals",
    "drift",
    "period",
    "descent_cv",
    "tilt",
    "tilt_std",
];

/// Units of [`NAMES`], for tables.
pub const UNITS: [&str; 10] = [
    "m/s", "rad/s", "rad/s", "1/s", "1/s", "", "s", "", "deg", "deg",
];

/// What each of [`NAMES`] measures, for tables (the module docs' table).
pub const MEANINGS: [&str; 10] = [
    "mean descent speed",
    "|mean rotation rate about the vertical|",
    "net rotation rate about the dominant horizontal axis",
    "normal flips per second",
    "pitch-rate reversals per second",
    "horizontal travel / descent",
    "oscillation period (none without 3 turning points)",
    "spread of the descent speed (std / mean)",
    "mean tilt of the plate from horizontal",
    "spread of that tilt",
];

/// Why descriptor `k` of a record without orientation is not measured: the
/// rotation rate about a horizontal axis also comes from projected areas
/// (two maxima per turn); the rest need the attitude itself.
pub fn unmeasured_because(k: usize) -> &'static str {
    if NAMES[k] == "tumble" {
        "needs orientation or projected areas"
    } else {
        "needs orientation"
    }
}

/// Descriptor `k`'s name with its unit, as tables head its row
/// (`descent (m/s)`, `drift`).
pub fn label(k: usize) -> String {
    if UNITS[k].is_empty() {
        NAMES[k].to_string()
    } else {
        format!("{} ({})", NAMES[k], UNITS[k])
    }
}

/// Scale of each descriptor in the distance: its standard deviation across
/// the reference population of the module docs (rounded to two figures).
pub const SCALES: [f64; 10] = [0.93, 7.1, 3.1, 1.4, 1.6, 0.23, 0.54, 0.11, 26.0, 9.3];

/// The descriptors of one fall.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Descriptors {
    /// The classifier's class.
    pub class: MotionClass,
    /// The classifier's regime.
    pub regime: Regime,
    /// Values in [`NAMES`] order (`period` is NaN when the fall has none).
    pub values: [f64; 10],
    /// Which values the record let one measure: all of them from a pose
    /// record; from a record without orientation (video) only `descent` and
    /// `drift`, and `tumble` (π × area maxima per second) when it has
    /// projected areas. A descriptor not measured is left out of distances.
    #[serde(default = "all_measured")]
    pub measured: [bool; 10],
}

/// Every descriptor measured (a pose record).
fn all_measured() -> [bool; 10] {
    [true; 10]
}

/// A `--target-features` list that names no target: what is wrong with it.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct FeatureError(pub String);

/// Why a fall has no descriptors.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("the fall cannot be described (the classifier says undetermined: {reason})")]
pub struct Undescribable {
    /// The classifier's reason.
    pub reason: String,
}

impl Descriptors {
    /// The descriptors of a classified fall; an undetermined fall has none.
    pub fn of(c: &Classification) -> Result<Descriptors, Undescribable> {
        if c.class == MotionClass::Undetermined {
            return Err(Undescribable {
                reason: c.reason.clone().unwrap_or_default(),
            });
        }
        if let Some(p) = &c.path {
            // Without orientation: what the path measures as the full
            // classifier does (same window, same definitions), and the turn
            // rate the area signals give. The rest is not measured (the
            // path's `reversals` are of the horizontal velocity, not of the
            // pitch rate; its descent modulation is smoothed and denoised).
            let mut values = [f64::NAN; 10];
            let mut measured = [false; 10];
            let mut set = |name: &str, v: f64| {
                let k = NAMES.iter().position(|n| *n == name).unwrap_or(0);
                values[k] = v;
                measured[k] = true;
            };
            set("descent", p.mean_descent_speed_m_s);
            set("drift", p.drift_ratio);
            if let Some(w) = p.area_turn_rate_rad_s {
                set("tumble", w);
            }
            return Ok(Descriptors {
                class: c.class,
                regime: c.regime,
                values,
                measured,
            });
        }
        let f = &c.features;
        Ok(Descriptors {
            class: c.class,
            regime: c.regime,
            measured: all_measured(),
            values: [
                f.mean_descent_speed_m_s,
                f.mean_yaw_rate_rad_s.abs(),
                f.tumbling_rate_rad_s(),
                f.flips_per_s,
                f.reversals_per_s,
                f.drift_ratio,
                f.oscillation_period_s.unwrap_or(f64::NAN),
                f.descent_speed_cv,
                f.tilt_mean_deg,
                f.tilt_std_deg,
            ],
        })
    }

    /// A descriptor by name.
    pub fn get(&self, name: &str) -> Option<f64> {
        NAMES
            .iter()
            .position(|n| *n == name)
            .map(|k| self.values[k])
    }
}

/// What breeding aims at: a class (optional for `--target-features`) and
/// some descriptors (unset ones are free).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MotionTarget {
    /// Where the target came from: the example's path, or `features`.
    pub source: String,
    /// The class a fall must have to be close (none: any class).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub class: Option<MotionClass>,
    /// The regime of the example (informative; not gated).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub regime: Option<Regime>,
    /// The example's size (chord) it was classified with, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub size_m: Option<f64>,
    /// Target value of each descriptor, by name; absent = free.
    pub descriptors: std::collections::BTreeMap<String, f64>,
}

impl MotionTarget {
    /// The target of `breed --like`: every descriptor of the example, and
    /// its class.
    pub fn like(source: &str, size_m: f64, example: &Descriptors) -> MotionTarget {
        MotionTarget {
            source: source.to_string(),
            class: Some(example.class),
            regime: Some(example.regime),
            size_m: Some(size_m),
            descriptors: NAMES
                .iter()
                .zip(example.values)
                .zip(example.measured)
                .filter(|((_, v), measured)| *measured && v.is_finite())
                .map(|((n, v), _)| (n.to_string(), v))
                .collect(),
        }
    }

    /// The target of `breed --target-features descent=0.6,spin=20`: SI
    /// values by name, gated to `class` (`breed --target`) if one is given;
    /// without one every described fall has a distance. Unknown names are
    /// all listed in the error.
    pub fn parse_features(
        text: &str,
        class: Option<MotionClass>,
    ) -> Result<MotionTarget, FeatureError> {
        if class == Some(MotionClass::Undetermined) {
            return Err(FeatureError(format!(
                "{} must be floater, spinner or lilter",
                Setting::Target
            )));
        }
        let mut descriptors = std::collections::BTreeMap::new();
        let mut unknown = Vec::new();
        for item in text.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            let Some((name, value)) = item.split_once('=') else {
                return Err(FeatureError(format!(
                    "{}: '{item}' is not NAME=VALUE (names: {})",
                    Setting::TargetFeatures,
                    NAMES.join(", ")
                )));
            };
            let (name, value) = (name.trim(), value.trim());
            if !NAMES.contains(&name) {
                unknown.push(name.to_string());
                continue;
            }
            let v: f64 = value
                .parse()
                .ok()
                .filter(|v: &f64| v.is_finite() && *v >= 0.0)
                .ok_or_else(|| {
                    FeatureError(format!(
                        "{}: {name}: '{value}' is not a number ≥ 0",
                        Setting::TargetFeatures
                    ))
                })?;
            descriptors.insert(name.to_string(), v);
        }
        if !unknown.is_empty() {
            return Err(FeatureError(format!(
                "{}: unknown descriptor{} {}; known: {}",
                Setting::TargetFeatures,
                if unknown.len() > 1 { "s" } else { "" },
                unknown.join(", "),
                NAMES.join(", ")
            )));
        }
        if descriptors.is_empty() {
            return Err(FeatureError(format!(
                "{}: set at least one descriptor ({})",
                Setting::TargetFeatures,
                NAMES.join(", ")
            )));
        }
        Ok(MotionTarget {
            source: "features".to_string(),
            class,
            regime: None,
            size_m: None,
            descriptors,
        })
    }

    /// Distance of a fall to the target (module docs): the root mean square
    /// of its [`MotionTarget::residuals`]; infinite across the class gate.
    pub fn distance(&self, fall: &Descriptors) -> f64 {
        self.residuals(fall)
            .map_or(f64::INFINITY, |r| root_mean_square(&r))
    }

    /// The scaled differences (fall − target) / scale of every descriptor
    /// the target sets, in the target's (name) order, whose root mean square
    /// is the distance: a value only one side has counts as +1, one that
    /// neither has as 0. What the hybrid's Levenberg–Marquardt steps fit
    /// (`breed::least_squares`). `None` across the class gate.
    pub fn residuals(&self, fall: &Descriptors) -> Option<Vec<f64>> {
        if self.class.is_some_and(|c| c != fall.class) {
            return None;
        }
        Some(
            self.descriptors
                .iter()
                .map(|(name, &target)| {
                    let k = NAMES
                        .iter()
                        .position(|n| n == name)
                        .expect("names checked when the target was made");
                    difference(target, fall.values[k], SCALES[k])
                })
                .collect(),
        )
    }
}

/// √(Σ rᵢ² / n) of residuals (0 for none): a distance from its residuals.
pub fn root_mean_square(residuals: &[f64]) -> f64 {
    let sum = residuals.iter().fold(0.0, |s, r| s + r * r);
    (sum / residuals.len().max(1) as f64).sqrt()
}

/// One descriptor's scaled difference (b − a) / scale; a value only one
/// side has (a period) counts as one scale apart, one neither has as none.
fn difference(a: f64, b: f64, scale: f64) -> f64 {
    match (a.is_finite(), b.is_finite()) {
        (true, true) => (b - a) / scale,
        (false, false) => 0.0,
        _ => 1.0,
    }
}

/// Distance between two described falls: every descriptor both measured
/// (all ten between pose records), class-gated.
pub fn distance(a: &Descriptors, b: &Descriptors) -> f64 {
    if a.class != b.class {
        return f64::INFINITY;
    }
    let residuals: Vec<f64> = (0..NAMES.len())
        .filter(|&k| a.measured[k] && b.measured[k])
        .map(|k| difference(a.values[k], b.values[k], SCALES[k]))
        .collect();
    root_mean_square(&residuals)
}

/// A side-by-side table of descriptor vectors (columns), for the terminal.
pub fn table(columns: &[(&str, &Descriptors)]) -> String {
    let mut out = String::new();
    let _ = write!(out, "{:<16}", "");
    for (label, _) in columns {
        let _ = write!(out, " {label:>14}");
    }
    out.push('\n');
    let _ = write!(out, "{:<16}", "class");
    for (_, d) in columns {
        let _ = write!(out, " {:>14}", d.class.as_str());
    }
    out.push('\n');
    let _ = write!(out, "{:<16}", "regime");
    for (_, d) in columns {
        let _ = write!(out, " {:>14}", d.regime.as_str());
    }
    out.push('\n');
    for k in 0..NAMES.len() {
        let _ = write!(out, "{:<16}", label(k));
        for (_, d) in columns {
            let v = d.values[k];
            let cell = if !d.measured[k] {
                "not measured".to_string()
            } else if v.is_finite() {
                format!("{v:.3}")
            } else {
                "—".to_string()
            };
            let _ = write!(out, " {cell:>14}");
        }
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fall(class: MotionClass, values: [f64; 10]) -> Descriptors {
        Descriptors {
            class,
            regime: Regime::Glide,
            values,
            measured: all_measured(),
        }
    }

    const A: [f64; 10] = [0.6, 1.0, 0.5, 0.2, 0.3, 0.1, 1.0, 0.1, 30.0, 5.0];

    #[test]
    fn distance_is_a_scaled_rms_and_a_metric_within_a_class() {
        let a = fall(MotionClass::Floater, A);
        assert_eq!(distance(&a, &a), 0.0);
        // Move one descriptor by one scale: d = √(1/10).
        let mut b = a.clone();
        b.values[1] += SCALES[1];
        assert!((distance(&a, &b) - 0.1f64.sqrt()).abs() < 1e-12);
        assert_eq!(distance(&a, &b), distance(&b, &a));
        // Triangle inequality on a third point.
        let mut c = b.clone();
        c.values[8] -= 2.0 * SCALES[8];
        assert!(distance(&a, &c) <= distance(&a, &b) + distance(&b, &c) + 1e-12);
        // A period only one side has is one scale apart.
        let mut d = a.clone();
        d.values[6] = f64::NAN;
        assert!((distance(&a, &d) - 0.1f64.sqrt()).abs() < 1e-12);
    }

    #[test]
    fn different_classes_are_never_close() {
        let a = fall(MotionClass::Floater, A);
        let b = fall(MotionClass::Spinner, A);
        assert_eq!(distance(&a, &b), f64::INFINITY);
        let t = MotionTarget::like("a.csv", 0.05, &a);
        assert_eq!(t.distance(&b), f64::INFINITY);
        assert_eq!(t.distance(&a), 0.0);
    }

    #[test]
    fn target_features_weigh_only_what_is_set() {
        let t = MotionTarget::parse_features("descent=0.6, spin=20", Some(MotionClass::Spinner))
            .unwrap();
        assert_eq!(t.class, Some(MotionClass::Spinner));
        let mut a = fall(MotionClass::Spinner, A);
        a.values[1] = 20.0;
        // Only descent and spin count: both match, whatever the rest.
        assert_eq!(t.distance(&a), 0.0);
        a.values[0] = 0.6 + SCALES[0];
        assert!((t.distance(&a) - 0.5f64.sqrt()).abs() < 1e-12);
        let gated =
            MotionTarget::parse_features("descent=0.6", Some(MotionClass::Floater)).unwrap();
        assert_eq!(gated.distance(&a), f64::INFINITY);
        // Without --target no class is gated: a spinner and a floater with
        // the same descriptors are equally close.
        let free = MotionTarget::parse_features("descent=0.6", None).unwrap();
        let floater = Descriptors {
            class: MotionClass::Floater,
            ..a.clone()
        };
        assert!(free.distance(&a).is_finite());
        assert_eq!(free.distance(&a), free.distance(&floater));
    }

    #[test]
    fn descriptors_not_measured_are_left_out() {
        let a = fall(MotionClass::Spinner, A);
        let mut video = a.clone();
        video.measured = [false; 10];
        video.measured[0] = true;
        video.measured[5] = true;
        video.values[1] = f64::NAN;
        video.values[5] += SCALES[5];
        // Only descent and drift count: √(1/2).
        assert!((distance(&a, &video) - 0.5f64.sqrt()).abs() < 1e-12);
        let t = MotionTarget::like("v.csv", 0.04, &video);
        let names: Vec<&str> = t.descriptors.keys().map(String::as_str).collect();
        assert_eq!(names, ["descent", "drift"]);
        assert!((t.distance(&a) - 0.5f64.sqrt()).abs() < 1e-12);
    }

    #[test]
    fn unknown_names_are_all_listed() {
        let floater = Some(MotionClass::Floater);
        let e = MotionTarget::parse_features("descent=1,speed=2,wobble=3", floater)
            .unwrap_err()
            .0;
        assert!(
            e.contains("speed") && e.contains("wobble") && e.contains("known"),
            "{e}"
        );
        assert!(MotionTarget::parse_features("descent", floater).is_err());
        assert!(MotionTarget::parse_features("descent=-1", floater).is_err());
        assert!(MotionTarget::parse_features("spin=1", Some(MotionClass::Undetermined)).is_err());
        assert!(MotionTarget::parse_features("", floater).is_err());
    }
}
