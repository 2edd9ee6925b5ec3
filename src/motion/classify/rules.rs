//! Step 4 of the method ([`super`]): the ordered rules and the thresholds
//! they test, and the [`Classification`] they give, with its margins and
//! reason.

use crate::motion::at_rest::AtRest;
use serde::Serialize;

use super::features::{FLIP_HYSTERESIS_DEG, Features};
use crate::motion::class::{MotionClass, Regime};
use crate::motion::path::{Inputs, PathFeatures};
use crate::motion::rules::{self, Cond};

/// Fewest oscillation periods needed to call a rocking fall a flutter
/// (docs/design/falling-plates.md, "Classifier rules", step 1).
pub const MIN_OSCILLATION_PERIODS: f64 = 3.0;

/// Fewest net turns about the dominant horizontal axis for a tumble
/// (docs/design/falling-plates.md, "Classifier rules", step 4: N_turn ≥ 1); a
/// floater cannot turn past ±90° (Belmonte, Eisenberg & Moses 1998, Phys.
/// Rev. Lett. 81, 345; Andersen, Pesavento & Wang 2005, J. Fluid Mech. 541,
/// 65).
pub const SPIN_MIN_NET_TURNS: f64 = 1.0;

/// Least rotation consistency |∫ω dt| / ∫|ω| dt about the horizontal axis for
/// a tumble: "ω keeps its sign" (Belmonte 1998, APW 2005); s > 0.9 in
/// docs/design/falling-plates.md, "Classifier rules", step 4.
pub const TUMBLE_MIN_CONSISTENCY: f64 = 0.9;

/// Fewest pitch reversals (rocks) for a lilter: Field et al. 1997 chaotic =
/// oscillation, then a flip, irregularly; "reversals between flips" in
/// docs/design/falling-plates.md, "Classifier rules", step 4.
pub const LILT_MIN_REVERSALS: usize = 2;

/// Smallest rocking amplitude of a flutter, degrees (half the mean swing).
/// Steady if θ stays within ~10°, flutter otherwise (docs/design/falling-plates.md,
/// "Classifier rules", step 4).
pub const FLUTTER_MIN_AMPLITUDE_DEG: f64 = 10.0;

/// Fewest turns about the vertical for autorotation (N_z ≥ 1:
/// docs/design/falling-plates.md, "Classifier rules", step 4).
pub const AUTOROTATION_MIN_YAW_TURNS: f64 = 1.0;

/// Least yaw consistency |∫ω_z dt| / ∫|ω_z| dt for autorotation (the
/// vertical counterpart of [`TUMBLE_MIN_CONSISTENCY`]).
pub const AUTOROTATION_MIN_YAW_CONSISTENCY: f64 = 0.9;

/// Least |mean ω_z| / rms |ω| for autorotation: the spin axis lies on
/// average within ~45° of the vertical. Lilters also yaw at 1–9 rad/s
/// (docs/design/falling-plates.md, "Folded leaves under the linear law") but their
/// rocking and flips dominate ω.
pub const AUTOROTATION_MIN_VERTICAL_SHARE: f64 = 0.7;

/// Least mean plate tilt for autorotation, degrees. Autorotating spinners'
/// planes sat 42–103° from horizontal (docs/design/falling-plates.md, "Folded leaves
/// under the linear law"); a flat leaf turning about its own normal is still a
/// floater ("did not rotate" visibly).
pub const AUTOROTATION_MIN_TILT_DEG: f64 = 30.0;

/// Dive: the plate spends 90 % of the window within 30° of edge-on (10th
/// percentile of tilt ≥ 60°). Divers fall edge-on; planes 30–60° from
/// edge-on are "neither clearly floater nor diver" (docs/design/falling-plates.md,
/// "Folded leaves under the linear law").
pub const DIVE_MIN_TILT_DEG: f64 = 60.0;

