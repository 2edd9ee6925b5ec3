//! A second aerodynamic law for triangles: quadratic drag with lift and a
//! centre of pressure that moves with the angle of attack.
//!
//! # Why
//!
//! The paper's linear law (eq. 9–10) applied at the corners of a flat leaf of
//! uniform mass has no pitching moment (docs/design/falling-plates.md, "Linear law:
//! no pitching moment"): such a leaf can only float. Real plates flutter,
//! tumble or do both (Field et al. 1997) because the force on a plate is
//! quadratic in speed and, at small angles of attack, acts ahead of the
//! plate's centre. This law adds both, triangle by
//! triangle, so that a leaf of any shape gets a pitching moment that changes
//! with its attitude.
//!
//! # Equations
//!
//! For each triangle of area A, unit normal n and centroid c, the air's
//! velocity relative to the triangle is v = G − v_c (G and the triangle's
//! velocity v_c are the means over its three corners, so a spinning leaf sees
//! faster air at its tips). The angle of attack α ∈ [0, π/2] is the angle
//! between v and the triangle's plane: sin α = |v̂·n|. The force is
//!
//! F = ½ ρ A |v|² [C_D(α) v̂ + C_L(α) l̂],
//!
//! with drag along the relative air velocity and lift perpendicular to it, in
//! the plane of v and n, on the side the air pushes the plate to
//! (l̂ ∝ sgn(v·n) n − sin α v̂). The coefficients are those Wang, Birch &
//! Dickinson (J. Exp. Biol. 207, 2004) fitted to a translating plate and that
//! Andersen, Pesavento & Wang (J. Fluid Mech. 541, 2005) use for falling
//! plates (C_D(0) = 0.4, C_D(π/2) = 2.4):
//!
//! C_D(α) = C_D∥ cos²α + C_D⊥ sin²α   (= 1.4 − cos 2α),
//! C_L(α) = C_L★ sin 2α               (= 1.2 sin 2α).
//!
//! Written without angles (u = |v|, q = v·n, sin²α = q²/u²):
//!
//! F = ½ ρ A u [ (C_D∥ + (C_D⊥ − C_D∥ − 2 C_L★) q²/u²) v + 2 C_L★ q n ].
//!
//! Lift does no work: F·v = ½ ρ A u³ C_D(α) ≥ 0, so the law only dissipates.
//!
//! # Centre of pressure
//!
//! The force acts at a point p of the triangle's plane that moves with the
//! angle of attack: from the quarter-chord point at α = 0 (thin-aerofoil
//! theory puts a plate's centre of pressure a quarter chord behind its leading
//! edge) to the centroid at α = π/2 (symmetry), linearly in α. Li, Goodwill,
//! Wang & Ristroph (J. Fluid Mech. 937, A6, 2022) show that such a dynamic
//! centre of pressure is what makes quasi-steady plate models flutter, tumble
//! and glide; the linear interpolation is our choice (the Kirchhoff–Rayleigh
//! free-streamline plate gives a similar path, 0.31 → 0.5 chord). The chord
//! of a triangle is its extent along the in-plane flow direction and its
//! leading edge the upstream end:
//!
//! p = c + d (1 − 2α/π)(h_lead − f c_d),
//!
//! d the upstream in-plane unit vector, h_lead = maxᵢ (xᵢ − c)·d, c_d the
//! extent along d and f = 0.25 the quarter chord. F is shared among the
//! corners by the barycentric coordinates of p, which reproduces both the
//! force and its moment exactly.
//!
//! # Rotational lift (optional)
//!
//! APW add a circulation Γ = ½ C_R c² ω from the plate's own rotation (a
//! Magnus-like lift ρ Γ × v). `rotational_lift = C_R` adds, per triangle,
//! F = ½ ρ C_R c A (v × ω_in), with ω_in the triangle's in-plane angular
//! velocity (from the turning of its normal, ω_in = n × ṅ) and c its extent
//! across the rotation axis, applied at the centroid; it does no work. It is
//! off by default: with APW's C_R = π the square card of
//! [`crate::leaf::plates::square_card`] tumbles in a narrow band of densities
//! *between* fluttering and chaotic falls (flutter → tumble → chaos →
//! tumble, as APW's own ODE does: docs/design/falling-plates.md, "APW quasi-steady
//! model"), instead of the experiments' flutter → chaos → tumble (Field et
//! al. 1997); without it the card follows the experiments' order.
//!
//! # Air density and numbers
//!
//! ρ = 1.2 kg/m³ (air at 20 °C). A flat plate falling face-down reaches
//! σ g = ½ ρ C_D⊥ V², V = √(2 σ g / (ρ C_D⊥)): 0.74 m/s at σ = 80 g/m², close
//! to the 0.72–0.78 m/s measured for 70 g/m² paper shapes
//! (docs/design/falling-plates.md, "Measured regimes", row 4), whereas the linear
//! law's V = σ g /(3 αⁿ) is set by the chosen αⁿ.
//!
//! # Integrators
//!
//! All explicit integrators evaluate this law like any other force. The
//! implicit (linearised backward Euler) integrator treats it explicitly: its
//! Jacobian has no aerodynamic block under this law, so its step is bounded
//! by the drag rate ([`drag_rate`]) as for forward Euler.

pub mod coefficients;
mod forces;

pub use coefficients::{
    AIR_DENSITY, APW_ROTATIONAL_LIFT, CD_NORMAL, CD_PARALLEL, CL_AMPLITUDE, COP_LEADING,
    QuadraticAero, ROTATIONAL_LIFT,
};
pub use forces::{SPEED_MARGIN, drag_rate, edge_on_speed, quadratic_forces};

/// What one triangle costs a step under this law, in elements of
/// [`crate::physics::run::REFERENCE_RATE`]: measured at 4.7 (prototype A)
/// and 5.1 (a rigid 5 cm plate) by drops at a fixed step (A at
/// dt = 1.6e-7 s: 2.1, 3.5 and 5.8 s under the linear, quadratic and
/// unsteady laws; the plate, 0.037, 0.078 and 0.152 s for 20 s of fall).
pub const TRIANGLE_COST: usize = 5;
