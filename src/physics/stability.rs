//! How large a time step a model can take: the stiffest spring mode from a
//! power iteration on M⁻¹K (with the block-Gershgorin bound as a guaranteed
//! fallback), its damping, and the drag rate; then, for each integrator, the
//! largest step whose amplification on that mode stays ≤ 1
//! (docs/design/numerics.md, "Stability limits" and "Stable-step estimate").

use crate::physics::model::Model;
use crate::physics::params::Integrator;
use nalgebra::{Matrix3, Vector3};

type V3 = Vector3<f64>;

/// Fraction of the stability limit that `--dt auto` uses. Stay at or below
/// about 0.7 × the limit (docs/design/numerics.md, "Auto step"; near it symplectic
/// Euler is stable but its invariant ellipse is very eccentric); the estimate
/// is made at the rest shape and a deforming leaf measured 2–3 % stiffer.
pub const AUTO_SAFETY: f64 = 0.7;

/// Largest turn of a tumbling plate per step at the stable limit, rad: the
/// step is at most this over [`StabilityEstimate::tumbling_rate`], so
/// `--dt auto` turns a plate at most [`AUTO_SAFETY`] × 0.2 = 0.14 rad per
/// step at that bound, and 0.02–0.09 rad at the rates real and simulated
/// plates reach (docs/lab/real-falls.md, "The step of a tumbling plate": at
/// 0.18 rad per step a 3.2 cm square tumbled 12 % too fast, and a 5 mm
/// strip of 280 g/m² card diverged at 0.23).
pub const MAX_TURN_PER_STEP: f64 = 0.2;

/// Most added mass a free particle may carry under the unsteady law, in
/// multiples of its own mass. (m I + M) has condition number about 1 + M/m,
/// and its solve keeps about 16 − log₁₀(1 + M/m) digits: at 10⁹ still 7, a
/// few ulps of M beyond it as large as m itself. Real paper is far below:
/// 10 g/m² paper's added mass is 2.6 times its own (docs/lab/real-falls.md,
/// "The law"); only a coefficient such as `added_mass = 1e30`, or a particle
/// of 10⁻³⁰⁰ kg, comes near.
pub const MAX_ADDED_MASS_RATIO: f64 = 1e9;

/// Mass ratios above this make a network ill-conditioned (docs/design/numerics.md,
/// "Conditioning warnings").
pub const WARN_MASS_RATIO: f64 = 1e4;
/// Spring rates k (1/mᵢ + 1/mⱼ) above this, s⁻², need tiny explicit steps.
pub const WARN_SPRING_RATE: f64 = 1e8;

const POWER_ITERATIONS: usize = 200;
const POWER_TOLERANCE: f64 = 1e-10;
/// The Rayleigh quotient is a lower bound of ω²; when the power iteration has
/// not settled, multiply it by this margin (capped by Gershgorin).
const UNCONVERGED_MARGIN: f64 = 1.1;

/// The stability-relevant numbers of a model.
#[derive(Clone, Debug, PartialEq)]
pub struct StabilityEstimate {
    /// Best estimate of the highest spring-network frequency ω_max, rad/s.
    pub omega_max: f64,
    /// Lower bound √max_s k_s (1/mᵢ + 1/mⱼ), rad/s (with the added mass,
    /// √max_s k_s bᵀ(M + M_a)⁻¹b).
    pub omega_lower: f64,
    /// Upper bound from block Gershgorin, √(2 maxᵢ Σ k / mᵢ), rad/s.
    pub omega_upper: f64,
    /// Whether the power iteration converged (else ω_max leans on the bounds).
    pub power_converged: bool,
    /// Whether the spring modes count the unsteady law's added mass, those
    /// of (M + M_a)⁻¹K (docs/design/numerics.md, "Added mass").
    pub with_added_mass: bool,
    /// Damping rate 2ζω of the top mode (dashpots plus air), 1/s.
    pub mode_damping_rate: f64,
    /// The fastest damping rate of the network, 1/s: the top eigenvalue of
    /// M⁻¹C, C the springs' and hinges' dashpots with the linear law's air
    /// damping. It bounds an explicit step as a drag rate does, which
    /// matters where the top stiffness mode is overdamped.
    pub damping_rate_max: f64,
    /// Damping ratio ζ of the top mode.
    pub zeta: f64,
    /// Largest drag rate γ of any particle, 1/s: α A / m under the linear
    /// law; under the quadratic and unsteady laws their bounds at the
    /// reference speed ([`crate::physics::aero::quadratic::drag_rate`],
    /// [`crate::physics::aero::unsteady::drag_rate`]).
    pub drag_rate: f64,
    /// The part of [`StabilityEstimate::drag_rate`] that the implicit
    /// integrator treats explicitly (the quadratic law, and the unsteady
    /// law but for its added mass, which the implicit matrix holds), 1/s;
    /// 0 otherwise.
    pub explicit_drag_rate: f64,
    /// Fastest rate at which a plate of the model can tumble under the
    /// unsteady law, 1/s (0 under the other laws, which do not turn a
    /// plate by its own rotation):
    /// [`crate::physics::aero::unsteady::tumbling_rate`]. An explicit step
    /// evaluates the rotational lift, the Munk moment and the damping at
    /// the start of a turn of Ω h radians, so its error grows as (Ω h)²;
    /// [`MAX_TURN_PER_STEP`] bounds it.
    pub tumbling_rate: f64,
    /// The spring with the largest k (1/mᵢ + 1/mⱼ).
    pub stiffest_spring: Option<usize>,
    /// A free particle whose added mass under the unsteady law (the largest
    /// eigenvalue of its tensor M_i), kg, given here, is over
    /// [`MAX_ADDED_MASS_RATIO`] times its own mass: its own mass is then
    /// lost to round-off in the 3 × 3 solve of every step
    /// ([`crate::physics::forces::Forces::acceleration`]) and in every rate
    /// read through it, and no step can be chosen.
    pub mass_lost_to_added_mass: Option<(usize, f64)>,
    /// The lightest free particle.
    pub lightest_particle: usize,
    /// Heaviest mass over lightest mass.
    pub mass_ratio: f64,
    /// Warnings worth showing a user, each naming the item.
    pub warnings: Vec<String>,
}

