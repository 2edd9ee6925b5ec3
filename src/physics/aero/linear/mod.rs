//! The paper's linear law, eq. 9–10: for each corner particle i of a
//! triangle of area A and unit normal n, the relative velocity
//! v_rᵢ = G(x_i) − v_i (eq. 6) is split into its normal part
//! vⁿ = (v_r·n) n and tangential part vᵗ = v_r − vⁿ (eq. 8), and the corner
//! receives
//!
//! Fⁿ = αⁿ A vⁿ,  Fᵗ = αᵗ A vᵗ   (eq. 9, 10).
//!
//! Convention: each corner gets the whole triangle area A with its own
//! relative velocity, so a flat leaf of areal density σ falls at
//! σ g / (3 αⁿ); the other reading (A/3 per corner) only rescales α.
//!
//! The law is written once, in [`kernel`], over a lane type: one f64 for a
//! lone drop ([`linear_forces`]), `L` of them for the lockstep batch
//! ([`crate::physics::batch`]), whose four-lane AVX2 form is the one
//! hand-vectorised specialisation; the batch tests hold all of them bit
//! for bit to this one.

pub mod coefficients;
pub mod kernel;

use crate::physics::aero::surfaces::surface;
use crate::physics::model::Model;
use kernel::LinearTriangle;
use nalgebra::{Matrix3, Vector3};

type V3 = Vector3<f64>;

/// What one triangle costs a step under this law, in elements of
/// [`crate::physics::run::REFERENCE_RATE`]: one element's (the rate was
/// measured on drops under this law).
pub const TRIANGLE_COST: usize = 1;

/// The linear law's forces on every triangle that is not torn (`torn[t]`;
/// an empty mask tears none), added into `force`. `wind` holds G at every
/// particle, or is `None` in still air.
pub fn linear_forces(
    model: &Model,
    x: &[V3],
    v: &[V3],
    wind: Option<&[V3]>,
    torn: &[bool],
    force: &mut [V3],
) {
    for (t, tri) in model.triangles.iter().enumerate() {
        let Some((big_n, n2)) = surface(t, tri, x, torn) else {
            continue;
        };
        let law = LinearTriangle::new(big_n.into(), n2, tri.alpha_n, tri.alpha_t);
        match wind {
            Some(g) => {
                for &i in &tri.corners {
                    force[i] += V3::from(law.corner_force((g[i] - v[i]).into()));
                }
            }
            // Still air: v_r = −v, written out so the hot loop has no branch.
            None => {
                for &i in &tri.corners {
                    force[i] -= V3::from(law.corner_force(v[i].into()));
                }
            }
        }
    }
}

/// Adds each triangle's linear air damping ∂F/∂v = A (αᵗ I + (αⁿ − αᵗ) n nᵀ)
/// at the rest shape to its corners' blocks: the law's rates, which the
/// stability estimate bounds the step with (zero blocks under the other
/// laws, whose α are 0).
pub fn add_damping_blocks(model: &Model, blocks: &mut [Matrix3<f64>]) {
    for tri in &model.triangles {
        let [a, b, c] = tri.corners;
        let x = &model.rest_position;
        let big_n = (x[b] - x[a]).cross(&(x[c] - x[a]));
        let doubled = big_n.norm();
        if doubled == 0.0 {
            continue;
        }
        let nrm = big_n / doubled;
        let blk = (Matrix3::identity() * tri.alpha_t
            + nrm * nrm.transpose() * (tri.alpha_n - tri.alpha_t))
            * (0.5 * doubled);
        for &i in &tri.corners {
            blocks[i] += blk;
        }
    }
}
