//! Linear blend skinning, as glTF 2.0 ("Skins", "Joint hierarchy") and
//! UsdSkel ("Skinning", `UsdSkelSkinPointsLBS`) both define it: a vertex
//! bound to joints j with weights w_j moves to Σ_j w_j M_j p, where M_j
//! takes the bind pose to joint j's pose at that time. How a leaf rigged
//! with bones (an animator bending it along its midrib) reaches the glTF
//! and USD readers (`gltf::read`, `usd::read`).

use nalgebra::{Matrix4, Point3, Quaternion, UnitQuaternion, Vector3};

type V3 = Vector3<f64>;
type M4 = Matrix4<f64>;

/// Which joints move each vertex, and how much: `per_vertex` (joint,
/// weight) pairs per vertex, flattened.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Influences {
    /// Influences per vertex (glTF: 4 per JOINTS_n/WEIGHTS_n set; UsdSkel:
    /// the primvars' `elementSize`).
    pub per_vertex: usize,
    /// Joint index of each influence, into the matrices [`blend`] gets.
    pub joints: Vec<usize>,
    /// Weight of each influence.
    pub weights: Vec<f64>,
}

impl Influences {
    /// Checks the influences against `vertices` and `joint_count` and
    /// normalises each vertex's weights to sum to one (both formats ask
    /// writers for normalised weights; exporters round them). A vertex
    /// with no weight at all is an error, as glTF says; so is a joint past
    /// the skeleton's.
    pub fn normalised(mut self, vertices: usize, joint_count: usize) -> Result<Self, String> {
        let k = self.per_vertex;
        if k == 0 || self.joints.len() != vertices * k || self.weights.len() != vertices * k {
            return Err(format!(
                "{} joint indices and {} weights for {vertices} vertices at {k} a vertex",
                self.joints.len(),
                self.weights.len()
            ));
        }
        for (i, (joints, weights)) in self
            .joints
            .chunks(k)
            .zip(self.weights.chunks_mut(k))
            .enumerate()
        {
            if let Some(j) = joints
                .iter()
                .zip(weights.iter())
                .find(|(j, w)| **w != 0.0 && **j >= joint_count)
            {
                return Err(format!(
                    "vertex {i} is bound to joint {}, past the skeleton's {joint_count}",
                    j.0
                ));
            }
            if weights.iter().any(|w| !(w.is_finite() && *w >= 0.0)) {
                return Err(format!(
                    "vertex {i} has a negative or non-finite joint weight"
                ));
            }
            let sum: f64 = weights.iter().sum();
            if sum <= 0.0 {
                return Err(format!("vertex {i} has no joint weight"));
            }
            weights.iter_mut().for_each(|w| *w /= sum);
        }
        Ok(self)
    }
}

/// A joint's (a glTF node's, a PointInstancer instance's) local transform
/// T·R·S (column vectors) from its translation, its rotation as a
/// quaternion (real part first; normalised here) and its scale, as glTF
/// and UsdGeom/UsdSkel compose them.
pub(super) fn trs_matrix(translation: &[f64], rotation: [f64; 4], scale: &[f64]) -> M4 {
    let [w, x, y, z] = rotation;
    let mut m = UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z)).to_homogeneous();
    for c in 0..3 {
        for r in 0..3 {
            m[(r, c)] *= scale[c];
        }
        m[(c, 3)] = translation[c];
    }
    m
}

/// The skinned positions of `points` (in the bind pose's space) under
/// `matrices` (one per joint, column vectors): Σ_j w_j M_j p per vertex.
/// The influences must have been [`Influences::normalised`] against these
/// points and matrices.
pub(super) fn blend(points: &[V3], influences: &Influences, matrices: &[M4]) -> Vec<V3> {
    let k = influences.per_vertex;
    points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let p = Point3::from(*p);
            let mut out = V3::zeros();
            for (j, w) in influences.joints[i * k..(i + 1) * k]
                .iter()
                .zip(&influences.weights[i * k..(i + 1) * k])
            {
                if *w != 0.0 {
                    out += *w * matrices[*j].transform_point(&p).coords;
                }
            }
            out
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Rotation3, Translation3};

    #[test]
    fn one_joint_moves_a_vertex_rigidly_and_two_blend_linearly() {
        let turn = Rotation3::from_axis_angle(&V3::z_axis(), 0.7).to_homogeneous();
        let shift = Translation3::new(1.0, 2.0, 3.0).to_homogeneous();
        let p = V3::new(0.3, -0.2, 0.1);
        // Unnormalised weights (3, 1) are read as (0.75, 0.25).
        let inf = Influences {
            per_vertex: 2,
            joints: vec![0, 1, 1, 0],
            weights: vec![3.0, 1.0, 1.0, 0.0],
        }
        .normalised(2, 2)
        .unwrap();
        let out = blend(&[p, p], &inf, &[turn, shift]);
        let rigid = |m: &M4| m.transform_point(&Point3::from(p)).coords;
        assert!((out[0] - (0.75 * rigid(&turn) + 0.25 * rigid(&shift))).norm() < 1e-15);
        assert!((out[1] - rigid(&shift)).norm() < 1e-15);
    }

    #[test]
    fn bad_bindings_are_named() {
        let inf = |joints: Vec<usize>, weights: Vec<f64>| Influences {
            per_vertex: 1,
            joints,
            weights,
        };
        let e = inf(vec![0], vec![0.0]).normalised(1, 1).unwrap_err();
        assert!(e.contains("vertex 0 has no joint weight"), "{e}");
        let e = inf(vec![2], vec![1.0]).normalised(1, 2).unwrap_err();
        assert!(e.contains("joint 2, past the skeleton's 2"), "{e}");
        let e = inf(vec![0], vec![1.0]).normalised(2, 1).unwrap_err();
        assert!(e.contains("for 2 vertices"), "{e}");
        // A joint index past the skeleton with no weight is padding.
        assert!(
            Influences {
                per_vertex: 2,
                joints: vec![0, 9],
                weights: vec![1.0, 0.0]
            }
            .normalised(1, 1)
            .is_ok()
        );
    }
}
