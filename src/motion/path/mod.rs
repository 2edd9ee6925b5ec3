//! Names the motion of a fall from its path alone — and from the projected
//! areas a camera saw, when the record has them — as video tracking gives
//! falls: positions, maybe silhouettes, no rotation, a second or two,
//! noise, gaps.
//!
//! Its files, one job each: `features` (step 3: velocities and the path
//! features, [`PathFeatures`]), `areas` (step 4: the area features),
//! `signal` (the tools both measure with: local-fit slopes, noise,
//! detrending, periodicity) and `rules` (step 5: the rules and their
//! thresholds, [`Calibration`], and the verdict); this file keeps the
//! checks and the window (steps 1–2) with their thresholds and the entry
//! points, and re-exports what the others make public, so every
//! `motion::path::…` path is unchanged.
//!
//! # Method
//!
//! 1. **Checks**: ≥ [`MIN_PATH_SAMPLE_RATE_HZ`] sampling, ≥
//!    [`MIN_PATH_DURATION_S`] of record, gaps (intervals longer than
//!    [`GAP_FACTOR`] × the median one) no longer than [`MAX_GAP_S`] each and
//!    [`MAX_GAP_SHARE`] of the window in all, else `Undetermined` with the
//!    reason. The record is then put on a uniform grid at its median rate by
//!    linear interpolation (uneven steps and short gaps, which are counted
//!    and reported).
//! 2. **Window**: a record longer than [`WHOLE_RECORD_S`] loses its start as
//!    the full classifier's does (the first [`TRANSIENT_FRACTION`]), but never down to
//!    less than [`WHOLE_RECORD_S`]; a shorter one is taken whole (a real
//!    drop of about a metre lasts 1–1.5 s from release). It must fall at
//!    least [`MIN_PATH_DESCENT_CHORDS`] chord lengths ("not falling"
//!    otherwise).
//! 3. **Path**: velocities by a local linear fit over ±[`SMOOTHING_S`]
//!    (noise of a millimetre at 100 Hz moves them by ~1 cm/s). From them:
//!    the descent speed and its spread, the drift ratio (glide angle), the
//!    straightness of the horizontal path |∫v_h dt| / ∫|v_h| dt (1: a
//!    straight slanted line, ~0: swinging back and forth), the reversals of
//!    the horizontal velocity along its dominant axis (a swing), and the
//!    turning of the horizontal velocity's direction (a helix).
//! 4. **Areas** (each signal detrended): maxima per second (swings of at
//!    least [`AREA_MIN_SWING`] of the signal's range and
//!    [`AREA_MIN_SWING_OF_LEVEL`] of its mean level) — a plate turning
//!    about a horizontal axis shows two per turn, so the turn rate is π ×
//!    maxima per second — and the periodicity of the signal (its
//!    autocorrelation at the first peak after the first zero).
//! 5. **Rules**, first match wins (the thresholds and where they come from
//!    are the constants below; docs/guide/classification.md reports how they
//!    were calibrated and checked).
//!
//! "Steady" is a modulation below
//! [`STEADY_MAX_MODULATION`] (or below what the record's noise leaves,
//! [`PathFeatures::modulation_noise`], if that is larger):
//!
//! | # | class / regime | conditions |
//! |---|---|---|
//! | 1 | spinner / autorotation | a tight helix: the horizontal velocity turns ≥ [`HELIX_MIN_TURNS`] the same way (≥ [`HELIX_MIN_CONSISTENCY`]) round a circle of radius < [`HELIX_MAX_RADIUS_CHORDS`], modulation < [`HELIX_MAX_MODULATION`] |
//! | 2 | floater / flutter | ≥ [`FLUTTER_MIN_REVERSALS`] reversals of a swing with periodicity ≥ [`FLUTTER_MIN_PERIODICITY`] that comes to rest at each (horizontal speed spread ≥ [`FLUTTER_MIN_SPEED_SPREAD`]), drift < [`GLIDE_MIN_DRIFT`] |
//! | 3 | floater / steady | steady, drift < [`GLIDE_MIN_DRIFT`], Fr < [`STEADY_MAX_FROUDE`] |
//! | 4 | spinner / autorotation | steady, drift < [`GLIDE_MIN_DRIFT`], Fr ≥ [`STEADY_MAX_FROUDE`]: straight down, fast (or an edge-on dive: the path cannot tell) |
//! | 5 | floater / glide | steady, drift ≥ [`GLIDE_MIN_DRIFT`]; with areas, if the record's jitter hides a modulation of [`STEADY_MAX_MODULATION`], < [`TUMBLE_MIN_AREA_MAXIMA_PER_S`] area maxima per second (no plate turning at a tumble's rate) |
//! | 6 | spinner / tumble | straightness ≥ [`TUMBLE_MIN_STRAIGHTNESS`], drift ≥ [`GLIDE_MIN_DRIFT`] (modulated); with areas, ≥ [`TUMBLE_MIN_AREA_MAXIMA_PER_S`] area maxima per second |
//! | 6b | spinner / tumble | with areas only: as 6 but turning regularly instead of fast: area periodicity ≥ [`TUMBLE_MIN_AREA_PERIODICITY`] and ≥ [`TUMBLE_REGULAR_MIN_AREA_MAXIMA_PER_S`] maxima per second |
//! | 7 | spinner / autorotation | drift < [`GLIDE_MIN_DRIFT`], Fr ≥ [`PLUNGE_MIN_FROUDE`] (modulated: not caught by 4) |
//! | 7b | spinner / autorotation | drift < [`GLIDE_MIN_DRIFT`], Fr ≥ [`STEADY_MAX_FROUDE`], modulation < [`HELIX_MAX_MODULATION`], the horizontal velocity turned ≥ [`HELIX_MIN_TURNS`] net (a helix too irregular for 1) |
//! | 8 | lilter / chaotic | otherwise: swings, reverses and wanders |

