//! Bending hinges: the fold angle between two triangles that share an edge,
//! its gradient, and the restoring torque that keeps a folded leaf folded.

use crate::physics::model::{Hinge, Model};
use nalgebra::Vector3;

type V3 = Vector3<f64>;

/// The fold angle θ of a hinge and its gradient with respect to the four
/// particles (edge a, edge b, apex p, apex q), in that order.
///
/// With ê the unit edge direction and u, w the parts of x_p − x_a and
/// x_q − x_a perpendicular to it (heights h_p = |u|, h_q = |w|),
/// θ = atan2((û × ŵ)·ê, −û·ŵ), which is 0 for a flat pair and ±π when folded
/// shut. Turning û about ê raises θ and turning ŵ lowers it, so
/// ∇_p θ = (ê × û)/h_p and ∇_q θ = −(ê × ŵ)/h_q; the edge particles take
/// ∇_a θ = −(1 − t_p)∇_p θ − (1 − t_q)∇_q θ and ∇_b θ = −t_p ∇_p θ − t_q ∇_q θ
/// with t the apexes' positions along the edge, which makes the gradient
/// invariant under translation and rotation (no net force or torque).
/// `None` for a degenerate hinge (zero-length edge or an apex on the edge).
pub fn dihedral(x: &[V3], hinge: &Hinge) -> Option<(f64, [V3; 4])> {
    fold_sin_cos(x, hinge).map(|(sin, cos, grad)| (sin.atan2(cos), grad))
}

/// Smallest apex height, relative to the hinge's edge length, used for the
/// fold-angle gradient (see `fold_sin_cos`).
pub const MIN_HINGE_HEIGHT_RATIO: f64 = 0.1;

/// sin θ and cos θ of the fold angle (see [`dihedral`]) and its gradient,
/// without the arctangent: the hot path needs only sin(θ − θ₀). Written with
/// the unnormalised normals N_p = e × (x_p − x_a), N_q = e × (x_q − x_a),
/// since N_p/|N_p| = ê × û and |N_p| = |e| h_p: ∇_p θ = |e| N_p / |N_p|².
// Inlined into the hinge loop: returned by value it costs a 120-byte copy.
#[inline(always)]
fn fold_sin_cos(x: &[V3], hinge: &Hinge) -> Option<(f64, f64, [V3; 4])> {
    let [a, b] = hinge.edge;
    let [p, q] = hinge.apexes;
    let xa = x[a];
    let e = x[b] - xa;
    let (rp, rq) = (x[p] - xa, x[q] - xa);
    let (np, nq) = (e.cross(&rp), e.cross(&rq));
    let (np2, nq2, len2) = (np.norm_squared(), nq.norm_squared(), e.norm_squared());
    if np2 <= f64::MIN_POSITIVE || nq2 <= f64::MIN_POSITIVE {
        return None;
    }
    let len = len2.sqrt();
    let inv_norms = 1.0 / (np2 * nq2).sqrt();
    let sin = np.cross(&nq).dot(&e) * (inv_norms / len);
    let cos = -np.dot(&nq) * inv_norms;
    // |∇_p θ| = 1/h_p grows without bound as a triangle collapses onto the
    // hinge; bound the lever at a tenth of the edge (as ARCSim clamps its
    // bending "height"), so a crumpled leaf gets finite forces.
    let floor = MIN_HINGE_HEIGHT_RATIO * MIN_HINGE_HEIGHT_RATIO * len2 * len2;
    let gp = np * (len / np2.max(floor));
    let gq = nq * (-len / nq2.max(floor));
    let inv_len2 = 1.0 / len2;
    let (tp, tq) = (rp.dot(&e) * inv_len2, rq.dot(&e) * inv_len2);
    let ga = -gp * (1.0 - tp) - gq * (1.0 - tq);
    let gb = -gp * tp - gq * tq;
    Some((sin, cos, [ga, gb, gp, gq]))
}

