//! The unsteady law for triangles: added mass with the fluid impulse that
//! comes with it, circulation from translation and from rotation,
//! rotational damping, drag by angle of attack with skin friction, and
//! optional buoyancy. What each triangle needs to know about its plate is
//! measured once ([`crate::physics::model::SurfaceGeometry`]).
//!
//! # Why
//!
//! The quasi-steady laws miss what makes real paper flutter and tumble
//! (docs/real-falls.md): the air a plate sets moving (added mass, 0.2–0.6
//! of a paper card's own), the torque that comes with it (the Munk moment,
//! which is also what puts a thin aerofoil's centre of pressure at its
//! quarter chord), the lift from the plate's own rotation that Andersen,
//! Pesavento & Wang (2005, "APW") found dominant in flutter and tumble,
//! and damping of the rotation.
//!
//! # Added mass as a fluid impulse
//!
//! Each corner k of a triangle carries a share m_k of its plate's added
//! mass along the triangle's normal n (Lamb 1932, §§ 117–121: the flow's
//! impulse is what the body gave it; for a flat plate it is normal to the
//! plate). With w_k the corner's velocity relative to the air, the fluid
//! impulse is p_k = m_k (n·w_k) n and the air pushes back with −dp_k/dt:
//!
//! f_k = −m_k (n·ẇ_k) n − m_k (ṅ·w_k) n − m_k (n·w_k) ṅ,
//!
//! the last two from the normal turning. The impulse sits at the corners,
//! so the fluid's angular impulse is Σ x_k × p_k; its rate has, besides
//! the moment of the f_k, the part −Σ ẋ_k × p_k, a couple on the triangle:
//!
//! C = −Σ_k w_k × p_k = −Q × n,  Q = Σ_k m_k (n·w_k) w_k.
//!
//! For a plate moving at an angle it is Kirchhoff's Munk moment
//! −w × m_a (w·n) n, which turns the plate broadside. A couple in the
//! plane of a triangle is applied as normal forces λ_k n on its corners,
//! λ_k = ∇β_k·(n × C) (β_k the barycentric coordinates: Σλ_k = 0 and
//! Σ x_k × λ_k n = C exactly). With the couple the law is energy-exact:
//! the power of all these forces is −dT/dt, T = ½ Σ m_k (n·w_k)² the
//! flow's kinetic energy, for any motion of the triangle, rigid or not —
//! so added rotational inertia and the Munk moment follow without a
//! rigid-body assumption (a test checks the identity).
//!
//! The first term, −m_k n nᵀ a_k, is the added mass proper: it is moved to
//! the left of Newton's law and solved, (m_i I + M_i) a_i = f_i with
//! M_i = Σ m_k n nᵀ over the triangles at particle i — a 3 × 3 system per
//! particle ([`super::Forces::acceleration`]), or the 6 × 6 of a rigid
//! body ([`crate::physics::rigid`]). Lagged explicitly it would be
//! unstable for a body lighter than its added mass. The wind's own
//! acceleration (the force an accelerating stream puts on a body at rest)
//! is left out: the impulse is written with the relative velocity of a
//! steady wind.
//!
//! # Circulation, drag, damping
//!
//! With u the air's velocity relative to the triangle (means over its
//! corners) less its plate's rotation, A its area, q = u·n and α its angle
//! of attack (sin α = |q|/|u|):
//!
//! - u = −w̄ + (1 − κ) Ω × (c − C), w̄ the corners' mean velocity against
//!   the air, c the triangle's centroid, C and Ω the area-weighted centre
//!   and in-plane angular velocity (n × ṅ) of its plate, κ =
//!   `rotation_drag` (default 0). APW's drag and circulation act on the
//!   plate's centre velocity and their μ₁ is fitted as the whole damping of
//!   the rotation; drag on each triangle's own velocity (κ = 1, strip
//!   theory) adds ρ C_D⊥ U ω ∫r² dA on top, 2.5 times APW's μ₁ term for a
//!   plate falling face-on, and keeps a flat-released square from ever
//!   tumbling (docs/real-falls.md). A flexible leaf's deformation still
//!   enters drag in full: only the plate's mean rotation is taken out;
//! - drag and translational lift, APW's C_D(α) = C_D∥ cos²α + C_D⊥ sin²α
//!   and translational circulation C_L = C_T sin 2α (APW 2005; Wang, Birch
//!   & Dickinson 2004), F = ½ ρ A |u| [(C_D∥ + (C_D⊥ − C_D∥ − 2C_T) q²/|u|²) u
//!   + 2 C_T q n], shared equally by the corners;
//! - C_D∥ = `cd_parallel` + skin friction: laminar Blasius friction,
//!   1.328/√Re on each face, Re = |u∥| c∥/ν on the plate's chord c∥ along
//!   the in-plane flow (Schlichting, *Boundary-Layer Theory*, ch. 7), plus
//!   `cd_parallel` (default 0.65; APW's edge-on C_D(0) is 0.4). For paper a thousandth as
//!   thick as it is wide this is not edge thickness but what the 2-D law
//!   leaves out of a finite plate's separated flow; without it the real
//!   squares glide up to 6 times too far (docs/real-falls.md, "The defaults");
//! - rotational circulation Γ = ½ C_R c² ω (APW: C_R = π; default 1.5,
//!   fitted with the other defaults to the real squares), c the plate's
//!   chord through the triangle across the rotation axis and ω = n × ṅ the
//!   triangle's in-plane angular velocity: F = ½ ρ C_R c A (u × ω) at the
//!   centroid, which does no work on a rigid plate;
//! - rotational damping, APW's τ = (μ₁ + μ₂|ω̃|) ω̃ in their units, per area
//!   τ = −(π/2) ρ A a² (μ₁ |u| + μ₂ a |ω|) ω with a = c/2, applied as a
//!   couple. APW's μ₂ = 0.2 damps a plate turning in place; measured on
//!   the real squares it stops the tumbling ones gliding (score 1.88 against
//!   1.29 without, docs/real-falls.md), so μ₂ defaults to 0, and μ₁ to 0.1,
//!   half APW's 0.2 (fitted with the other defaults; with `rotation_drag = 1`, drag on each triangle's own velocity
//!   damps rotation quadratically about as much as APW's μ₂: for a 2-D
//!   plate of half-chord a, ρ C_D⊥ a⁴ ω|ω|/4 = 0.60 ρ a⁴ ω|ω| per span
//!   against π μ₂ ρ a⁴ ω|ω| = 0.63 ρ a⁴ ω|ω|);
//! - buoyancy (optional): ρ (m_i/ρ_s) g upward on every particle.
//!
//! # Lagged centre of pressure
//!
//! On by default (`pressure_lag_gain` 0.6, `pressure_lag` 3; a gain of 0
//! turns it off). In steady flow a plate's normal force acts f(α) c∥
//! upstream of mid-chord, f(α) = ¼ (1 − 2α/π): a quarter chord at small
//! angles (thin-aerofoil theory, which the Munk couple above already
//! gives), none broadside. Separated flow answers a
//! changing angle of attack late; dynamic-stall models lag the centre of
//! pressure behind α by first-order lags measured in the time the flow
//! takes to cross the chord (Leishman & Beddoes 1989, J. Am. Helicopter
//! Soc. 34(3)). Here each triangle's α is followed by α_L,
//! dα_L/dt = (α − α_L)/τ, τ = k c∥/|u| (k = `pressure_lag` chord
//! transits), and the normal force ½ ρ A C_D⊥ |u| (u·n) n is moved
//! G c∥ (f(α_L) − f(α)) cos α further upstream along the in-plane flow
//! (G = `pressure_lag_gain`): a couple, applied as the Munk couple is. On a
//! gliding plate (α slow) α_L ≈ α and it vanishes; on a turning one it
//! leads the turn, and since a lag's response falls once the turn is faster
//! than 1/τ, it drives autorotation up to a rate set by |u|/c∥ and not by
//! the plate's inertia: the torque balance behind Mahadevan, Ryu & Samuel's
//! Ω ∝ σ^½ w⁻¹ (1999), and in line with Iversen (1979), who found the
//! tip-speed ratio of autorotating plates set by their shape and by their
//! inertia only when that is small.
//! α_L is state: [`PressureLag`], kept by the simulator; each force
//! evaluation reads it at its own time by a second-order exponential
//! integrator and each step commits its last evaluation's. The stability
//! estimate leaves the term out. Screened on the real squares,
//! the strips and the disks in docs/real-falls.md, "A lagged centre of
//! pressure".
//!
//! # Wake
//!
//! Off by default (`wake_couple` 0). A bluff plate falling face-on sheds
//! vortices from alternate edges at f = St |u| / c (`wake_strouhal`,
//! default 0.15), and the uneven pressure rocks it; the quasi-steady terms
//! above have no such thing, and a plate let go at 1–5° rocks about
//! face-on for 0.76–1.05 s where real paper leaves its flat fall in
//! 0.13–0.37 s (docs/real-falls.md, "When a flat release departs"). With
//! the term on, each plate carries a wake phase φ turning at 2π St U / c
//! and each of its triangles the normal force C_W ½ ρ U² sin φ sin⁴α A
//! (d / c) n, d its distance from the plate's centre along an axis fixed
//! in the plate: a couple that acts only near face-on. The equations,
//! their integration and what the term leaves out are in
//! `src/physics/forces/unsteady/wake.rs`; what it does to the real falls
//! in docs/real-falls.md, "A wake that rocks the face-on fall".
//!
//! # Munk relief
//!
//! Off by default (`munk_relief` β = 0). The Munk couple is potential
//! flow's steady moment: at small angles it is what puts the centre of
//! pressure a quarter chord upstream; near broadside it turns a plate back
//! to face-on in proportion to its tilt ε = π/2 − α, and a plate falling
//! face-on rocks at that couple's period (some 0.1 s for a 3 cm square)
//! with hardly any sideways motion. A real plate held near broadside in a
//! steady stream has its centre of pressure at mid-chord, leaving it only
//! to second order in ε (Joessel's empirical rule for flat rudders,
//! x_cp/c ≈ 0.195 + 0.305 sin α from the leading edge, as naval-architecture
//! texts quote it): in the separated flow behind the plate the potential
//! couple mostly does not act. With the term on, each triangle's Munk
//! couple is scaled by 1 − β sin⁶α: kept whole to within β/8 below 45°,
//! where the flow is attached, and at β = 1 left only at third order in ε
//! near broadside. The added-mass forces, and with them the added mass and
//! added inertia, are untouched; the relieved couple no longer conserves
//! the fluid's kinetic energy, so the energy identity holds at β = 0 only.
//! The power 6 was chosen on the real squares among sin⁴–sin¹⁶ and
//! cosᵠα forms; what the term does there is in docs/real-falls.md, "Munk
//! relief near broadside".
//!
//! Coefficients and defaults: [`UnsteadyAero`] (docs/real-falls.md has the
//! table). One set serves every shape and size; the lengths come from each
//! leaf's own geometry. The defaults C_D⊥ = 2.6, C_D∥ = 0.65, C_T = 1.2,
//! C_R = 1.5, μ₁ = 0.1, G = 0.6 and k = 3 were fitted as one set to the
//! real paper squares (mean of two seeds; first without the lag term over
//! 144 candidate sets and 108 around the best, then with it over 270 more),
//! every fall at a step that bounds a tumbling plate's turn, with the
//! strips' scaling law and the disks' regimes as the lag term's check, and
//! then checked on ten other seeds of the squares (docs/real-falls.md,
//! "The defaults"). They were kept when the lag's couple was made
//! continuous through face-on (cos α above), which moved the fit a little
//! (docs/real-falls.md, "A couple without a jump").