mod areas;
mod features;
mod rules;
mod signal;

pub use areas::{AREA_MIN_SWING, AREA_MIN_SWING_OF_LEVEL, AREA_SMOOTHING_S};
pub use features::{
    HELIX_SPEED_FRACTION, NOISE_MULTIPLE, PathFeatures, REVERSAL_SPEED_FRACTION, SMOOTHING_S,
};
pub use rules::{
    Calibration, FLUTTER_MIN_PERIODICITY, FLUTTER_MIN_REVERSALS, FLUTTER_MIN_SPEED_SPREAD,
    GLIDE_MIN_DRIFT, HELIX_MAX_MODULATION, HELIX_MAX_RADIUS_CHORDS, HELIX_MIN_CONSISTENCY,
    HELIX_MIN_TURNS, Inputs, PLUNGE_MIN_FROUDE, PathVerdict, STEADY_MAX_FROUDE,
    STEADY_MAX_MODULATION, TUMBLE_MIN_AREA_MAXIMA_PER_S, TUMBLE_MIN_AREA_PERIODICITY,
    TUMBLE_MIN_STRAIGHTNESS, TUMBLE_REGULAR_MIN_AREA_MAXIMA_PER_S, verdict,
};

use crate::motion::class::{MotionClass, Regime};
use crate::motion::trajectory::Trajectory;
use crate::util::setting::Setting;
use areas::measure_areas;
use features::measure_path;
use rules::decide;

// ---------------------------------------------------------------- record checks

/// Lowest accepted sampling rate, Hz: film's 24 frames per second (NTSC's
/// 23.976 with [`SAMPLE_RATE_TOLERANCE`]), as the full classifier's
/// [`crate::motion::classify::MIN_SAMPLE_RATE_HZ`]. The fastest tumbling of
/// paper squares, 26 rad/s, shows area maxima at 8 Hz, below that rate's
/// Nyquist frequency of 12 Hz.
pub const MIN_PATH_SAMPLE_RATE_HZ: f64 = 24.0;

