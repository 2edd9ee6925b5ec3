//! Step 3 of the method ([`super`]): the kinematics of a pose record —
//! angular increments, yaw, the dominant pitch/roll axis and the pitch
//! angle about it, the plate's tilt and the normal's flips — measured
//! into [`Features`].

use nalgebra::{Matrix2, Matrix3, SymmetricEigen, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

use crate::motion::trajectory::Trajectory;

/// Hysteresis of a normal flip, degrees: the normal must go from ≥ 30° above
/// the horizontal plane to ≥ 30° below it (or back). The APW ODE's largest
/// flutter reaches ±96° without flipping over (docs/design/falling-plates.md, "APW
/// quasi-steady model"), and an edge-on diver wobbling a few degrees must not
/// count flips.
pub const FLIP_HYSTERESIS_DEG: f64 = 30.0;

/// Smallest pitch swing counted as a reversal, degrees peak to peak.
/// docs/design/falling-plates.md, "Classifier rules", step 4, calls θ within ~±10°
/// steady; we read that as amplitude, so a swing must at least equal that
/// band's width to count as a rock rather than jitter.
pub const REVERSAL_MIN_SWING_DEG: f64 = 10.0;

/// Body and world axis shares closer than this count as a tie (body wins).
const AXIS_FRAME_TIE: f64 = 1e-3;

/// Frame in which the dominant pitch/roll axis is held fixed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AxisFrame {
    /// Fixed in the leaf (e.g. its span): the usual case.
    #[default]
    Body,
    /// Fixed in the world (a plate spinning about its normal while rocking).
    World,
}

/// The numbers behind a decision, all measured over the analysis window.
/// Angles about axes are in turns (1 turn = 2π rad) or degrees as named.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Features {
    /// Start of the analysis window, s (after the discarded transient).
    pub t_start_s: f64,
    /// End of the analysis window, s (last sample).
    pub t_end_s: f64,
    /// Samples in the window.
    pub samples: usize,
    /// Sampling rate of the whole record, Hz (1 / median interval).
    pub sample_rate_hz: f64,
    /// Longest interval between samples in the window, s.
    pub max_gap_s: f64,
    /// Largest rotation between two consecutive samples in the window,
    /// degrees: how close the record comes to the half turn per sample at
    /// which the direction of a rotation can no longer be told.
    pub max_sample_turn_deg: f64,
    /// Fall over the window (z at start − z at end), m.
    pub descent_m: f64,
    /// [`Features::descent_m`] in chord lengths (leaf size).
    pub descent_chords: f64,
    /// Mean descent speed, m/s (descent / window duration).
    pub mean_descent_speed_m_s: f64,
    /// Mean descent speed in chord lengths per second.
    pub descent_speed_chords_per_s: f64,
    /// Standard deviation / mean of the per-interval vertical speed
    /// (Howison & Iida's `SpeedZ` analogue); dimensionless.
    pub descent_speed_cv: f64,
    /// Horizontal displacement / descent over the window; dimensionless.
    pub drift_ratio: f64,
    /// |net rotation| about the dominant horizontal (pitch/roll) axis, turns.
    pub net_turns: f64,
    /// Total rotation ∫|ω·a| dt about that axis, turns (≥ net_turns).
    pub total_turns: f64,
    /// net_turns / total_turns: 1 = one sign of rotation, 0 = pure rocking.
    pub rotation_consistency: f64,
    /// Share of the horizontal angular "energy" ∫ω_h ω_hᵀ dt on the dominant
    /// axis (1 = a single axis; 1/3 in body axes or 1/2 in world axes = none).
    pub horizontal_axis_share: f64,
    /// Frame in which that axis is fixed.
    pub axis_frame: AxisFrame,
    /// Time per net turn about the horizontal axis, s (when net_turns ≥ 0.5).
    pub turn_period_s: Option<f64>,
    /// Reversals of the pitch rate (turning points of θ with swings of at
    /// least [`REVERSAL_MIN_SWING_DEG`]).
    pub reversals: usize,
    /// [`Features::reversals`] per second.
    pub reversals_per_s: f64,
    /// Number of full oscillation periods (reversals / 2).
    pub oscillation_periods: f64,
    /// Rocking amplitude, degrees: half the mean swing between successive
    /// turning points of θ (0 without reversals).
    pub rocking_amplitude_deg: f64,
    /// Oscillation period, s, from the turning points (at least 3 needed).
    pub oscillation_period_s: Option<f64>,
    /// Times the normal crossed the horizontal plane (with
    /// [`FLIP_HYSTERESIS_DEG`] hysteresis).
    pub normal_flips: usize,
    /// [`Features::normal_flips`] per second.
    pub flips_per_s: f64,
    /// Largest angle of the normal from the pole of the hemisphere it started
    /// the window in, degrees; a flip needs 90 + [`FLIP_HYSTERESIS_DEG`].
    pub max_excursion_deg: f64,
    /// Net rotation about the world vertical, turns (signed, + = counter-clockwise seen from above).
    pub yaw_turns: f64,
    /// Mean rotation rate about the vertical, rad/s (signed).
    pub mean_yaw_rate_rad_s: f64,
    /// |∫ω_z dt| / ∫|ω_z| dt: 1 = yaw keeps its sign.
    pub yaw_consistency: f64,
    /// |mean ω_z| / rms |ω|: 1 = rotation purely about the vertical.
    pub vertical_spin_share: f64,
    /// Time-weighted mean tilt of the plate from horizontal, degrees (0–90).
    pub tilt_mean_deg: f64,
    /// Time-weighted standard deviation of that tilt, degrees.
    pub tilt_std_deg: f64,
    /// 10th percentile of the tilt, degrees.
    pub tilt_p10_deg: f64,
    /// Mean angle of the normal from straight up, degrees (0–180; > 90 =
    /// upside down).
    pub normal_tilt_mean_deg: f64,
    /// Distance to the nearest class boundary, in threshold scale units,
    /// clipped to [0, 1] (see the module docs).
    pub margin: f64,
    /// Distance to the nearest regime boundary, same units.
    pub regime_margin: f64,
}

