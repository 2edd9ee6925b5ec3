//! Gravity on every particle.

use crate::physics::model::Model;
use nalgebra::Vector3;

type V3 = Vector3<f64>;

/// Gravity: F_i = m_i g.
pub fn gravity(model: &Model, force: &mut [V3]) {
    let g = model.gravity;
    for (f, &m) in force.iter_mut().zip(&model.mass) {
        *f += m * g;
    }
}
