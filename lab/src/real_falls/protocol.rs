//! How the simulated experiment lets its plates go: heights, tilts, the
//! release mix and the optional draught in the room.

use nalgebra::{UnitQuaternion, Vector3};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

type V3 = Vector3<f64>;

/// Fluid density of the experiment (the authors' value), kg/m³.
pub const AIR_DENSITY: f64 = 1.2754;

/// Kinematic viscosity of the experiment's air, m²/s.
pub const AIR_VISCOSITY: f64 = 1.48e-5;

/// Areal density of the experiment's paper, kg/m².
pub const PAPER: f64 = 0.070;

/// A flat release: at rest, centre 1.000 m above the floor.
pub const FLAT_HEIGHT: f64 = 1.000;

/// An edge-on release: at rest from 1.160 m, filmed from 1.097 m (real
/// on-edge drops are first seen there, already at about 1.1 m/s).
pub const EDGE_HEIGHT: f64 = 1.160;

/// Height of the first filmed frame of an edge-on release, m.
pub const EDGE_SEEN: f64 = 1.097;

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
/// (docs/lab/real-falls.md, "The release protocol" and "When a flat release
/// departs"): the real flat releases depart 0.2 r sideways 0.13–0.37 s
/// after their first frame ([`departure`](super::departure)), which a 1–5° tilt from rest
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
    /// that bend ([`leafmagic::leaf::plates::flexible`]; docs/lab/real-falls.md,
    /// "Paper that bends").
    pub bending: Option<f64>,
    /// Plates meshed this many times finer across than `leafmagic plate`'s
    /// (1; [`leafmagic::leaf::plates::plate_meshed`]): for convergence studies
    /// (docs/lab/real-falls.md, "Is the experiment converged?").
    pub refine: usize,
    /// A draught in the room ([`Draught`]): `None` is still air, the
    /// experiment's and the cross-check's.
    pub draught: Option<Draught>,
    /// A cross's arm width over its span (crosses only, which need it: the
    /// plates are `leafmagic plate --shape cross --arm-width` ratio × size).
    pub cross_arm: Option<f64>,
}

/// A draught in the room: a uniform horizontal wind, each component a
/// stationary Ornstein–Uhlenbeck process (Gaussian, of standard deviation
/// `speed` and exponential autocorrelation e^(−|Δt|/`correlation`)), its
/// own for each release ([`draught_field`]; docs/lab/real-falls.md, "Paper that
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
) -> leafmagic::physics::field::WindField {
    use leafmagic::physics::field::{Interpolation, Keyframes, Primitive, WindField};
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
    /// stiffness that is not finite and positive, a refinement of 0, a
    /// draught without a positive speed and correlation time or a cross's
    /// arm not between 0 and its span, naming it.
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
        if let Some(r) = self.cross_arm
            && !(r > 0.0 && r < 1.0)
        {
            return Err(format!(
                "cross arm {r}: expected an arm width over span between 0 and 1"
            ));
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

impl Protocol {
    /// The aspect [`leafmagic::leaf::plates::plate`] takes for a plate of
    /// `shape`: a cross's span over its arm width ([`Protocol::cross_arm`];
    /// without it 1, which `plate` refuses for a cross, naming the arm),
    /// 1 for the other outlines.
    pub fn plate_aspect(&self, shape: leafmagic::leaf::plates::PlateShape) -> f64 {
        match (shape, self.cross_arm) {
            (leafmagic::leaf::plates::PlateShape::Cross, Some(r)) => 1.0 / r,
            _ => 1.0,
        }
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
            cross_arm: None,
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
    /// chaotic drops ([`real_flat_share`](super::real_flat_share)), rounded to whole releases.
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