impl Features {
    /// The mean tumbling rate over the window, rad/s: the net turns about
    /// the dominant horizontal axis over the window's length.
    pub fn tumbling_rate_rad_s(&self) -> f64 {
        let window = (self.t_end_s - self.t_start_s).max(f64::MIN_POSITIVE);
        std::f64::consts::TAU * self.net_turns.abs() / window
    }
}

/// World z component of the plate normal (body z axis): cos of its angle
/// from straight up.
fn normal_z(q: &UnitQuaternion<f64>) -> f64 {
    1.0 - 2.0 * (q.i * q.i + q.j * q.j)
}

/// Rotation vector (axis × angle, world frame) of the shortest rotation from
/// `a` to `b`: log(b a⁻¹). q and −q give the same result.
fn increment(a: &UnitQuaternion<f64>, b: &UnitQuaternion<f64>) -> Vector3<f64> {
    let d = b * a.inverse();
    let (mut w, mut v) = (d.w, d.vector().into_owned());
    if w < 0.0 {
        w = -w;
        v = -v;
    }
    let s = v.norm();
    if s < 1e-300 {
        return v * 2.0;
    }
    v * (2.0 * s.atan2(w) / s)
}

/// The features [`classify`](super::classify) measures from a pose record, over the whole of
/// `trajectory` (no start-up window, no sampling checks, no decision): for
/// a caller that has cut its record already, such as the real-falls
/// experiment's filmed fall (`leafmagic_lab::real_falls::rotation_of`, in the workspace's lab).
/// Without an orientation per sample, the default (all zero).
pub fn pose_features(trajectory: &Trajectory, size: f64) -> Features {
    let n = trajectory.time.len();
    if n < 2 || trajectory.orientation.len() != n || trajectory.position.len() != n {
        return Features::default();
    }
    extract(trajectory, 0, size)
}