impl StabilityEstimate {
    /// Whether every rate is finite: false when a stiffness, drag or 1/m is
    /// so extreme that k/m or α/m overflows f64, or a particle's mass is lost
    /// beside its added mass ([`Self::mass_lost_to_added_mass`]), and no step
    /// can be chosen.
    pub fn is_finite(&self) -> bool {
        self.mass_lost_to_added_mass.is_none()
            && [
                self.omega_max,
                self.omega_lower,
                self.omega_upper,
                self.mode_damping_rate,
                self.damping_rate_max,
                self.drag_rate,
                self.tumbling_rate,
            ]
            .iter()
            .all(|v| v.is_finite())
    }

    /// The drag time constant 1/γ of the particle that reacts fastest to air, s
    /// (infinite without drag).
    pub fn drag_time_constant(&self) -> f64 {
        1.0 / self.drag_rate
    }

    /// The largest stable step for `integrator`, s; `None` means
    /// unconditionally stable (implicit under the linear law, or nothing
    /// stiff at all; the implicit step treats the quadratic law explicitly,
    /// so that law bounds it as it bounds forward Euler); `Some(0)`
    /// means unstable at any step (forward Euler on an undamped spring).
    /// Under the unsteady law every integrator's limit is also at most
    /// [`Self::tumbling_step`].
    pub fn dt_max(&self, integrator: Integrator) -> Option<f64> {
        self.limits(integrator)
            .into_iter()
            .map(|(_, h)| h)
            .reduce(min_step)
            .flatten()
    }

    /// Each limit on the step of `integrator` that [`Self::dt_max`] takes
    /// the smallest of, s (`None`: that one does not limit it). The implicit
    /// step is limited by the quadratic law's drag, which it treats
    /// explicitly, and not by the springs.
    pub fn limits(&self, integrator: Integrator) -> [(StepBound, Option<f64>); 4] {
        let (spring, drag, damping) = if integrator == Integrator::Implicit {
            (
                None,
                largest_stable_step(Integrator::Euler, 0.0, self.explicit_drag_rate),
                None,
            )
        } else {
            (
                largest_stable_step(integrator, self.omega_max.powi(2), self.mode_damping_rate),
                largest_stable_step(integrator, 0.0, self.drag_rate),
                largest_stable_step(integrator, 0.0, self.damping_rate_max),
            )
        };
        [
            (StepBound::Spring, spring),
            (StepBound::Drag, drag),
            (StepBound::Damping, damping),
            (StepBound::Tumbling, self.tumbling_step()),
        ]
    }

    /// Which of [`Self::limits`] sets [`Self::dt_max`] (the spring's on a
    /// tie), or `None` when nothing limits the step.
    pub fn bound(&self, integrator: Integrator) -> Option<StepBound> {
        self.limits(integrator)
            .into_iter()
            .filter_map(|(b, h)| h.map(|h| (b, h)))
            .reduce(|best, next| if next.1 < best.1 { next } else { best })
            .map(|(b, _)| b)
    }

    /// The step [`MAX_TURN_PER_STEP`] allows at [`Self::tumbling_rate`], s
    /// (`None` when nothing tumbles).
    pub fn tumbling_step(&self) -> Option<f64> {
        (self.tumbling_rate > 0.0).then(|| MAX_TURN_PER_STEP / self.tumbling_rate)
    }

    /// The step `--dt auto` takes: [`AUTO_SAFETY`] × dt_max, made an integer
    /// fraction of `frame_dt` so output frames fall exactly on steps. Implicit
    /// (and anything unconditionally stable) takes one step per frame.
    /// `None` when no stable step exists (forward Euler on undamped springs).
    pub fn auto_dt(&self, integrator: Integrator, frame_dt: f64) -> Option<f64> {
        match self.dt_max(integrator) {
            None => Some(frame_dt),
            Some(m) if m <= 0.0 => None,
            Some(m) => Some(snap_to_frame(AUTO_SAFETY * m, frame_dt)),
        }
    }

