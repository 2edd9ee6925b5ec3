//! Step 3 of the method ([`super`]): velocities by a local linear fit
//! over the uniform record, and the path features they give, kept in
//! [`PathFeatures`] with the rest of the numbers behind a decision.

use serde::{Deserialize, Serialize};

use super::signal::{detrended, noise, periodicity, slope};
use crate::motion::trajectory::Trajectory;

/// Standard gravity, m/s² (for the Froude number).
const STANDARD_GRAVITY: f64 = 9.80665;

/// Half-width of the local linear fit that gives velocities, s. It spans
/// ±4 frames at 98 fps: noise of 1 mm then moves a velocity by ~1.3 cm/s,
/// while the descent-speed modulation of a tumbling square (twice its turn
/// rate, ~6 Hz) keeps about half its amplitude.
pub const SMOOTHING_S: f64 = 0.04;

/// A reversal must swing the horizontal velocity from +this fraction of the
/// descent speed to −this along the swing axis (our choice: well above the
/// noise of a tracked record, well below the swinging of a fluttering
/// plate).
pub const REVERSAL_SPEED_FRACTION: f64 = 0.15;

/// Horizontal speeds below this fraction of the descent speed carry no
/// direction to follow for a helix (our choice: a leaf autorotating about
/// the vertical drags its centre round a circle of about a centimetre at
/// a few tenths of a metre per second, 5–10 % of its descent speed).
pub const HELIX_SPEED_FRACTION: f64 = 0.03;

/// Speeds must also exceed this many times the noise the record's own
/// noise leaves in a velocity (estimated from the record, see
/// [`PathFeatures::position_noise_m`]).
pub const NOISE_MULTIPLE: f64 = 4.0;

/// The numbers behind a decision from the path (and areas), measured over
/// the window.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PathFeatures {
    /// Start of the window, s.
    pub t_start_s: f64,
    /// End of the window, s.
    pub t_end_s: f64,
    /// Samples in the window on the uniform grid.
    pub samples: usize,
    /// Sampling rate, Hz (1 / median interval): the grid's.
    pub sample_rate_hz: f64,
    /// Gaps (intervals over [`GAP_FACTOR`](super::GAP_FACTOR) median intervals) bridged by
    /// interpolation in the window.
    pub gaps: usize,
    /// The longest of them, s (0 without).
    pub longest_gap_s: f64,
    /// Their total, s.
    pub interpolated_s: f64,
    /// Fall over the window, m.
    pub descent_m: f64,
    /// That fall in chord lengths.
    pub descent_chords: f64,
    /// Mean descent speed, m/s.
    pub mean_descent_speed_m_s: f64,
    /// Noise of the vertical position, m, estimated from the record (median
    /// absolute second difference / (0.6745 √6)).
    pub position_noise_m: f64,
    /// The same for the horizontal position (the larger of x and y), m.
    pub horizontal_noise_m: f64,
    /// Modulation of the descent: the spread of the smoothed descent speed
    /// about its linear trend, over its mean.
    pub descent_speed_cv: f64,
    /// What the record's noise alone would give as a modulation (its
    /// spread in a velocity over the descent speed): a modulation below it
    /// is not measured.
    pub modulation_noise: f64,
    /// Froude number U / √(g L) of the descent (Belmonte, Eisenberg & Moses
    /// 1998), U the mean descent speed and L the chord.
    pub froude_number: f64,
    /// Horizontal displacement / descent.
    pub drift_ratio: f64,
    /// Angle of the mean path from the vertical, degrees (atan of the drift
    /// ratio).
    pub glide_angle_deg: f64,
    /// |∫v_h dt| / ∫|v_h| dt: 1 = a straight path, 0 = back and forth.
    pub straightness: f64,
    /// Mean horizontal speed / mean descent speed.
    pub horizontal_speed_ratio: f64,
    /// Spread (std / mean) of the horizontal speed: a swing comes to rest
    /// at each reversal (a sine's |·| has 0.48), a helix or a glide keeps
    /// its speed (0).
    pub horizontal_speed_spread: f64,
    /// Reversals of the horizontal velocity along its dominant axis (from
    /// above +[`REVERSAL_SPEED_FRACTION`] of the descent speed to below −).
    pub reversals: usize,
    /// [`PathFeatures::reversals`] per second.
    pub reversals_per_s: f64,
    /// Periodicity of the horizontal velocity along that axis (its
    /// autocorrelation at the first peak; 1 = a regular swing).
    pub swing_periodicity: f64,
    /// Net turns of the direction of the horizontal velocity (signed).
    pub path_turns: f64,
    /// |net| / total turning of that direction: 1 = always the same way.
    pub path_turn_consistency: f64,
    /// Radius of the circle the centre goes round, in chords: the mean
    /// horizontal speed over the net rate of turning of its direction
    /// (infinite without turning).
    #[serde(serialize_with = "finite_or_null")]
    pub helix_radius_chords: f64,
    /// Area signals used.
    pub area_signals: usize,
    /// Area maxima per second (mean over the signals), if any.
    pub area_maxima_per_s: Option<f64>,
    /// π × that: the turn rate of a plate turning about a horizontal axis,
    /// rad/s.
    pub area_turn_rate_rad_s: Option<f64>,
    /// Periodicity of the area signals (the best one's autocorrelation at
    /// its first peak; 1 = perfectly periodic), if any.
    pub area_periodicity: Option<f64>,
    /// Distance to the nearest class boundary, in threshold scale units,
    /// clipped to [0, 1].
    pub margin: f64,
    /// Distance to the nearest regime boundary, same units.
    pub regime_margin: f64,
}

