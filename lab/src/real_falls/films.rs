//! What the experiment's cameras see: the rig, a fall as filmed at 98
//! frames per second, and the features the authors' rule reads from it.

use nalgebra::Vector3;
use std::f64::consts::{PI, TAU};

type V3 = Vector3<f64>;

/// Frames per second of the experiment's cameras.
pub const FPS: f64 = 98.0;

/// Least sideways run of a third of a film for [`Film::path_turn`], m.
pub const MIN_THIRD_RUN: f64 = 0.02;

/// The end of every fall that is trimmed (classifyBehaviour.m), m.
pub const FLOOR_TRIM: f64 = 0.05;

/// One camera of the rig: centre (m, the data's frame: x, y, height),
/// unit optical axis and focal lengths (px).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Centre of projection, m.
    pub centre: [f64; 3],
    /// Unit optical axis.
    pub axis: [f64; 3],
    /// Focal lengths f_x, f_y, px.
    pub focal: [f64; 2],
}

/// The experiment's two cameras (Video Processing/Extrinsics.mat and
/// stereoParams.mat of the authors' data, as decoded by the project's
/// realfalls tool).
pub const CAMERAS: [Camera; 2] = [
    Camera {
        centre: [-0.1220, -0.2652, 1.8123],
        axis: [0.4370, 0.3798, -0.8153],
        focal: [501.62, 502.46],
    },
    Camera {
        centre: [-0.1425, 0.7581, 1.8062],
        axis: [0.3940, -0.0857, -0.9151],
        focal: [501.60, 502.21],
    },
];

/// Where the paper was let go (horizontal position, m), from the same source.
pub const DROP_POINT: [f64; 2] = [0.9157, 0.4033];

/// A label: the experiment's 1 (tumbling), 2 (chaotic), 3 (steady start).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Label {
    /// Turning end over end, gliding off on a slanted line.
    Tumbling,
    /// Swinging, reversing and wandering.
    Chaotic,
    /// The first frames of a flat release (a release artefact).
    Steady,
}

impl Label {
    pub(super) fn from_code(code: u32) -> Option<Label> {
        match code {
            1 => Some(Label::Tumbling),
            2 => Some(Label::Chaotic),
            3 => Some(Label::Steady),
            _ => None,
        }
    }
}

/// A segment's features (classifyBehaviour.m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Features {
    /// Sideways displacements and the fall, m.
    pub dx: f64,
    /// See `dx`.
    pub dy: f64,
    /// |Δz|, m.
    pub dz: f64,
    /// Duration: frames / [`FPS`], s.
    pub time: f64,
    /// Projected-area maxima per second, mean of the two cameras.
    pub osc: f64,
    /// Standard deviation of the per-frame change of height, m.
    pub speed_z: f64,
}

impl Features {
    /// Descent speed dz/t, m/s.
    pub fn descent(&self) -> f64 {
        self.dz / self.time
    }
    /// Drift √(dx² + dy²)/dz.
    pub fn drift(&self) -> f64 {
        self.dx.hypot(self.dy) / self.dz
    }
}

/// A filmed fall or segment: positions (x, y relative to the first frame,
/// z the height) and the two cameras' projected areas, at [`FPS`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Film {
    /// Centre of the paper per frame, m.
    pub position: Vec<V3>,
    /// Projected area per frame, per camera (any unit).
    pub area: [Vec<f64>; 2],
}