mod wake;

use super::surfaces::surface;
use crate::physics::model::{AeroLaw, Model, SurfaceGeometry, UnsteadyAero};
use nalgebra::{Matrix3, Vector3};
use std::ops::AddAssign;

type V3 = Vector3<f64>;

/// Laminar skin friction on one face, 1.328/√Re (Blasius).
pub const BLASIUS: f64 = 1.328;

/// Reynolds numbers below this are taken as this in the skin-friction
/// coefficient (Blasius' law is for Re ≫ 1; below, the force is already
/// negligible).
pub const MIN_REYNOLDS: f64 = 1.0;

/// Factor on the fastest steady fall ([`edge_on_speed`]) that bounds the
/// air speed of any triangle for the stability estimate (as the quadratic
/// law's [`super::quadratic::SPEED_MARGIN`]).
pub const SPEED_MARGIN: f64 = 2.0;

/// Edge-on drag coefficient C_D∥ at in-plane relative speed `speed` along
/// a chord `chord`: form drag plus skin friction on both faces.
#[inline]
pub fn cd_parallel(law: &UnsteadyAero, speed: f64, chord: f64) -> f64 {
    let friction = if law.kinematic_viscosity > 0.0 && law.skin_friction > 0.0 {
        let re = (speed * chord / law.kinematic_viscosity).max(MIN_REYNOLDS);
        2.0 * BLASIUS * law.skin_friction / re.sqrt()
    } else {
        0.0
    };
    law.cd_parallel + friction
}

/// Adds the unsteady law's velocity-dependent forces on every triangle of
/// `model` that is not torn (`torn[t]`; an empty mask tears none), and
/// each corner's added-mass tensor m_k n nᵀ into `added` (which the caller
/// zeroes; an empty slice skips them, for callers that read only the
/// forces). `wind` holds G at every particle, or is `None` in still air.
/// `lag` is the simulator's lagged centre of pressure: read, and each
/// triangle's angle of attack recorded for [`PressureLag::advance`]
/// (`None`, or `pressure_lag_gain = 0`, leaves that term out). See the
/// module docs for the equations.
#[allow(clippy::too_many_arguments)]
pub fn unsteady_forces(
    law: &UnsteadyAero,
    model: &Model,
    x: &[V3],
    v: &[V3],
    wind: Option<&[V3]>,
    torn: &[bool],
    force: &mut [V3],
    added: &mut [Matrix3<f64>],
    mut lag: Option<&mut PressureLag>,
) {
    SCRATCH.with_borrow_mut(|scratch| {
        scratch.measure(law, model, x, v, wind, torn);
        let Scratch {
            triangles,
            plates,
            flows,
            wake,
        } = scratch;
        flow_coefficients(law, model, flows);
        if let Some(lag) = lag.as_deref_mut().filter(|_| law.pressure_lag_gain > 0.0) {
            lagged_pressure(law, triangles, flows, lag);
        }
        per_triangle(law, model, v, wind, triangles, flows, force, added);
        if let Some(lag) = lag.filter(|_| law.wake_couple > 0.0) {
            wake_couples(law, model, x, triangles, plates, flows, lag, wake, force);
        }
    });
    if law.buoyancy {
        let lift = -model.gravity * (law.air_density / law.solid_density);
        for (fi, &m) in force.iter_mut().zip(&model.mass) {
            *fi += lift * m;
        }
    }
}

/// The lagged angle of attack α_L of every triangle: the state of the
/// law's lagged centre of pressure, carried by the simulator from step to
/// step (module docs, "Lagged centre of pressure").
///
/// A force evaluation a time Δ after the committed state reads α_L at its
/// own time: dα_L/dt = r (α − α_L), r = 1/τ, solved exactly with α taken
/// linear between the committed α and the evaluation's own, and r their
/// mean (exponential time differencing; Cox & Matthews 2002, J. Comput.
/// Phys. 176): with x = r Δ and φ = (1 − e^(−x))/x,
/// α_L(Δ) = e^(−x) α_L + (φ − e^(−x)) α₀ + (1 − φ) α, a convex combination
/// (α_L stays between the angles it follows, at any step) and second order
/// in Δ. So Verlet's end-of-step evaluation, whose acceleration it carries
/// into the next step, sees the lag at that step's end, and the term keeps
/// Verlet second order (a test measures it). RK4 under this law is not
/// fourth order, with the term or without it (docs/real-falls.md).
/// [`Self::advance`] then commits the step's last evaluation. The same
/// state carries each plate's wake phase when the opt-in wake term is on
/// (module docs, "Wake"), read and committed the same way.
#[derive(Clone, Debug, PartialEq)]
pub struct PressureLag {
    /// Committed α_L per triangle, rad; NaN until the triangle has met the
    /// air.
    lagged: Vec<f64>,
    /// Committed α and lag rate r = |u|/(k c∥) of each triangle (α NaN: no
    /// flow over it then; rate ∞: broadside, no lag).
    alpha: Vec<f64>,
    rate: Vec<f64>,
    /// The last evaluation's α_L, α and r, not yet committed.
    pending_lagged: Vec<f64>,
    pending_alpha: Vec<f64>,
    pending_rate: Vec<f64>,
    /// The angle the flow over each triangle starts at where it had none
    /// at the committed state ([`seed_flow_start`]; NaN: not known).
    start: Vec<f64>,
    /// Whether some triangle has not yet met the air (α_L NaN).
    waiting: bool,
    /// Whether a force evaluation has run since the last commit.
    evaluated: bool,
    /// Time of the committed state, s (NaN before the first evaluation),
    /// and the next (or last) evaluation's time after it, Δ.
    time: f64,
    elapsed: f64,
    /// Whether the lag term is on (`pressure_lag_gain > 0`); the state also
    /// carries the wake's phases ([`wake`]) when only that term is on.
    lag_on: bool,
    /// Each plate's wake ([`wake::WakePhase`]); empty with the term off.
    wake: Vec<wake::WakePhase>,
}

impl PressureLag {
    /// The state for `model`, all triangles unlagged and every plate's wake
    /// at its start; `None` unless its law is the unsteady one with a lag
    /// term (`pressure_lag_gain > 0`) or a wake (`wake_couple > 0`).
    pub fn for_model(model: &Model) -> Option<PressureLag> {
        let AeroLaw::Unsteady(law) = &model.aero else {
            return None;
        };
        let lag_on = law.pressure_lag_gain > 0.0;
        (lag_on || law.wake_couple > 0.0).then(|| {
            let n = model.triangles.len();
            PressureLag {
                lagged: vec![f64::NAN; n],
                alpha: vec![f64::NAN; n],
                rate: vec![f64::NAN; n],
                pending_lagged: vec![f64::NAN; n],
                pending_alpha: vec![f64::NAN; n],
                pending_rate: vec![f64::NAN; n],
                start: vec![f64::NAN; n],
                waiting: lag_on && n > 0,
                evaluated: false,
                time: f64::NAN,
                elapsed: 0.0,
                lag_on,
                wake: if law.wake_couple > 0.0 {
                    wake::WakePhase::for_model(model, plate_count(model))
                } else {
                    Vec::new()
                },
            }
        })
    }