/// Serializes a non-finite number as `null` (JSON has no infinity).
fn finite_or_null<S: serde::Serializer>(x: &f64, s: S) -> Result<S::Ok, S::Error> {
    if x.is_finite() {
        s.serialize_f64(*x)
    } else {
        s.serialize_none()
    }
}

/// The path features of a uniform record.
pub(super) fn measure_path(g: &Trajectory, dt: f64, size: f64, f: &mut PathFeatures) {
    let m = g.len();
    let duration = (m - 1) as f64 * dt;
    let (pa, pb) = (g.position[0], g.position[m - 1]);
    f.descent_m = pa.z - pb.z;
    f.descent_chords = f.descent_m / size;
    f.mean_descent_speed_m_s = f.descent_m / duration;
    let horizontal = (pb.x - pa.x).hypot(pb.y - pa.y);
    f.drift_ratio = if f.descent_m > 0.0 {
        horizontal / f.descent_m
    } else {
        0.0
    };
    f.glide_angle_deg = f.drift_ratio.atan().to_degrees();

    let h = ((SMOOTHING_S / dt).round() as usize).max(1);
    let coord = |d: usize| g.position.iter().map(|p| p[d]).collect::<Vec<f64>>();
    let (x, y, z) = (coord(0), coord(1), coord(2));
    let (mut vx, mut vy, mut vz) = (Vec::new(), Vec::new(), Vec::new());
    slope(&x, h, dt, &mut vx);
    slope(&y, h, dt, &mut vy);
    slope(&z, h, dt, &mut vz);
    // The noise of the record and what it leaves in a velocity: the slope
    // of a least-squares line through 2h + 1 points of independent noise σ
    // has the spread σ / (dt √Σj²), Σj² = h(h + 1)(2h + 1)/3.
    f.position_noise_m = noise(&z);
    f.horizontal_noise_m = noise(&x).max(noise(&y));
    let sum_j2 = (h * (h + 1) * (2 * h + 1)) as f64 / 3.0;
    let noise_v = f.position_noise_m / (dt * sum_j2.sqrt());
    let noise_vh = f.horizontal_noise_m / (dt * sum_j2.sqrt());

    // The spread about a linear trend (a plate still speeding up is not
    // modulating its descent), less what the noise puts there.
    // Statistics of velocities leave out the h samples at each end, whose
    // fits are one-sided (and three times noisier).
    let inner = if m > 4 * h { h..m - h } else { 0..m };
    let vz_inner = &vz[inner.clone()];
    let mean_vz = vz_inner.iter().sum::<f64>() / vz_inner.len() as f64;
    let residual = detrended(vz_inner);
    let var_vz = residual.iter().map(|v| v * v).sum::<f64>() / residual.len() as f64;
    (f.descent_speed_cv, f.modulation_noise) = if mean_vz != 0.0 {
        (
            (var_vz - noise_v * noise_v).max(0.0).sqrt() / mean_vz.abs(),
            noise_v / mean_vz.abs(),
        )
    } else {
        (0.0, 0.0)
    };
    f.froude_number = speed_of(f.mean_descent_speed_m_s) / (STANDARD_GRAVITY * size).sqrt();
    let (sx, sy): (f64, f64) = (vx.iter().sum(), vy.iter().sum());
    let path: f64 = vx.iter().zip(&vy).map(|(a, b)| a.hypot(*b)).sum();
    f.straightness = if path > 0.0 { sx.hypot(sy) / path } else { 0.0 };
    let speed = f.mean_descent_speed_m_s.abs();
    f.horizontal_speed_ratio = if speed > 0.0 {
        path / m as f64 / speed
    } else {
        0.0
    };
    // How much the horizontal speed itself varies: a swing passes through
    // rest at every reversal, a helix keeps its speed.
    let hs: Vec<f64> = vx[inner.clone()]
        .iter()
        .zip(&vy[inner.clone()])
        .map(|(a, b)| a.hypot(*b))
        .collect();
    let hs_mean = hs.iter().sum::<f64>() / hs.len() as f64;
    let hs_var = hs.iter().map(|v| (v - hs_mean).powi(2)).sum::<f64>() / hs.len() as f64;
    f.horizontal_speed_spread = if hs_mean > 0.0 {
        hs_var.sqrt() / hs_mean
    } else {
        0.0
    };

    // Reversals along the dominant horizontal axis of the velocity.
    let (mut cxx, mut cxy, mut cyy) = (0.0, 0.0, 0.0);
    for (a, b) in vx.iter().zip(&vy) {
        cxx += a * a;
        cxy += a * b;
        cyy += b * b;
    }
    let angle = 0.5 * (2.0 * cxy).atan2(cxx - cyy);
    let (ux, uy) = (angle.cos(), angle.sin());

    let threshold = (REVERSAL_SPEED_FRACTION * speed).max(NOISE_MULTIPLE * noise_vh);
    let mut state = 0i8;
    for (a, b) in vx.iter().zip(&vy) {
        let along = a * ux + b * uy;
        let now = if along > threshold {
            1
        } else if along < -threshold {
            -1
        } else {
            0
        };
        if now != 0 && now != state {
            if state != 0 {
                f.reversals += 1;
            }
            state = now;
        }
    }
    f.reversals_per_s = f.reversals as f64 / duration;
    let along: Vec<f64> = vx.iter().zip(&vy).map(|(a, b)| a * ux + b * uy).collect();
    f.swing_periodicity = periodicity(&detrended(&along));

    // Turning of the horizontal velocity's direction, where it is fast
    // enough to have one.
    // A direction is followed only between consecutive samples that both
    // have one, so a swing through zero speed (a reversal) is not a turn.
    let (mut net, mut total) = (0.0f64, 0.0f64);
    let mut last: Option<f64> = None;
    let threshold = (HELIX_SPEED_FRACTION * speed).max(NOISE_MULTIPLE * noise_vh);
    for (a, b) in vx.iter().zip(&vy) {
        if a.hypot(*b) < threshold {
            last = None;
            continue;
        }
        let phi = b.atan2(*a);
        if let Some(prev) = last {
            let d = (phi - prev + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                - std::f64::consts::PI;
            net += d;
            total += d.abs();
        }
        last = Some(phi);
    }
    f.path_turns = net / std::f64::consts::TAU;
    f.path_turn_consistency = if total > 0.0 { net.abs() / total } else { 0.0 };
    // The radius of the circle the centre goes round: horizontal speed over
    // the rate at which its direction turns.
    let rate = net.abs() / duration;
    f.helix_radius_chords = if rate > 0.0 {
        (path / m as f64) / rate / size
    } else {
        f64::INFINITY
    };
}

/// |v|, for speeds.
fn speed_of(v: f64) -> f64 {
    v.abs()
}
