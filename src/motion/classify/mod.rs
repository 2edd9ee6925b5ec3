//! Names the motion of a fall — floater, spinner or lilter (Haumann et al.
//! 1991, §4.1) — from its trajectory alone.
//!
//! Its files, one job each: `features` (step 3: the kinematics of a pose
//! record, [`Features`]), `rules` (step 4: the rules and their
//! thresholds, and the [`Classification`] they give with its margins and
//! reason) and `tests`; this file keeps the checks and the window (steps
//! 1–2) with their thresholds, [`ClassifyOptions`] and the entry points,
//! and re-exports what the others make public, so every
//! `motion::classify::…` path is unchanged.
//!
//! # Method
//!
//! 0. **In the air**: a still start before release and a still end after
//!    landing are left out ([`crate::motion::at_rest`]), and said.
//! 1. **Checks**: ≥ [`MIN_SAMPLE_RATE_HZ`] sampling, no gap over 1.5
//!    frames at that rate, no rotation between two samples past
//!    [`MAX_SAMPLE_TURN_DEG`].
//! 2. **Window**: the first [`TRANSIENT_FRACTION`] of the record's duration is
//!    discarded as start-up transient; the rest must hold
//!    ≥ [`MIN_WINDOW_SAMPLES`] samples (or span [`MIN_WINDOW_S`]) and ≥ [`MIN_DESCENT_CHORDS`] chord
//!    lengths of descent, else the result is `Undetermined` with a reason.
//! 3. **Kinematics** (all rate independent): the world angular increment
//!    between samples, r = log(q₁ q₀⁻¹) (shortest arc, so q ≡ −q is harmless),
//!    split into a vertical part (yaw, ψ = Σ r_z) and a horizontal part
//!    (pitch/roll). The dominant pitch/roll axis is the principal axis of
//!    ∫ω_h ω_hᵀ dt, held fixed in the body (ω_h mapped with the mid-interval
//!    orientation) or in the world, whichever frame concentrates more of the
//!    horizontal rotation on one axis: a body-fixed axis follows a leaf that
//!    rocks or tumbles about its own span while yawing (most lilters,
//!    docs/design/falling-plates.md, "Folded leaves under the linear law"; the
//!    precessing MuJoCo card). The pitch angle θ(t) is the integral of ω_h
//!    about that axis; its turning points (swings ≥ 10°) are the reversals.
//!    The plate normal is body z; a flip is the normal crossing the
//!    horizontal plane with ±30° hysteresis.
//! 4. **Rules**, first match wins (docs/design/falling-plates.md, "Classifier rules",
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
//! | 9 | undetermined | mean tilt ≥ 30° without rocking: between glide and dive (docs/design/falling-plates.md, "Folded leaves under the linear law") |
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
mod rules;

pub use crate::motion::class::{MotionClass, ParseNameError, Regime};
pub use features::{
    AxisFrame, FLIP_HYSTERESIS_DEG, Features, REVERSAL_MIN_SWING_DEG, pose_features,
};
pub use rules::{
    AUTOROTATION_MIN_TILT_DEG, AUTOROTATION_MIN_VERTICAL_SHARE, AUTOROTATION_MIN_YAW_CONSISTENCY,
    AUTOROTATION_MIN_YAW_TURNS, Classification, DIVE_MIN_TILT_DEG, FLUTTER_MIN_AMPLITUDE_DEG,
    GLIDE_MIN_DRIFT_RATIO, LILT_MIN_REVERSALS, MIN_OSCILLATION_PERIODS, SPIN_MIN_NET_TURNS,
    STEEP_TILT_DEG, TUMBLE_MIN_CONSISTENCY,
};

use crate::motion::at_rest;
use crate::motion::path::{Inputs, classify_path};
use crate::motion::trajectory::Trajectory;
use features::extract;
use rules::decide;

// ---------------------------------------------------------------- thresholds

/// The chord a fall is classified at when nothing gives its size (a CSV
/// record without `--size`, a particle whose cache has no widths), m: a
/// leaf of the prototypes' size (prototype A's chord is 4.8 cm).
pub const DEFAULT_CHORD_M: f64 = 0.05;

/// Lowest accepted sampling rate, Hz: film's 24 frames per second (and,
/// with [`SAMPLE_RATE_TOLERANCE`], NTSC's 23.976), the slowest rate an
/// animation pipeline bakes a simulation at. Every rule is written in
/// seconds, turns and degrees, not in samples, and measured so: the 245
/// falls of the classifier's corpus and its held-out falls get at 24 Hz
/// the class they get at 240 Hz (`cargo run --release
/// --example real_falls_classify`, docs/guide/classification.md, "Frame rates"). What a
/// slow rate cannot follow, a rotation near half a turn per sample, is
/// checked on the record itself ([`MAX_SAMPLE_TURN_DEG`]).
pub const MIN_SAMPLE_RATE_HZ: f64 = 24.0;

