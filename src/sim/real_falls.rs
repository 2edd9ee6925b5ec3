//! The real-falls experiment of Howison, Hughes & Iida (2020, *Nature
//! Machine Intelligence* 2, 68) redone in the simulator, and the
//! comparison with their tracked falls of paper squares
//! (`tests/data/real-falls/squares/`, docs/real-falls.md).
//!
//! Both sides are measured the same way, as the experiment measured its
//! drops (its `classifyBehaviour.m`, re-implemented from its description):
//! a fall is filmed at 98 frames per second by two cameras looking down at
//! it; the first frames of a flat release, until the paper has moved 0.2 ×
//! its half-side sideways, are cut off as "steady"; the rest is one
//! segment, labelled tumbling or chaotic by the nearer of two cluster
//! centres in the plane of two features — projected-area maxima per second
//! (`Osc`, the two cameras averaged) and the spread of the per-frame fall
//! (`SpeedZ`). The centres are the means of the real segments of each of
//! the authors' automatic labels. Per size bin: the fraction tumbling among
//! tumbling + chaotic segments (the real side by people's labels), the
//! median descent speed dz/t and drift √(dx² + dy²)/dz over those segments,
//! and the median tumbling rate Ω = π × area maxima per second.
//!
//! The simulated cameras are the experiment's rig (positions, optical axes
//! and focal lengths decoded from its calibration files by the project's
//! `realfalls` tool; constants below) as ideal pinholes: no pixel rounding,
//! no smallest blob.

use crate::leaf::AeroSpec;
use crate::leaf::plates::{PlateShape, plate_meshed};
use crate::motion::trajectory::Trajectory;
use crate::physics::model::{Model, STANDARD_GRAVITY};
use crate::physics::params::{Integrator, TimeStep};
use crate::physics::pose::PoseTracker;
use crate::physics::run::{StepError, resolve_step, run_sampled};
use crate::physics::state::State;
use nalgebra::{UnitQuaternion, Vector3};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use rayon::prelude::*;
use std::f64::consts::{PI, TAU};
use std::path::Path;

pub mod departure;

type V3 = Vector3<f64>;

/// Frames per second of the experiment's cameras.
pub const FPS: f64 = 98.0;
/// Fluid density of the experiment (the authors' value), kg/m³.
pub const AIR_DENSITY: f64 = 1.2754;
/// Kinematic viscosity of the experiment's air, m²/s.
pub const AIR_VISCOSITY: f64 = 1.48e-5;
/// Areal density of the experiment's paper, kg/m².
pub const PAPER: f64 = 0.070;

/// The experiment's size bins, on the half-side r (m): [lo, hi).
pub const SQUARE_BINS: [(f64, f64); 5] = [
    (0.015, 0.019),
    (0.019, 0.0225),
    (0.0225, 0.030),
    (0.030, 0.040),
    (0.040, 0.0505),
];

/// Least sideways run of a third of a film for [`Film::path_turn`], m.
pub const MIN_THIRD_RUN: f64 = 0.02;