    /// Plate `p`'s wake phase φ at the committed state, rad (NaN without
    /// the wake term or such a plate).
    pub fn wake_phase(&self, p: usize) -> f64 {
        self.wake.get(p).map_or(f64::NAN, |w| w.phase)
    }

    /// The committed lagged angle of attack of triangle `t`, rad (NaN
    /// before it has met the air).
    pub fn lagged(&self, t: usize) -> f64 {
        self.lagged[t]
    }

    /// Whether the evaluation just placed is at the committed time and a
    /// triangle there has not met the air: then the flow's start angles
    /// are wanted ([`seed_flow_start`]).
    pub fn wants_start(&self) -> bool {
        self.waiting && self.elapsed <= 0.0
    }

    /// Places the next force evaluation at time `t`, s: Δ = t − the
    /// committed state's time (the first evaluation fixes that time).
    pub fn evaluate_at(&mut self, t: f64) {
        if self.time.is_nan() {
            self.time = t;
        }
        self.elapsed = (t - self.time).max(0.0);
    }

    /// Commits the last evaluation and carries it to `h` s after the
    /// committed state (the step just taken): from the evaluation's time
    /// to the step's end with α and r held, α_L ← α + (α_L − α) e^(−r h′),
    /// h′ = h − Δ (none after an end-of-step evaluation; the whole step
    /// after Euler's, at its start). Without an evaluation since the last
    /// commit, the committed α and r are held over the whole of `h`. A
    /// triangle meeting the air for the first time starts from the angle
    /// its flow started at ([`seed_flow_start`]) where that is known, and
    /// unlagged (α_L = α) where not; one with no flow keeps α_L.
    pub fn advance(&mut self, h: f64) {
        // After an end-of-step evaluation Δ is h up to the clock's
        // round-off: nothing is left to carry.
        let rest = if self.evaluated {
            let rest = h - self.elapsed;
            if rest > 1e-9 * h { rest } else { 0.0 }
        } else {
            h
        };
        for t in 0..self.lagged.len() {
            let (lagged, alpha, rate) = if self.evaluated {
                let pending = (
                    self.pending_lagged[t],
                    self.pending_alpha[t],
                    self.pending_rate[t],
                );
                self.pending_alpha[t] = f64::NAN;
                pending
            } else {
                (self.lagged[t], self.alpha[t], self.rate[t])
            };
            if alpha.is_nan() {
                continue;
            }
            self.lagged[t] = if lagged.is_nan() || rate == f64::INFINITY {
                alpha
            } else if rest > 0.0 {
                alpha + (lagged - alpha) * (-rest * rate).exp()
            } else {
                lagged
            };
            self.alpha[t] = alpha;
            self.rate[t] = rate;
            self.start[t] = f64::NAN;
        }
        self.waiting = self.lag_on && self.lagged.iter().any(|l| l.is_nan());
        for w in &mut self.wake {
            w.advance(h, self.evaluated);
        }
        if !self.time.is_nan() {
            self.time += h;
        }
        self.evaluated = false;
        self.elapsed = 0.0;
    }
}

/// α_L a time `elapsed` after the committed state (α_L, α₀, r₀) =
/// `committed`, where the angle of attack is `alpha` and the lag rate
/// `rate` ([`PressureLag`]: exponential time differencing).
#[inline]
fn lag_at(committed: (f64, f64, f64), elapsed: f64, alpha: f64, rate: f64) -> f64 {
    let (lagged, alpha0, rate0) = committed;
    if lagged.is_nan() || rate == f64::INFINITY || rate0 == f64::INFINITY {
        return if lagged.is_nan() || elapsed > 0.0 {
            alpha
        } else {
            lagged
        };
    }
    if elapsed <= 0.0 {
        return lagged;
    }
    // No committed flow: α held at the evaluation's over the interval.
    let (alpha0, rate0) = if alpha0.is_nan() {
        (alpha, rate)
    } else {
        (alpha0, rate0)
    };
    let x = 0.5 * (rate0 + rate) * elapsed;
    let em1 = (-x).exp_m1();
    let decay = 1.0 + em1;
    let phi = if x > 0.0 { -em1 / x } else { 1.0 };
    decay * lagged + (phi - decay) * alpha0 + (1.0 - phi) * alpha
}

/// The angle of attack α = asin(|u·n|/|u|) of a flow of normal part `qn`
/// and speed `speed` > 0, rad (min 1: round-off).
#[inline]
fn angle_of_attack(qn: f64, speed: f64) -> f64 {
    (qn.abs() / speed).min(1.0).asin()
}

/// The centre of pressure's offset upstream of mid-chord in steady flow,
/// in chords: a quarter chord at α = 0 (thin-aerofoil theory), none
/// broadside, linear between (module docs).
#[inline]
pub fn pressure_offset(alpha: f64) -> f64 {
    0.25 * (1.0 - alpha * std::f64::consts::FRAC_2_PI)
}

/// The lagged centre of pressure's couple on every intact triangle with
/// flow over it, as its in-plane arm in `flows` (which [`per_triangle`]
/// applies with the Munk couple's), and each triangle's α and lag rate
/// recorded in `lag` (module docs): the normal force ½ ρ A C_D⊥ |u| (u·n) n
/// moved G c∥ (f(α_L) − f(α)) cos α upstream along the in-plane flow (the
/// cos α, |u∥|/|u|, takes the couple through zero where the in-plane flow
/// reverses, instead of through a jump).
fn lagged_pressure(
    law: &UnsteadyAero,
    triangles: &[Option<TriangleMotion>],
    flows: &mut [Flow],
    lag: &mut PressureLag,
) {
    lag.evaluated = true;
    // The angles first, back to back: each arcsine is a long chain of
    // its own, and independent ones overlap (as in `flow_coefficients`).
    for ((alpha, flow), tm) in lag
        .pending_alpha
        .iter_mut()
        .zip(flows.iter())
        .zip(triangles)
    {
        *alpha = if tm.is_some() && flow.u2 > f64::MIN_POSITIVE {
            angle_of_attack(flow.qn, flow.speed)
        } else {
            f64::NAN
        };
    }
    // Then the lag rates, each a division; then α_L at the evaluation,
    // each an exponential and a division; then the couples. Passes of
    // their own for the same reason: one triangle's chain (arcsine, rate,
    // exponential, quotient, couple) filled the reorder window, so no two
    // triangles' chains overlapped (perf). Same operations per triangle,
    // same bits.
    for (t, (flow, tm)) in flows.iter_mut().zip(triangles).enumerate() {
        flow.lag = LagCouple::None;
        let alpha = lag.pending_alpha[t];
        if tm.is_none() || alpha.is_nan() {
            continue;
        }
        // Broadside (no in-plane flow) there is no upstream and no chord
        // along the flow: α_L still follows α, no couple acts.
        if flow.along2 <= f64::MIN_POSITIVE {
            lag.pending_rate[t] = f64::INFINITY;
            lag.pending_lagged[t] = alpha;
            continue;
        }
        let rate = flow.speed / (law.pressure_lag * flow.along_chord);
        let mut fresh = lag.lagged[t].is_nan();
        if fresh && lag.elapsed <= 0.0 {
            // Met at the committed time: that is where its lag starts, so
            // later evaluations of the step integrate from it.
            (lag.lagged[t], lag.alpha[t], lag.rate[t]) = (alpha, alpha, rate);
        } else if fresh && !lag.start[t].is_nan() {
            // The flow began at the committed time, from none, at the
            // angle `seed_flow_start` found and at rate |u|/(k c) = 0: the
            // lag starts there (started at this evaluation's α instead, it
            // begins O(h) late, an error of first order in every fall from
            // rest: small under Verlet's own, but RK4's whole error).
            let start = lag.start[t];
            (lag.lagged[t], lag.alpha[t], lag.rate[t]) = (start, start, 0.0);
            fresh = false;
        }
        lag.pending_rate[t] = rate;
        flow.lag = if fresh {
            LagCouple::Follows
        } else {
            LagCouple::Acts
        };
    }
    let elapsed = lag.elapsed;
    for (((((pending, flow), &alpha), &rate), &lagged), (&alpha0, &rate0)) in lag
        .pending_lagged
        .iter_mut()
        .zip(flows.iter())
        .zip(&lag.pending_alpha)
        .zip(&lag.pending_rate)
        .zip(&lag.lagged)
        .zip(lag.alpha.iter().zip(&lag.rate))
    {
        if flow.lag != LagCouple::None {
            *pending = lag_at((lagged, alpha0, rate0), elapsed, alpha, rate);
        }
    }
    let half_rho = 0.5 * law.air_density;
    for (((flow, tm), &alpha), &lagged) in flows
        .iter_mut()
        .zip(triangles)
        .zip(&lag.pending_alpha)
        .zip(&lag.pending_lagged)
    {
        let Some(tm) = tm.as_ref().filter(|_| flow.lag == LagCouple::Acts) else {
            continue;
        };
        let shift = law.pressure_lag_gain
            * flow.along_chord
            * (pressure_offset(lagged) - pressure_offset(alpha));
        let normal_force = half_rho * tm.area * law.cd_normal * flow.speed * flow.qn;
        // Offset −e s upstream of the force F n, along e = u∥/|u| (the
        // in-plane flow's direction times cos α): couple C = −s F e × n,
        // so n × C = −s F e. With the unit direction u∥/|u∥| instead, the
        // couple reversed in a jump whenever the in-plane flow passed
        // through zero (a plate rocking through face-on with α_L behind
        // α), and a 5 cm plate's fall converged erratically, its Verlet
        // error at 0.25 s 60× the smooth law's (docs/real-falls.md,
        // "A couple without a jump").
        let along_flow = (flow.u - tm.n * flow.qn) / flow.speed;
        flow.lag_arm = along_flow * (-shift * normal_force);
    }
}