    /// The step a drop takes with `--dt auto`: [`AUTO_SAFETY`] × dt_max,
    /// at most `frame_dt`, not snapped to divide the frame (drops sample
    /// their frames by interpolation, [`crate::physics::run::run_sampled`], so
    /// snapping would only shorten the step). Steps per frame are rounded
    /// up to a multiple of 1/64 (a step at most 1.6 % shorter): the power
    /// iteration's last bits depend on the particles' order, and a step
    /// that moved with them would make a renumbered leaf fall differently.
    /// `None` as for [`Self::auto_dt`].
    pub fn auto_step(&self, integrator: Integrator, frame_dt: f64) -> Option<f64> {
        match self.dt_max(integrator) {
            None => Some(frame_dt),
            Some(m) if m <= 0.0 => None,
            Some(m) => {
                let per_frame = (frame_dt / (AUTO_SAFETY * m) * 64.0).ceil().max(64.0) / 64.0;
                Some(frame_dt / per_frame)
            }
        }
    }
}

/// Which limit of [`StabilityEstimate::dt_max`] sets a step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StepBound {
    /// The stiffest spring mode.
    Spring,
    /// The fastest drag rate.
    Drag,
    /// The network's fastest damping rate
    /// ([`StabilityEstimate::damping_rate_max`]).
    Damping,
    /// The turn of a tumbling plate per step ([`MAX_TURN_PER_STEP`]).
    Tumbling,
}

/// The smaller of two limits, `None` meaning unlimited.
fn min_step(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    match (a, b) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}

/// The largest step ≤ `dt` that divides `frame_dt` a whole number of times.
pub fn snap_to_frame(dt: f64, frame_dt: f64) -> f64 {
    let n = (frame_dt / dt * (1.0 - 1e-12)).ceil().max(1.0);
    frame_dt / n
}

/// (m_i I + M_i)^(-1/2) for every particle, M_i its rest added-mass tensor
/// under the unsteady law ([`rest_tensors`]; zero for a fixed particle,
/// m_i^(-1/2) I for a member of a rigid body), or `None` where the spring
/// modes see the particles' own masses only: where a spring can break (a
/// torn triangle takes its added mass with it, and its corners are then as
/// light as their own mass), as under the other laws and without added
/// mass, where there are no tensors.
///
/// Why: an explicit step solves (m_i I + M_i) a_i = f_i
/// ([`crate::physics::forces::Forces::acceleration`]), so its spring
/// limit is set by λ_max((M + M_a)⁻¹ K), at most λ_max(M⁻¹ K): the air a
/// leaf's flaps move along their normals slows their bending and
/// stretching modes (prototype A: ω_max 636 against 743 rad/s). At rest
/// as the springs' stiffness is: a leaf turning as a whole turns its
/// tensors with its springs and keeps the spectrum.
fn effective_mass_roots(
    model: &Model,
    free: &[bool],
    tensors: &[Matrix3<f64>],
) -> Option<Vec<Matrix3<f64>>> {
    if model.springs.iter().any(|s| s.break_strain.is_some()) {
        return None;
    }
    let body_of = model.body_of();
    let roots = (0..model.len())
        .map(|i| {
            let m = model.mass[i];
            if !free[i] {
                Matrix3::zeros()
            } else if body_of[i].is_some() {
                Matrix3::identity() * m.powf(-0.5)
            } else {
                let eig = (Matrix3::identity() * m + tensors[i]).symmetric_eigen();
                let scale = Matrix3::from_diagonal(&eig.eigenvalues.map(|l| l.powf(-0.5)));
                eig.eigenvectors * scale * eig.eigenvectors.transpose()
            }
        })
        .collect();
    Some(roots)
}

/// The unsteady law's rest added-mass tensors of every particle, `None`
/// under the other laws and without added mass.
fn rest_tensors(model: &Model) -> Option<Vec<Matrix3<f64>>> {
    crate::physics::aero::rest_added_mass_tensors(model)
}

/// The free particle, if any, whose added mass at rest under the unsteady
/// law (the largest eigenvalue of its tensor M_i) is over
/// [`MAX_ADDED_MASS_RATIO`] times its own mass, the one of largest ratio,
/// with that added mass, kg ([`StabilityEstimate::mass_lost_to_added_mass`]).
/// Breakable springs or not: every step solves (m_i I + M_i) a_i = f_i.
/// A member of a rigid body is left out: its body's 6 × 6 solve sums the
/// members' masses, and its rates, which grow with the added mass, meet the
/// step's work bound instead.
pub fn mass_lost_to_added_mass(model: &Model) -> Option<(usize, f64)> {
    rest_tensors(model).and_then(|tensors| lost_mass(model, &tensors))
}

/// A particle and its added mass, kg
/// ([`StabilityEstimate::mass_lost_to_added_mass`]).
type LostMass = (usize, f64);

/// [`mass_lost_to_added_mass`] from the rest tensors.
fn lost_mass(model: &Model, tensors: &[Matrix3<f64>]) -> Option<LostMass> {
    let body_of = model.body_of();
    let mut lost: Option<LostMass> = None;
    for i in (0..model.len()).filter(|&i| !model.fixed[i] && body_of[i].is_none()) {
        // The eigenvalue iteration never settles on inf or NaN.
        let added = if tensors[i].iter().all(|v| v.is_finite()) {
            tensors[i].symmetric_eigenvalues().max()
        } else {
            f64::INFINITY
        };
        let m = model.mass[i];
        if added > MAX_ADDED_MASS_RATIO * m
            && lost.is_none_or(|(j, a)| added / m > a / model.mass[j])
        {
            lost = Some((i, added));
        }
    }
    lost
}