/// A flat release: at rest, centre 1.000 m above the floor.
pub const FLAT_HEIGHT: f64 = 1.000;
/// An edge-on release: at rest from 1.160 m, filmed from 1.097 m (real
/// on-edge drops are first seen there, already at about 1.1 m/s).
pub const EDGE_HEIGHT: f64 = 1.160;
/// Height of the first filmed frame of an edge-on release, m.
pub const EDGE_SEEN: f64 = 1.097;
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
    fn from_code(code: u32) -> Option<Label> {
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
    fn slice(&self, from: usize, to: usize) -> Film {
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
    /// (docs/real-falls.md, "How fast real paper dives").
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
    /// median 16–125° per bin and kind of release (docs/real-falls.md, "How
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

/// Local maxima of `y` strictly above both neighbours (a flat top counts
/// once), the ends excluded: MATLAB's `findpeaks` without options.
pub fn count_peaks(y: &[f64]) -> usize {
    let n = y.len();
    let mut count = 0;
    let mut i = 1;
    while i + 1 < n {
        if y[i] > y[i - 1] {
            let mut j = i;
            while j + 1 < n && y[j + 1] == y[i] {
                j += 1;
            }
            if j + 1 < n && y[j + 1] < y[i] {
                count += 1;
            }
            i = j + 1;
        } else {
            i += 1;
        }
    }
    count
}

/// Indices of the local maxima of `y` (a flat top at its middle, rounded
/// down) with prominence at least `min_prominence`: the height above the
/// higher of the lowest points between it and the nearest higher sample on
/// either side (or the signal's end), as SciPy's `find_peaks` defines it.
pub fn prominent_peaks(y: &[f64], min_prominence: f64) -> Vec<usize> {
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
            i = j + 1;
        } else {
            i += 1;
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

/// One real segment of `tests/data/real-falls/squares/`.
#[derive(Clone, Debug, PartialEq)]
pub struct RealSegment {
    /// File name without extension.
    pub name: String,
    /// Half the side, m.
    pub radius: f64,
    /// Released on edge (else flat).
    pub on_edge: bool,
    /// People's label.
    pub human: Label,
    /// The authors' k-means label.
    pub auto: Label,
    /// The segment as filmed.
    pub film: Film,
}

/// Why the real data cannot be read.
#[derive(Debug, thiserror::Error)]
#[error("{file}: {reason}")]
pub struct RealFallsError {
    /// The file.
    pub file: String,
    /// What is wrong.
    pub reason: String,
}

/// Reads `labels.csv` and every segment it lists from `dir`.
pub fn read_squares(dir: &Path) -> Result<Vec<RealSegment>, RealFallsError> {
    let fail = |file: &Path, reason: String| RealFallsError {
        file: file.display().to_string(),
        reason,
    };
    let labels = dir.join("labels.csv");
    let text =
        std::fs::read_to_string(&labels).map_err(|e| fail(&labels, format!("cannot read: {e}")))?;
    let mut out = Vec::new();
    for (line, row) in text.lines().enumerate().skip(1) {
        let f: Vec<&str> = row.split(',').collect();
        let bad = |what: &str| fail(&labels, format!("line {}: {what}", line + 1));
        if f.len() < 7 {
            return Err(bad(
                "expected name,shape,radius_m,width_px,release_vertical,human,auto,rows",
            ));
        }
        let num = |k: usize| {
            f[k].trim()
                .parse::<f64>()
                .map_err(|_| bad(&format!("column {} is not a number", k + 1)))
        };
        let label = |k: usize| {
            f[k].trim()
                .parse::<u32>()
                .ok()
                .and_then(Label::from_code)
                .ok_or_else(|| bad(&format!("column {} is not a label 1, 2 or 3", k + 1)))
        };
        let name = f[0].trim().to_string();
        let path = dir.join(format!("{name}.csv"));
        let data =
            std::fs::read_to_string(&path).map_err(|e| fail(&path, format!("cannot read: {e}")))?;
        let mut film = Film::default();
        for (k, r) in data.lines().enumerate().skip(1) {
            let v: Vec<f64> = r
                .split(',')
                .map(|s| s.trim().parse::<f64>())
                .collect::<Result<_, _>>()
                .map_err(|_| fail(&path, format!("line {}: not numbers", k + 1)))?;
            if v.len() != 6 {
                return Err(fail(
                    &path,
                    format!("line {}: expected t,x,y,z,area1,area2", k + 1),
                ));
            }
            if let Some(c) = v.iter().position(|x| !x.is_finite()) {
                let column = ["t", "x", "y", "z", "area1", "area2"][c];
                return Err(fail(
                    &path,
                    format!(
                        "line {}: {column} is {} (a film's values are finite)",
                        k + 1,
                        v[c]
                    ),
                ));
            }
            film.position.push(V3::new(v[1], v[2], v[3]));
            film.area[0].push(v[4]);
            film.area[1].push(v[5]);
        }
        out.push(RealSegment {
            name,
            radius: num(2)?,
            on_edge: num(4)? != 0.0,
            human: label(5)?,
            auto: label(6)?,
            film,
        });
    }
    Ok(out)
}

/// The two cluster centres (Osc, SpeedZ) of tumbling and chaotic segments:
/// the means of the real segments of each automatic label.
pub fn centres(real: &[RealSegment]) -> [[f64; 2]; 2] {
    let mean = |label: Label| {
        let f: Vec<Features> = real
            .iter()
            .filter(|s| s.auto == label)
            .filter_map(|s| s.film.features())
            .collect();
        let n = f.len().max(1) as f64;
        [
            f.iter().map(|f| f.osc).sum::<f64>() / n,
            f.iter().map(|f| f.speed_z).sum::<f64>() / n,
        ]
    };
    [mean(Label::Tumbling), mean(Label::Chaotic)]
}

/// The experiment's rule: the label of the nearer centre.
pub fn label_of(f: &Features, centres: &[[f64; 2]; 2]) -> Label {
    let d = |c: [f64; 2]| (f.osc - c[0]).powi(2) + (f.speed_z - c[1]).powi(2);
    if d(centres[0]) <= d(centres[1]) {
        Label::Tumbling
    } else {
        Label::Chaotic
    }
}

/// One size bin's numbers, real or simulated.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct BinStats {
    /// Falls (drops) in the bin.
    pub drops: usize,
    /// Tumbling, chaotic and steady segments.
    pub counts: [usize; 3],
    /// Fraction tumbling among tumbling + chaotic (NaN without any).
    pub tumbling: f64,
    /// Median descent speed, m/s.
    pub descent: f64,
    /// Median drift.
    pub drift: f64,
    /// Median tumbling rate over the drops that give one, rad/s.
    pub omega: f64,
    /// Drops with a tumbling rate.
    pub omega_drops: usize,
    /// The plate's side, m (the bin's median).
    pub side: f64,
}

/// Median of the finite values (NaN if none).
pub fn median(values: impl IntoIterator<Item = f64>) -> f64 {
    let mut v: Vec<f64> = values.into_iter().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Weighted median of the finite values with positive weight, each pair
/// (value, weight): the least value whose cumulative weight passes half
/// the total, or the mean of the two values on either side where the
/// cumulative weight meets half exactly (to 1e-12 of the total). With equal
/// weights it is [`median`] (NaN if none).
pub fn weighted_median(values: impl IntoIterator<Item = (f64, f64)>) -> f64 {
    let mut v: Vec<(f64, f64)> = values
        .into_iter()
        .filter(|(x, w)| x.is_finite() && w.is_finite() && *w > 0.0)
        .collect();
    v.sort_by(|a, b| a.0.total_cmp(&b.0));
    let half = 0.5 * v.iter().map(|(_, w)| w).sum::<f64>();
    let mut below = 0.0;
    for (k, &(x, w)) in v.iter().enumerate() {
        below += w;
        if (below - half).abs() <= 1e-12 * half && k + 1 < v.len() {
            return 0.5 * (x + v[k + 1].0);
        }
        if below > half {
            return x;
        }
    }
    v.last().map_or(f64::NAN, |&(x, _)| x)
}

/// One labelled segment with its features, and its drop's tumbling rate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measured {
    /// The label.
    pub label: Label,
    /// The features.
    pub features: Features,
}

fn stats(segments: &[Measured], omegas: &[Option<f64>], drops: usize, side: f64) -> BinStats {
    let count = |l: Label| segments.iter().filter(|s| s.label == l).count();
    let (t, c, s) = (
        count(Label::Tumbling),
        count(Label::Chaotic),
        count(Label::Steady),
    );
    let moving: Vec<&Measured> = segments
        .iter()
        .filter(|s| s.label != Label::Steady)
        .collect();
    BinStats {
        drops,
        counts: [t, c, s],
        tumbling: if t + c > 0 {
            t as f64 / (t + c) as f64
        } else {
            f64::NAN
        },
        descent: median(moving.iter().map(|s| s.features.descent())),
        drift: median(moving.iter().map(|s| s.features.drift())),
        omega: median(omegas.iter().flatten().copied()),
        omega_drops: omegas.iter().flatten().count(),
        side,
    }
}

/// The real side of the table: per bin of [`SQUARE_BINS`], people's labels.
/// Each drop has one tumbling or chaotic segment; its tumbling rate is
/// measured on that segment.
pub fn real_table(real: &[RealSegment]) -> Vec<BinStats> {
    real_bins(real)
        .iter()
        .map(|bin| bin.stats(&(0..bin.len()).collect::<Vec<_>>()))
        .collect()
}

/// The share of one simulated bin's moving drops (`drops`, as
/// [`sim_by_release`] splits them) that were let go flat: the share to
/// re-weight the films to ([`real_table_at_mix`]); NaN without any.
pub fn sim_flat_share(drops: &[SimulatedDrop]) -> f64 {
    sim_by_release(drops).flat_share()
}

/// The real table with each bin's flat and on-edge drops re-weighted so
/// that flat ones carry the share `flat_share[b]` of bin b's tumbling and
/// chaotic drops (each kind's drops equally), as if the films had let go
/// that mix: weighted medians of descent, drift and Ω, and the weighted
/// fraction tumbling. With the films' own shares ([`real_flat_share`]) it
/// is [`real_table`]. Pooled medians mix the two kinds of release, which
/// fall differently (the smallest squares drift 0.26 let go flat and 0.72
/// on edge), so a simulation that lets go half and half is compared like
/// for like with the films re-weighted to halves, not with their own mix
/// (5 flat to 9 on edge in that bin; docs/real-falls.md, "The films at the
/// simulated mix"). A bin without one kind keeps its drops unweighted; the
/// counts and the side are the films'.
pub fn real_table_at_mix(real: &[RealSegment], flat_share: &[f64]) -> Vec<BinStats> {
    real_bins(real)
        .iter()
        .zip(flat_share)
        .map(|(bin, &share)| bin.stats_at_mix(share))
        .collect()
}

/// One kind of release's numbers in one bin, real or simulated: what the
/// bin's pooled medians ([`BinStats`]) mix in the proportion of its flat
/// and on-edge drops.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct ReleaseStats {
    /// Tumbling and chaotic drops.
    pub drops: usize,
    /// Median descent speed over their segments, m/s.
    pub descent: f64,
    /// Median drift over their segments.
    pub drift: f64,
    /// Median tumbling rate over the drops that give one, rad/s.
    pub omega: f64,
    /// Median duration of a flat release's steady start (filmed until the
    /// plate is 0.2 r sideways; kept where it lasts over 2 frames), s; NaN
    /// without any. On the real side this times the films' first-frames
    /// artefact ([`departure`]), not the fall.
    pub steady: f64,
    /// Steady starts behind [`ReleaseStats::steady`].
    pub steady_drops: usize,
    /// Median time a flat release takes to leave its flat fall, s
    /// ([`departure`]: on the real side past the films' first-frames
    /// artefact); NaN without any.
    pub departs: f64,
    /// Flat releases behind [`ReleaseStats::departs`].
    pub departs_drops: usize,
    /// Median over the moving drops of their fastest descent
    /// ([`Film::fastest_descent`] on the moving segment), m/s.
    pub fastest: f64,
    /// Median over the moving drops of how far their path turns
    /// ([`Film::path_turn`] on the moving segment, its size), degrees; NaN
    /// without any.
    pub turn: f64,
    /// Moving drops behind [`ReleaseStats::turn`].
    pub turn_drops: usize,
}

/// A bin's drops split by how they were let go.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct ByRelease {
    /// Let go flat.
    pub flat: ReleaseStats,
    /// Let go on edge.
    pub edge: ReleaseStats,
}