/// What the lagged centre of pressure does on a triangle in an evaluation
/// ([`lagged_pressure`]'s passes).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
enum LagCouple {
    /// No flow over it, or broadside: no lag rate, no couple.
    #[default]
    None,
    /// Its lag starts at this evaluation: α_L follows, no couple yet.
    Follows,
    /// α_L lags α and the couple acts.
    Acts,
}

/// Records in `lag` the angle of attack at which the flow over each
/// triangle starts where it has none at the committed state (a release
/// from rest in still air): `acc` holds the particles' accelerations
/// there. The relative flow u is linear in the particles' velocities at
/// fixed positions (the corners' mean, less the plate's rotation), so
/// where they are all zero it grows as u(t) ≈ t L(a): its direction, and
/// so α(0⁺), is the flow's own formula read with the accelerations for
/// the velocities. Call after an evaluation at the committed time
/// ([`PressureLag::wants_start`]); still air only (in wind the flow's
/// start would need the wind's rate of change too, and a triangle falls
/// back to starting unlagged).
pub fn seed_flow_start(model: &Model, x: &[V3], acc: &[V3], torn: &[bool], lag: &mut PressureLag) {
    let AeroLaw::Unsteady(law) = &model.aero else {
        return;
    };
    SCRATCH.with_borrow_mut(|scratch| {
        scratch.measure(law, model, x, acc, None, torn);
        let Scratch {
            triangles, flows, ..
        } = scratch;
        for (t, (flow, tm)) in flows.iter().zip(triangles.iter()).enumerate() {
            let unmet = lag.lagged[t].is_nan() && lag.pending_alpha[t].is_nan();
            if unmet && tm.is_some() && flow.u2 > f64::MIN_POSITIVE {
                lag.start[t] = angle_of_attack(flow.qn, flow.u2.sqrt());
            }
        }
    });
}

/// What drag and translational lift remove from a triangle's velocity: its
/// plate's rotation about the plate's centre (area-weighted means over the
/// plate's intact triangles).
#[derive(Clone, Copy, Debug, Default)]
struct PlateMotion {
    area: f64,
    /// Σ A c, then the centre.
    centre: V3,
    /// Σ A ω, then the mean in-plane angular velocity n × ṅ.
    omega: V3,
}

/// One intact triangle's shape and turning, measured once per evaluation
/// and read by both passes ([`plate_motions`], [`per_triangle`]).
#[derive(Clone, Copy, Debug)]
struct TriangleMotion {
    /// N = e₁ × e₂ and |N|².
    big_n: V3,
    n2: f64,
    /// n = N/|N| and the area |N|/2.
    n: V3,
    area: f64,
    /// ṅ = (Ṅ − n (n·Ṅ))/|N|.
    n_dot: V3,
    /// x_a + x_b + x_c (three times the centroid).
    corner_sum: V3,
}

/// Per-thread scratch of [`unsteady_forces`], kept so that the step loop
/// does not allocate (tests/integration/alloc.rs) without widening the
/// force kernels' signatures.
#[derive(Default)]
struct Scratch {
    /// One per triangle; `None` for a torn or degenerate one.
    triangles: Vec<Option<TriangleMotion>>,
    plates: Vec<PlateMotion>,
    /// One per triangle, as `triangles`; read only where that is `Some`.
    flows: Vec<Flow>,
    /// One per plate, for the wake's couple (empty with it off).
    wake: Vec<WakeSums>,
}

impl Scratch {
    /// The first passes of an evaluation at (x, v): each triangle's shape
    /// and turning, each plate's motion, each triangle's relative flow.
    fn measure(
        &mut self,
        law: &UnsteadyAero,
        model: &Model,
        x: &[V3],
        v: &[V3],
        wind: Option<&[V3]>,
        torn: &[bool],
    ) {
        triangle_motions(model, x, v, torn, &mut self.triangles);
        plate_motions(law, model, &self.triangles, &mut self.plates);
        relative_flows(
            law,
            model,
            x,
            v,
            wind,
            &self.triangles,
            &self.plates,
            &mut self.flows,
        );
    }
}

thread_local! {
    static SCRATCH: std::cell::RefCell<Scratch> = std::cell::RefCell::new(Scratch::default());
}

/// Fills `out` with every triangle's [`TriangleMotion`] (`None` where
/// [`surface`] finds it torn or degenerate).
fn triangle_motions(
    model: &Model,
    x: &[V3],
    v: &[V3],
    torn: &[bool],
    out: &mut Vec<Option<TriangleMotion>>,
) {
    out.clear();
    out.extend(model.triangles.iter().enumerate().map(|(t, tri)| {
        let (big_n, n2) = surface(t, tri, x, torn)?;
        let [a, b, c] = tri.corners;
        let (e1, e2) = (x[b] - x[a], x[c] - x[a]);
        let doubled = n2.sqrt();
        // One division, then products: the law's kernel is bound by its
        // divider (perf), and six divisions by |N| cost five more than one.
        let inv_doubled = 1.0 / doubled;
        let n = big_n * inv_doubled;
        let n_dot_raw = (v[b] - v[a]).cross(&e2) + e1.cross(&(v[c] - v[a]));
        Some(TriangleMotion {
            big_n,
            n2,
            n,
            area: 0.5 * doubled,
            n_dot: (n_dot_raw - n * n.dot(&n_dot_raw)) * inv_doubled,
            corner_sum: x[a] + x[b] + x[c],
        })
    }));
}

/// Adds the wake's couple (module docs, "Wake") on every plate of `model` to
/// `force`, from the evaluation's triangle motions, plate motions (area and
/// centre, [`plate_motions`]) and flows, and records each plate's rate in
/// `lag`.
#[allow(clippy::too_many_arguments)]
fn wake_couples(
    law: &UnsteadyAero,
    model: &Model,
    x: &[V3],
    triangles: &[Option<TriangleMotion>],
    plates: &[PlateMotion],
    flows: &[Flow],
    lag: &mut PressureLag,
    sums: &mut Vec<WakeSums>,
    force: &mut [V3],
) {
    lag.evaluated = true;
    let elapsed = lag.elapsed;
    sums.clear();
    sums.resize(lag.wake.len(), WakeSums::default());
    for ((tm, flow), (geom, tri)) in triangles
        .iter()
        .zip(flows)
        .zip(model.surfaces.iter().zip(&model.triangles))
    {
        let Some(tm) = tm else {
            continue;
        };
        let sum = &mut sums[geom.plate];
        sum.speed += tm.area * flow.speed;
        if sum.axis.is_none() {
            let [a, b, _] = tri.corners;
            sum.axis = Some((x[b] - x[a]).normalize());
        }
    }
    // Each plate's pressure scale ½ ρ U² sin φ / c at this evaluation.
    for ((sum, w), p) in sums.iter_mut().zip(lag.wake.iter_mut()).zip(plates) {
        if p.area <= 0.0 || w.chord <= 0.0 {
            continue;
        }
        let u = sum.speed / p.area;
        let rate = std::f64::consts::TAU * law.wake_strouhal * u / w.chord;
        w.pending = rate;
        let phase = w.phase_at(elapsed, rate);
        sum.scale = law.wake_couple * 0.5 * law.air_density * u * u * phase.sin() / w.chord;
    }
    for ((tm, flow), (geom, tri)) in triangles
        .iter()
        .zip(flows)
        .zip(model.surfaces.iter().zip(&model.triangles))
    {
        let sum = &sums[geom.plate];
        let (Some(tm), Some(e)) = (tm, sum.axis) else {
            continue;
        };
        if flow.u2 <= f64::MIN_POSITIVE {
            continue;
        }
        let sin2 = flow.qn * flow.qn / flow.u2;
        let d = (tm.corner_sum / 3.0 - plates[geom.plate].centre).dot(&e);
        let f = tm.n * (sum.scale * sin2 * sin2 * tm.area * d / 3.0);
        for &i in &tri.corners {
            force[i] += f;
        }
    }
}

/// One plate's sums for [`wake_couples`]: Σ A |u|, its axis, and its
/// pressure scale ½ ρ U² sin φ / c times C_W.
#[derive(Clone, Copy, Debug, Default)]
struct WakeSums {
    speed: f64,
    axis: Option<V3>,
    scale: f64,
}

/// Fills `plates` with each plate's [`PlateMotion`]; left empty when no
/// term reads them: the law keeps the whole rotation in drag
/// (`rotation_drag = 1`) and has no wake.
fn plate_motions(
    law: &UnsteadyAero,
    model: &Model,
    triangles: &[Option<TriangleMotion>],
    plates: &mut Vec<PlateMotion>,
) {
    plates.clear();
    if law.rotation_drag >= 1.0 && law.wake_couple <= 0.0 {
        return;
    }
    plates.resize(plate_count(model), PlateMotion::default());
    for (tm, geom) in triangles.iter().zip(&model.surfaces) {
        let Some(tm) = tm else {
            continue;
        };
        let p = &mut plates[geom.plate];
        p.area += tm.area;
        p.centre += tm.corner_sum * (tm.area / 3.0);
        p.omega += tm.n.cross(&tm.n_dot) * tm.area;
    }
    for p in plates.iter_mut().filter(|p| p.area > 0.0) {
        p.centre /= p.area;
        p.omega /= p.area;
    }
}