/// Mean tilt above which a non-rocking, non-rotating fall is neither a clear
/// floater nor a diver, degrees (30–60° from edge-on: docs/design/falling-plates.md,
/// "Folded leaves under the linear law").
pub const STEEP_TILT_DEG: f64 = 30.0;

/// Least drift ratio (horizontal displacement / fall) for a glide: a path
/// ≥ 5.7° from vertical. Our choice: steady fallers and flutterers have zero
/// mean drift (Field 1997, APW 2005), tumblers 0.5–2.3 (docs/design/falling-plates.md,
/// "Measured regimes", row 4, and "Classifier rules").
pub const GLIDE_MIN_DRIFT_RATIO: f64 = 0.1;

/// Result of [`classify`](super::classify).
#[derive(Clone, Debug)]
pub struct Classification {
    /// Floater, spinner, lilter or undetermined.
    pub class: MotionClass,
    /// The finer regime.
    pub regime: Regime,
    /// Why: always set; for `Undetermined` it says what was missing.
    pub reason: Option<String>,
    /// Which inputs the decision used: the orientation (this module's
    /// classifier), or the path with or without area signals
    /// ([`crate::motion::path`]).
    pub inputs: Inputs,
    /// The numbers behind a decision from the orientation. From the path,
    /// only the translation part (window, rate, descent, drift, their
    /// spread) and the margins are filled in; the rest is 0.
    pub features: Features,
    /// The numbers behind a decision from the path (`None` when the
    /// orientation was used).
    pub path: Option<PathFeatures>,
    /// What was left out of the record as rest before release and after
    /// landing (`None`: the record was classified as it is;
    /// [`crate::motion::at_rest`]).
    pub at_rest: Option<AtRest>,
}

/// `class`, `regime`, `reason`, `inputs`, and as `features` the numbers
/// behind the decision: [`Features`] or [`PathFeatures`].
impl Serialize for Classification {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let mut s = serializer.serialize_struct("Classification", 5)?;
        s.serialize_field("class", &self.class)?;
        s.serialize_field("regime", &self.regime)?;
        s.serialize_field("reason", &self.reason)?;
        s.serialize_field("inputs", &self.inputs)?;
        match &self.path {
            Some(p) => s.serialize_field("features", p)?,
            None => s.serialize_field("features", &self.features)?,
        }
        if let Some(rest) = &self.at_rest {
            s.serialize_field("at_rest", rest)?;
        }
        s.end()
    }
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum RuleId {
    Tumble,
    Lilt,
    Autorotation,
    FlipTransient,
    Dive,
    Flutter,
    FewPeriods,
    SteepRocking,
    Steep,
    Glide,
    Steady,
}

type Rule = rules::Rule<RuleId>;