impl ByRelease {
    /// The share of the moving drops let go flat (NaN without any).
    pub fn flat_share(&self) -> f64 {
        self.flat.drops as f64 / (self.flat.drops + self.edge.drops) as f64
    }
}

/// One moving segment as [`release_stats`] reads it.
#[derive(Clone, Copy, Debug)]
struct MovingDrop {
    features: Features,
    /// Its drop's tumbling rate.
    omega: Option<f64>,
    /// Its fastest descent, m/s.
    fastest: Option<f64>,
    /// How far its path turns, degrees.
    turn: Option<f64>,
}

/// The statistics of one kind of release from its moving segments (with
/// the tumbling rate of each one's drop) and its steady starts.
fn release_stats(moving: &[MovingDrop], steady: &[f64], departs: &[f64]) -> ReleaseStats {
    ReleaseStats {
        drops: moving.len(),
        descent: median(moving.iter().map(|m| m.features.descent())),
        drift: median(moving.iter().map(|m| m.features.drift())),
        omega: median(moving.iter().filter_map(|m| m.omega)),
        steady: median(steady.iter().copied()),
        steady_drops: steady.len(),
        departs: median(departs.iter().copied()),
        departs_drops: departs.len(),
        fastest: median(moving.iter().filter_map(|m| m.fastest)),
        turn: median(moving.iter().filter_map(|m| m.turn.map(f64::abs))),
        turn_drops: moving.iter().filter(|m| m.turn.is_some()).count(),
    }
}

/// The real side split by release, per bin of [`SQUARE_BINS`] (people's
/// labels, the drops as [`real_table`] measures them).
pub fn real_by_release(real: &[RealSegment]) -> Vec<ByRelease> {
    let departures = departure::departures_by_bin(real);
    real_bins(real)
        .iter()
        .zip(&departures)
        .map(|(bin, departs)| {
            let side = |on_edge: bool| {
                let mine = bin.drops.iter().filter(|d| d.on_edge == on_edge);
                let moving: Vec<MovingDrop> = mine
                    .clone()
                    .filter(|d| d.moving)
                    .filter_map(|d| {
                        d.measured.map(|m| MovingDrop {
                            features: m.features,
                            omega: d.omega,
                            fastest: d.fastest,
                            turn: d.turn,
                        })
                    })
                    .collect();
                let steady: Vec<f64> = mine
                    .filter(|d| !d.moving)
                    .filter_map(|d| d.measured.map(|m| m.features.time))
                    .collect();
                let departs: &[f64] = if on_edge { &[] } else { departs };
                release_stats(&moving, &steady, departs)
            };
            ByRelease {
                flat: side(false),
                edge: side(true),
            }
        })
        .collect()
}

/// Like for like: how far each kind of release falls from the films' own
/// in one bin, as |ln(sim/real)| of the median drift and of the median
/// tumbling rate, for flat and for on-edge releases (in that order: flat
/// drift, flat Ω, edge drift, edge Ω); `None` where either side has no
/// positive median. The pooled table ([`BinStats`]) mixes the two releases
/// in each side's own proportion, and the films' bins are not half and
/// half (docs/real-falls.md, "The release protocol"), so a law can score
/// well pooled with each release off on its own.
pub fn release_mismatch(real: &ByRelease, sim: &ByRelease) -> [Option<f64>; 4] {
    let log_ratio = |r: f64, s: f64| (r > 0.0 && s > 0.0).then(|| (s / r).ln().abs());
    [
        log_ratio(real.flat.drift, sim.flat.drift),
        log_ratio(real.flat.omega, sim.flat.omega),
        log_ratio(real.edge.drift, sim.edge.drift),
        log_ratio(real.edge.omega, sim.edge.omega),
    ]
}

/// One bin's simulated drops split by release.
pub fn sim_by_release(drops: &[SimulatedDrop]) -> ByRelease {
    let side = |on_edge: bool| {
        let mine = drops.iter().filter(|d| d.on_edge == on_edge);
        let moving: Vec<MovingDrop> = mine
            .clone()
            .flat_map(|d| {
                d.segments
                    .iter()
                    .filter(|m| m.label != Label::Steady)
                    .map(|m| MovingDrop {
                        features: m.features,
                        omega: d.omega,
                        fastest: d.fastest,
                        turn: d.turn,
                    })
            })
            .collect();
        let steady: Vec<f64> = mine
            .clone()
            .flat_map(|d| d.segments.iter())
            .filter(|m| m.label == Label::Steady)
            .map(|m| m.features.time)
            .collect();
        let departs: Vec<f64> = mine.filter_map(|d| d.departs).collect();
        release_stats(&moving, &steady, &departs)
    };
    ByRelease {
        flat: side(false),
        edge: side(true),
    }
}

/// Confidence level of [`real_intervals`]: the 5th to the 95th percentile.
pub const BOOTSTRAP_LEVEL: f64 = 0.90;

/// How far each real statistic of one bin can be trusted: the central
/// [`BOOTSTRAP_LEVEL`] interval [lo, hi] of its percentile bootstrap
/// (Efron & Tibshirani 1993, ch. 13).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BinIntervals {
    /// Fraction tumbling among tumbling + chaotic.
    pub tumbling: [f64; 2],
    /// Median descent speed, m/s.
    pub descent: [f64; 2],
    /// Median drift.
    pub drift: [f64; 2],
    /// Median tumbling rate, rad/s.
    pub omega: [f64; 2],
}

impl BinIntervals {
    /// Whether each of `sim`'s four statistics (fraction tumbling, descent,
    /// drift, Ω) lies inside its interval.
    pub fn contains(&self, sim: &BinStats) -> [bool; 4] {
        let inside = |[lo, hi]: [f64; 2], v: f64| (lo..=hi).contains(&v);
        [
            inside(self.tumbling, sim.tumbling),
            inside(self.descent, sim.descent),
            inside(self.drift, sim.drift),
            inside(self.omega, sim.omega),
        ]
    }
}

/// The real table's sampling uncertainty: per bin of [`SQUARE_BINS`], the
/// bin's tumbling and chaotic drops resampled with replacement `resamples`
/// times (seeded by `seed`), each resample's [`BinStats`] computed as
/// [`real_table`] does, and the [`BOOTSTRAP_LEVEL`] percentile interval of
/// each statistic. A bin of 14 moving drops (the smallest squares) pins its
/// medians far less than one of 30: a simulated value inside the interval
/// is as close as the real data can tell (docs/real-falls.md, "How sure the
/// real side is").
pub fn real_intervals(real: &[RealSegment], resamples: usize, seed: u64) -> Vec<BinIntervals> {
    real_bins(real)
        .iter()
        .enumerate()
        .map(|(b, bin)| {
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ ((b as u64) << 32));
            // Steady segments enter no statistic: resample the others.
            let moving: Vec<usize> = (0..bin.len()).filter(|&k| bin.drops[k].moving).collect();
            let n = moving.len();
            let draws: Vec<BinStats> = (0..resamples)
                .map(|_| {
                    let pick: Vec<usize> = (0..n).map(|_| moving[rng.random_range(0..n)]).collect();
                    bin.stats(&pick)
                })
                .collect();
            let interval = |value: fn(&BinStats) -> f64| {
                let mut v: Vec<f64> = draws.iter().map(value).filter(|x| x.is_finite()).collect();
                v.sort_by(f64::total_cmp);
                let tail = 0.5 * (1.0 - BOOTSTRAP_LEVEL);
                [quantile(&v, tail), quantile(&v, 1.0 - tail)]
            };
            BinIntervals {
                tumbling: interval(|s| s.tumbling),
                descent: interval(|s| s.descent),
                drift: interval(|s| s.drift),
                omega: interval(|s| s.omega),
            }
        })
        .collect()
}