/// How many plates (triangles joined through shared edges) `model` has.
fn plate_count(model: &Model) -> usize {
    model
        .surfaces
        .iter()
        .map(|g| g.plate + 1)
        .max()
        .unwrap_or(0)
}

/// The air's flow over one intact triangle, in the two passes that precede
/// [`per_triangle`]: [`relative_flows`] fills the vectors and the
/// projections the chord look-ups read, [`flow_coefficients`] the square
/// roots, chords and quotients. They are apart so that the look-ups and
/// their chains of divisions and square roots, a third of the law's time
/// when each waited for its own triangle's (perf), run back to back over
/// all triangles and overlap. Every value is the expression the single
/// pass computed, in the same order, so the forces keep their bits.
#[derive(Clone, Copy, Debug, Default)]
struct Flow {
    /// The dual basis ∇β_b, ∇β_c of the corners.
    grad_b: V3,
    grad_c: V3,
    /// The air's velocity relative to the triangle (module docs), |u|² and
    /// its normal part u·n.
    u: V3,
    u2: f64,
    qn: f64,
    /// |u∥|² and u∥ on ∇β_b, ∇β_c (the chord along the flow).
    along2: f64,
    along_on: [f64; 2],
    /// ω = n × ṅ, |ω|², n × ω, and both on ∇β_b, ∇β_c (the chord across
    /// the rotation axis and the span along it).
    omega: V3,
    w2: f64,
    across: V3,
    across_on: [f64; 2],
    omega_on: [f64; 2],
    /// Then: |u|, the chord along u∥ (0 with no in-plane flow), C_D∥ (with
    /// skin friction), the chord across the axis and the finite-span
    /// factor.
    speed: f64,
    along_chord: f64,
    cd_par: f64,
    chord: f64,
    finite: f64,
    /// The lagged centre of pressure's share of the couples' in-plane arm
    /// (n × C; zero without the term), added with the Munk couple's.
    lag_arm: V3,
    /// What the lag does on the triangle in this evaluation.
    lag: LagCouple,
}

/// Whether the law's rotational terms act on a triangle turning at |ω|² =
/// `w2`.
#[inline]
fn turning(law: &UnsteadyAero, w2: f64) -> bool {
    w2 > f64::MIN_POSITIVE && (law.rotational_lift != 0.0 || damped(law))
}

/// Whether the law damps rotation at all.
#[inline]
fn damped(law: &UnsteadyAero) -> bool {
    law.rotational_damping != 0.0 || law.rotational_damping_quadratic != 0.0
}

/// First pass of the per-triangle terms: each intact triangle's [`Flow`]
/// vectors and projections.
#[allow(clippy::too_many_arguments)]
fn relative_flows(
    law: &UnsteadyAero,
    model: &Model,
    x: &[V3],
    v: &[V3],
    wind: Option<&[V3]>,
    triangles: &[Option<TriangleMotion>],
    plates: &[PlateMotion],
    flows: &mut Vec<Flow>,
) {
    let third = 1.0 / 3.0;
    flows.resize(triangles.len(), Flow::default());
    for (((tri, tm), geom), flow) in model
        .triangles
        .iter()
        .zip(triangles)
        .zip(&model.surfaces)
        .zip(flows.iter_mut())
    {
        let Some(tm) = tm else {
            continue;
        };
        let TriangleMotion {
            big_n,
            n2,
            n,
            n_dot,
            corner_sum,
            ..
        } = *tm;
        let [a, b, c] = tri.corners;
        let (e1, e2) = (x[b] - x[a], x[c] - x[a]);
        let w = corner_velocities(tri.corners, v, wind);
        let inv_n2 = 1.0 / n2;
        let grad_b = e2.cross(&big_n) * inv_n2;
        let grad_c = big_n.cross(&e1) * inv_n2;
        // Less the share (1 − rotation_drag) of what the plate's rotation
        // gives the triangle.
        let mut u = -(w[0] + w[1] + w[2]) * third;
        if let Some(p) = plates
            .get(geom.plate)
            .filter(|p| p.area > 0.0 && law.rotation_drag < 1.0)
        {
            let r = corner_sum * third - p.centre;
            u += p.omega.cross(&r) * (1.0 - law.rotation_drag);
        }
        let u2 = u.norm_squared();
        let qn = u.dot(&n);
        let u_plane = u - n * qn;
        let omega = n.cross(&n_dot);
        // Directions for `chord` unnormalised: it reads only their direction.
        let across = n.cross(&omega);
        *flow = Flow {
            grad_b,
            grad_c,
            u,
            u2,
            qn,
            along2: u_plane.norm_squared(),
            along_on: [u_plane.dot(&grad_b), u_plane.dot(&grad_c)],
            omega,
            w2: omega.norm_squared(),
            across,
            across_on: [across.dot(&grad_b), across.dot(&grad_c)],
            omega_on: [omega.dot(&grad_b), omega.dot(&grad_c)],
            ..Flow::default()
        };
    }
}

/// Second pass: each intact triangle's square roots, chord look-ups and
/// the coefficients they give ([`Flow`]).
fn flow_coefficients(law: &UnsteadyAero, model: &Model, flows: &mut [Flow]) {
    for (flow, geom) in flows.iter_mut().zip(&model.surfaces) {
        flow.speed = flow.u2.sqrt();
        let along = flow.along2.sqrt();
        // `chord` reads a direction, whatever its length: no division.
        (flow.along_chord, flow.cd_par) = if along > 0.0 {
            let chord = geom.chord(flow.along_on[0], flow.along_on[1]);
            (chord, cd_parallel(law, along, chord))
        } else {
            (0.0, law.cd_parallel)
        };
    }
    for (flow, geom) in flows.iter_mut().zip(&model.surfaces) {
        if turning(law, flow.w2) {
            flow.chord = geom.chord(flow.across_on[0], flow.across_on[1]);
            if law.rotational_lift != 0.0 {
                // A plate of finite span s along the axis sheds tip
                // vortices: Prandtl's lifting line scales a wing's
                // circulation by AR/(AR + 2), AR = s/c (→ 1 in 2-D).
                let span = geom.chord(flow.omega_on[0], flow.omega_on[1]);
                flow.finite = span / (span + 2.0 * flow.chord);
            }
        }
    }
}

/// Each corner's velocity relative to the air (`wind` at the particles, or
/// still air).
#[inline(always)]
fn corner_velocities(corners: [usize; 3], v: &[V3], wind: Option<&[V3]>) -> [V3; 3] {
    let [a, b, c] = corners;
    match wind {
        Some(g) => [v[a] - g[a], v[b] - g[b], v[c] - g[c]],
        None => [v[a], v[b], v[c]],
    }
}

/// The per-triangle terms of [`unsteady_forces`], from each intact
/// triangle's [`Flow`].
#[allow(clippy::too_many_arguments)]
fn per_triangle(
    law: &UnsteadyAero,
    model: &Model,
    v: &[V3],
    wind: Option<&[V3]>,
    triangles: &[Option<TriangleMotion>],
    flows: &[Flow],
    force: &mut [V3],
    added: &mut [Matrix3<f64>],
) {
    let rho = law.air_density;
    let half_rho = 0.5 * rho;
    let rho_added = rho * law.added_mass;
    let third = 1.0 / 3.0;
    let half_pi_rho = std::f64::consts::FRAC_PI_2 * rho;
    let damped = damped(law);
    for (((tri, tm), geom), flow) in model
        .triangles
        .iter()
        .zip(triangles)
        .zip(&model.surfaces)
        .zip(flows)
    {
        let Some(tm) = tm else {
            continue;
        };
        let geom: &SurfaceGeometry = geom;
        let TriangleMotion { n, area, n_dot, .. } = *tm;
        let Flow {
            grad_b,
            grad_c,
            u,
            u2,
            qn,
            omega,
            w2,
            across,
            speed,
            cd_par,
            chord,
            finite,
            ..
        } = *flow;
        let corners = tri.corners;
        let w = corner_velocities(corners, v, wind);
        let grads = [-(grad_b + grad_c), grad_b, grad_c];
        let mut f = [V3::zeros(); 3];
        // In-plane vector whose projection on the corner gradients gives
        // the normal forces of the triangle's couples (n × C).
        let mut couple_arm = flow.lag_arm;

        if rho_added > 0.0 {
            let mut q = V3::zeros();
            for k in 0..3 {
                let m = rho_added * geom.added_mass[k];
                let wn = n.dot(&w[k]);
                f[k] -= (n * n_dot.dot(&w[k]) + n_dot * wn) * m;
                q += w[k] * (m * wn);
            }
            // Munk couple C = −Q × n: n × C = −Q∥; relieved near
            // broadside where the flow has separated (module docs, "Munk
            // relief").
            let munk = q - n * n.dot(&q);
            if law.munk_relief > 0.0 && u2 > f64::MIN_POSITIVE {
                let sin2 = qn * qn / u2;
                couple_arm -= munk * (1.0 - law.munk_relief * sin2 * sin2 * sin2);
            } else {
                couple_arm -= munk;
            }
        }

        if u2 > f64::MIN_POSITIVE {
            let k_normal = law.cd_normal - cd_par - 2.0 * law.translational_lift;
            let drag = (u * (cd_par + k_normal * qn * qn / u2)
                + n * (2.0 * law.translational_lift * qn))
                * (half_rho * area * speed * third);
            for fk in &mut f {
                *fk += drag;
            }
        }

        if turning(law, w2) {
            if law.rotational_lift != 0.0 {
                let lift = u.cross(&omega)
                    * (half_rho * law.rotational_lift * finite * chord * area * third);
                for fk in &mut f {
                    *fk += lift;
                }
            }
            if damped {
                // τ = −(π/2) ρ A a² (μ₁|u| + μ₂ a |ω|) ω, a = c/2: n × τ.
                let half = 0.5 * chord;
                let quadratic = if law.rotational_damping_quadratic != 0.0 {
                    law.rotational_damping_quadratic * half * w2.sqrt()
                } else {
                    0.0
                };
                let rate =
                    half_pi_rho * area * half * half * (law.rotational_damping * speed + quadratic);
                couple_arm -= across * rate;
            }
        }

        for k in 0..3 {
            force[corners[k]] += f[k] + n * grads[k].dot(&couple_arm);
        }
    }
    // The added-mass tensors in a pass of their own (the same sums in the
    // same order): interleaved with the forces, the read-modify-write of
    // each corner's 3 × 3 tensor stalled the loop (perf).
    if rho_added > 0.0 && !added.is_empty() {
        added_mass_tensors(rho_added, model, triangles, added);
    }
}

