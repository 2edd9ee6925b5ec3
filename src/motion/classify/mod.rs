//! Names the motion of a fall — floater, spinner or lilter (Haumann et al.
//! 1991, §4.1) — from its trajectory alone.
//!
//! Its files, one job each: `features` (step 3: the kinematics of a pose
//! record, [`Features`]) and `tests`; this file keeps the checks and the
//! window (steps 1–2), the rules (step 4) and the entry points, and
//! re-exports what the others make public, so every
//! `motion::classify::…` path is unchanged.
//!
//! # Method
//!
//! 1. **Checks**: ≥ 60 Hz sampling, no gap over 1.5 frames at 60 Hz.
//! 2. **Window**: the first [`TRANSIENT_FRACTION`] of the record's duration is
//!    discarded as start-up transient; the rest must hold
//!    ≥ [`MIN_WINDOW_SAMPLES`] samples and ≥ [`MIN_DESCENT_CHORDS`] chord
//!    lengths of descent, else the result is `Undetermined` with a reason.
//! 3. **Kinematics** (all rate independent): the world angular increment
//!    between samples, r = log(q₁ q₀⁻¹) (shortest arc, so q ≡ −q is harmless),
//!    split into a vertical part (yaw, ψ = Σ r_z) and a horizontal part
//!    (pitch/roll). The dominant pitch/roll axis is the principal axis of
//!    ∫ω_h ω_hᵀ dt, held fixed in the body (ω_h mapped with the mid-interval
//!    orientation) or in the world, whichever frame concentrates more of the
//!    horizontal rotation on one axis: a body-fixed axis follows a leaf that
//!    rocks or tumbles about its own span while yawing (most lilters,
//!    docs/falling-plates.md, "Folded leaves under the linear law"; the
//!    precessing MuJoCo card). The pitch angle θ(t) is the integral of ω_h
//!    about that axis; its turning points (swings ≥ 10°) are the reversals.
//!    The plate normal is body z; a flip is the normal crossing the
//!    horizontal plane with ±30° hysteresis.
//! 4. **Rules**, first match wins (docs/falling-plates.md, "Classifier rules",
//!    reordered as the boundary cases in "Folded leaves under the linear law"
//!    demand: flips and reversals are looked at before a *slow* turn about the
//!    vertical — lilters yaw at 1–9 rad/s — but a rotation that is mostly
//!    about the vertical, vertical share ≥ 0.7, i.e. an axis within ~45° of
//!    it, is autorotation even when its leaning axis makes the normal cross
//!    the horizontal: such a leaf spins, it does not turn end over end):
//!
//! | # | class / regime | conditions |
//! |---|---|---|
//! | 1 | spinner / tumble | net turns about the horizontal axis ≥ 1, rotation consistency ≥ 0.9, vertical share of ω < 0.7 |
//! | 2 | spinner / autorotation | yaw turns ≥ 1, yaw consistency ≥ 0.9, vertical share of ω ≥ 0.7, mean plate tilt ≥ 30° |
//! | 3 | lilter / chaotic | ≥ 1 normal flip, ≥ 2 pitch reversals |
//! | 4 | undetermined | ≥ 1 flip but < 2 reversals (one flip, no rocking: transient) |
//! | 5 | undetermined / dive | plate within 30° of edge-on 90 % of the time (10th percentile tilt ≥ 60°) |
//! | 6 | floater / flutter | rocking amplitude ≥ 10°, ≥ 3 periods, 10th percentile tilt < 30° (swings through flat) |
//! | 7 | undetermined | rocking amplitude ≥ 10° but < 3 periods (too transient) |
//! | 8 | undetermined | rocking ≥ 10° about a steep attitude (10th percentile tilt ≥ 30°) |
//! | 9 | undetermined | mean tilt ≥ 30° without rocking: between glide and dive (docs/falling-plates.md, "Folded leaves under the linear law") |
//! | 10 | floater / glide | drift ratio ≥ 0.1 |
//! | 11 | floater / steady | otherwise |
//!
//! # Margin
//!
//! Every condition is `feature ≥ threshold` (or `<`) with a natural scale:
//! 1 turn (net or yaw turns), 0.1 (consistencies), 0.3 (vertical share),
//! 2 reversals, 3 periods, 10° (amplitude), 30° (tilts), 0.1 (drift ratio),
//! and for flips a continuous "flip progress" (the flip count, or without a
//! flip the normal's largest excursion / 120°) with scale 1. Its *slack* is
//! (feature − threshold)/scale,
//! positive when the condition holds. A rule that did not fire is at
//! distance max over its conditions of the missing slack (all of them must be
//! met for it to fire). [`Features::margin`] is the smallest of: the slacks
//! of the firing rule's conditions whose failure would change the *class*,
//! and the distances to every earlier rule of a different class; it is
//! clipped to [0, 1] (1 = at least one full scale unit from any class
//! boundary). [`Features::regime_margin`] is the same counting every rule
//! and condition (distance to the nearest regime boundary). Both are 0 when
//! the record is insufficient.