/// The `p`-quantile of sorted `v` by linear interpolation between order
/// statistics (NaN if empty).
fn quantile(v: &[f64], p: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    let pos = p * (v.len() - 1) as f64;
    let lo = pos.floor() as usize;
    let hi = (lo + 1).min(v.len() - 1);
    v[lo] + (v[hi] - v[lo]) * (pos - lo as f64)
}

/// One real drop, measured once.
struct RealDrop {
    /// Its segment's label and features (`None` where the experiment drops
    /// the segment).
    measured: Option<Measured>,
    /// Its tumbling rate (`None` for a steady one or without three maxima).
    omega: Option<f64>,
    /// Half the side, m.
    radius: f64,
    /// Labelled tumbling or chaotic.
    moving: bool,
    /// Let go on edge.
    on_edge: bool,
    /// Its segment's fastest descent ([`Film::fastest_descent`]), m/s.
    fastest: Option<f64>,
    /// How far its segment's path turns ([`Film::path_turn`]), degrees.
    turn: Option<f64>,
}

/// One bin's real drops: what [`real_table`] and [`real_intervals`] take
/// their statistics from.
struct RealBin {
    drops: Vec<RealDrop>,
}

impl RealBin {
    fn len(&self) -> usize {
        self.drops.len()
    }

    /// The statistics of the drops `pick` (indices, repeats allowed).
    fn stats(&self, pick: &[usize]) -> BinStats {
        let chosen: Vec<&RealDrop> = pick.iter().map(|&k| &self.drops[k]).collect();
        let segments: Vec<Measured> = chosen.iter().filter_map(|d| d.measured).collect();
        let moving: Vec<&RealDrop> = chosen.iter().copied().filter(|d| d.moving).collect();
        let omegas: Vec<Option<f64>> = moving.iter().map(|d| d.omega).collect();
        let side = 2.0 * median(moving.iter().map(|d| d.radius));
        stats(&segments, &omegas, moving.len(), side)
    }

    /// The statistics of every drop, the flat ones weighted to the share
    /// `flat_share` of the moving drops ([`real_table_at_mix`]).
    fn stats_at_mix(&self, flat_share: f64) -> BinStats {
        let all: Vec<usize> = (0..self.len()).collect();
        let mut out = self.stats(&all);
        let moving: Vec<&RealDrop> = self.drops.iter().filter(|d| d.moving).collect();
        let flat = moving.iter().filter(|d| !d.on_edge).count() as f64;
        let edge = moving.len() as f64 - flat;
        if flat == 0.0 || edge == 0.0 || !(0.0..=1.0).contains(&flat_share) {
            return out;
        }
        let weight = |d: &RealDrop| {
            if d.on_edge {
                (1.0 - flat_share) / edge
            } else {
                flat_share / flat
            }
        };
        let of = |value: fn(&Features) -> f64| {
            weighted_median(
                moving
                    .iter()
                    .filter_map(|d| d.measured.map(|m| (value(&m.features), weight(d)))),
            )
        };
        out.descent = of(Features::descent);
        out.drift = of(Features::drift);
        out.omega = weighted_median(
            moving
                .iter()
                .filter_map(|d| d.omega.map(|o| (o, weight(d)))),
        );
        let labelled = |l: Label| {
            moving
                .iter()
                .filter(|d| d.measured.is_some_and(|m| m.label == l))
                .map(|d| weight(d))
                .sum::<f64>()
        };
        let (t, c) = (labelled(Label::Tumbling), labelled(Label::Chaotic));
        out.tumbling = if t + c > 0.0 { t / (t + c) } else { f64::NAN };
        out
    }
}

/// The bin of [`SQUARE_BINS`] a square of half-side `radius` falls in.
pub fn bin_of(radius: f64) -> Option<usize> {
    SQUARE_BINS
        .iter()
        .position(|&(lo, hi)| (lo..hi).contains(&radius))
}

/// The real segments of each bin of [`SQUARE_BINS`], each measured once.
fn real_bins(real: &[RealSegment]) -> Vec<RealBin> {
    (0..SQUARE_BINS.len())
        .map(|b| RealBin {
            drops: real
                .iter()
                .filter(|s| bin_of(s.radius) == Some(b))
                .map(|s| {
                    let moving = s.human != Label::Steady;
                    RealDrop {
                        measured: s.film.features().map(|features| Measured {
                            label: s.human,
                            features,
                        }),
                        omega: if moving { s.film.tumbling_rate() } else { None },
                        radius: s.radius,
                        moving,
                        on_edge: s.on_edge,
                        fastest: s.film.fastest_descent(),
                        turn: s.film.path_turn(),
                    }
                })
                .collect(),
        })
        .collect()
}

/// How a plate is let go.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Release {
    /// On edge (else flat).
    pub on_edge: bool,
    /// Body to world at release.
    pub rotation: UnitQuaternion<f64>,
}

/// How the simulated experiment lets its plates go: how far a flat
/// release is tilted and which share of a bin's releases is on edge; and
/// whether its paper bends, how finely its plates are meshed and whether
/// the room's air moves.
///
/// The default is the protocol of the project's cross-check
/// (`../shared/tools/realfalls/`, `simdrops.py`): flat releases tilted
/// 1–5°, half the releases on edge. The films say otherwise on both counts
/// (docs/real-falls.md, "The release protocol" and "When a flat release
/// departs"): the real flat releases depart 0.2 r sideways 0.13–0.37 s
/// after their first frame ([`departure`]), which a 1–5° tilt from rest
/// takes 0.76–1.05 s to do, and the real bins hold 5:9 to 17:7 flat to
/// on-edge drops, not 1:1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Protocol {
    /// A flat release's tilt out of the horizontal, degrees: uniform in
    /// [lo, hi) about a horizontal axis at a random azimuth.
    pub flat_tilt_deg: [f64; 2],
    /// Which releases are on edge.
    pub mix: ReleaseMix,
    /// The paper's bending stiffness D, N·m: `None` cuts rigid plates (the
    /// falling-plate literature's, and the cross-check's); `Some(D)` sheets
    /// that bend ([`crate::leaf::plates::flexible`]; docs/real-falls.md,
    /// "Paper that bends").
    pub bending: Option<f64>,
    /// Plates meshed this many times finer across than `leafmagic plate`'s
    /// (1; [`crate::leaf::plates::plate_meshed`]): for convergence studies
    /// (docs/real-falls.md, "Is the experiment converged?").
    pub refine: usize,
    /// A draught in the room ([`Draught`]): `None` is still air, the
    /// experiment's and the cross-check's.
    pub draught: Option<Draught>,
}

/// A draught in the room: a uniform horizontal wind, each component a
/// stationary Ornstein–Uhlenbeck process (Gaussian, of standard deviation
/// `speed` and exponential autocorrelation e^(−|Δt|/`correlation`)), its
/// own for each release ([`draught_field`]; docs/real-falls.md, "Paper that
/// bends, and a draught in the room").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Draught {
    /// Standard deviation of each horizontal component, m/s.
    pub speed: f64,
    /// Correlation time, s.
    pub correlation: f64,
}

/// Keyframes of a [`draught_field`] per correlation time: the wind is
/// linear between them, so a quarter of τ keeps the process's own
/// variation well above what the interpolation smooths away.
pub const DRAUGHT_KEYS_PER_CORRELATION: f64 = 4.0;

/// The random stream of release `k` of bin `bin` at `seed`: what
/// [`release`] draws its attitude from, and (offset) what
/// [`draught_field`] draws its wind from.
fn release_stream(seed: u64, bin: usize, k: usize) -> u64 {
    seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ ((bin as u64) << 32) ^ k as u64
}