/// Builds the ordered rule list from the features (thresholds and scales in
/// one place).
fn rules(f: &Features) -> Vec<Rule> {
    use MotionClass as C;
    // Continuous "how close to a flip": flips if any, else the excursion of
    // the normal as a fraction of the excursion a flip needs, kept below 1 so
    // that only a counted flip can fire a rule (a plate hanging steeply
    // upside down has a large excursion without ever flipping).
    let flip_progress = if f.normal_flips > 0 {
        f.normal_flips as f64
    } else {
        (f.max_excursion_deg / (90.0 + FLIP_HYSTERESIS_DEG)).min(0.99)
    };
    let reversals = f.reversals as f64;
    let lilt_rev = LILT_MIN_REVERSALS as f64;
    let rule = |id, class, regime, conds| Rule {
        id,
        class,
        regime,
        conds,
    };
    vec![
        rule(
            RuleId::Tumble,
            C::Spinner,
            Regime::Tumble,
            vec![
                Cond::ge(f.net_turns, SPIN_MIN_NET_TURNS, 1.0),
                Cond::ge(f.rotation_consistency, TUMBLE_MIN_CONSISTENCY, 0.1),
                // A spin about an axis tilted < 45° from vertical has a steady
                // horizontal part too; it is autorotation, not a tumble.
                Cond::lt(f.vertical_spin_share, AUTOROTATION_MIN_VERTICAL_SHARE, 0.3),
            ],
        ),
        rule(
            RuleId::Autorotation,
            C::Spinner,
            Regime::Autorotation,
            // Before the lilt rule: a leaf whose rotation is mostly about the
            // vertical is seen to spin, even if its spin axis leans enough
            // for the normal to cross the horizontal twice a turn (a
            // wobbling spinner "flips" without turning end over end).
            vec![
                Cond::ge(f.yaw_turns.abs(), AUTOROTATION_MIN_YAW_TURNS, 1.0),
                Cond::ge(f.yaw_consistency, AUTOROTATION_MIN_YAW_CONSISTENCY, 0.1),
                Cond::ge(f.vertical_spin_share, AUTOROTATION_MIN_VERTICAL_SHARE, 0.3),
                Cond::ge(f.tilt_mean_deg, AUTOROTATION_MIN_TILT_DEG, 30.0),
            ],
        ),
        rule(
            RuleId::Lilt,
            C::Lilter,
            Regime::Chaotic,
            vec![
                Cond::ge(flip_progress, 1.0, 1.0),
                Cond::ge(reversals, lilt_rev, lilt_rev),
            ],
        ),
        rule(
            RuleId::FlipTransient,
            C::Undetermined,
            Regime::Undetermined,
            vec![
                Cond::ge(flip_progress, 1.0, 1.0),
                Cond::lt(reversals, lilt_rev, lilt_rev),
            ],
        ),
        rule(
            RuleId::Dive,
            C::Undetermined,
            Regime::Dive,
            vec![Cond::ge(f.tilt_p10_deg, DIVE_MIN_TILT_DEG, 30.0)],
        ),
        rule(
            RuleId::Flutter,
            C::Floater,
            Regime::Flutter,
            vec![
                {
                    // Without rocking a steep plate is "undetermined" (rule 9),
                    // a flat one still a floater.
                    let c = Cond::ge(f.rocking_amplitude_deg, FLUTTER_MIN_AMPLITUDE_DEG, 10.0);
                    if f.tilt_mean_deg >= STEEP_TILT_DEG {
                        c
                    } else {
                        c.regime_only()
                    }
                },
                Cond::ge(
                    f.oscillation_periods,
                    MIN_OSCILLATION_PERIODS,
                    MIN_OSCILLATION_PERIODS,
                ),
                // Flutter swings about a flat attitude (Field 1997, APW 2005):
                // the plate passes within 30° of horizontal.
                Cond::lt(f.tilt_p10_deg, STEEP_TILT_DEG, 30.0),
            ],
        ),
        rule(
            RuleId::FewPeriods,
            C::Undetermined,
            Regime::Undetermined,
            vec![
                Cond::ge(f.rocking_amplitude_deg, FLUTTER_MIN_AMPLITUDE_DEG, 10.0),
                Cond::lt(
                    f.oscillation_periods,
                    MIN_OSCILLATION_PERIODS,
                    MIN_OSCILLATION_PERIODS,
                ),
            ],
        ),
        rule(
            RuleId::SteepRocking,
            C::Undetermined,
            Regime::Undetermined,
            vec![
                Cond::ge(f.rocking_amplitude_deg, FLUTTER_MIN_AMPLITUDE_DEG, 10.0),
                Cond::ge(f.tilt_p10_deg, STEEP_TILT_DEG, 30.0),
            ],
        ),
        rule(
            RuleId::Steep,
            C::Undetermined,
            Regime::Undetermined,
            vec![
                Cond::ge(f.tilt_mean_deg, STEEP_TILT_DEG, 30.0),
                Cond::lt(f.rocking_amplitude_deg, FLUTTER_MIN_AMPLITUDE_DEG, 10.0),
            ],
        ),
        rule(
            RuleId::Glide,
            C::Floater,
            Regime::Glide,
            vec![
                Cond::ge(f.drift_ratio, GLIDE_MIN_DRIFT_RATIO, GLIDE_MIN_DRIFT_RATIO).regime_only(),
            ],
        ),
        rule(RuleId::Steady, C::Floater, Regime::Steady, vec![]),
    ]
}