/// Computes the estimate at the rest shape: bounds on the stiffest mode
/// from the springs and hinges one by one, the mode itself by power
/// iteration on the network (`RestNetwork`), its damping, and the
/// spread of the masses.
pub fn estimate(model: &Model) -> StabilityEstimate {
    let free: Vec<bool> = model.fixed.iter().map(|f| !f).collect();
    let mut warnings = Vec::new();
    let tensors = rest_tensors(model);
    let mass_lost_to_added_mass = tensors.as_deref().and_then(|t| lost_mass(model, t));
    // A particle whose mass is lost makes the estimate refused: its roots
    // are not worth taking (nor safe: an eigen-solve on inf never settles).
    let roots = tensors
        .as_deref()
        .filter(|_| mass_lost_to_added_mass.is_none())
        .and_then(|t| effective_mass_roots(model, &free, t));
    let network = RestNetwork::new(model, &free, roots);
    let bounds = network.bounds();
    warnings.extend(bounds.too_stiff.clone());

    let (lambda, y, converged) = network.power(Network::Stiffness);
    // The damping's fastest rate λ_max(M⁻¹C). Where the top stiffness mode
    // is overdamped, the damping's own fastest decay, not that mode's share
    // of it (qᵀCq), bounds an explicit step: a leaf of 1e-9 kg particles
    // (tests/data/hardening/light-masses.toml, ζ 11) diverged under Verlet
    // at 0.75 of the modal estimate. An unsettled iteration is taken with
    // the margin the stiffness's is.
    let damping_rate_max = match network.power(Network::Damping) {
        (rate, _, true) => rate,
        (rate, _, false) => UNCONVERGED_MARGIN * rate,
    };
    let omega2 = if converged {
        lambda.min(bounds.omega2_upper)
    } else if bounds.omega2_lower <= bounds.omega2_upper {
        (UNCONVERGED_MARGIN * lambda).clamp(bounds.omega2_lower, bounds.omega2_upper)
    } else {
        // A bound overflowed (or is NaN: inf − inf through an infinite root
        // above): the mode is unbounded, and `check_estimate` refuses it.
        f64::INFINITY
    };

    // The quadratic law's damping is not added to the mode's: at
    // γ/(2ω_max) ~ 1e-2 it moves no scheme's spring limit by more than
    // ~1 %, well inside AUTO_SAFETY; its own limit is the drag bound.
    // Only the model's own law gives a non-zero rate. The unsteady law's
    // bound divides by each particle's effective mass, added mass included.
    let law_rate = crate::physics::aero::explicit_drag_rate(model);
    let c_eff = network.mode_damping(&y);
    // A NaN ω² (k/m overflowed to inf, then inf − inf in the iteration) is
    // an unbounded mode, not a zero one: `max` would make it 0 and hide it.
    let omega = if omega2.is_nan() {
        f64::INFINITY
    } else {
        omega2.max(0.0).sqrt()
    };
    let zeta = if omega > 0.0 {
        c_eff / (2.0 * omega)
    } else {
        0.0
    };

    let (lightest, mass_ratio) = mass_spread(model, &free);
    if mass_ratio > WARN_MASS_RATIO {
        warnings.push(format!(
            "particle[{lightest}]: mass ratio heaviest/lightest = {mass_ratio:.3e} exceeds {WARN_MASS_RATIO:.0e}: the light particle sets the stable step"
        ));
    }

    StabilityEstimate {
        omega_max: omega,
        omega_lower: bounds.omega2_lower.sqrt(),
        omega_upper: bounds.omega2_upper.sqrt(),
        power_converged: converged,
        with_added_mass: network.roots.is_some(),
        mode_damping_rate: c_eff,
        damping_rate_max,
        zeta,
        drag_rate: network.air.rate_max.max(law_rate),
        explicit_drag_rate: law_rate,
        tumbling_rate: crate::physics::aero::tumbling_rate(model),
        stiffest_spring: bounds.stiffest,
        mass_lost_to_added_mass,
        lightest_particle: lightest,
        mass_ratio,
        warnings,
    }
}

/// The lightest free particle and the heaviest/lightest mass ratio (1
/// with no free particle).
fn mass_spread(model: &Model, free: &[bool]) -> (usize, f64) {
    let (mut lightest, mut m_min, mut m_max) = (0, f64::INFINITY, 0.0f64);
    for i in (0..model.len()).filter(|&i| free[i]) {
        if model.mass[i] < m_min {
            m_min = model.mass[i];
            lightest = i;
        }
        m_max = m_max.max(model.mass[i]);
    }
    let mass_ratio = if m_min.is_finite() {
        m_max / m_min
    } else {
        1.0
    };
    (lightest, mass_ratio)
}

/// What bounds the stiffest mode before any iteration.
struct ModeBounds {
    /// Largest single spring's or hinge's k bᵀ M⁻¹ b: a lower bound on
    /// λ_max(M⁻¹K).
    omega2_lower: f64,
    /// Gershgorin's bound 2 Σ k / m over the rows: an upper bound.
    omega2_upper: f64,
    /// The spring that sets the lower bound.
    stiffest: Option<usize>,
    /// One warning for the springs above [`WARN_SPRING_RATE`].
    too_stiff: Option<String>,
}