/// The draught `draught` of release `k` of bin `bin` at `seed`, laid down
/// for `seconds` (and one correlation time more): for each horizontal axis
/// a uniform wind primitive keyframed every τ/[`DRAUGHT_KEYS_PER_CORRELATION`]
/// with the exact Ornstein–Uhlenbeck update x ← a x + σ √(1 − a²) z,
/// a = e^(−Δt/τ), z standard normal, from x₀ of the stationary law N(0, σ²).
/// The same arguments give the same field; its random stream is not the
/// release's ([`release`]), so a draught leaves the releases as they were.
pub fn draught_field(
    draught: &Draught,
    seed: u64,
    bin: usize,
    k: usize,
    seconds: f64,
) -> crate::physics::field::WindField {
    use crate::physics::field::{Interpolation, Keyframes, Primitive, WindField};
    use rand_distr::{Distribution, StandardNormal};
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(
        release_stream(seed, bin, k).wrapping_add(0xD1B5_4A32_D192_ED03),
    );
    let (sigma, tau) = (draught.speed, draught.correlation);
    let h = tau / DRAUGHT_KEYS_PER_CORRELATION;
    let a = (-h / tau).exp();
    let kick = sigma * (1.0 - a * a).sqrt();
    let count = ((seconds + tau) / h).ceil() as usize + 1;
    let primitives = [V3::x(), V3::y()]
        .into_iter()
        .map(|axis| {
            let z: f64 = StandardNormal.sample(&mut rng);
            let mut x = sigma * z;
            let keys = (0..count)
                .map(|n| {
                    let key = (n as f64 * h, x);
                    let z: f64 = StandardNormal.sample(&mut rng);
                    x = a * x + kick * z;
                    key
                })
                .collect();
            Primitive::uniform(axis).with_keys(Keyframes {
                keys,
                interpolation: Interpolation::Linear,
            })
        })
        .collect();
    WindField::new(primitives)
}

impl Protocol {
    /// Refuses a tilt range that is not 0 ≤ lo ≤ hi ≤ 90°, a bending
    /// stiffness that is not finite and positive, a refinement of 0 or a
    /// draught without a positive speed and correlation time, naming it.
    ///
    /// # Errors
    /// The reason, for the caller to prefix with where the range came from.
    pub fn check(&self) -> Result<(), String> {
        let [lo, hi] = self.flat_tilt_deg;
        if !(lo.is_finite() && hi.is_finite() && 0.0 <= lo && lo <= hi && hi <= 90.0) {
            return Err(format!(
                "flat tilt {lo},{hi}: expected degrees with 0 <= lo <= hi <= 90"
            ));
        }
        if let Some(d) = self.bending
            && !(d.is_finite() && d > 0.0)
        {
            return Err(format!(
                "bending stiffness {d}: expected a finite number > 0 N·m"
            ));
        }
        if self.refine == 0 {
            return Err("mesh refinement 0: expected a whole number >= 1".to_string());
        }
        if let Some(d) = self.draught
            && !(d.speed.is_finite()
                && d.speed > 0.0
                && d.correlation.is_finite()
                && d.correlation > 0.0)
        {
            return Err(format!(
                "draught {},{}: expected a speed > 0 m/s and a correlation time > 0 s",
                d.speed, d.correlation
            ));
        }
        Ok(())
    }
}

impl Default for Protocol {
    fn default() -> Self {
        Self {
            flat_tilt_deg: [1.0, 5.0],
            mix: ReleaseMix::Halves,
            bending: None,
            refine: 1,
            draught: None,
        }
    }
}

/// Which share of a bin's releases is on edge.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ReleaseMix {
    /// The first half (rounded up) flat, the rest on edge: the
    /// cross-check's protocol.
    Halves,
    /// Each bin's share of on-edge drops among its real tumbling and
    /// chaotic drops ([`real_flat_share`]), rounded to whole releases.
    AsFilmed,
}

impl std::str::FromStr for ReleaseMix {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "halves" => Ok(Self::Halves),
            "filmed" => Ok(Self::AsFilmed),
            other => Err(format!(
                "release mix {other:?}: expected \"halves\" or \"filmed\""
            )),
        }
    }
}

/// Per bin of [`SQUARE_BINS`], the share of the real tumbling and chaotic
/// drops that were let go flat (NaN for a bin without any).
pub fn real_flat_share(real: &[RealSegment]) -> Vec<f64> {
    real_by_release(real)
        .iter()
        .map(ByRelease::flat_share)
        .collect()
}

/// How many of `releases` are flat under `mix`, given the bin's real flat
/// share `flat_share` (used by [`ReleaseMix::AsFilmed`] only; a NaN share
/// falls back to halves).
pub fn flat_releases(mix: ReleaseMix, releases: usize, flat_share: f64) -> usize {
    match mix {
        ReleaseMix::AsFilmed if flat_share.is_finite() => {
            ((releases as f64 * flat_share).round() as usize).min(releases)
        }
        _ => releases.div_ceil(2),
    }
}

/// The `k`-th release of bin `bin` at `seed`, of which the first `flat`
/// are flat (tilted as `protocol` says, about a horizontal axis at a random
/// azimuth), the rest on edge (90 ± 1–5° about one in-plane axis, ±5° about
/// the other), each at a random in-plane angle and turned by a random yaw.
pub fn release(protocol: &Protocol, seed: u64, bin: usize, k: usize, flat: usize) -> Release {
    let on_edge = k >= flat;
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(release_stream(seed, bin, k));
    let tau = std::f64::consts::TAU;
    let psi = rng.random_range(0.0..tau);
    let yaw = rng.random_range(0.0..tau);
    let (tx, ty) = if on_edge {
        let d = rng.random_range(1.0..5.0)
            * if rng.random_range(0.0..1.0) < 0.5 {
                1.0
            } else {
                -1.0
            };
        (90.0 + d, rng.random_range(-5.0..5.0))
    } else {
        let [lo, hi] = protocol.flat_tilt_deg;
        let t: f64 = if hi > lo {
            rng.random_range(lo..hi)
        } else {
            lo
        };
        let a: f64 = rng.random_range(0.0..tau);
        (t * a.cos(), t * a.sin())
    };
    let axis = |v: V3| nalgebra::Unit::new_normalize(v);
    let rotation = UnitQuaternion::from_axis_angle(&axis(V3::z()), yaw)
        * UnitQuaternion::from_axis_angle(&axis(V3::x()), f64::to_radians(tx))
        * UnitQuaternion::from_axis_angle(&axis(V3::y()), f64::to_radians(ty))
        * UnitQuaternion::from_axis_angle(&axis(V3::z()), psi);
    Release { on_edge, rotation }
}

