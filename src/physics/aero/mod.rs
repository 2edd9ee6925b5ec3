//! The aerodynamic law: how relative wind becomes force on a model's
//! triangles (the paper's eq. 6–10 and the two laws that replace it).
//!
//! Each law lives in its own module, which owns all of it:
//!
//! | law | module | coefficients, keys, validation | forces | rate bound for the auto step | cost |
//! |---|---|---|---|---|---|
//! | linear (paper, eq. 9–10) | [`linear`] | [`linear::coefficients`] (α per triangle) | [`linear::linear_forces`], over lanes in [`linear::kernel`] | [`linear::add_damping_blocks`] | [`linear::TRIANGLE_COST`] |
//! | quadratic | [`quadratic`] | [`quadratic::coefficients`] | [`quadratic::quadratic_forces`] | [`quadratic::drag_rate`] | [`quadratic::TRIANGLE_COST`] |
//! | unsteady | [`unsteady`] | [`unsteady::coefficients`] | [`unsteady::unsteady_forces`] | [`unsteady::drag_rate`], [`unsteady::tumbling_rate`], [`unsteady::rest_added_mass_tensors`] | [`unsteady::TRIANGLE_COST`] |
//!
//! [`AeroLaw`] ([`law`]) is what a model holds: the law and its
//! coefficients, read from a leaf file's `[aero]` keys ([`keys`]) by the
//! law's own `from_keys`. Callers never ask which law a model has: they ask
//! the law, through [`AeroLaw`]'s methods and the functions below, which
//! dispatch to the law's module.
//!
//! The model imports [`law`] and the laws' `coefficients` files, data that
//! import nothing of the engine (`tests/integration/layers.rs` holds it so).

pub mod keys;
pub mod law;
pub mod linear;
pub mod quadratic;
mod surfaces;
pub mod unsteady;

pub use law::{AeroLaw, AeroLawName};

use crate::physics::model::Model;
use nalgebra::{Matrix3, Vector3};

type V3 = Vector3<f64>;

/// The model's aerodynamic forces on its triangles (eq. 6–10 under the
/// linear law, or the law the model chooses), added into `force`. `wind`
/// holds G at every particle, or is `None` in still air. Under a law that
/// adds mass, only its velocity-dependent forces (the added mass is not a
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
    if model.aero.adds_mass() {
        let mut added = vec![Matrix3::zeros(); model.len()];
        return triangle_aero_solved(model, x, v, wind, torn, force, &mut added, None);
    }
    triangle_aero_solved(model, x, v, wind, torn, force, &mut [], None)
}

/// [`triangle_aero_intact`], and under a law that adds mass each particle's
/// added-mass tensor M_i = Σ m_k n nᵀ added into `added` (one per particle,
/// zeroed by the caller; unused under the other laws), which Newton's law
/// then solves for: (m_i I + M_i) a_i = f_i. `lag` is the unsteady law's
/// lagged centre of pressure ([`unsteady::PressureLag`]; `None` leaves that
/// term out).
#[allow(clippy::too_many_arguments)]
pub fn triangle_aero_solved(
    model: &Model,
    x: &[V3],
    v: &[V3],
    wind: Option<&[V3]>,
    torn: &[bool],
    force: &mut [V3],
    added: &mut [Matrix3<f64>],
    lag: Option<&mut unsteady::PressureLag>,
) {
    match &model.aero {
        AeroLaw::Linear => linear::linear_forces(model, x, v, wind, torn, force),
        AeroLaw::Quadratic(law) => quadratic::quadratic_forces(law, model, x, v, wind, torn, force),
        AeroLaw::Unsteady(law) => {
            unsteady::unsteady_forces(law, model, x, v, wind, torn, force, added, lag);
        }
    }
}

/// The largest rate, 1/s, of the model's law's forces that an integrator
/// treats explicitly (the implicit step holds the linear law's, whose rate
/// is [`linear::add_damping_blocks`]'s and not counted here): the
/// quadratic law's drag, the unsteady law's but for its added mass.
pub fn explicit_drag_rate(model: &Model) -> f64 {
    match &model.aero {
        AeroLaw::Linear => 0.0,
        AeroLaw::Quadratic(_) => quadratic::drag_rate(model),
        AeroLaw::Unsteady(_) => unsteady::drag_rate(model),
    }
}

/// The fastest a plate can turn under the model's law, 1/s (0 under the
/// laws that do not turn a plate by themselves; [`unsteady::tumbling_rate`]).
pub fn tumbling_rate(model: &Model) -> f64 {
    match &model.aero {
        AeroLaw::Unsteady(_) => unsteady::tumbling_rate(model),
        AeroLaw::Linear | AeroLaw::Quadratic(_) => 0.0,
    }
}

/// Every particle's added-mass tensor at the rest shape, `None` under a law
/// that adds no mass (or whose added mass is switched off).
pub fn rest_added_mass_tensors(model: &Model) -> Option<Vec<Matrix3<f64>>> {
    let AeroLaw::Unsteady(law) = &model.aero else {
        return None;
    };
    (law.air_density * law.added_mass > 0.0).then(|| unsteady::rest_added_mass_tensors(law, model))
}

/// What one triangle costs a step under `law`, in elements of
/// [`crate::physics::run::REFERENCE_RATE`] (each law's `TRIANGLE_COST`).
pub fn triangle_cost(law: &AeroLaw) -> usize {
    match law {
        AeroLaw::Linear => linear::TRIANGLE_COST,
        AeroLaw::Quadratic(_) => quadratic::TRIANGLE_COST,
        AeroLaw::Unsteady(_) => unsteady::TRIANGLE_COST,
    }
}