impl Film {
    /// Frames.
    pub fn len(&self) -> usize {
        self.position.len()
    }
    /// No frame.
    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }
    pub(super) fn slice(&self, from: usize, to: usize) -> Film {
        Film {
            position: self.position[from..to].to_vec(),
            area: [
                self.area[0][from..to].to_vec(),
                self.area[1][from..to].to_vec(),
            ],
        }
    }

    /// The features, or `None` if a step between frames exceeds 0.1 m (the
    /// experiment drops such a segment) or there are fewer than 3 frames.
    pub fn features(&self) -> Option<Features> {
        let p = &self.position;
        let n = p.len();
        if n < 3 || p.windows(2).any(|w| (w[1] - w[0]).norm() > 0.1) {
            return None;
        }
        let time = n as f64 / FPS;
        let steps: Vec<f64> = p.windows(2).map(|w| w[1].z - w[0].z).collect();
        let mean = steps.iter().sum::<f64>() / steps.len() as f64;
        let var = steps.iter().map(|s| (s - mean).powi(2)).sum::<f64>() / (steps.len() - 1) as f64;
        Some(Features {
            dx: p[n - 1].x - p[0].x,
            dy: p[n - 1].y - p[0].y,
            dz: (p[n - 1].z - p[0].z).abs(),
            time,
            osc: (count_peaks(&self.area[0]) + count_peaks(&self.area[1])) as f64 / (2.0 * time),
            speed_z: var.sqrt(),
        })
    }

    /// The fastest descent over the film, m/s: the largest central
    /// difference (z_k − z_{k+2}) · FPS / 2 (exact for a fall at constant
    /// acceleration); `None` under 3 frames. A plate that falls edge-first
    /// gains speed until it turns, so this is how fast its dives went
    /// (docs/lab/real-falls.md, "How fast real paper dives").
    pub fn fastest_descent(&self) -> Option<f64> {
        self.position
            .windows(3)
            .map(|w| (w[0].z - w[2].z) * FPS / 2.0)
            .reduce(f64::max)
    }

    /// How far the horizontal path turns over the film, degrees in
    /// (−180, 180]: the heading of the sideways displacement over its last
    /// third less that over its first third. `None` under 6 frames, or where
    /// either third moves less than [`MIN_THIRD_RUN`] sideways (a fall
    /// nearly straight down has no heading). A plate tumbling in one plane
    /// glides on a straight line and turns 0°; the films' squares turn a
    /// median 16–125° per bin and kind of release (docs/lab/real-falls.md, "How
    /// far a tumbling path turns").
    pub fn path_turn(&self) -> Option<f64> {
        let p = &self.position;
        let n = p.len();
        if n < 6 {
            return None;
        }
        let run = |a: usize, b: usize| (p[b] - p[a]).xy();
        let (first, last) = (run(0, n / 3), run(2 * n / 3, n - 1));
        if first.norm() < MIN_THIRD_RUN || last.norm() < MIN_THIRD_RUN {
            return None;
        }
        // A difference of two headings in (−π, π] lies in (−2π, 2π): one
        // turn at most brings it into (−π, π].
        let mut turn = last.y.atan2(last.x) - first.y.atan2(first.x);
        if turn > PI {
            turn -= TAU;
        } else if turn <= -PI {
            turn += TAU;
        }
        Some(turn.to_degrees())
    }

    /// The tumbling rate Ω = π × area maxima per second, rad/s: frames above
    /// [`FLOOR_TRIM`], the first 30 dropped, maxima of prominence at least
    /// 5 % of the range, (count − 1) over the time from the first to the
    /// last; the mean of the cameras with at least 3; `None` if neither has.
    pub fn tumbling_rate(&self) -> Option<f64> {
        let keep: Vec<usize> = (0..self.len())
            .filter(|&k| self.position[k].z >= FLOOR_TRIM)
            .collect();
        let mut rates = Vec::new();
        for area in &self.area {
            let a: Vec<f64> = keep.iter().skip(30).map(|&k| area[k]).collect();
            if a.len() < 30 {
                continue;
            }
            let (lo, hi) = a
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
                    (l.min(v), h.max(v))
                });
            let peaks = prominent_peaks(&a, 0.05 * (hi - lo));
            if peaks.len() >= 3 {
                let span = (peaks[peaks.len() - 1] - peaks[0]) as f64 / FPS;
                rates.push((peaks.len() - 1) as f64 / span);
            }
        }
        (!rates.is_empty())
            .then(|| std::f64::consts::PI * rates.iter().sum::<f64>() / rates.len() as f64)
    }
}

/// The local maxima of `y` strictly above both neighbours, each as the
/// first and last index of its flat top, the ends excluded: the scan both
/// peak finders below share.
fn plateau_maxima(y: &[f64]) -> Vec<(usize, usize)> {
    let n = y.len();
    let mut out = Vec::new();
    let mut i = 1;
    while i + 1 < n {
        if y[i] > y[i - 1] {
            let mut j = i;
            while j + 1 < n && y[j + 1] == y[i] {
                j += 1;
            }
            if j + 1 < n && y[j + 1] < y[i] {
                out.push((i, j));
            }
            i = j + 1;
        } else {
            i += 1;
        }
    }
    out
}

/// Local maxima of `y` strictly above both neighbours (a flat top counts
/// once), the ends excluded: MATLAB's `findpeaks` without options.
pub fn count_peaks(y: &[f64]) -> usize {
    plateau_maxima(y).len()
}

/// Indices of the local maxima of `y` (a flat top at its middle, rounded
/// down) with prominence at least `min_prominence`: the height above the
/// higher of the lowest points between it and the nearest higher sample on
/// either side (or the signal's end), as SciPy's `find_peaks` defines it.
pub fn prominent_peaks(y: &[f64], min_prominence: f64) -> Vec<usize> {
    let n = y.len();
    let mut out = Vec::new();
    for (i, j) in plateau_maxima(y) {
        let peak = (i + j) / 2;
        let h = y[peak];
        let mut left_min = h;
        let mut k = i;
        while k > 0 {
            k -= 1;
            if y[k] > h {
                break;
            }
            left_min = left_min.min(y[k]);
        }
        let mut right_min = h;
        let mut k = j;
        while k + 1 < n {
            k += 1;
            if y[k] > h {
                break;
            }
            right_min = right_min.min(y[k]);
        }
        if h - left_min.max(right_min) >= min_prominence {
            out.push(peak);
        }
    }
    out
}

/// MATLAB's `smooth(y)`: a 5-point moving average whose span shrinks at the
/// ends (what the experiment's tracking applied to positions and areas).
pub fn smooth5(y: &[f64]) -> Vec<f64> {
    let n = y.len();
    (0..n)
        .map(|i| {
            let k = 2.min(i).min(n - 1 - i);
            y[i - k..=i + k].iter().sum::<f64>() / (2 * k + 1) as f64
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Both peak finders read the same maxima: a single sample, a flat top
    /// (its middle, rounded down) and a shoulder, never an end; and the
    /// prominences SciPy's definition gives by hand (1, 3 and 0.5).
    #[test]
    fn peaks_flat_tops_and_prominences() {
        let y = [0.0, 2.0, 1.0, 3.0, 3.0, 1.0, 1.5, 0.0];
        assert_eq!(count_peaks(&y), 3);
        assert_eq!(prominent_peaks(&y, 0.5), vec![1, 3, 6]);
        assert_eq!(prominent_peaks(&y, 0.6), vec![1, 3]);
        assert_eq!(prominent_peaks(&y, 1.5), vec![3]);
        // Rising to the end, or a plateau at the end: no peak.
        assert_eq!(count_peaks(&[0.0, 1.0, 2.0, 2.0]), 0);
        assert_eq!(count_peaks(&[3.0, 1.0, 2.0]), 0);
    }
}
