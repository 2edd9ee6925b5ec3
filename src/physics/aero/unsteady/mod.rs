//! The unsteady law for triangles: added mass with the fluid impulse that
//! comes with it, circulation from translation and from rotation,
//! rotational damping, drag by angle of attack with skin friction, and
//! optional buoyancy. What each triangle needs to know about its plate is
//! measured once ([`crate::physics::model::SurfaceGeometry`]).
//!
//! # Why
//!
//! The quasi-steady laws miss what makes real paper flutter and tumble
//! (docs/lab/real-falls.md): the air a plate sets moving (added mass, 0.2–0.6
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
//! particle ([`crate::physics::forces::Forces::acceleration`]), or the 6 × 6 of a rigid
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
//!   tumbling (docs/lab/real-falls.md). A flexible leaf's deformation still
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
//!   squares glide up to 6 times too far (docs/lab/real-falls.md, "The defaults");
//! - rotational circulation Γ = ½ C_R c² ω (APW: C_R = π; default 1.5,
//!   fitted with the other defaults to the real squares), c the plate's
//!   chord through the triangle across the rotation axis and ω = n × ṅ the
//!   triangle's in-plane angular velocity: F = ½ ρ C_R c A (u × ω) at the
//!   centroid, which does no work on a rigid plate;
//! - rotational damping, APW's τ = (μ₁ + μ₂|ω̃|) ω̃ in their units, per area
//!   τ = −(π/2) ρ A a² (μ₁ |u| + μ₂ a |ω|) ω with a = c/2, applied as a
//!   couple. APW's μ₂ = 0.2 damps a plate turning in place; measured on
//!   the real squares it stops the tumbling ones gliding (score 1.88 against
//!   1.29 without, docs/lab/real-falls.md), so μ₂ defaults to 0, and μ₁ to 0.1,
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
//! the strips and the disks in docs/lab/real-falls.md, "A lagged centre of
//! pressure".
//!
//! # Wake
//!
//! Off by default (`wake_couple` 0). A bluff plate falling face-on sheds
//! vortices from alternate edges at f = St |u| / c (`wake_strouhal`,
//! default 0.15), and the uneven pressure rocks it; the quasi-steady terms
//! above have no such thing, and a plate let go at 1–5° rocks about
//! face-on for 0.76–1.05 s where real paper leaves its flat fall in
//! 0.13–0.37 s (docs/lab/real-falls.md, "When a flat release departs"). With
//! the term on, each plate carries a wake phase φ turning at 2π St U / c
//! and each of its triangles the normal force C_W ½ ρ U² sin φ sin⁴α A
//! (d / c) n, d its distance from the plate's centre along an axis fixed
//! in the plate: a couple that acts only near face-on. The equations,
//! their integration and what the term leaves out are in
//! `src/physics/aero/unsteady/wake.rs`; what it does to the real falls
//! in docs/lab/real-falls.md, "A wake that rocks the face-on fall".
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
//! cosᵠα forms; what the term does there is in docs/lab/real-falls.md, "Munk
//! relief near broadside".
//!
//! Coefficients and defaults: [`UnsteadyAero`] (docs/lab/real-falls.md has the
//! table). One set serves every shape and size; the lengths come from each
//! leaf's own geometry. The defaults C_D⊥ = 2.6, C_D∥ = 0.65, C_T = 1.2,
//! C_R = 1.5, μ₁ = 0.1, G = 0.6 and k = 3 were fitted as one set to the
//! real paper squares (mean of two seeds; first without the lag term over
//! 144 candidate sets and 108 around the best, then with it over 270 more),
//! every fall at a step that bounds a tumbling plate's turn, with the
//! strips' scaling law and the disks' regimes as the lag term's check, and
//! then checked on ten other seeds of the squares (docs/lab/real-falls.md,
//! "The defaults"). They were kept when the lag's couple was made
//! continuous through face-on (cos α above), which moved the fit a little
//! (docs/lab/real-falls.md, "A couple without a jump").

pub mod coefficients;
mod lag;
mod rates;
mod triangle_forces;
mod wake;

pub use coefficients::{
    AIR_DENSITY_20C, AIR_VISCOSITY_20C, PAPER_DENSITY, UNSTEADY_CD_NORMAL, UNSTEADY_CD_PARALLEL,
    UNSTEADY_PRESSURE_LAG, UNSTEADY_PRESSURE_LAG_GAIN, UNSTEADY_ROTATION_DRAG,
    UNSTEADY_ROTATIONAL_DAMPING, UNSTEADY_ROTATIONAL_DAMPING_QUADRATIC, UNSTEADY_ROTATIONAL_LIFT,
    UNSTEADY_TRANSLATIONAL_LIFT, UNSTEADY_WAKE_STROUHAL, UnsteadyAero,
};
pub use lag::{PressureLag, pressure_offset};
pub use rates::{
    MEASURED_MARGIN, drag_rate, drag_rate_parts, edge_on_speed, face_on_speed, free_particle_rate,
    rest_added_mass_tensors, rigid_body_rate, tumbling_rate,
};
pub use triangle_forces::{
    BLASIUS, MIN_REYNOLDS, SPEED_MARGIN, added_mass_energy, cd_parallel, plate_added_masses,
    seed_flow_start, unsteady_forces,
};

/// What one triangle costs a step under this law, in elements of
/// [`crate::physics::run::REFERENCE_RATE`]: measured at 10 (prototype A)
/// and 10.6 (a rigid 5 cm plate) by drops at a fixed step (A at
/// dt = 1.6e-7 s: 2.1, 3.5 and 5.8 s under the linear, quadratic and
/// unsteady laws; the plate, 0.037, 0.078 and 0.152 s for 20 s of fall).
/// Without it a run under this law took three to seven times the time its
/// note quoted.
pub const TRIANGLE_COST: usize = 10;