/// Bending hinges: F_i = −(k_b sin(θ − θ₀) + c_b θ̇) ∇_i θ with
/// θ̇ = Σ ∇_j θ · v_j: the force of the energy k_b (1 − cos(θ − θ₀)), which
/// equals ½ k_b (θ − θ₀)² to fourth order, is smooth at every angle and
/// needs no arctangent; plus a damper on the fold rate.
///
/// `rest` holds (sin θ₀, cos θ₀) of every hinge ([`hinge_rest`]), computed
/// once rather than at every evaluation. A hinge with a torn wing
/// (`torn[h]`; an empty mask tears none, see [`super::Tears`]) bends no more.
pub fn hinges(
    model: &Model,
    rest: &[(f64, f64)],
    x: &[V3],
    v: &[V3],
    torn: &[bool],
    force: &mut [V3],
) {
    for (h, (hinge, &(rest_sin, rest_cos))) in model.hinges.iter().zip(rest).enumerate() {
        if !torn.is_empty() && torn[h] {
            continue;
        }
        let Some((sin, cos, grad)) = fold_sin_cos(x, hinge) else {
            continue;
        };
        let sin_delta = sin * rest_cos - cos * rest_sin;
        let ids = hinge.particles();
        let rate = fold_rate(&ids, &grad, v);
        let torque = -hinge.stiffness * sin_delta - hinge.damping * rate;
        for (&i, g) in ids.iter().zip(&grad) {
            force[i] += g * torque;
        }
    }
}

/// The fold rate θ̇ = Σ ∇_j θ · v_j of a hinge over its particles `ids`.
#[inline]
pub fn fold_rate(ids: &[usize; 4], grad: &[V3; 4], v: &[V3]) -> f64 {
    ids.iter().zip(grad).map(|(&i, g)| g.dot(&v[i])).sum()
}

/// (sin θ₀, cos θ₀) of every hinge's rest angle, for [`hinges`].
pub fn hinge_rest(model: &Model) -> Vec<(f64, f64)> {
    model
        .hinges
        .iter()
        .map(|h| h.rest_angle.sin_cos())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hinge() -> Hinge {
        Hinge {
            edge: [0, 1],
            apexes: [2, 3],
            rest_angle: 0.0,
            stiffness: 1.0,
            damping: 0.0,
        }
    }

    fn points() -> Vec<V3> {
        vec![
            V3::new(0.0, 0.0, 0.0),
            V3::new(0.03, 0.004, -0.002),
            V3::new(0.012, 0.02, 0.003),
            V3::new(0.018, -0.017, 0.006),
        ]
    }

    /// The analytic gradient of the fold angle matches central differences.
    #[test]
    fn dihedral_gradient_matches_finite_differences() {
        let x = points();
        let (theta, grad) = dihedral(&x, &hinge()).unwrap();
        assert!(
            theta.abs() > 0.05,
            "test geometry should be folded, θ = {theta}"
        );
        let eps = 1e-7;
        for p in 0..4 {
            for k in 0..3 {
                let mut plus = x.clone();
                let mut minus = x.clone();
                plus[p][k] += eps;
                minus[p][k] -= eps;
                let fd = (dihedral(&plus, &hinge()).unwrap().0
                    - dihedral(&minus, &hinge()).unwrap().0)
                    / (2.0 * eps);
                assert!(
                    (fd - grad[p][k]).abs() < 1e-5 * grad[p][k].abs().max(1.0),
                    "particle {p} axis {k}: {fd} vs {}",
                    grad[p][k]
                );
            }
        }
    }

    /// Flat is 0; folding both apexes up gives the same sign as folding the
    /// leaf's flaps up; the force has no net force or torque.
    #[test]
    fn hinge_force_is_internal_and_restoring() {
        let mut x = vec![
            V3::new(0.0, 0.0, 0.0),
            V3::new(1.0, 0.0, 0.0),
            V3::new(0.5, 1.0, 0.0),
            V3::new(0.5, -1.0, 0.0),
        ];
        assert!(dihedral(&x, &hinge()).unwrap().0.abs() < 1e-15);
        x[2].z = 0.3;
        x[3].z = 0.3;
        let (theta, _) = dihedral(&x, &hinge()).unwrap();
        assert!(theta.abs() > 0.1);
        let mut parts = crate::physics::model::ModelParts {
            mass: vec![1.0; 4],
            fixed: vec![false; 4],
            rest_position: x.clone(),
            ..Default::default()
        };
        parts.hinges = vec![hinge()];
        let model = Model::new(parts).unwrap();
        let mut f = vec![V3::zeros(); 4];
        hinges(
            &model,
            &hinge_rest(&model),
            &x,
            &[V3::zeros(); 4],
            &[],
            &mut f,
        );
        let net: V3 = f.iter().sum();
        let torque: V3 = x.iter().zip(&f).map(|(p, f)| p.cross(f)).sum();
        assert!(net.norm() < 1e-14 && torque.norm() < 1e-14);
        // Restoring: the force pushes the apexes back towards flat (down).
        assert!(f[2].z < 0.0 && f[3].z < 0.0, "{f:?}");
    }
}