/// Computes every feature except the sampling rate and margins over samples
/// `i0..n`.
pub(super) fn extract(tr: &Trajectory, i0: usize, size: f64) -> Features {
    let n = tr.time.len();
    let m = n - i0;
    let mut f = Features {
        t_start_s: tr.time[i0],
        t_end_s: tr.time[n - 1],
        samples: m,
        ..Features::default()
    };
    let duration = f.t_end_s - f.t_start_s;
    if m < 2 || duration <= 0.0 {
        return f;
    }

    // Pass 1: per interval — angular increments, yaw, vertical speed.
    let inc = increments(tr, i0, &mut f);
    translation_and_yaw(tr, i0, size, duration, &inc, &mut f);
    // The increments are dropped once the pitch is read from them.
    let pitch = pitch_increments(inc, &mut f);
    rotation_and_rocking(tr, i0, &pitch, duration, &mut f);
    tilt_and_flips(tr, i0, duration, &mut f);
    f
}

/// What pass 1 of [`extract`] gathers over the intervals.
struct Increments {
    /// Each interval's horizontal rotation, world axes.
    world_h: Vec<[f64; 2]>,
    /// The same in body axes.
    body_h: Vec<Vector3<f64>>,
    /// The net yaw, rad.
    psi: f64,
    /// The yaw's total, rad.
    abs_rz: f64,
    /// ∫ω_h ω_hᵀ dt, world axes.
    s_world: Matrix2<f64>,
    /// The same in body axes.
    s_body: Matrix3<f64>,
    /// ∫|ω|² dt.
    w2: f64,
}

/// The angular increments of samples `i0..` (pass 1): per interval, the
/// horizontal (pitch/roll) part of each increment in world axes and in body
/// axes (mapped with the mid-interval orientation), the yaw, and their
/// integrals; the largest gap and turn, and the descent speed's spread, go
/// to `f`.
fn increments(tr: &Trajectory, i0: usize, f: &mut Features) -> Increments {
    let n = tr.time.len();
    let m = n - i0;
    let mut world_h: Vec<[f64; 2]> = Vec::with_capacity(m - 1);
    let mut body_h: Vec<Vector3<f64>> = Vec::with_capacity(m - 1);
    let (mut psi, mut abs_rz) = (0.0f64, 0.0f64);
    let mut s_world = Matrix2::<f64>::zeros(); // ∫ω_h ω_hᵀ dt, world axes
    let mut s_body = Matrix3::<f64>::zeros(); // the same in body axes
    let mut w2 = 0.0f64; // ∫|ω|² dt
    let (mut vz_sum, mut vz_sq) = (0.0f64, 0.0f64);
    for k in i0..n - 1 {
        let dt = tr.time[k + 1] - tr.time[k];
        f.max_gap_s = f.max_gap_s.max(dt);
        let r = increment(&tr.orientation[k], &tr.orientation[k + 1]);
        f.max_sample_turn_deg = f.max_sample_turn_deg.max(r.norm().to_degrees());
        psi += r.z;
        abs_rz += r.z.abs();
        w2 += r.norm_squared() / dt;
        let h = Vector3::new(r.x, r.y, 0.0);
        let mid = UnitQuaternion::from_scaled_axis(r * 0.5) * tr.orientation[k];
        let u = mid.inverse_transform_vector(&h);
        s_world += Matrix2::new(h.x * h.x, h.x * h.y, h.x * h.y, h.y * h.y) / dt;
        s_body += u * u.transpose() / dt;
        world_h.push([h.x, h.y]);
        body_h.push(u);
        let vz = (tr.position[k + 1].z - tr.position[k].z) / dt;
        vz_sum += vz;
        vz_sq += vz * vz;
    }
    let intervals = (m - 1) as f64;
    let vz_mean = vz_sum / intervals;
    let vz_std = (vz_sq / intervals - vz_mean * vz_mean).max(0.0).sqrt();
    f.descent_speed_cv = if vz_mean != 0.0 {
        vz_std / vz_mean.abs()
    } else {
        0.0
    };
    Increments {
        world_h,
        body_h,
        psi,
        abs_rz,
        s_world,
        s_body,
        w2,
    }
}