/// Adds each intact triangle's m_k n nᵀ to its corners' tensors in `added`
/// (m_k its corner's share of the plate's added mass times `rho_added`).
fn added_mass_tensors(
    rho_added: f64,
    model: &Model,
    triangles: &[Option<TriangleMotion>],
    added: &mut [Matrix3<f64>],
) {
    for ((tri, tm), geom) in model.triangles.iter().zip(triangles).zip(&model.surfaces) {
        let Some(tm) = tm else {
            continue;
        };
        let nn = tm.n * tm.n.transpose();
        for (&i, &share) in tri.corners.iter().zip(&geom.added_mass) {
            added[i] += nn * (rho_added * share);
        }
    }
}

/// The flow's kinetic energy T = ½ Σ m_k (n·w_k)² of every intact triangle's
/// added mass, J (w relative to `wind`, or to still air): with the body's
/// own kinetic energy, what the added-mass forces conserve.
pub fn added_mass_energy(model: &Model, x: &[V3], v: &[V3], wind: Option<&[V3]>) -> f64 {
    let AeroLaw::Unsteady(law) = &model.aero else {
        return 0.0;
    };
    let rho_added = law.air_density * law.added_mass;
    let mut energy = 0.0;
    for (t, tri) in model.triangles.iter().enumerate() {
        let Some((big_n, n2)) = surface(t, tri, x, &[]) else {
            continue;
        };
        let n = big_n / n2.sqrt();
        for (k, &i) in tri.corners.iter().enumerate() {
            let w = match wind {
                Some(g) => v[i] - g[i],
                None => v[i],
            };
            energy += 0.5 * rho_added * model.surfaces[t].added_mass[k] * n.dot(&w).powi(2);
        }
    }
    energy
}

/// The plate's added mass at rest per plate (the sum of its corners'
/// shares, times ρ and the law's factor), kg, in the order of
/// [`crate::physics::model::plates`]; empty under the other laws.
pub fn plate_added_masses(model: &Model) -> Vec<f64> {
    let AeroLaw::Unsteady(law) = &model.aero else {
        return Vec::new();
    };
    let corners: Vec<[usize; 3]> = model.triangles.iter().map(|t| t.corners).collect();
    crate::physics::model::plates(&corners)
        .iter()
        .map(|plate| {
            plate
                .iter()
                .map(|&t| model.surfaces[t].added_mass.iter().sum::<f64>())
                .sum::<f64>()
                * law.air_density
                * law.added_mass
        })
        .collect()
}