/// The spring and hinge network at rest, scaled by the particles' inverse
/// mass roots M^(-1/2) (the effective masses' where the law adds mass): the
/// operator S = M^(-1/2) K M^(-1/2), same spectrum as M⁻¹K, whose top
/// eigenvalue is ω_max², and the same for the damping C.
struct RestNetwork<'a> {
    model: &'a Model,
    free: &'a [bool],
    /// (m_i I + M_i)^(-1/2) per particle, where the unsteady law adds mass.
    roots: Option<Vec<Matrix3<f64>>>,
    inv_sqrt_m: Vec<f64>,
    /// Each spring's ends, unit direction and [stiffness, damping].
    springs: Vec<(usize, usize, V3, [f64; 2])>,
    /// Each hinge's particles, ∇θ at rest, stiffness and damping.
    hinges: Vec<([usize; 4], [V3; 4], f64, f64)>,
    air: AirDamping,
}

impl<'a> RestNetwork<'a> {
    fn new(model: &'a Model, free: &'a [bool], roots: Option<Vec<Matrix3<f64>>>) -> Self {
        let springs = model
            .springs
            .iter()
            .map(|s| {
                let d = model.rest_position[s.i] - model.rest_position[s.j];
                let l = d.norm();
                // A zero-length spring has no direction and no stiffness mode.
                let dir = if l > 0.0 { d / l } else { V3::zeros() };
                (s.i, s.j, dir, [s.stiffness, s.damping])
            })
            .collect();
        // Hinges at rest: K_h = k_b g gᵀ with g = ∇θ (4 particles).
        let hinges = model
            .hinges
            .iter()
            .filter_map(|h| {
                crate::physics::forces::dihedral(&model.rest_position, h)
                    .map(|(_, g)| (h.particles(), g, h.stiffness, h.damping))
            })
            .collect();
        let inv_sqrt_m = (0..model.len())
            .map(|i| {
                if free[i] {
                    model.mass[i].powf(-0.5)
                } else {
                    0.0
                }
            })
            .collect();
        RestNetwork {
            model,
            free,
            roots,
            inv_sqrt_m,
            springs,
            hinges,
            air: air_damping(model),
        }
    }

    /// |(m_i I + M_i)^(-1/2) v|² = vᵀ (m_i I + M_i)⁻¹ v: particle i's
    /// inverse mass along v, times |v|².
    fn inverse_mass_along(r: &[Matrix3<f64>], i: usize, v: &V3) -> f64 {
        (r[i] * v).norm_squared()
    }

    /// The bounds, and the stiffest spring. A spring's k bᵀ M⁻¹ b (b its
    /// unit direction on its two particles) bounds λ_max(M⁻¹K) from below,
    /// the effective masses' M included; with added mass (m_i I + M_i ≥
    /// m_i I) Gershgorin's bound on the masses alone stays an upper bound.
    fn bounds(&self) -> ModeBounds {
        let model = self.model;
        let n = model.len();
        let mut omega2_lower: f64 = 0.0;
        let mut stiffest = None;
        let mut row_sum = vec![0.0; n];
        // Springs above WARN_SPRING_RATE: how many, and the stiffest of them
        // (one warning, not one per spring: a sheet has hundreds alike).
        let mut too_stiff: (usize, Option<(usize, f64)>) = (0, None);
        for (k, (s, (_, _, dir, _))) in model.springs.iter().zip(&self.springs).enumerate() {
            let rate = match &self.roots {
                Some(r) => {
                    s.stiffness
                        * (Self::inverse_mass_along(r, s.i, dir)
                            + Self::inverse_mass_along(r, s.j, dir))
                }
                None => s.stiffness * (model.inv_mass[s.i] + model.inv_mass[s.j]),
            };
            if rate > omega2_lower {
                omega2_lower = rate;
                stiffest = Some(k);
            }
            row_sum[s.i] += s.stiffness;
            row_sum[s.j] += s.stiffness;
            if rate > WARN_SPRING_RATE {
                too_stiff.0 += 1;
                if too_stiff.1.is_none_or(|(_, r)| rate > r) {
                    too_stiff.1 = Some((k, rate));
                }
            }
        }
        let too_stiff = match too_stiff {
            (count, Some((k, rate))) => {
                let others = if count > 1 {
                    format!(" (the stiffest of {count} springs above it)")
                } else {
                    String::new()
                };
                Some(format!(
                    "spring[{k}]: k (1/m_i + 1/m_j) = {rate:.3e} s^-2 exceeds {WARN_SPRING_RATE:.0e}{others}: explicit steps must be tiny"
                ))
            }
            _ => None,
        };
        for (ids, g, k, _) in &self.hinges {
            let total: f64 = g.iter().map(|v| v.norm()).sum();
            for (&i, gi) in ids.iter().zip(g) {
                row_sum[i] += 0.5 * k * gi.norm() * total;
            }
            for (&i, gi) in ids.iter().zip(g) {
                let rate = match &self.roots {
                    Some(r) => k * Self::inverse_mass_along(r, i, gi),
                    None => k * gi.norm_squared() * model.inv_mass[i],
                };
                if rate > omega2_lower {
                    omega2_lower = rate;
                }
            }
        }
        let omega2_upper = (0..n)
            .filter(|&i| self.free[i])
            .map(|i| 2.0 * row_sum[i] / model.mass[i])
            .fold(0.0, f64::max);
        ModeBounds {
            omega2_lower,
            omega2_upper,
            stiffest,
            too_stiff,
        }
    }

