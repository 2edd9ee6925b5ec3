//! Linear drag on particles that belong to no triangle (eq. 7).

use crate::physics::model::Model;
use nalgebra::Vector3;

type V3 = Vector3<f64>;

/// Linear drag on particles outside any surface, eq. 7: F_i = α (G_i − v_i).
pub fn particle_drag(model: &Model, v: &[V3], wind: Option<&[V3]>, force: &mut [V3]) {
    for (i, &alpha) in model.particle_drag.iter().enumerate() {
        if alpha == 0.0 {
            continue;
        }
        let v_rel = match wind {
            Some(g) => g[i] - v[i],
            None => -v[i],
        };
        force[i] += alpha * v_rel;
    }
}
