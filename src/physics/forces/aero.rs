//! The per-triangle aerodynamics of eq. 6–10: the paper's linear law, or
//! the quadratic law of [`super::quadratic`] or the unsteady law of
//! [`super::unsteady`] where the model chooses it.

use super::quadratic::quadratic_forces;
use super::surfaces::surface;
use super::unsteady::{PressureLag, unsteady_forces};
use crate::physics::model::{AeroLaw, Model};
use nalgebra::{Matrix3, Vector3};

type V3 = Vector3<f64>;

/// The paper's per-triangle aerodynamics, eq. 6–10, read literally: for each
/// corner particle i of a triangle of area A and unit normal n, the relative
/// velocity v_rᵢ = G(x_i) − v_i (eq. 6) is split into its normal part
/// vⁿ = (v_r·n) n and tangential part vᵗ = v_r − vⁿ (eq. 8), and the corner
/// receives
///
/// Fⁿ = αⁿ A vⁿ,  Fᵗ = αᵗ A vᵗ   (eq. 9, 10).
///
/// Convention: each corner gets the whole triangle area A with its own
/// relative velocity, so a flat leaf of areal density σ falls at
/// σ g / (3 αⁿ); the other reading (A/3 per corner) only rescales α.
/// Written with the unnormalised normal N = e₁ × e₂ (|N| = 2A) so that a
/// triangle squeezed to zero area gets no force instead of NaN.
///
/// `wind` holds G at every particle, or is `None` in still air. A model
/// with [`AeroLaw::Quadratic`] gets that law instead
/// ([`quadratic_forces`]); with [`AeroLaw::Unsteady`], that law's
/// velocity-dependent forces ([`unsteady_forces`]; its added mass is not a
/// force but a term of Newton's law, see [`triangle_aero_solved`]).
pub fn triangle_aero(model: &Model, x: &[V3], v: &[V3], wind: Option<&[V3]>, force: &mut [V3]) {
    triangle_aero_intact(model, x, v, wind, &[], force);
}

/// [`triangle_aero`] on the triangles that are not torn (`torn[t]`; an empty
/// mask tears none). A triangle whose edge spring has broken is no longer a
/// surface: left in, its corners, held by nothing, would be spread by the
/// wind, whose force grows with the area it spreads (a runaway).
pub fn triangle_aero_intact(
    model: &Model,
    x: &[V3],
    v: &[V3],
    wind: Option<&[V3]>,
    torn: &[bool],
    force: &mut [V3],
) {
    if matches!(model.aero, AeroLaw::Unsteady(_)) {
        let mut added = vec![Matrix3::zeros(); model.len()];
        return triangle_aero_solved(model, x, v, wind, torn, force, &mut added, None);
    }
    triangle_aero_solved(model, x, v, wind, torn, force, &mut [], None)
}

/// [`triangle_aero_intact`], and under the unsteady law each particle's
/// added-mass tensor M_i = Σ m_k n nᵀ added into `added` (one per particle,
/// zeroed by the caller; unused under the other laws), which Newton's law
/// then solves for: (m_i I + M_i) a_i = f_i. `lag` is the unsteady law's
/// lagged centre of pressure ([`PressureLag`]; `None` leaves that term out).
#[allow(clippy::too_many_arguments)]
pub fn triangle_aero_solved(
    model: &Model,
    x: &[V3],
    v: &[V3],
    wind: Option<&[V3]>,
    torn: &[bool],
    force: &mut [V3],
    added: &mut [Matrix3<f64>],
    lag: Option<&mut PressureLag>,
) {
    match &model.aero {
        AeroLaw::Quadratic(law) => return quadratic_forces(law, model, x, v, wind, torn, force),
        AeroLaw::Unsteady(law) => {
            return unsteady_forces(law, model, x, v, wind, torn, force, added, lag);
        }
        AeroLaw::Linear => {}
    }
    for (t, tri) in model.triangles.iter().enumerate() {
        let Some((big_n, n2)) = surface(t, tri, x, torn) else {
            continue;
        };
        let doubled_area = n2.sqrt();
        let area = 0.5 * doubled_area;
        // αᵗ A v_r + (αⁿ − αᵗ) A (n·v_r) n, with A n (n·v) = N (N·v) / (2|N|).
        let tangential = tri.alpha_t * area;
        let normal_excess = (tri.alpha_n - tri.alpha_t) / (2.0 * doubled_area);
        match wind {
            Some(g) => {
                for &i in &tri.corners {
                    let v_rel = g[i] - v[i];
                    force[i] += tangential * v_rel + big_n * (normal_excess * big_n.dot(&v_rel));
                }
            }
            // Still air: v_r = −v, written out so the hot loop has no branch.
            None => {
                for &i in &tri.corners {
                    let v_i = v[i];
                    force[i] -= tangential * v_i + big_n * (normal_excess * big_n.dot(&v_i));
                }
            }
        }
    }
}