    /// M^(-1/2) v at particle i: the effective mass's root where the law
    /// adds mass, else v/√m_i (in the order the scalar products always had).
    fn root(&self, i: usize, v: V3) -> V3 {
        match &self.roots {
            Some(r) => r[i] * v,
            None => v * self.inv_sqrt_m[i],
        }
    }

    /// g · M^(-1/2) y at particle i (M^(-1/2) is symmetric).
    fn root_dot(&self, i: usize, g: &V3, y: &V3) -> f64 {
        match &self.roots {
            Some(r) => (r[i] * g).dot(y),
            None => g.dot(y) * self.inv_sqrt_m[i],
        }
    }

    /// S y for the network's stiffnesses K (`Network::Stiffness`), or for
    /// its damping C: dashpots and the linear law's air damping.
    fn apply(&self, network: Network, y: &[V3], out: &mut [V3]) {
        out.fill(V3::zeros());
        let pick = network as usize;
        for &(i, j, dir, coefficient) in &self.springs {
            let k = coefficient[pick];
            let u = self.root(i, y[i]) - self.root(j, y[j]);
            let f = dir * (k * dir.dot(&u));
            out[i] += self.root(i, f);
            out[j] -= self.root(j, f);
        }
        for (ids, g, stiffness, damping) in &self.hinges {
            let k = [*stiffness, *damping][pick];
            let gy: f64 = ids
                .iter()
                .zip(g)
                .map(|(&i, gi)| self.root_dot(i, gi, &y[i]))
                .sum();
            for (&i, gi) in ids.iter().zip(g) {
                out[i] += match &self.roots {
                    Some(r) => r[i] * gi * (k * gy),
                    None => gi * (k * gy * self.inv_sqrt_m[i]),
                };
            }
        }
        if network == Network::Damping {
            for (i, block) in self.air.blocks.iter().enumerate() {
                out[i] += self.root(i, block * self.root(i, y[i]));
            }
        }
    }

    /// The top eigenvalue of S (for `network`), its vector, and whether the
    /// iteration settled.
    fn power(&self, network: Network) -> (f64, Vec<V3>, bool) {
        let n = self.model.len();
        let stiff = !self.springs.is_empty() || !self.hinges.is_empty();
        // A fixed, irregular start vector: deterministic, and not
        // orthogonal to the top mode for any realistic network.
        let mut y: Vec<V3> = (0..n)
            .map(|i| {
                let a = i as f64 + 1.0;
                V3::new(
                    (1.3 * a).sin(),
                    (2.7 * a + 0.5).cos(),
                    (0.9 * a + 1.1).sin() + 0.1,
                ) * if self.free[i] { 1.0 } else { 0.0 }
            })
            .collect();
        let mut sy = vec![V3::zeros(); n];
        let mut lambda = 0.0;
        let mut converged = !stiff;
        for _ in 0..POWER_ITERATIONS {
            if !stiff {
                break;
            }
            let norm = norm(&y);
            if norm == 0.0 {
                break;
            }
            y.iter_mut().for_each(|v| *v /= norm);
            self.apply(network, &y, &mut sy);
            let rq = dot(&y, &sy);
            let change = (rq - lambda).abs();
            lambda = rq;
            std::mem::swap(&mut y, &mut sy);
            if change <= POWER_TOLERANCE * rq.abs() {
                converged = true;
                break;
            }
        }
        let norm_y = norm(&y);
        if norm_y > 0.0 {
            y.iter_mut().for_each(|v| *v /= norm_y);
        }
        (lambda, y, converged)
    }

    /// Damping of the mode y: c_eff = qᵀ C q / qᵀ M q with q = M^-1/2 y.
    fn mode_damping(&self, y: &[V3]) -> f64 {
        let mut c_eff = 0.0;
        for (s, &(i, j, dir, _)) in self.model.springs.iter().zip(&self.springs) {
            let u = self.root(i, y[i]) - self.root(j, y[j]);
            c_eff += s.damping * dir.dot(&u).powi(2);
        }
        for (ids, g, _, c) in &self.hinges {
            let gq: f64 = ids
                .iter()
                .zip(g)
                .map(|(&i, gi)| self.root_dot(i, gi, &y[i]))
                .sum();
            c_eff += c * gq * gq;
        }
        for (i, block) in self.air.blocks.iter().enumerate() {
            let q = self.root(i, y[i]);
            c_eff += q.dot(&(block * q));
        }
        c_eff
    }
}

/// The operator a power iteration in [`estimate`] reads: the network's
/// stiffnesses or its damping.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Network {
    Stiffness = 0,
    Damping = 1,
}

struct AirDamping {
    blocks: Vec<nalgebra::Matrix3<f64>>,
    rate_max: f64,
}