/// Translation and yaw: descent, drift and the yaw's rate and consistency.
fn translation_and_yaw(
    tr: &Trajectory,
    i0: usize,
    size: f64,
    duration: f64,
    inc: &Increments,
    f: &mut Features,
) {
    let n = tr.time.len();
    let (psi, abs_rz, w2) = (inc.psi, inc.abs_rz, inc.w2);
    // Translation.
    let (pa, pb) = (tr.position[i0], tr.position[n - 1]);
    f.descent_m = pa.z - pb.z;
    f.descent_chords = f.descent_m / size;
    f.mean_descent_speed_m_s = f.descent_m / duration;
    f.descent_speed_chords_per_s = f.descent_chords / duration;
    let horizontal = (pb.x - pa.x).hypot(pb.y - pa.y);
    f.drift_ratio = if f.descent_m > 0.0 {
        horizontal / f.descent_m
    } else {
        0.0
    };

    // Yaw.
    f.yaw_turns = psi / std::f64::consts::TAU;
    f.mean_yaw_rate_rad_s = psi / duration;
    f.yaw_consistency = if abs_rz > 0.0 {
        psi.abs() / abs_rz
    } else {
        0.0
    };
    let rms_w = (w2 / duration).sqrt();
    f.vertical_spin_share = if rms_w > 0.0 {
        (f.mean_yaw_rate_rad_s.abs() / rms_w).min(1.0)
    } else {
        0.0
    };
}

/// The pitch increments about the dominant horizontal axis (its frame and
/// share go to `f`).
fn pitch_increments(inc: Increments, f: &mut Features) -> Vec<f64> {
    let Increments {
        world_h,
        body_h,
        s_world,
        s_body,
        ..
    } = inc;
    // Dominant horizontal axis: the principal axis of ∫ω_h ω_hᵀ dt, fixed
    // either in the body or in the world, whichever explains more of the
    // horizontal rotation (ties go to the body). A body-fixed axis follows a
    // leaf that rocks or tumbles about its own span while yawing (lilters in
    // docs/design/falling-plates.md, "Folded leaves under the linear law"; the
    // precessing MuJoCo card); a world-fixed one suits a plate that spins about
    // its normal while rocking.
    let world = SymmetricEigen::new(s_world);
    let body = SymmetricEigen::new(s_body);
    let share = |vals: &[f64], tr: f64| {
        if tr > 0.0 {
            vals.iter().copied().fold(0.0, f64::max) / tr
        } else {
            0.0
        }
    };
    let world_share = share(world.eigenvalues.as_slice(), s_world.trace());
    let body_share = share(body.eigenvalues.as_slice(), s_body.trace());
    let principal = |vals: &[f64]| {
        (0..vals.len())
            .max_by(|&a, &b| vals[a].total_cmp(&vals[b]))
            .unwrap_or(0)
    };
    if world_share > body_share + AXIS_FRAME_TIE {
        f.axis_frame = AxisFrame::World;
        f.horizontal_axis_share = world_share;
        let a = world
            .eigenvectors
            .column(principal(world.eigenvalues.as_slice()));
        world_h.iter().map(|h| h[0] * a[0] + h[1] * a[1]).collect()
    } else {
        f.axis_frame = AxisFrame::Body;
        f.horizontal_axis_share = body_share;
        let a = body
            .eigenvectors
            .column(principal(body.eigenvalues.as_slice()));
        body_h.iter().map(|u| u.dot(&a)).collect()
    }
}