mod features;

pub use crate::motion::class::{MotionClass, ParseNameError, Regime};
pub use features::{
    AxisFrame, FLIP_HYSTERESIS_DEG, Features, REVERSAL_MIN_SWING_DEG, pose_features,
};

use serde::Serialize;

use crate::motion::path::{Inputs, PathFeatures, classify_path};
use crate::motion::rules::{self, Cond};
use crate::motion::trajectory::Trajectory;
use features::extract;

// ---------------------------------------------------------------- thresholds

/// Lowest accepted sampling rate, Hz. Field et al. (1997) recorded θ(t) at
/// 60 Hz; the issue requires correct results from 60 Hz up.
pub const MIN_SAMPLE_RATE_HZ: f64 = 60.0;

/// Relative slack on [`MIN_SAMPLE_RATE_HZ`]: time stamps are often printed
/// with 6 decimals (the MuJoCo files), which jitters 1/60 s by ~1e-4.
pub const SAMPLE_RATE_TOLERANCE: f64 = 0.01;

/// Longest accepted interval between two samples in the window, s: one
/// dropped frame at the minimum rate (our choice).
pub const MAX_GAP_S: f64 = 1.5 / MIN_SAMPLE_RATE_HZ;

/// Fraction of the record's duration discarded as start-up transient.
/// Classify only the last 50–70 % of the fall (docs/falling-plates.md,
/// "Classifier rules", step 1); we keep 60 %.
pub const TRANSIENT_FRACTION: f64 = 0.4;

/// Fewest samples in the analysis window (1 s at the minimum rate; our
/// choice, so that rates and periods have support).
pub const MIN_WINDOW_SAMPLES: usize = 60;

/// Fewest chord lengths of descent in the analysis window
/// (docs/falling-plates.md, "Classifier rules", step 1; Howison & Iida 2020
/// drops are ≈ 10–30 sizes).
pub const MIN_DESCENT_CHORDS: f64 = 10.0;

/// Fewest oscillation periods needed to call a rocking fall a flutter
/// (docs/falling-plates.md, "Classifier rules", step 1).
pub const MIN_OSCILLATION_PERIODS: f64 = 3.0;

/// Fewest net turns about the dominant horizontal axis for a tumble
/// (docs/falling-plates.md, "Classifier rules", step 4: N_turn ≥ 1); a
/// floater cannot turn past ±90° (Belmonte, Eisenberg & Moses 1998, Phys.
/// Rev. Lett. 81, 345; Andersen, Pesavento & Wang 2005, J. Fluid Mech. 541,
/// 65).
pub const SPIN_MIN_NET_TURNS: f64 = 1.0;

/// Least rotation consistency |∫ω dt| / ∫|ω| dt about the horizontal axis for
/// a tumble: "ω keeps its sign" (Belmonte 1998, APW 2005); s > 0.9 in
/// docs/falling-plates.md, "Classifier rules", step 4.
pub const TUMBLE_MIN_CONSISTENCY: f64 = 0.9;

/// Fewest pitch reversals (rocks) for a lilter: Field et al. 1997 chaotic =
/// oscillation, then a flip, irregularly; "reversals between flips" in
/// docs/falling-plates.md, "Classifier rules", step 4.
pub const LILT_MIN_REVERSALS: usize = 2;

/// Smallest rocking amplitude of a flutter, degrees (half the mean swing).
/// Steady if θ stays within ~10°, flutter otherwise (docs/falling-plates.md,
/// "Classifier rules", step 4).
pub const FLUTTER_MIN_AMPLITUDE_DEG: f64 = 10.0;