/// Applies the rules to sufficient data and fills in margins and the reason.
pub(super) fn decide(mut f: Features) -> Classification {
    let rules = rules(&f);
    // The last rule has no conditions, so one always fires.
    let k = rules
        .iter()
        .position(Rule::fires)
        .unwrap_or(rules.len() - 1);
    let chosen = &rules[k];
    (f.margin, f.regime_margin) = rules::margins(&rules, k);
    let reason = reason(chosen.id, &f);
    Classification {
        class: chosen.class,
        regime: chosen.regime,
        reason: Some(reason),
        inputs: Inputs::Orientation,
        features: f,
        path: None,
        at_rest: None,
    }
}

/// Human-readable justification quoting the deciding features.
fn reason(id: RuleId, f: &Features) -> String {
    match id {
        RuleId::Tumble => format!(
            "tumble about a horizontal axis: {:.1} net turns, rotation consistency {:.2}, {} normal flips",
            f.net_turns, f.rotation_consistency, f.normal_flips
        ),
        RuleId::Lilt => format!(
            "rocks and flips: {} normal flips and {} pitch reversals, rotation consistency {:.2} (not a tumble)",
            f.normal_flips, f.reversals, f.rotation_consistency
        ),
        RuleId::Autorotation => format!(
            "autorotation about the vertical: {:.1} yaw turns at {:.1} rad/s, plate tilted {:.0}° from horizontal, vertical share of spin {:.2}",
            f.yaw_turns.abs(),
            f.mean_yaw_rate_rad_s.abs(),
            f.tilt_mean_deg,
            f.vertical_spin_share
        ),
        RuleId::FlipTransient => format!(
            "flipped over {} time(s) without rocking and without a full turn: too transient to tell",
            f.normal_flips
        ),
        RuleId::Dive => format!(
            "dive: plate within 30° of edge-on 90 % of the time (10th-percentile tilt {:.0}°, mean {:.0}°), no rotation, falling at {:.2} m/s ({:.1} chords/s); not a floater (notes §4e)",
            f.tilt_p10_deg, f.tilt_mean_deg, f.mean_descent_speed_m_s, f.descent_speed_chords_per_s
        ),
        RuleId::Flutter => format!(
            "flutter: rocks ±{:.0}° with period {} ({} reversals), no flips",
            f.rocking_amplitude_deg,
            f.oscillation_period_s
                .map_or_else(|| "?".to_string(), |p| format!("{p:.3} s")),
            f.reversals
        ),
        RuleId::FewPeriods => format!(
            "rocks ±{:.0}° but only {:.1} oscillation periods in the window (need {MIN_OSCILLATION_PERIODS}): too transient to tell",
            f.rocking_amplitude_deg, f.oscillation_periods
        ),
        RuleId::SteepRocking => format!(
            "rocks ±{:.0}° about a steep attitude (mean tilt {:.0}°, within 30° of flat less than 10 % of the time): neither flutter nor dive",
            f.rocking_amplitude_deg, f.tilt_mean_deg
        ),
        RuleId::Steep => format!(
            "steady at a mean tilt of {:.0}° from horizontal: between glide and dive (notes §4e), neither clearly floater nor diver",
            f.tilt_mean_deg
        ),
        RuleId::Glide => format!(
            "glide: steady attitude (tilt {:.0}° ± {:.0}°), drift ratio {:.2}",
            f.tilt_mean_deg, f.tilt_std_deg, f.drift_ratio
        ),
        RuleId::Steady => format!(
            "steady: attitude within ±{FLUTTER_MIN_AMPLITUDE_DEG}° (tilt {:.0}° ± {:.0}°), drift ratio {:.2}",
            f.tilt_mean_deg, f.tilt_std_deg, f.drift_ratio
        ),
    }
}