/// Per-particle linear air damping ∂F/∂v (the linear law's αA terms) and the
/// largest rate λ_max(block)/m over free particles.
fn air_damping(model: &Model) -> AirDamping {
    let n = model.len();
    let mut blocks = vec![nalgebra::Matrix3::identity() * 0.0; n];
    for (i, b) in blocks.iter_mut().enumerate() {
        *b = nalgebra::Matrix3::identity() * model.particle_drag[i];
    }
    crate::physics::aero::linear::add_damping_blocks(model, &mut blocks);
    let rate_max = (0..n)
        .filter(|&i| !model.fixed[i])
        .map(|i| {
            // The blocks are symmetric PSD; their largest eigenvalue is what sets the limit.
            let eig = blocks[i].symmetric_eigenvalues();
            eig.max() / model.mass[i]
        })
        .fold(0.0, f64::max);
    AirDamping { blocks, rate_max }
}

/// The one-step map of `integrator` on the test problem
/// x'' = −ω² x − c x', acting on (x, v, a), where a is the acceleration
/// Verlet carries from one step to the next (the other schemes ignore it).
/// Built by running the scheme's update formulas on the basis vectors, so it
/// is the scheme's exact amplification, not an approximation of it.
pub fn step_matrix(integrator: Integrator, h: f64, omega2: f64, c: f64) -> Matrix3<f64> {
    let acc = |x: f64, v: f64| -omega2 * x - c * v;
    let step = |x: f64, v: f64, a_carried: f64| -> (f64, f64, f64) {
        let (x1, v1) = match integrator {
            Integrator::Euler => (x + h * v, v + h * acc(x, v)),
            Integrator::Symplectic => {
                let v1 = v + h * acc(x, v);
                (x + h * v1, v1)
            }
            Integrator::Verlet => {
                // As in `Simulator::step_verlet`: the carried acceleration was
                // evaluated at the previous step's predicted velocity.
                let a0 = a_carried;
                let vh = v + 0.5 * h * a0;
                let x1 = x + h * vh;
                let a1 = acc(x1, v + h * a0);
                return (x1, vh + 0.5 * h * a1, a1);
            }
            Integrator::Rk4 => {
                let (k1x, k1v) = (v, acc(x, v));
                let (k2x, k2v) = (v + 0.5 * h * k1v, acc(x + 0.5 * h * k1x, v + 0.5 * h * k1v));
                let (k3x, k3v) = (v + 0.5 * h * k2v, acc(x + 0.5 * h * k2x, v + 0.5 * h * k2v));
                let (k4x, k4v) = (v + h * k3v, acc(x + h * k3x, v + h * k3v));
                (
                    x + h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x),
                    v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v),
                )
            }
            Integrator::Implicit => {
                // (1 + h c + h² ω²) v1 = v − h ω² x ; x1 = x + h v1.
                let v1 = (v - h * omega2 * x) / (1.0 + h * c + h * h * omega2);
                (x + h * v1, v1)
            }
        };
        (x1, v1, 0.0)
    };
    let mut m = Matrix3::zeros();
    for k in 0..3 {
        let mut e = [0.0; 3];
        e[k] = 1.0;
        let (x1, v1, a1) = step(e[0], e[1], e[2]);
        m[(0, k)] = x1;
        m[(1, k)] = v1;
        m[(2, k)] = a1;
    }
    m
}

/// Spectral radius of the 3×3 step map. The schemes other than Verlet have
/// a zero third row and column, so their 2×2 block is solved in closed form;
/// a triangular block (the drag-only mode, where the velocity update does not
/// see the position) is read off its diagonal exactly, because the quadratic
/// formula would lose half the digits to cancellation near its double root.
pub fn spectral_radius(m: &Matrix3<f64>) -> f64 {
    // A step map with an overflowed entry amplifies without bound (and the
    // Schur iteration would never converge on it).
    if m.iter().any(|v| !v.is_finite()) {
        return f64::INFINITY;
    }
    let coupled = m[(2, 0)] != 0.0 || m[(2, 1)] != 0.0 || m[(2, 2)] != 0.0;
    if coupled {
        // (x, v, a) differ in scale by powers of ω and 1/h; unbalanced, the
        // eigenvalue solver's round-off (≈ ε‖M‖) can push a root that lies
        // just inside the unit circle (a strongly overdamped mode) outside it.
        return balanced(m)
            .complex_eigenvalues()
            .iter()
            .map(|z| z.norm())
            .fold(0.0, f64::max);
    }
    if m[(1, 0)] == 0.0 || m[(0, 1)] == 0.0 {
        return m[(0, 0)].abs().max(m[(1, 1)].abs());
    }
    let tr = m[(0, 0)] + m[(1, 1)];
    let det = m[(0, 0)] * m[(1, 1)] - m[(0, 1)] * m[(1, 0)];
    let disc = tr * tr - 4.0 * det;
    if disc >= 0.0 {
        // Larger root without cancellation, the other from the product.
        let big = 0.5 * (tr + tr.signum() * disc.sqrt());
        let small = if big != 0.0 { det / big } else { 0.0 };
        big.abs().max(small.abs())
    } else {
        det.abs().sqrt()
    }
}