/// Fewest turns about the vertical for autorotation (N_z ≥ 1:
/// docs/falling-plates.md, "Classifier rules", step 4).
pub const AUTOROTATION_MIN_YAW_TURNS: f64 = 1.0;

/// Least yaw consistency |∫ω_z dt| / ∫|ω_z| dt for autorotation (the
/// vertical counterpart of [`TUMBLE_MIN_CONSISTENCY`]).
pub const AUTOROTATION_MIN_YAW_CONSISTENCY: f64 = 0.9;

/// Least |mean ω_z| / rms |ω| for autorotation: the spin axis lies on
/// average within ~45° of the vertical. Lilters also yaw at 1–9 rad/s
/// (docs/falling-plates.md, "Folded leaves under the linear law") but their
/// rocking and flips dominate ω.
pub const AUTOROTATION_MIN_VERTICAL_SHARE: f64 = 0.7;

/// Least mean plate tilt for autorotation, degrees. Autorotating spinners'
/// planes sat 42–103° from horizontal (docs/falling-plates.md, "Folded leaves
/// under the linear law"); a flat leaf turning about its own normal is still a
/// floater ("did not rotate" visibly).
pub const AUTOROTATION_MIN_TILT_DEG: f64 = 30.0;

/// Dive: the plate spends 90 % of the window within 30° of edge-on (10th
/// percentile of tilt ≥ 60°). Divers fall edge-on; planes 30–60° from
/// edge-on are "neither clearly floater nor diver" (docs/falling-plates.md,
/// "Folded leaves under the linear law").
pub const DIVE_MIN_TILT_DEG: f64 = 60.0;

/// Mean tilt above which a non-rocking, non-rotating fall is neither a clear
/// floater nor a diver, degrees (30–60° from edge-on: docs/falling-plates.md,
/// "Folded leaves under the linear law").
pub const STEEP_TILT_DEG: f64 = 30.0;

/// Least drift ratio (horizontal displacement / fall) for a glide: a path
/// ≥ 5.7° from vertical. Our choice: steady fallers and flutterers have zero
/// mean drift (Field 1997, APW 2005), tumblers 0.5–2.3 (docs/falling-plates.md,
/// "Measured regimes", row 4, and "Classifier rules").
pub const GLIDE_MIN_DRIFT_RATIO: f64 = 0.1;

// ---------------------------------------------------------------- public types

/// Result of [`classify`].
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
        s.end()
    }
}

/// What [`classify_with`] may look at.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ClassifyOptions {
    /// Use the orientation when the record has one (the full classifier);
    /// otherwise classify from the path.
    pub orientation: bool,
    /// Use the projected-area signals when the path decides.
    pub areas: bool,
}

impl Default for ClassifyOptions {
    fn default() -> Self {
        ClassifyOptions {
            orientation: true,
            areas: true,
        }
    }
}

// ---------------------------------------------------------------- classify

/// Classifies a fall from everything its record holds: from the
/// orientation when it has one (this module's method), else from the path
/// and any area signals ([`crate::motion::path`]). `size` is the leaf's
/// chord (longest extent), m.
pub fn classify(trajectory: &Trajectory, size: f64) -> Classification {
    classify_with(trajectory, size, ClassifyOptions::default())
}

/// [`classify`] with a choice of inputs: e.g. the path only of a pose
/// record, to compare with what video of the same fall would say.
pub fn classify_with(trajectory: &Trajectory, size: f64, use_: ClassifyOptions) -> Classification {
    let posed = !trajectory.orientation.is_empty() || trajectory.time.is_empty();
    if use_.orientation && posed {
        return classify_pose(trajectory, size);
    }
    let v = classify_path(trajectory, size, use_.areas);
    let p = &v.features;
    let features = Features {
        t_start_s: p.t_start_s,
        t_end_s: p.t_end_s,
        samples: p.samples,
        sample_rate_hz: p.sample_rate_hz,
        max_gap_s: p.longest_gap_s,
        descent_m: p.descent_m,
        descent_chords: p.descent_chords,
        mean_descent_speed_m_s: p.mean_descent_speed_m_s,
        descent_speed_chords_per_s: if p.t_end_s > p.t_start_s {
            p.descent_chords / (p.t_end_s - p.t_start_s)
        } else {
            0.0
        },
        descent_speed_cv: p.descent_speed_cv,
        drift_ratio: p.drift_ratio,
        margin: p.margin,
        regime_margin: p.regime_margin,
        ..Features::default()
    };
    Classification {
        class: v.class,
        regime: v.regime,
        reason: Some(v.reason),
        inputs: v.inputs,
        features,
        path: Some(v.features),
    }
}