/// Fastest steady fall of `model` under `law`: edge-on, its weight carried
/// by in-plane drag alone, M g = ½ ρ A C_D∥(V) V², on the longest chord of
/// any triangle (the least skin friction), m/s.
pub fn edge_on_speed(law: &UnsteadyAero, model: &Model) -> f64 {
    let area = model.surface_area();
    if area <= 0.0 {
        return 0.0;
    }
    let chord = model
        .surfaces
        .iter()
        .flat_map(|g| g.chords.iter().copied())
        .fold(0.0, f64::max);
    let weight = model.total_mass() * model.gravity.norm();
    let drag =
        |speed: f64| 0.5 * law.air_density * area * cd_parallel(law, speed, chord) * speed * speed;
    // Drag grows without bound with speed (at least as V^1.5): bisect.
    let (mut lo, mut hi) = (0.0, 1.0);
    while drag(hi) < weight && hi < 1e6 {
        hi *= 2.0;
    }
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if drag(mid) < weight {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}

/// Per-triangle bounds shared by the particle and rigid-body rates, at
/// relative speed `v_ref` and rotation rate `omega_ref` (module docs for
/// the terms).
struct TriangleBounds {
    /// ‖∂F/∂u‖ of drag, translational lift and skin friction, N·s/m.
    drag: f64,
    /// Rotational lift ½ρ C_R c A: multiplies (ω, |u|) in its derivatives.
    rot_lift: f64,
    /// Rotational damping (π/2) ρ A a²: its couple's scale, with a = c/2.
    damping: f64,
    /// a = half the longest chord, m.
    half_chord: f64,
    /// Each corner's added mass, kg.
    added: [f64; 3],
}

fn triangle_bounds(
    law: &UnsteadyAero,
    geom: &SurfaceGeometry,
    area: f64,
    u_ref: f64,
    q_ref: f64,
) -> TriangleBounds {
    let rho = law.air_density;
    let chord_max = geom.chords.iter().copied().fold(0.0, f64::max);
    let chord_min = geom
        .chords
        .iter()
        .copied()
        .filter(|&c| c > 0.0)
        .fold(f64::INFINITY, f64::min)
        .min(chord_max)
        .max(1e-12);
    // F = ½ρA [C_D∥ |u| u + k q² u/|u| + 2 C_T |u| q n], k = C_D⊥ − C_D∥ − 2C_T:
    // ‖∂‖ ≤ ½ρA [(2 C_D∥ + 1.5 C_f) |u| + 4 |k| |q| + 2 C_T (|u| + |q|)]
    // (skin friction C_f ∝ |u|^−½, so its force grows as |u|^1.5), with
    // |u| ≤ u_ref and the normal part |q| ≤ q_ref.
    let cf = cd_parallel(law, u_ref, chord_min) - law.cd_parallel;
    let k = (law.cd_normal - law.cd_parallel - 2.0 * law.translational_lift).abs() + cf;
    TriangleBounds {
        drag: 0.5
            * rho
            * area
            * ((2.0 * law.cd_parallel + 1.5 * cf) * u_ref
                + 4.0 * k * q_ref
                + 2.0 * law.translational_lift * (u_ref + q_ref)),
        rot_lift: 0.5 * rho * law.rotational_lift * chord_max * area,
        damping: std::f64::consts::FRAC_PI_2 * rho * area * (0.5 * chord_max).powi(2),
        half_chord: 0.5 * chord_max,
        added: std::array::from_fn(|k| rho * law.added_mass * geom.added_mass[k]),
    }
}

/// Fastest rate at which a plate of `model` can tumble, 1/s (0 under the
/// other laws): Ω = 2 U / c with U the [`face_on_speed`] and c the
/// narrowest plate's width (the largest, over its triangles, of the
/// shortest chord through a triangle's centroid: a strip's width, a
/// square's side, a disk's diameter). A tumbling plate's edges move at
/// about its fall speed or slower (Ω c/2 ≲ U; Mahadevan, Ryu & Samuel
/// 1999): measured at the defaults, real and simulated squares turn at
/// 0.6–0.7 of it and a narrow heavy strip at 0.2 (docs/real-falls.md), so this is a bound,
/// not an estimate.
pub fn tumbling_rate(model: &Model) -> f64 {
    let AeroLaw::Unsteady(law) = &model.aero else {
        return 0.0;
    };
    let mut width = vec![0.0f64; plate_count(model)];
    for g in &model.surfaces {
        let shortest = g
            .chords
            .iter()
            .copied()
            .filter(|&c| c > 0.0)
            .fold(f64::INFINITY, f64::min);
        if shortest.is_finite() {
            width[g.plate] = width[g.plate].max(shortest);
        }
    }
    let narrowest = width
        .into_iter()
        .filter(|&w| w > 0.0)
        .fold(f64::INFINITY, f64::min);
    if narrowest.is_finite() {
        2.0 * face_on_speed(law, model) / narrowest
    } else {
        0.0
    }
}

/// Fastest face-on fall of `model` under `law`, M g = ½ ρ A C_D⊥ V², m/s:
/// what bounds the normal part of the air's relative velocity.
pub fn face_on_speed(law: &UnsteadyAero, model: &Model) -> f64 {
    let area = model.surface_area();
    if area <= 0.0 {
        return 0.0;
    }
    (2.0 * model.total_mass() * model.gravity.norm() / (law.air_density * area * law.cd_normal))
        .sqrt()
}

/// Largest rate of the explicit part of the unsteady law, 1/s (0 under the
/// other laws): a Gershgorin bound at the rest shape, every relative speed
/// up to v_ref = wind bound + [`SPEED_MARGIN`] × [`edge_on_speed`].
///
/// - A particle of no rigid body: ‖(m_i I + M_i)⁻¹ Σⱼ ∂f_i/∂v_j‖, term by
///   term with every corner moving independently (|ṅ| ≤ v_ref Σ 1/h_j);
///   forces along a triangle's normal are divided by the particle's
///   effective mass along it, |(m I + M)⁻¹ n| (M its rest added-mass
///   tensor, which a rigid motion only turns), in-plane ones by m — the
///   added mass these terms scale with also slows the particle they push,
///   so a very light leaf's rate stays bounded.
/// - A rigid body: its members cannot move apart, so corner-by-corner
///   bounds would be far too pessimistic (a fine plate's triangles are
///   small, its rotation slow); its rate is measured instead
///   ([`rigid_body_rate`]).
///
/// The normal part of any triangle's relative velocity is bounded by
/// q_ref = wind bound + [`SPEED_MARGIN`] × [`face_on_speed`]: faster, the
/// face-on drag exceeds the weight several times and brakes it within
/// V/g (a test measures it in falls of plates and the recipes).
pub fn drag_rate(model: &Model) -> f64 {
    let (particles, bodies) = drag_rate_parts(model);
    particles.max(bodies)
}

/// Each particle's added-mass tensor M_i = Σ m_k n nᵀ at the rest shape
/// (the sum over the triangles at it, m_k its corner's share times ρ and
/// the law's factor), kg: what [`super::Forces::acceleration`] solves with
/// at a shape where every triangle lies as at rest.
pub fn rest_added_mass_tensors(law: &UnsteadyAero, model: &Model) -> Vec<Matrix3<f64>> {
    let x = &model.rest_position;
    let mut tensor = vec![Matrix3::<f64>::zeros(); model.len()];
    for (t, tri) in model.triangles.iter().enumerate() {
        let [a, b, c] = tri.corners;
        let nrm = (x[b] - x[a]).cross(&(x[c] - x[a])).normalize();
        for (k, &i) in tri.corners.iter().enumerate() {
            tensor[i] += nrm
                * nrm.transpose()
                * (law.air_density * law.added_mass * model.surfaces[t].added_mass[k]);
        }
    }
    tensor
}

/// [`drag_rate`] split: (free particles, rigid bodies).
pub fn drag_rate_parts(model: &Model) -> (f64, f64) {
    let AeroLaw::Unsteady(law) = &model.aero else {
        return (0.0, 0.0);
    };
    let wind = model.wind.speed_bound();
    let v_ref = wind + SPEED_MARGIN * edge_on_speed(law, model);
    let q_ref = wind + SPEED_MARGIN * face_on_speed(law, model);
    let x = &model.rest_position;
    let n = model.len();
    let body_of = model.body_of();
    let tensor = rest_added_mass_tensors(law, model);
    let mut normal_rate = vec![0.0; n];
    let mut plane_rate = vec![0.0; n];
    for (t, tri) in model.triangles.iter().enumerate() {
        let geom = &model.surfaces[t];
        let [a, b, c] = tri.corners;
        let big_n = (x[b] - x[a]).cross(&(x[c] - x[a]));
        let doubled = big_n.norm();
        let nrm = big_n / doubled;
        let area = 0.5 * doubled;
        let tb = triangle_bounds(law, geom, area, v_ref, q_ref);
        let m_sum: f64 = tb.added.iter().sum();
        let rigid = tri
            .corners
            .iter()
            .map(|&i| body_of[i])
            .reduce(|p, q| if p == q { p } else { None })
            .flatten();
        if rigid.is_some() {
            continue;
        }
        let heights: [f64; 3] = std::array::from_fn(|k| {
            let (j, l) = (tri.corners[(k + 1) % 3], tri.corners[(k + 2) % 3]);
            doubled / (x[l] - x[j]).norm()
        });
        let s: f64 = heights.iter().map(|h| 1.0 / h).sum();
        // |ṅ| ≤ Σⱼ |n·w_j|/h_j with every corner at v_ref.
        let omega_ref = v_ref * s;
        // A third of drag and rotational lift on each corner, each corner
        // velocity a third of u: summed over the corners, a third of the
        // triangle's rate.
        let drag = tb.drag / 3.0;
        let rot_lift = tb.rot_lift * (omega_ref + v_ref * s) / 3.0;
        let tau = tb.damping
            * (law.rotational_damping * (omega_ref + v_ref * s)
                + 2.0 * law.rotational_damping_quadratic * tb.half_chord * omega_ref * s);
        for (k, &i) in tri.corners.iter().enumerate() {
            let h = heights[k];
            // −m_k (ṅ·w_k) n (normal) and −m_k (n·w_k) ṅ (in-plane), each
            // ≤ m_k (v_ref s + ω_ref); the Munk couple's λ_k = ∇β_k·Q∥ with
            // ‖∂Q/∂w_j‖ ≤ 2 m_j v_ref.
            let gyro = tb.added[k] * (v_ref * s + omega_ref);
            let munk = 2.0 * v_ref * m_sum / h;
            let along_n = (model.mass[i] * Matrix3::identity() + tensor[i])
                .try_inverse()
                .map_or(1.0 / model.mass[i], |inv| (inv * nrm).norm());
            normal_rate[i] += (gyro + munk + tau / h) * along_n;
            plane_rate[i] += (gyro + drag + rot_lift) / model.mass[i];
        }
    }
    let bound = (0..n)
        .filter(|&i| !model.fixed[i] && body_of[i].is_none())
        .map(|i| normal_rate[i] + plane_rate[i])
        .fold(0.0, f64::max);
    let particles = if bound > 0.0 {
        let free: Vec<bool> = (0..n)
            .map(|i| !model.fixed[i] && body_of[i].is_none())
            .collect();
        bound.min(MEASURED_MARGIN * free_particle_rate(law, model, &free, &tensor, v_ref, q_ref))
    } else {
        bound
    };
    let bodies = (0..model.rigid.len())
        .map(|b| rigid_body_rate(law, model, b, v_ref, q_ref))
        .fold(0.0, f64::max);
    (particles, bodies)
}

/// Factor on the measured rate of the free particles ([`free_particle_rate`])
/// before it replaces the corner-by-corner bound: the measurement samples
/// states, so it is kept with a margin.
pub const MEASURED_MARGIN: f64 = 1.5;

/// Power iterations per sampled state in [`free_particle_rate`]: on
/// prototype A the largest rate after 12 agrees with 24 to 1e-4 (163.35
/// against 163.37 1/s; its complex pairs settle within a dozen), far
/// inside the [`MEASURED_MARGIN`] the estimate keeps on top.
const POWER_ITERATIONS: usize = 12;

/// The rate of the free particles (`free[i]`) under the unsteady law, 1/s:
/// the spectral radius of K⁻¹ ∂f/∂v (K_i = m_i I + M_i, the rest
/// added-mass tensors `tensor`), by power iteration on forward-difference
/// products ∂f/∂v · y at the rest shape (relative error about 1e-6, the
/// step's, against a margin of 1.5; central differences cost twice), for the relative velocities of
/// [`rigid_body_rate`] (speeds q_ref and v_ref along nine directions of the
/// leaf's best-fit frame, with and without a rotation of rate
/// 2 v_ref / (its extent across that axis) about each in-plane axis,
/// `tumbling_rates`). The corner-by-corner bound
/// of [`drag_rate`] lets every corner move independently at v_ref and is
/// far above what a leaf's motion reaches (60× on prototype A); this is a
/// measurement, not a bound, which `--dt auto` keeps with
/// [`MEASURED_MARGIN`] and its safety factor, and a test checks drops at
/// the auto step against half of it.
pub fn free_particle_rate(
    law: &UnsteadyAero,
    model: &Model,
    free: &[bool],
    tensor: &[Matrix3<f64>],
    v_ref: f64,
    q_ref: f64,
) -> f64 {
    let x = &model.rest_position;
    let n = model.len();
    let members: Vec<usize> = (0..n).filter(|&i| free[i]).collect();
    if members.is_empty() {
        return 0.0;
    }
    let centre = members.iter().map(|&i| x[i]).sum::<V3>() / members.len() as f64;
    let mut cov = Matrix3::zeros();
    for &i in &members {
        let r = x[i] - centre;
        cov += r * r.transpose();
    }
    let eig = cov.symmetric_eigen();
    let mut order = [0usize, 1, 2];
    // Largest spread first: the normal (least spread) is axes[2].
    order.sort_by(|&p, &q| eig.eigenvalues[q].total_cmp(&eig.eigenvalues[p]));
    let axes: [V3; 3] = order.map(|k| eig.eigenvectors.column(k).into());
    let omega_ref = tumbling_rates(&axes, members.iter().map(|&i| x[i]), v_ref);
    let inverse: Vec<Matrix3<f64>> = (0..n)
        .map(|i| {
            (Matrix3::identity() * model.mass[i] + tensor[i])
                .try_inverse()
                .unwrap_or_else(Matrix3::zeros)
        })
        .collect();
    let mut f_plus = vec![V3::zeros(); n];
    let mut f_base = vec![V3::zeros(); n];
    let mut v = vec![V3::zeros(); n];
    let mut worst: f64 = 0.0;
    for (vel, spin) in sampled_motions(&axes, v_ref, q_ref, omega_ref) {
        let base: Vec<V3> = (0..n).map(|i| vel + spin.cross(&(x[i] - centre))).collect();
        f_base.fill(V3::zeros());
        unsteady_forces(law, model, x, &base, None, &[], &mut f_base, &mut [], None);
        // A deterministic start with every component.
        let mut y: Vec<V3> = (0..n)
            .map(|i| {
                if free[i] {
                    let k = i as f64;
                    V3::new(1.0 + 0.37 * k, -0.6 + 0.11 * k, 0.8 - 0.23 * k)
                } else {
                    V3::zeros()
                }
            })
            .collect();
        let norm = |y: &[V3]| y.iter().map(|a| a.norm_squared()).sum::<f64>().sqrt();
        let mut log_growth = Vec::with_capacity(POWER_ITERATIONS);
        for _ in 0..POWER_ITERATIONS {
            let size = norm(&y);
            if size <= 0.0 || !size.is_finite() {
                break;
            }
            let eps = 1e-6 * v_ref.max(1e-9) / size;
            for i in 0..n {
                v[i] = base[i] + y[i] * eps;
            }
            f_plus.fill(V3::zeros());
            unsteady_forces(law, model, x, &v, None, &[], &mut f_plus, &mut [], None);
            for i in 0..n {
                y[i] = if free[i] {
                    inverse[i] * (f_plus[i] - f_base[i]) / eps
                } else {
                    V3::zeros()
                };
            }
            log_growth.push((norm(&y) / size).ln());
        }
        // The mean growth over the second half: the spectral radius
        // (a complex pair makes single ratios oscillate).
        let tail = &log_growth[log_growth.len() / 2..];
        if !tail.is_empty() {
            let rate = (tail.iter().sum::<f64>() / tail.len() as f64).exp();
            if rate.is_finite() {
                worst = worst.max(rate);
            }
        }
    }
    worst
}

/// The rates 2 v_ref / c at which a plate tumbling about `axes[0]` and
/// about `axes[1]` turns, c the extent of `points` across that axis (along
/// the other in-plane axis): a tumbling plate's edges move at about its
/// fall speed (Ω ≈ 2U/c; Mahadevan, Ryu & Samuel 1999), so a strip turns
/// about its long axis at 2 v_ref over its width, not over its length.
fn tumbling_rates(
    axes: &[V3; 3],
    points: impl Iterator<Item = V3> + Clone,
    v_ref: f64,
) -> [f64; 2] {
    let extent = |a: &V3| {
        let (lo, hi) = points
            .clone()
            .map(|p| p.dot(a))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), d| {
                (lo.min(d), hi.max(d))
            });
        (hi - lo).max(f64::MIN_POSITIVE)
    };
    [
        2.0 * v_ref / extent(&axes[1]),
        2.0 * v_ref / extent(&axes[0]),
    ]
}