/// A diagonal similarity D⁻¹ M D (so the same eigenvalues) with power-of-two
/// factors chosen so that each row and column have comparable off-diagonal
/// norms (Parlett & Reinsch's balancing, as LAPACK's `gebal` does before an
/// eigenvalue solve). Powers of two keep the scaling exact.
fn balanced(m: &Matrix3<f64>) -> Matrix3<f64> {
    let mut a = *m;
    for _ in 0..64 {
        let mut changed = false;
        for i in 0..3 {
            let col: f64 = (0..3).filter(|&j| j != i).map(|j| a[(j, i)].abs()).sum();
            let row: f64 = (0..3).filter(|&j| j != i).map(|j| a[(i, j)].abs()).sum();
            if col == 0.0 || row == 0.0 {
                continue;
            }
            let f = 2f64.powi((row / col).sqrt().log2().round() as i32);
            if col * f + row / f < 0.95 * (col + row) {
                changed = true;
                for j in 0..3 {
                    a[(j, i)] *= f;
                    a[(i, j)] /= f;
                }
            }
        }
        if !changed {
            break;
        }
    }
    a
}

/// Amplification above 1 by less than this counts as neutral (round-off).
const NEUTRAL_TOLERANCE: f64 = 1e-13;

/// Largest h with spectral radius ≤ 1 for x'' = −ω² x − c x', found by a
/// geometric scan then bisection. `None` if stable for every h tried (or no
/// dynamics at all); `Some(0)` if unstable even for tiny steps.
pub fn largest_stable_step(integrator: Integrator, omega2: f64, c: f64) -> Option<f64> {
    let rate = omega2.sqrt().max(c);
    if rate <= 0.0 || integrator == Integrator::Implicit {
        return None;
    }
    // An overflowed rate (k/m or α/m beyond f64) is stable at no step.
    if !rate.is_finite() {
        return Some(0.0);
    }
    let stable =
        |h: f64| spectral_radius(&step_matrix(integrator, h, omega2, c)) <= 1.0 + NEUTRAL_TOLERANCE;
    // Start where round-off is harmless; step down if even that is unstable
    // (forward Euler with very light damping).
    let mut lo = 1e-3 / rate;
    let mut hi;
    if stable(lo) {
        hi = lo;
        loop {
            hi *= 1.5;
            if hi > 1e6 / rate {
                return None;
            }
            if !stable(hi) {
                break;
            }
            lo = hi;
        }
    } else {
        hi = lo;
        loop {
            lo /= 1.5;
            if lo < 1e-5 / rate {
                return Some(0.0);
            }
            if stable(lo) {
                break;
            }
            hi = lo;
        }
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if stable(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
        // 1e-10 relative: far below what any use of dt_max can resolve, and
        // 30 fewer eigenvalue solves per estimate than going to round-off.
        if hi - lo <= 1e-10 * hi {
            break;
        }
    }
    Some(lo)
}

fn dot(a: &[V3], b: &[V3]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x.dot(y)).sum()
}

fn norm(a: &[V3]) -> f64 {
    dot(a, a).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The closed-form limits of docs/design/numerics.md, "Stability limits".
    #[test]
    fn closed_form_limits_of_the_notes() {
        let w: f64 = 3.0;
        let limit = |i, c| largest_stable_step(i, w * w, c).unwrap();
        // Undamped: symplectic and Verlet ωh = 2, RK4 ωh = 2√2.
        assert!((limit(Integrator::Symplectic, 0.0) * w - 2.0).abs() < 1e-9);
        assert!((limit(Integrator::Verlet, 0.0) * w - 2.0).abs() < 1e-9);
        assert!((limit(Integrator::Rk4, 0.0) * w - 2.0 * 2f64.sqrt()).abs() < 1e-9);
        // Forward Euler never stable undamped; h < 2ζ/ω with damping.
        assert_eq!(
            largest_stable_step(Integrator::Euler, w * w, 0.0),
            Some(0.0)
        );
        let zeta = 0.2;
        let c = 2.0 * zeta * w;
        assert!((limit(Integrator::Euler, c) - 2.0 * zeta / w).abs() < 1e-9);
        // Damped symplectic: (2/ω)(√(1+ζ²) − ζ).
        let expect = 2.0 / w * ((1.0 + zeta * zeta).sqrt() - zeta);
        assert!((limit(Integrator::Symplectic, c) - expect).abs() < 1e-9);
        // Drag alone: Euler and symplectic h < 2/γ, RK4 γh ≤ 2.785.
        let gamma = 7.0;
        assert!(
            (largest_stable_step(Integrator::Euler, 0.0, gamma).unwrap() * gamma - 2.0).abs()
                < 1e-9
        );
        let rk = largest_stable_step(Integrator::Rk4, 0.0, gamma).unwrap() * gamma;
        assert!((rk - 2.785).abs() < 1e-3, "{rk}");
        assert_eq!(largest_stable_step(Integrator::Implicit, w * w, 0.0), None);
    }

    #[test]
    fn snapping_divides_the_frame() {
        let f = 1.0 / 240.0;
        let dt = snap_to_frame(0.0011, f);
        assert!(dt <= 0.0011);
        let n = f / dt;
        assert!((n - n.round()).abs() < 1e-9);
        assert_eq!(snap_to_frame(1.0, f), f);
    }
}
