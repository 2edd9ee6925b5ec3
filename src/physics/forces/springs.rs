//! Springs with parallel dashpots (the paper's section 2.1).

use crate::physics::model::Model;
use nalgebra::Vector3;

type V3 = Vector3<f64>;

/// Springs with dashpots (section 2.1, "internal forces ... stretching of the
/// springs"). With d = x_i − x_j, l = |d|, n = d/l, rest length L:
///
/// F_i = −k (l − L) n − c ((v_i − v_j)·n) n,   F_j = −F_i.
///
/// Broken springs (`alive[s] == false`) act no more. A spring squeezed to zero
/// length has no direction and exerts no force (rather than NaN).
pub fn springs(model: &Model, x: &[V3], v: &[V3], alive: &[bool], force: &mut [V3]) {
    for (spring, &alive) in model.springs.iter().zip(alive) {
        if !alive {
            continue;
        }
        let (i, j) = (spring.i, spring.j);
        let d = x[i] - x[j];
        let l2 = d.norm_squared();
        if l2 == 0.0 {
            continue;
        }
        let l = l2.sqrt();
        // One division, not three: n = d / l.
        let n = d * (1.0 / l);
        let stretch_rate = (v[i] - v[j]).dot(&n);
        let f = n * (-spring.stiffness * (l - spring.rest_length) - spring.damping * stretch_rate);
        force[i] += f;
        force[j] -= f;
    }
}