/// Relative slack on [`MIN_PATH_SAMPLE_RATE_HZ`] for time stamps printed
/// with few decimals (as the full classifier's
/// [`crate::motion::classify::SAMPLE_RATE_TOLERANCE`]).
pub const SAMPLE_RATE_TOLERANCE: f64 = 0.01;

/// Share of a long record's duration discarded as start-up transient (as
/// the full classifier's [`crate::motion::classify::TRANSIENT_FRACTION`]).
pub const TRANSIENT_FRACTION: f64 = 0.4;

/// Shortest record that can be classified, s (the floor).
pub const MIN_PATH_DURATION_S: f64 = 0.5;

/// An interval longer than this many median intervals is a gap (a dropped
/// frame or more; jitter of time stamps stays well below).
pub const GAP_FACTOR: f64 = 1.5;

/// Longest gap bridged by interpolation, s: a tenth of a second, about half
/// a turn of a tumbling paper square (our choice).
pub const MAX_GAP_S: f64 = 0.1;

/// Largest share of the window that may be interpolated gaps (our choice).
pub const MAX_GAP_SHARE: f64 = 0.2;

/// Records up to this long are classified whole, s: a real drop of about a
/// metre lasts 1.0–1.5 s from release and the start is part of it (Howison
/// et al. 2020); longer records lose their start as the full classifier's
/// do, down to this length at least.
pub const WHOLE_RECORD_S: f64 = 1.5;

/// Fewest chord lengths of descent in the window: "not falling" below
/// (our choice: the largest real squares fall about 4 diagonals in their
/// shortest segments).
pub const MIN_PATH_DESCENT_CHORDS: f64 = 2.0;

// ---------------------------------------------------------------- classify

/// Classifies a fall from its path, and from its area signals if it has any
/// and `use_areas` is set; the orientation, if any, is not looked at.
/// `size` is the leaf's chord (longest extent), m.
pub fn classify_path(tr: &Trajectory, size: f64, use_areas: bool) -> PathVerdict {
    classify_path_with(tr, size, use_areas, &Calibration::default())
}