/// Pass 2: pitch angle θ about the dominant axis; net/total rotation and
/// the turning points of θ (zig-zag with a minimum swing, so jitter is not
/// counted as rocking).
fn rotation_and_rocking(
    tr: &Trajectory,
    i0: usize,
    pitch: &[f64],
    duration: f64,
    f: &mut Features,
) {
    let swing = REVERSAL_MIN_SWING_DEG.to_radians();
    let (mut theta, mut total) = (0.0f64, 0.0f64);
    let mut dir = 0i8; // 0 = not yet moving by a full swing, ±1 = rising/falling
    let (mut lo, mut hi) = (0.0f64, 0.0f64);
    let (mut ext, mut ext_t) = (0.0f64, f.t_start_s);
    let mut turns_n = 0usize;
    let (mut first_turn_t, mut last_turn_t, mut last_turn_v) = (0.0f64, 0.0f64, 0.0f64);
    let mut swing_sum = 0.0f64;
    for (j, &d) in pitch.iter().enumerate() {
        theta += d;
        total += d.abs();
        let t = tr.time[i0 + j + 1];
        match dir {
            0 => {
                lo = lo.min(theta);
                hi = hi.max(theta);
                if theta - lo >= swing {
                    dir = 1;
                    (ext, ext_t) = (theta, t);
                } else if hi - theta >= swing {
                    dir = -1;
                    (ext, ext_t) = (theta, t);
                }
            }
            _ => {
                let sign = f64::from(dir);
                if (theta - ext) * sign > 0.0 {
                    (ext, ext_t) = (theta, t);
                } else if (ext - theta) * sign >= swing {
                    // ext was a turning point.
                    if turns_n == 0 {
                        first_turn_t = ext_t;
                    } else {
                        swing_sum += (ext - last_turn_v).abs();
                    }
                    turns_n += 1;
                    (last_turn_t, last_turn_v) = (ext_t, ext);
                    dir = -dir;
                    (ext, ext_t) = (theta, t);
                }
            }
        }
    }
    let tau = std::f64::consts::TAU;
    f.net_turns = theta.abs() / tau;
    f.total_turns = total / tau;
    f.rotation_consistency = if total > 0.0 {
        theta.abs() / total
    } else {
        0.0
    };
    f.turn_period_s = (f.net_turns >= 0.5).then(|| duration / f.net_turns);
    f.reversals = turns_n;
    f.reversals_per_s = turns_n as f64 / duration;
    f.oscillation_periods = turns_n as f64 / 2.0;
    f.rocking_amplitude_deg = if turns_n >= 2 {
        (0.5 * swing_sum / (turns_n - 1) as f64).to_degrees()
    } else if turns_n == 1 {
        // One turning point: the swing from it to the latest extreme.
        (0.5 * (last_turn_v - ext).abs()).to_degrees()
    } else {
        0.0
    };
    f.oscillation_period_s =
        (turns_n >= 3).then(|| 2.0 * (last_turn_t - first_turn_t) / (turns_n - 1) as f64);
}

/// Pass 3: per sample, tilt statistics and normal flips.
fn tilt_and_flips(tr: &Trajectory, i0: usize, duration: f64, f: &mut Features) {
    let n = tr.time.len();
    let m = n - i0;
    let flip_z = FLIP_HYSTERESIS_DEG.to_radians().sin();
    let nz0 = normal_z(&tr.orientation[i0]);
    let pole = if nz0 >= 0.0 { 1.0 } else { -1.0 };
    let mut state = if nz0 >= flip_z {
        1i8
    } else if nz0 <= -flip_z {
        -1
    } else {
        0
    };
    let mut tilts: Vec<f64> = Vec::with_capacity(m);
    let (mut wsum, mut tsum, mut tsq, mut nsum) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let mut max_exc = 0.0f64;
    for k in i0..n {
        let nz = normal_z(&tr.orientation[k]).clamp(-1.0, 1.0);
        let tilt = nz.abs().acos().to_degrees();
        let normal_tilt = nz.acos().to_degrees();
        let w = 0.5 * (tr.time[(k + 1).min(n - 1)] - tr.time[k.saturating_sub(1).max(i0)]);
        wsum += w;
        tsum += w * tilt;
        tsq += w * tilt * tilt;
        nsum += w * normal_tilt;
        tilts.push(tilt);
        max_exc = max_exc.max((pole * nz).acos().to_degrees());
        let now = if nz >= flip_z {
            1
        } else if nz <= -flip_z {
            -1
        } else {
            0
        };
        if now != 0 && now != state {
            if state != 0 {
                f.normal_flips += 1;
            }
            state = now;
        }
    }
    f.flips_per_s = f.normal_flips as f64 / duration;
    f.max_excursion_deg = max_exc;
    f.tilt_mean_deg = tsum / wsum;
    f.tilt_std_deg = (tsq / wsum - f.tilt_mean_deg.powi(2)).max(0.0).sqrt();
    f.normal_tilt_mean_deg = nsum / wsum;
    let p10 = (0.1 * (m - 1) as f64).floor() as usize;
    f.tilt_p10_deg = *tilts.select_nth_unstable_by(p10, f64::total_cmp).1;
}