/// The relative motions at which the measured rates are taken: a velocity
/// of speed q_ref or v_ref along each of [`RATE_DIRECTIONS`] (in the frame
/// `axes`, its normal part along `axes[2]` capped at q_ref, as in a fall),
/// each without rotation and with rate `omega_ref` about either in-plane axis.
/// A motion that capping makes equal to one already listed (along the
/// normal, v_ref capped is q_ref) is listed once: the rate is a maximum
/// over them, and each costs a dozen force evaluations.
fn sampled_motions(axes: &[V3; 3], v_ref: f64, q_ref: f64, omega_ref: [f64; 2]) -> Vec<(V3, V3)> {
    let to_world = |d: [f64; 3]| axes[0] * d[0] + axes[1] * d[1] + axes[2] * d[2];
    let mut motions = Vec::with_capacity(RATE_DIRECTIONS.len() * 6);
    for d in RATE_DIRECTIONS {
        let dir = to_world(d).normalize();
        for speed in [q_ref, v_ref] {
            let mut vel = dir * speed;
            let normal = vel.dot(&axes[2]);
            if normal.abs() > q_ref {
                vel -= axes[2] * (normal - q_ref * normal.signum());
            }
            for spin in [V3::zeros(), axes[0] * omega_ref[0], axes[1] * omega_ref[1]] {
                if !motions.contains(&(vel, spin)) {
                    motions.push((vel, spin));
                }
            }
        }
    }
    motions
}

/// Directions of the relative velocity, in the body frame of the rest
/// shape, at which [`rigid_body_rate`] measures: along each axis and the
/// diagonals between the plate's plane and its normal.
const RATE_DIRECTIONS: [[f64; 3]; 9] = [
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [1.0, 0.0, 1.0],
    [1.0, 0.0, -1.0],
    [0.0, 1.0, 1.0],
    [0.0, 1.0, -1.0],
    [1.0, 1.0, 1.0],
    [1.0, -1.0, 0.3],
];

/// The rate of rigid body `b` under the unsteady law, 1/s: the largest
/// |eigenvalue| of M_g⁻¹ ∂(F, τ)/∂(V, ω), with M_g the body's generalised
/// mass (its own and added, the 6 × 6 of [`crate::physics::rigid`]),
/// measured by forward differences at the rest shape for relative speeds
/// |V| ∈ {q_ref, v_ref} along nine directions (the normal part of
/// the larger capped at q_ref, as in a fall: see [`drag_rate`]), each with
/// and without a rotation of rate 2 v_ref / (the body's extent across that
/// axis) about each in-plane axis (`tumbling_rates`).
/// A measurement at sampled states, not a bound; `--dt auto` keeps
/// [`crate::physics::stability::AUTO_SAFETY`] below it and a test checks
/// drops at the auto step against half of it.
pub fn rigid_body_rate(law: &UnsteadyAero, model: &Model, b: usize, v_ref: f64, q_ref: f64) -> f64 {
    let body = &model.rigid[b];
    let x = &model.rest_position;
    let centre = body
        .members
        .iter()
        .zip(&body.member_mass)
        .map(|(&i, &m)| x[i] * m)
        .sum::<V3>()
        / body.mass;
    // The body's frame: its principal axes (the plate normal has the largest moment).
    let eig = body.inertia.symmetric_eigen();
    let mut order = [0usize, 1, 2];
    order.sort_by(|&p, &q| eig.eigenvalues[p].total_cmp(&eig.eigenvalues[q]));
    let axes: [V3; 3] = order.map(|k| eig.eigenvectors.column(k).into());
    let omega_ref = tumbling_rates(&axes, body.members.iter().map(|&i| x[i]), v_ref);
    let n = model.len();
    let mut v = vec![V3::zeros(); n];
    let mut f = vec![V3::zeros(); n];
    let mut added = vec![Matrix3::zeros(); n];
    let mut load = |vel: V3, omega: V3, added: &mut Vec<Matrix3<f64>>| -> (V3, V3) {
        for &i in &body.members {
            v[i] = vel + omega.cross(&(x[i] - centre));
        }
        f.fill(V3::zeros());
        added.fill(Matrix3::zeros());
        unsteady_forces(law, model, x, &v, None, &[], &mut f, added, None);
        let mut total = (V3::zeros(), V3::zeros());
        for &i in &body.members {
            total.0 += f[i];
            total.1 += (x[i] - centre).cross(&f[i]);
        }
        total
    };
    // Generalised mass at rest.
    load(V3::zeros(), V3::zeros(), &mut added);
    let mut mass = nalgebra::Matrix6::<f64>::zeros();
    for (&i, &m) in body.members.iter().zip(&body.member_mass) {
        let r = x[i] - centre;
        let k = Matrix3::identity() * m + added[i];
        let rx = Matrix3::new(0.0, -r.z, r.y, r.z, 0.0, -r.x, -r.y, r.x, 0.0);
        let blocks = [k, -(k * rx), rx * k, -(rx * k * rx)];
        for (q, blk) in blocks.iter().enumerate() {
            mass.fixed_view_mut::<3, 3>(3 * (q / 2), 3 * (q % 2))
                .add_assign(blk);
        }
    }
    let Some(inverse) = mass.try_inverse() else {
        return f64::INFINITY;
    };
    let mut worst: f64 = 0.0;
    for (vel, spin) in sampled_motions(&axes, v_ref, q_ref, omega_ref) {
        let mut jac = nalgebra::Matrix6::<f64>::zeros();
        let hv = 1e-6 * v_ref.max(1e-9);
        let hw = 1e-6 * omega_ref[0].max(omega_ref[1]).max(1e-9);
        // Forward differences: 7 loads per state instead of central
        // differences' 12, for a relative error of about 1e-6.
        let (f0, t0) = load(vel, spin, &mut added);
        for col in 0..6 {
            let mut e = nalgebra::Vector6::<f64>::zeros();
            e[col] = if col < 3 { hv } else { hw };
            let dv = V3::new(e[0], e[1], e[2]);
            let dw = V3::new(e[3], e[4], e[5]);
            let (fp, tp) = load(vel + dv, spin + dw, &mut added);
            for row in 0..3 {
                jac[(row, col)] = (fp[row] - f0[row]) / e[col];
                jac[(row + 3, col)] = (tp[row] - t0[row]) / e[col];
            }
        }
        let rate = (inverse * jac)
            .complex_eigenvalues()
            .iter()
            .map(|z| z.norm())
            .fold(0.0, f64::max);
        worst = worst.max(rate);
    }
    worst
}