/// The classifier from the orientation (module docs).
fn classify_pose(trajectory: &Trajectory, size: f64) -> Classification {
    let undetermined = |features: Features, why: String| Classification {
        class: MotionClass::Undetermined,
        regime: Regime::Undetermined,
        reason: Some(why),
        inputs: Inputs::Orientation,
        features,
        path: None,
    };
    let tr = trajectory;
    let n = tr.time.len();
    if !(size.is_finite() && size > 0.0) {
        return undetermined(
            Features::default(),
            format!("leaf size must be positive and finite, got {size}"),
        );
    }
    if tr.position.len() != n || tr.orientation.len() != n {
        return undetermined(
            Features::default(),
            format!(
                "inconsistent trajectory: {} times, {} positions, {} orientations",
                n,
                tr.position.len(),
                tr.orientation.len()
            ),
        );
    }
    if n < 2 {
        return undetermined(
            Features::default(),
            format!("too few samples: {n} (need {MIN_WINDOW_SAMPLES} in the analysis window)"),
        );
    }
    for k in 0..n {
        let p = &tr.position[k];
        let q = &tr.orientation[k].coords;
        if !(tr.time[k].is_finite()
            && p.iter().all(|x| x.is_finite())
            && q.iter().all(|x| x.is_finite()))
        {
            return undetermined(
                Features::default(),
                format!("non-finite value at sample {}", k + 1),
            );
        }
        if k > 0 && tr.time[k] <= tr.time[k - 1] {
            return undetermined(
                Features::default(),
                format!("time not strictly increasing at sample {}", k + 1),
            );
        }
    }

    // Sampling rate from the median interval (robust to an odd jitter).
    let mut dts: Vec<f64> = tr.time.windows(2).map(|w| w[1] - w[0]).collect();
    let mid = dts.len() / 2;
    let median_dt = *dts.select_nth_unstable_by(mid, f64::total_cmp).1;
    drop(dts);
    let rate = 1.0 / median_dt;

    let t0 = tr.time[0];
    let t_start = t0 + TRANSIENT_FRACTION * (tr.time[n - 1] - t0);
    let i0 = tr.time.partition_point(|&t| t < t_start).min(n - 1);
    let mut f = extract(tr, i0, size);
    f.sample_rate_hz = rate;

    if rate < MIN_SAMPLE_RATE_HZ * (1.0 - SAMPLE_RATE_TOLERANCE) {
        return undetermined(
            f,
            format!("sampled at {rate:.1} Hz, below the {MIN_SAMPLE_RATE_HZ} Hz minimum"),
        );
    }
    if f.samples < MIN_WINDOW_SAMPLES {
        return undetermined(
            f.clone(),
            format!(
                "too few samples: {} in the analysis window {:.3}–{:.3} s (need {MIN_WINDOW_SAMPLES}); record too short",
                f.samples, f.t_start_s, f.t_end_s
            ),
        );
    }
    if f.max_gap_s > MAX_GAP_S {
        return undetermined(
            f.clone(),
            format!(
                "gap of {:.4} s between samples (more than {MAX_GAP_S:.4} s: locally below {MIN_SAMPLE_RATE_HZ} Hz)",
                f.max_gap_s
            ),
        );
    }
    if f.descent_chords < MIN_DESCENT_CHORDS {
        return undetermined(
            f.clone(),
            format!(
                "fell only {:.2} chord lengths in the analysis window {:.3}–{:.3} s (need {MIN_DESCENT_CHORDS}); record too short or not falling",
                f.descent_chords, f.t_start_s, f.t_end_s
            ),
        );
    }
    decide(f)
}

// ---------------------------------------------------------------- features

// ---------------------------------------------------------------- rules

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
fn decide(mut f: Features) -> Classification {
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

#[cfg(test)]
mod tests;