/// Relative slack on [`MIN_SAMPLE_RATE_HZ`]: time stamps are often printed
/// with 6 decimals (the MuJoCo files), which jitters 1/60 s by ~1e-4.
pub const SAMPLE_RATE_TOLERANCE: f64 = 0.01;

/// Longest accepted interval between two samples in the window, s: one
/// dropped frame at the minimum rate (our choice).
pub const MAX_GAP_S: f64 = 1.5 / MIN_SAMPLE_RATE_HZ;

/// Largest rotation between two consecutive samples, degrees. The
/// rotation from one sample to the next is read as the shortest one, so a
/// leaf turning more than half a turn per sample reads as turning the
/// other way, and near half a turn its direction flips from sample to
/// sample (a spin would read as rocking). Our choice, 20° short of the
/// half turn: the corpus's fastest spinner (53 rad/s) turns 127° per
/// sample at 24 Hz and 153° at 20 Hz, and is classified at both as at 240
/// Hz.
pub const MAX_SAMPLE_TURN_DEG: f64 = 160.0;

/// Fraction of the record's duration discarded as start-up transient.
/// Classify only the last 50–70 % of the fall (docs/design/falling-plates.md,
/// "Classifier rules", step 1); we keep 60 %.
pub const TRANSIENT_FRACTION: f64 = 0.4;

/// Fewest samples in the analysis window, unless it spans
/// [`MIN_WINDOW_S`] (our choice, so that rates and periods have support:
/// 0.25 s at leafmagic's 240 Hz, 1 s at 60 Hz).
pub const MIN_WINDOW_SAMPLES: usize = 60;

/// A window this long is enough whatever its sample count, s: what
/// [`MIN_WINDOW_SAMPLES`] is at 60 Hz, so that from 24 to 60 Hz a record
/// needs the same 1.67 s as at 60 (at 24 Hz, 60 samples would ask 4.2 s).
/// At 60 Hz and faster the sample count decides, as before.
pub const MIN_WINDOW_S: f64 = 1.0;

/// Whether an analysis window holds enough to classify: at least
/// [`MIN_WINDOW_SAMPLES`] samples, or [`MIN_WINDOW_S`] of record.
pub fn window_is_long_enough(f: &Features) -> bool {
    f.samples >= MIN_WINDOW_SAMPLES || f.t_end_s - f.t_start_s >= MIN_WINDOW_S
}

/// Fewest chord lengths of descent in the analysis window
/// (docs/design/falling-plates.md, "Classifier rules", step 1; Howison & Iida 2020
/// drops are ≈ 10–30 sizes).
pub const MIN_DESCENT_CHORDS: f64 = 10.0;

// ---------------------------------------------------------------- public types

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
/// record, to compare with what video of the same fall would say. Either
/// way only the part of the record in the air is classified (step 0), and
/// a pose record whose orientation the checks of step 1 refuse is named
/// from its path instead.
pub fn classify_with(trajectory: &Trajectory, size: f64, use_: ClassifyOptions) -> Classification {
    // The fall is what the leaf does in the air: a still start before
    // release and a still end after landing are left out, and said.
    if let Some((air, rest)) = at_rest::in_air(trajectory, size) {
        let mut c = classify_in_air(&air, size, use_);
        c.reason = c.reason.map(|r| format!("{r} ({})", rest.describe()));
        c.at_rest = Some(rest);
        return c;
    }
    classify_in_air(trajectory, size, use_)
}

/// [`classify_with`] of a record that is all in the air.
fn classify_in_air(trajectory: &Trajectory, size: f64, use_: ClassifyOptions) -> Classification {
    let posed = !trajectory.orientation.is_empty() || trajectory.time.is_empty();
    if use_.orientation && posed {
        match classify_pose(trajectory, size) {
            Ok(c) => return c,
            // The orientation is sampled too coarsely (or too briefly) for
            // its rules, but the path rules may still name the fall, as
            // they would if the file had no orientation: a record with
            // more in it should not get less of an answer.
            Err(pose) => return from_path_instead(trajectory, size, use_.areas, *pose),
        }
    }
    path_classification(trajectory, size, use_.areas)
}