/// Why a simulated release failed.
#[derive(Debug, thiserror::Error)]
pub enum ExperimentError {
    /// The plate could not be built.
    #[error(transparent)]
    Plate(#[from] crate::leaf::plates::PlateError),
    /// The plate's model is invalid.
    #[error(transparent)]
    Model(#[from] crate::physics::model::ModelError),
    /// No step could be chosen.
    #[error(transparent)]
    Step(#[from] StepError),
    /// The fall diverged.
    #[error(transparent)]
    Sim(#[from] crate::physics::integrate::SimError),
    /// The release protocol is out of range ([`Protocol::check`]).
    #[error("release protocol: {0}")]
    Protocol(String),
}

/// The camera's projected area of every triangle of `model` at `x`, px.
fn projected_area(model: &Model, x: &[V3], camera: &Camera) -> f64 {
    let c = V3::from(camera.centre);
    let axis = V3::from(camera.axis);
    let f2 = camera.focal[0] * camera.focal[1];
    model
        .triangles
        .iter()
        .map(|t| {
            let [a, b, cc] = t.corners;
            let big_n = (x[b] - x[a]).cross(&(x[cc] - x[a]));
            let r = (x[a] + x[b] + x[cc]) / 3.0 - c;
            let depth = r.dot(&axis);
            0.5 * f2 * big_n.dot(&r).abs() / depth.powi(3)
        })
        .sum()
}

fn centroid(model: &Model, x: &[V3]) -> V3 {
    let (mut sum, mut total) = (V3::zeros(), 0.0);
    for t in &model.triangles {
        let [a, b, c] = t.corners;
        let area = 0.5 * (x[b] - x[a]).cross(&(x[c] - x[a])).norm();
        sum += (x[a] + x[b] + x[c]) * (area / 3.0);
        total += area;
    }
    sum / total
}

/// A simulated drop as the cameras saw it.
#[derive(Clone, Debug, PartialEq)]
pub struct SimulatedDrop {
    /// The release.
    pub on_edge: bool,
    /// The labelled segments (a flat release's steady start included).
    pub segments: Vec<Measured>,
    /// The tumbling rate of the whole filmed drop.
    pub omega: Option<f64>,
    /// The plate's normal turned past the horizontal this many times.
    pub flips: usize,
    /// Simulated seconds to the floor.
    pub seconds: f64,
    /// A flat release's departure from its flat fall, measured on its film
    /// as on the real ones ([`departure::departure`]), s; `None` on edge or
    /// if it never departs.
    pub departs: Option<f64>,
    /// Its moving segment's fastest descent ([`Film::fastest_descent`]),
    /// m/s; `None` without one.
    pub fastest: Option<f64>,
    /// How far its moving segment's path turns ([`Film::path_turn`]),
    /// degrees; `None` without one or without a heading.
    pub turn: Option<f64>,
    /// What the plate's rotation did over the filmed fall ([`rotation_of`]).
    pub rotation: Rotation,
}

/// Longest fall simulated, s: a drop that has not reached the floor by
/// then is filmed as far as it got.
pub const MAX_SECONDS: f64 = 8.0;

/// The step of every drop of `model` in the experiment: Verlet at `--dt
/// auto` against the camera's frames. Found once per plate, not per
/// release: under the unsteady law it costs more than a short fall.
pub fn experiment_step(model: &Model) -> Result<f64, ExperimentError> {
    Ok(resolve_step(
        model,
        Integrator::Verlet,
        TimeStep::Auto,
        1.0 / FPS,
    )?)
}

/// Drops `model` (a plate of half-side `radius`) at step `dt`
/// ([`experiment_step`]) as `release` says, films it and measures it as
/// the experiment did.
pub fn simulate_drop(
    model: &Model,
    dt: f64,
    radius: f64,
    release: &Release,
    centres: &[[f64; 2]; 2],
) -> Result<SimulatedDrop, ExperimentError> {
    let frame_dt = 1.0 / FPS;
    let height = if release.on_edge {
        EDGE_HEIGHT
    } else {
        FLAT_HEIGHT
    };
    let start = V3::new(DROP_POINT[0], DROP_POINT[1], height);
    let mut state = State::released(model, release.rotation, start);
    let mut raw = Film::default();
    let mut normals = Vec::new();
    // The plate's best-fit rotation per frame, for what its rotation did
    // ([`rotation_of`]).
    let mut poses = (PoseTracker::new(model, release.rotation), Vec::new());
    type Poses = (PoseTracker, Vec<UnitQuaternion<f64>>);
    let record = |x: &[V3], raw: &mut Film, normals: &mut Vec<f64>, poses: &mut Poses| {
        raw.position.push(centroid(model, x));
        for (k, cam) in CAMERAS.iter().enumerate() {
            raw.area[k].push(projected_area(model, x, cam));
        }
        let t = &model.triangles[0];
        let [a, b, c] = t.corners;
        normals.push((x[b] - x[a]).cross(&(x[c] - x[a])).z);
        let (_, rotation) = poses.0.pose(model, x);
        poses.1.push(rotation);
    };
    // In chunks of 0.5 s until the floor.
    let chunk = (0.5 * FPS).round() as u64;
    record(&state.position, &mut raw, &mut normals, &mut poses);
    while raw.position.last().is_some_and(|p| p.z > 0.0) && state.time < MAX_SECONDS {
        run_sampled(
            model,
            &mut state,
            Integrator::Verlet,
            dt,
            frame_dt,
            chunk,
            |k, x| {
                if k > 0 {
                    record(x, &mut raw, &mut normals, &mut poses);
                }
            },
        )?;
    }
    let seconds = state.time;
    // Film: from the first frame at or below the first filmed height, cut
    // at the first below the floor; smoothed; x, y from the first frame.
    let first = if release.on_edge {
        raw.position
            .iter()
            .position(|p| p.z <= EDGE_SEEN)
            .unwrap_or(0)
    } else {
        0
    };
    let last = raw
        .position
        .iter()
        .position(|p| p.z < 0.0)
        .unwrap_or(raw.len());
    let cut = raw.slice(first, last.max(first));
    let flips = normals[first..last.max(first)]
        .windows(2)
        .filter(|w| w[0].signum() != w[1].signum())
        .count();
    let rotation = rotation_of(
        &Trajectory {
            time: (first..last.max(first)).map(|k| k as f64 / FPS).collect(),
            position: cut.position.clone(),
            orientation: poses.1[first..last.max(first)].to_vec(),
            areas: Vec::new(),
        },
        2.0 * radius,
    );
    let coord = |k: usize| smooth5(&cut.position.iter().map(|p| p[k]).collect::<Vec<_>>());
    let (xs, ys, zs) = (coord(0), coord(1), coord(2));
    let mut film = Film {
        position: (0..cut.len())
            .map(|k| V3::new(xs[k] - xs[0], ys[k] - ys[0], zs[k]))
            .collect(),
        area: [smooth5(&cut.area[0]), smooth5(&cut.area[1])],
    };
    let omega = film.tumbling_rate();
    // Segments (classifyBehaviour.m): trim the end below FLOOR_TRIM; a flat
    // release's start until 0.2 r sideways is steady.
    let mut n = film.len();
    while n > 0 && film.position[n - 1].z < FLOOR_TRIM {
        n -= 1;
    }
    film = film.slice(0, n);
    let departs = if release.on_edge {
        None
    } else {
        departure::departure(radius, &film).and_then(|d| d.departs)
    };
    let threshold = if release.on_edge { 0.01 } else { 0.2 * radius };
    let mut tc = 1;
    while tc < n && film.position[tc - 1].xy().norm() < threshold {
        tc += 1;
    }
    let mut segments = Vec::new();
    let mut fastest = None;
    let mut turn = None;
    let mut push = |from: usize, to: usize, steady: bool| {
        let cut = film.slice(from, to);
        if let Some(features) = cut.features() {
            let label = if steady {
                Label::Steady
            } else {
                fastest = cut.fastest_descent();
                turn = cut.path_turn();
                label_of(&features, centres)
            };
            segments.push(Measured { label, features });
        }
    };
    if !release.on_edge && tc > 2 {
        push(0, tc, true);
        if n > tc + 10 {
            push(tc - 1, n, false);
        }
    } else if !release.on_edge {
        push(0, n, false);
    } else if n > tc + 10 {
        push(tc - 1, n, false);
    }
    Ok(SimulatedDrop {
        on_edge: release.on_edge,
        segments,
        omega,
        flips,
        seconds,
        departs,
        fastest,
        turn,
        rotation,
    })
}

/// What a simulated fall did, read from its rotation rather than from the
/// experiment's labelling rule ([`label_of`], whose features have units:
/// a large plate tumbling end over end shows as few area maxima per second
/// as a small one falling chaotically).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rotation {
    /// Turned end over end without reversing, a whole turn (two flips) or
    /// more.
    Tumbling,
    /// Swung back and forth without turning over.
    Fluttering,
    /// Both: turned over and swung back (the chaotic regime's mark).
    Mixed,
    /// Neither reversed nor turned over.
    Steady,
}

/// What a fall did by its plate's rotation over the whole of `trajectory`
/// (`size` its chord, m), read with the motion classifier's own kinematics
/// ([`crate::motion::classify::pose_features`]: a reversal is a turning
/// point of a swing of at least 10° about the dominant axis, a flip the
/// normal crossing the horizontal with ±30° hysteresis): tumbling with no
/// reversal and at least two flips (a whole turn), fluttering with
/// reversals and no flip, mixed with both, steady otherwise.
pub fn rotation_of(trajectory: &Trajectory, size: f64) -> Rotation {
    let f = crate::motion::classify::pose_features(trajectory, size);
    match (f.reversals > 0, f.normal_flips) {
        (false, flips) if flips >= 2 => Rotation::Tumbling,
        (true, 0) => Rotation::Fluttering,
        (true, _) => Rotation::Mixed,
        (false, _) => Rotation::Steady,
    }
}

/// How many of `drops` let go on edge (`on_edge`) or flat fell each way
/// ([`SimulatedDrop::rotation`]), in the order of [`Rotation`]'s variants:
/// tumbling, fluttering, mixed, steady.
pub fn rotation_counts(drops: &[SimulatedDrop], on_edge: bool) -> [usize; 4] {
    let mut counts = [0; 4];
    for d in drops.iter().filter(|d| d.on_edge == on_edge) {
        counts[d.rotation as usize] += 1;
    }
    counts
}

impl SimulatedDrop {
    /// The experiment's label of its moving (tumbling or chaotic) segment,
    /// if it has one.
    pub fn moving_label(&self) -> Option<Label> {
        self.segments
            .iter()
            .map(|s| s.label)
            .find(|&l| l != Label::Steady)
    }
}

/// Which releases one bin's simulation makes: `releases` drops at `seed`,
/// the first `flat` of them flat, let go as `protocol` says.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BinReleases {
    /// The bin's index in [`SQUARE_BINS`] (it seeds the releases).
    pub bin: usize,
    /// Drops in the bin.
    pub releases: usize,
    /// How many of them are flat ([`flat_releases`]).
    pub flat: usize,
    /// The seed.
    pub seed: u64,
    /// How they are let go.
    pub protocol: Protocol,
}

/// The simulated side of one bin: the drops of `run` with a plate of
/// `shape` and size `side` (twice the inradius, as `leafmagic plate` reads
/// it) under `aero` (air and paper of the experiment).
pub fn simulate_bin(
    shape: PlateShape,
    side: f64,
    aero: &AeroSpec,
    run: &BinReleases,
    centres: &[[f64; 2]; 2],
) -> Result<(BinStats, Vec<SimulatedDrop>), ExperimentError> {
    run.protocol.check().map_err(ExperimentError::Protocol)?;
    let mut spec = plate_meshed(shape, side, 1.0, PAPER, aero.clone(), run.protocol.refine)?;
    if let Some(d) = run.protocol.bending {
        spec = crate::leaf::plates::flexible(spec, d)?;
    }
    let model = spec.model()?;
    // Each release's own draught, if any; the step is found once, under the
    // strongest of them (a faster relative flow only shortens it).
    let fields: Vec<Option<crate::physics::field::WindField>> = (0..run.releases)
        .map(|k| {
            run.protocol
                .draught
                .map(|d| draught_field(&d, run.seed, run.bin, k, MAX_SECONDS))
        })
        .collect();
    let strongest = fields
        .iter()
        .flatten()
        .max_by(|a, b| a.speed_bound().total_cmp(&b.speed_bound()));
    let dt = match strongest {
        Some(field) => experiment_step(&Model {
            wind: field.clone(),
            ..model.clone()
        })?,
        None => experiment_step(&model)?,
    };
    let drops: Vec<SimulatedDrop> = (0..run.releases)
        .into_par_iter()
        .map(|k| {
            let gusty = fields[k].as_ref().map(|field| Model {
                wind: field.clone(),
                ..model.clone()
            });
            simulate_drop(
                gusty.as_ref().unwrap_or(&model),
                dt,
                0.5 * side,
                &release(&run.protocol, run.seed, run.bin, k, run.flat),
                centres,
            )
        })
        .collect::<Result<_, _>>()?;
    let segments: Vec<Measured> = drops
        .iter()
        .flat_map(|d| d.segments.iter().copied())
        .collect();
    let omegas: Vec<Option<f64>> = drops.iter().map(|d| d.omega).collect();
    Ok((stats(&segments, &omegas, drops.len(), side), drops))
}

/// The experiment's air in an `[aero]` table of law `law`: its density and
/// viscosity (the unsteady law), its density (the quadratic law).
pub fn experiment_air(mut aero: AeroSpec) -> AeroSpec {
    if aero.law != crate::leaf::AeroLawName::Linear {
        aero.air_density.get_or_insert(AIR_DENSITY);
    }
    if aero.law == crate::leaf::AeroLawName::Unsteady {
        aero.kinematic_viscosity.get_or_insert(AIR_VISCOSITY);
    }
    aero
}

/// The score's four parts for one bin: |Δ fraction tumbling|, |ln v ratio|,
/// |ln drift ratio|, |ln Ω ratio| (values floored at 0.01; a value the
/// simulation cannot give costs 1), as docs/real-falls.md defines them.
pub fn bin_score(real: &BinStats, sim: &BinStats) -> [f64; 4] {
    let log_ratio = |a: f64, b: f64| {
        if a.is_finite() && b.is_finite() {
            (a.max(0.01) / b.max(0.01)).ln().abs()
        } else {
            1.0
        }
    };
    [
        if sim.tumbling.is_finite() && real.tumbling.is_finite() {
            (sim.tumbling - real.tumbling).abs()
        } else {
            1.0
        },
        log_ratio(sim.descent, real.descent),
        log_ratio(sim.drift, real.drift),
        log_ratio(sim.omega, real.omega),
    ]
}

/// Issue 17's per-bin bounds on the simulated side against the real:
/// descent within 10 %, drift within a factor 1.5, tumbling rate within 15 %.
pub const DESCENT_BOUND: f64 = 0.10;
/// See [`DESCENT_BOUND`].
pub const DRIFT_FACTOR: f64 = 1.5;
/// See [`DESCENT_BOUND`].
pub const OMEGA_BOUND: f64 = 0.15;

/// The statistics of one bin that miss [`DESCENT_BOUND`], [`DRIFT_FACTOR`]
/// or [`OMEGA_BOUND`], each named (`"v"`, `"drift"`, `"Ω"`) with its ratio
/// sim/real (a ratio that is not finite misses).
pub fn bounds_missed(real: &BinStats, sim: &BinStats) -> Vec<(&'static str, f64)> {
    let (v, drift, omega) = (
        sim.descent / real.descent,
        sim.drift / real.drift,
        sim.omega / real.omega,
    );
    [
        ("v", v, (v - 1.0).abs() <= DESCENT_BOUND),
        ("drift", drift, drift.ln().abs() <= DRIFT_FACTOR.ln()),
        ("Ω", omega, (omega - 1.0).abs() <= OMEGA_BOUND),
    ]
    .into_iter()
    .filter(|&(_, q, within)| !(q.is_finite() && within))
    .map(|(name, q, _)| (name, q))
    .collect()
}

/// The whole comparison: the real table, the simulated one and the score.
#[derive(Clone, Debug)]
pub struct Comparison {
    /// Per bin, the real side.
    pub real: Vec<BinStats>,
    /// Per bin, the simulated side.
    pub sim: Vec<BinStats>,
    /// Per bin, the score's parts.
    pub parts: Vec<[f64; 4]>,
    /// Every simulated drop, per bin.
    pub drops: Vec<Vec<SimulatedDrop>>,
}

impl Comparison {
    /// The mean over bins of the summed parts.
    pub fn score(&self) -> f64 {
        self.parts
            .iter()
            .map(|p| p.iter().sum::<f64>())
            .sum::<f64>()
            / self.parts.len() as f64
    }

    /// The simulated bins' shares of flat releases among their moving
    /// drops ([`sim_flat_share`]).
    pub fn sim_flat_shares(&self) -> Vec<f64> {
        self.drops.iter().map(|d| sim_flat_share(d)).collect()
    }

    /// The films (`real`, the segments the real side came from)
    /// re-weighted to the simulated bins' mix of releases
    /// ([`real_table_at_mix`]): the real side like for like.
    pub fn films_at_simulated_mix(&self, real: &[RealSegment]) -> Vec<BinStats> {
        real_table_at_mix(real, &self.sim_flat_shares())
    }

    /// The score of the simulated side against another real side (`real`,
    /// one [`BinStats`] per bin, such as
    /// [`Comparison::films_at_simulated_mix`]): the mean over bins of the
    /// summed [`bin_score`] parts.
    pub fn score_against(&self, real: &[BinStats]) -> f64 {
        real.iter()
            .zip(&self.sim)
            .map(|(r, s)| bin_score(r, s).iter().sum::<f64>())
            .sum::<f64>()
            / real.len() as f64
    }
}

/// Simulates the experiment for every bin of the real table (`releases`
/// per bin) under `aero` and compares, releasing as the cross-check does
/// ([`Protocol::default`]).
pub fn compare(
    real_segments: &[RealSegment],
    aero: &AeroSpec,
    releases: usize,
    seed: u64,
) -> Result<Comparison, ExperimentError> {
    compare_with(real_segments, aero, releases, seed, &Protocol::default())
}

/// [`compare`] with the plates let go as `protocol` says.
pub fn compare_with(
    real_segments: &[RealSegment],
    aero: &AeroSpec,
    releases: usize,
    seed: u64,
    protocol: &Protocol,
) -> Result<Comparison, ExperimentError> {
    let real = real_table(real_segments);
    let (sim, drops): (Vec<BinStats>, Vec<Vec<SimulatedDrop>>) = simulate_table(
        PlateShape::Square,
        &real,
        real_segments,
        aero,
        releases,
        seed,
        protocol,
    )?
    .into_iter()
    .unzip();
    let parts = real
        .iter()
        .zip(&sim)
        .map(|(r, s)| bin_score(r, s))
        .collect();
    Ok(Comparison {
        real,
        sim,
        parts,
        drops,
    })
}

/// The experiment simulated for plates of another `shape` at the squares'
/// bin sizes (`real_segments` give the sizes and the labelling rule's
/// centres): the simulated side of each bin, with no real side to score it
/// against. The study's circles and hexagons are held back to check what
/// was tuned on the squares, so this is a prediction for them, written
/// down before they are seen (docs/real-falls.md, "Predictions for the
/// held-out shapes"). The plates are let go as `protocol` says (the
/// recorded predictions: [`Protocol::default`]).
pub fn predict(
    shape: PlateShape,
    real_segments: &[RealSegment],
    aero: &AeroSpec,
    releases: usize,
    seed: u64,
    protocol: &Protocol,
) -> Result<Vec<BinStats>, ExperimentError> {
    let real = real_table(real_segments);
    let table = simulate_table(shape, &real, real_segments, aero, releases, seed, protocol)?;
    Ok(table.into_iter().map(|(stats, _)| stats).collect())
}

/// Every bin of `real` simulated with plates of `shape` at the bin's size,
/// in the experiment's air and labelled by the centres of `real_segments`,
/// let go as `protocol` says (the release mix read from `real_segments`).
fn simulate_table(
    shape: PlateShape,
    real: &[BinStats],
    real_segments: &[RealSegment],
    aero: &AeroSpec,
    releases: usize,
    seed: u64,
    protocol: &Protocol,
) -> Result<Vec<(BinStats, Vec<SimulatedDrop>)>, ExperimentError> {
    let centres = centres(real_segments);
    let aero = experiment_air(aero.clone());
    let shares = real_flat_share(real_segments);
    real.iter()
        .enumerate()
        .map(|(bin, r)| {
            let run = BinReleases {
                bin,
                releases,
                flat: flat_releases(protocol.mix, releases, shares[bin]),
                seed,
                protocol: *protocol,
            };
            simulate_bin(shape, r.side, &aero, &run, &centres)
        })
        .collect()
}

/// Mahadevan, Ryu & Samuel's scaling of a tumbling card, Ω ∝ √(σ g/ρ)/w:
/// the dimensionless rate Ω w / √(σ g / ρ) of a plate of width `width`.
pub fn tumbling_number(omega: f64, width: f64, sigma: f64, rho: f64) -> f64 {
    omega * width / (sigma * STANDARD_GRAVITY / rho).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What a law that fell exactly as the films' drops would score at the
    /// cross-check's protocol (docs/real-falls.md, "The films at the
    /// simulated mix"): each bin's own drops resampled 12 flat and 12 on
    /// edge, 4,000 times, against the films' table. The smallest squares'
    /// pooled drift is within ×1.5 of the films' in only a quarter of the
    /// resamples (their bin is 5 flat drops to 9 on edge), every other
    /// bin's in at least 80 %, and Ω within 15 % and descent within 10 % in
    /// at least 95 % of every bin's.
    #[test]
    fn the_films_own_drops_let_go_half_and_half_miss_the_smallest_drift() {
        let real = read_squares(
            &Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/real-falls/squares"),
        )
        .unwrap();
        let table = real_table(&real);
        for (b, bin) in real_bins(&real).iter().enumerate() {
            let kind = |edge: bool| -> Vec<usize> {
                (0..bin.len())
                    .filter(|&k| bin.drops[k].moving && bin.drops[k].on_edge == edge)
                    .collect()
            };
            let (flat, edge) = (kind(false), kind(true));
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(7 + b as u64);
            let mut pick = |from: &[usize]| from[rng.random_range(0..from.len())];
            let resamples = 4000;
            let (mut drift, mut omega, mut descent) = (0, 0, 0);
            let mut ratios = Vec::with_capacity(resamples);
            for _ in 0..resamples {
                let drops: Vec<usize> = (0..24)
                    .map(|k| if k < 12 { pick(&flat) } else { pick(&edge) })
                    .collect();
                let stats = bin.stats(&drops);
                ratios.push(stats.drift / table[b].drift);
                let missed = bounds_missed(&table[b], &stats);
                drift += missed.iter().all(|(n, _)| *n != "drift") as usize;
                omega += missed.iter().all(|(n, _)| *n != "Ω") as usize;
                descent += missed.iter().all(|(n, _)| *n != "v") as usize;
            }
            let share = |count: usize| count as f64 / resamples as f64;
            let (drift, omega, descent) = (share(drift), share(omega), share(descent));
            println!(
                "bin {b}: drift ratio median {:.2}, within ×1.5 {drift:.2}; Ω within 15 % {omega:.2}; descent within 10 % {descent:.2}",
                median(ratios)
            );
            if b == 0 {
                assert!(drift < 0.4, "{drift}");
            } else {
                assert!(drift >= 0.8, "bin {b}: {drift}");
            }
            assert!(omega >= 0.95, "bin {b}: {omega}");
            assert!(descent >= 0.95, "bin {b}: {descent}");
        }
    }
}