/// [`classify_path`] with the thresholds calibrated on people's labels set
/// otherwise: what cross-validation refits on part of the data.
pub fn classify_path_with(
    tr: &Trajectory,
    size: f64,
    use_areas: bool,
    calibration: &Calibration,
) -> PathVerdict {
    let inputs = if use_areas && !tr.areas.is_empty() {
        Inputs::Areas
    } else {
        Inputs::Path
    };
    let undetermined = |features: PathFeatures, reason: String| PathVerdict {
        class: MotionClass::Undetermined,
        regime: Regime::Undetermined,
        reason,
        inputs,
        features,
    };
    let n = tr.time.len();
    if !(size.is_finite() && size > 0.0) {
        return undetermined(
            PathFeatures::default(),
            format!("leaf size must be positive and finite, got {size}"),
        );
    }
    if tr.position.len() != n || tr.areas.iter().any(|a| a.values.len() != n) {
        return undetermined(
            PathFeatures::default(),
            format!(
                "inconsistent trajectory: {n} times, {} positions",
                tr.position.len()
            ),
        );
    }
    for k in 0..n {
        let finite = tr.time[k].is_finite()
            && tr.position[k].iter().all(|x| x.is_finite())
            && (!use_areas || tr.areas.iter().all(|a| a.values[k].is_finite()));
        if !finite {
            return undetermined(
                PathFeatures::default(),
                format!("non-finite value at sample {}", k + 1),
            );
        }
        if k > 0 && tr.time[k] <= tr.time[k - 1] {
            return undetermined(
                PathFeatures::default(),
                format!("time not strictly increasing at sample {}", k + 1),
            );
        }
    }
    let duration = if n > 0 {
        tr.time[n - 1] - tr.time[0]
    } else {
        0.0
    };
    if n < 3 || duration < MIN_PATH_DURATION_S {
        return undetermined(
            PathFeatures {
                samples: n,
                ..PathFeatures::default()
            },
            format!(
                "too short: {n} samples over {duration:.3} s (need at least {MIN_PATH_DURATION_S} s)"
            ),
        );
    }
    let mut dts: Vec<f64> = tr.time.windows(2).map(|w| w[1] - w[0]).collect();
    let mid = dts.len() / 2;
    let median_dt = *dts.select_nth_unstable_by(mid, f64::total_cmp).1;
    let rate = 1.0 / median_dt;
    let mut f = PathFeatures {
        sample_rate_hz: rate,
        ..PathFeatures::default()
    };
    if rate < MIN_PATH_SAMPLE_RATE_HZ * (1.0 - SAMPLE_RATE_TOLERANCE) {
        return undetermined(
            f,
            format!("sampled at {rate:.1} Hz, below the {MIN_PATH_SAMPLE_RATE_HZ} Hz minimum"),
        );
    }

    // The window, then its gaps.
    let t0 = tr.time[0];
    let skip = (TRANSIENT_FRACTION * duration).min((duration - WHOLE_RECORD_S).max(0.0));
    let t_start = t0 + skip;
    let i0 = tr.time.partition_point(|&t| t < t_start - 1e-9).min(n - 1);
    f.t_start_s = tr.time[i0];
    f.t_end_s = tr.time[n - 1];
    let window = f.t_end_s - f.t_start_s;
    for k in i0..n - 1 {
        let dt = tr.time[k + 1] - tr.time[k];
        if dt > GAP_FACTOR * median_dt {
            f.gaps += 1;
            f.longest_gap_s = f.longest_gap_s.max(dt);
            f.interpolated_s += dt - median_dt;
        }
    }
    if f.longest_gap_s > MAX_GAP_S {
        return undetermined(
            f.clone(),
            format!(
                "too gappy: a gap of {:.3} s (longest bridged: {MAX_GAP_S} s)",
                f.longest_gap_s
            ),
        );
    }
    if f.interpolated_s > MAX_GAP_SHARE * window {
        return undetermined(
            f.clone(),
            format!(
                "too gappy: {:.3} s of the {window:.3} s window missing in {} gaps (at most {:.0} %)",
                f.interpolated_s,
                f.gaps,
                100.0 * MAX_GAP_SHARE
            ),
        );
    }

    // The uniform grid.
    let m = ((window * rate) + 1e-6).floor() as usize + 1;
    let times: Vec<f64> = (0..m).map(|k| f.t_start_s + k as f64 * median_dt).collect();
    let grid = tr.sampled_at(&times);
    f.samples = m;
    measure_path(&grid, median_dt, size, &mut f);
    if inputs == Inputs::Areas {
        measure_areas(&grid, median_dt, &mut f);
    }
    // NaN-safe: a NaN descent is "not falling" too.
    if f.descent_chords.is_nan() || f.descent_chords < MIN_PATH_DESCENT_CHORDS {
        return undetermined(
            f.clone(),
            format!(
                "not falling: {:.2} chord lengths of descent in the window {:.3}–{:.3} s (need {MIN_PATH_DESCENT_CHORDS}){}",
                f.descent_chords,
                f.t_start_s,
                f.t_end_s,
                rising_hint(f.descent_chords, MIN_PATH_DESCENT_CHORDS)
            ),
        );
    }
    decide(f, inputs, calibration)
}

/// What to say of a record that rises at least as far as a fall must
/// descend (`chords` of descent, negative): its vertical is most likely
/// another axis, or points down (image rows count downward).
pub(crate) fn rising_hint(chords: f64, min_chords: f64) -> String {
    if chords <= -min_chords {
        format!(
            "; it rises instead: is its vertical the right axis ({} for y up, {} for a y that points down as image rows do)?",
            Setting::Up.set("y"),
            Setting::Up.set("-y")
        )
    } else {
        String::new()
    }
}