/// The path's verdict for a pose record whose orientation cannot be used
/// (`pose`, undetermined with the reason): the path's class if it names
/// one, with both reasons; else `pose`'s, with the path's reason added.
fn from_path_instead(
    trajectory: &Trajectory,
    size: f64,
    areas: bool,
    pose: Classification,
) -> Classification {
    let why = pose.reason.clone().unwrap_or_default();
    let mut c = path_classification(trajectory, size, areas);
    let path_reason = c.reason.take().unwrap_or_default();
    if c.class == MotionClass::Undetermined {
        return Classification {
            reason: Some(format!("{why}; from the path alone: {path_reason}")),
            ..pose
        };
    }
    c.reason = Some(format!(
        "{path_reason} (from the path: the orientation is not used, {why})"
    ));
    c
}

/// [`classify_path`]'s verdict as a [`Classification`].
fn path_classification(trajectory: &Trajectory, size: f64, areas: bool) -> Classification {
    let v = classify_path(trajectory, size, areas);
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
        at_rest: None,
    }
}

/// The classifier from the orientation (module docs).
fn classify_pose(
    trajectory: &Trajectory,
    size: f64,
) -> Result<Classification, Box<Classification>> {
    let undetermined = |features: Features, why: String| Classification {
        class: MotionClass::Undetermined,
        regime: Regime::Undetermined,
        reason: Some(why),
        inputs: Inputs::Orientation,
        features,
        path: None,
        at_rest: None,
    };
    let tr = trajectory;
    let n = tr.time.len();
    if !(size.is_finite() && size > 0.0) {
        return Ok(undetermined(
            Features::default(),
            format!("leaf size must be positive and finite, got {size}"),
        ));
    }
    if tr.position.len() != n || tr.orientation.len() != n {
        return Ok(undetermined(
            Features::default(),
            format!(
                "inconsistent trajectory: {} times, {} positions, {} orientations",
                n,
                tr.position.len(),
                tr.orientation.len()
            ),
        ));
    }
    if n < 2 {
        return Ok(undetermined(
            Features::default(),
            format!("too few samples: {n} (need {MIN_WINDOW_SAMPLES} in the analysis window)"),
        ));
    }
    for k in 0..n {
        let p = &tr.position[k];
        let q = &tr.orientation[k].coords;
        if !(tr.time[k].is_finite()
            && p.iter().all(|x| x.is_finite())
            && q.iter().all(|x| x.is_finite()))
        {
            return Ok(undetermined(
                Features::default(),
                format!("non-finite value at sample {}", k + 1),
            ));
        }
        if k > 0 && tr.time[k] <= tr.time[k - 1] {
            return Ok(undetermined(
                Features::default(),
                format!("time not strictly increasing at sample {}", k + 1),
            ));
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
        return Err(Box::new(undetermined(
            f,
            format!("sampled at {rate:.1} Hz, below the {MIN_SAMPLE_RATE_HZ} Hz minimum"),
        )));
    }
    if !window_is_long_enough(&f) {
        return Err(Box::new(undetermined(
            f.clone(),
            format!(
                "too few samples: {} in the analysis window {:.3}–{:.3} s (need {MIN_WINDOW_SAMPLES}, or {MIN_WINDOW_S} s); record too short",
                f.samples, f.t_start_s, f.t_end_s
            ),
        )));
    }
    if f.max_gap_s > MAX_GAP_S {
        return Err(Box::new(undetermined(
            f.clone(),
            format!(
                "gap of {:.4} s between samples (more than {MAX_GAP_S:.4} s: locally below {MIN_SAMPLE_RATE_HZ} Hz)",
                f.max_gap_s
            ),
        )));
    }
    if f.max_sample_turn_deg > MAX_SAMPLE_TURN_DEG {
        let needed = rate * f.max_sample_turn_deg / (0.5 * MAX_SAMPLE_TURN_DEG);
        return Err(Box::new(undetermined(
            f.clone(),
            format!(
                "turns {:.0}° between two samples (more than {MAX_SAMPLE_TURN_DEG}°): at {rate:.1} Hz the direction of so fast a rotation cannot be told; sample at {needed:.0} Hz or more",
                f.max_sample_turn_deg
            ),
        )));
    }
    if f.descent_chords < MIN_DESCENT_CHORDS {
        return Ok(undetermined(
            f.clone(),
            format!(
                "fell only {:.2} chord lengths in the analysis window {:.3}–{:.3} s (need {MIN_DESCENT_CHORDS}); record too short or not falling{}",
                f.descent_chords,
                f.t_start_s,
                f.t_end_s,
                crate::motion::path::rising_hint(f.descent_chords, MIN_DESCENT_CHORDS)
            ),
        ));
    }
    Ok(decide(f))
}

#[cfg(test)]
mod tests;
