//! An object's motion split into a moving frame and a shape in it: the
//! rigid part (origin and rotation per frame, what a glTF node's TRS or a
//! USD Xform carries, so the object's origin follows it) and the deformation
//! relative to it (the local shape per frame). What dressing a mesh needs
//! from its rest shape, smooth vertex normals and UVs, is re-exported here
//! from the folder's `dress.rs`.
//!
//! The frame of a deforming object is fitted like the pose of a leaf
//! ([`crate::physics::pose`]): its origin is the mass-weighted centre of the
//! vertices, its rotation the one that best maps the rest shape onto them
//! (mass-weighted least squares). The split is exact whatever rotation is
//! chosen (the local shape is Rᵀ(x − c)); the fit only keeps the local
//! deformation small, so that what clients interpolate between keys is
//! mostly the rigid motion.

pub use super::Body;
pub use super::dress::{outline_uvs, triangle_normals, vertex_normals};

use super::{ClipObject, Motion};
use crate::physics::pose::best_rotation;
use nalgebra::{Matrix3, UnitQuaternion, Vector3};

type V3 = Vector3<f64>;

/// An object's motion as a moving frame and a shape in it.
#[derive(Clone, Debug, PartialEq)]
pub struct Framed {
    /// Origin of the body frame per frame (world, m).
    pub origin: Vec<V3>,
    /// Body-to-world rotation per frame, without sign jumps between frames.
    pub rotation: Vec<UnitQuaternion<f64>>,
    /// The shape in the body frame: one entry per frame, or a single entry
    /// for a rigid object (its shape never changes).
    pub local: Vec<Vec<V3>>,
    /// The rest shape the deformation is measured from (the body's rest,
    /// or the first frame), body frame.
    pub rest: Vec<V3>,
}

impl Framed {
    /// The local shape at frame `k`.
    pub fn local_at(&self, k: usize) -> &[V3] {
        &self.local[k.min(self.local.len() - 1)]
    }

    /// Whether the shape changes over time.
    pub fn deforms(&self) -> bool {
        self.local.len() > 1
    }
}

/// Whether points lie within `tol` of one line (a rope, or one point): then
/// no rotation is defined by them and the frame does not turn.
fn collinear(points: &[V3], tol: f64) -> bool {
    let Some(&a) = points.first() else {
        return true;
    };
    let Some(far) = points
        .iter()
        .max_by(|p, q| (*p - a).norm().total_cmp(&(*q - a).norm()))
    else {
        return true;
    };
    let axis = far - a;
    if axis.norm() < tol {
        return true;
    }
    let u = axis.normalize();
    points.iter().all(|p| {
        let d = p - a;
        (d - u * d.dot(&u)).norm() < tol
    })
}

/// Sweeps the eigen and singular value solvers may take: they converge in
/// a few dozen on any finite 3×3 matrix (nalgebra's default, 0, means no
/// bound, and loops for ever on a matrix with an infinity in it).
pub(crate) const MAX_SOLVER_ITERATIONS: usize = 1000;

/// The rotation R maximising Σ mᵢ (R rᵢ)·(pᵢ − c) with no previous frame to
/// start from: by the singular value decomposition of A (Kabsch), with the
/// sign fixed so that R is a proper rotation.
pub(crate) fn kabsch(a: &Matrix3<f64>) -> UnitQuaternion<f64> {
    // nalgebra's own tolerance for `svd` (5 ε), with a bound on sweeps.
    let Some(svd) = a.try_svd(true, true, 5.0 * f64::EPSILON, MAX_SOLVER_ITERATIONS) else {
        return UnitQuaternion::identity();
    };
    let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
        return UnitQuaternion::identity();
    };
    let d = (u * v_t).determinant().signum();
    let r = u * Matrix3::from_diagonal(&V3::new(1.0, 1.0, d)) * v_t;
    UnitQuaternion::from_matrix(&r)
}

impl ClipObject {
    /// The body of the object: its own if it has one, else the first frame
    /// about its centroid, all vertices weighted alike.
    pub fn body_or_first_frame(&self) -> Body {
        if let Some(b) = &self.body {
            return b.clone();
        }
        let p = self.positions(0);
        let c = p.iter().sum::<V3>() / p.len().max(1) as f64;
        Body {
            rest: p.iter().map(|x| x - c).collect(),
            mass: vec![1.0; p.len()],
        }
    }

    /// The motion as a moving frame and a shape in it (see the module doc).
    pub fn framed(&self) -> Framed {
        match &self.motion {
            Motion::Rigid {
                local,
                translation,
                rotation,
            } => Framed {
                origin: translation.clone(),
                rotation: rotation.clone(),
                local: vec![local.clone()],
                rest: local.clone(),
            },
            Motion::Deforming { frames } => {
                let body = self.body_or_first_frame();
                let total: f64 = body.mass.iter().sum();
                let turns = !collinear(&body.rest, 1e-9);
                let mut origin = Vec::with_capacity(frames.len());
                let mut rotation = Vec::with_capacity(frames.len());
                let mut local = Vec::with_capacity(frames.len());
                let mut previous: Option<UnitQuaternion<f64>> = None;
                for f in frames {
                    let c = f.iter().zip(&body.mass).map(|(x, m)| x * *m).sum::<V3>() / total;
                    let q = if turns {
                        let mut a = Matrix3::zeros();
                        for ((p, r), m) in f.iter().zip(&body.rest).zip(&body.mass) {
                            a += (p - c) * (r * *m).transpose();
                        }
                        // Newton from the previous frame keeps the quaternion
                        // continuous; the first frame starts from Kabsch.
                        best_rotation(&a, previous.unwrap_or_else(|| kabsch(&a)))
                    } else {
                        UnitQuaternion::identity()
                    };
                    let inv = q.inverse();
                    local.push(f.iter().map(|x| inv * (x - c)).collect());
                    origin.push(c);
                    rotation.push(q);
                    previous = Some(q);
                }
                Framed {
                    origin,
                    rotation,
                    local,
                    rest: body.rest,
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn object(frames: Vec<Vec<V3>>, body: Option<Body>) -> ClipObject {
        ClipObject {
            first_frame: 0,
            name: "o".into(),
            kind: "leaf".into(),
            label: String::new(),
            regime: String::new(),
            features: Vec::new(),
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            segments: vec![],
            body,
            render: None,
            motion: Motion::Deforming { frames },
        }
    }

    #[test]
    fn a_rigidly_moving_shape_has_a_constant_local_shape_and_the_true_frame() {
        // A square turned by a known rotation and moved: the fitted frame is
        // that rotation and the centre, and the local shape the rest shape.
        let rest = vec![
            V3::new(-0.1, -0.05, 0.0),
            V3::new(0.1, -0.05, 0.0),
            V3::new(0.1, 0.05, 0.0),
            V3::new(-0.1, 0.05, 0.0),
        ];
        let body = Body {
            rest: rest.clone(),
            mass: vec![1.0, 2.0, 1.0, 2.0],
        };
        // Mass-weighted centre of the rest shape is not at the origin here,
        // so shift it first.
        let c: V3 = rest.iter().zip(&body.mass).map(|(x, m)| x * *m).sum::<V3>() / 6.0;
        let body = Body {
            rest: rest.iter().map(|x| x - c).collect(),
            ..body
        };
        let frames: Vec<Vec<V3>> = (0..20)
            .map(|k| {
                let q =
                    UnitQuaternion::from_scaled_axis(V3::new(0.3, -2.0, 1.0) * (k as f64 * 0.2));
                let t = V3::new(1.0, 2.0, -0.5 * k as f64);
                body.rest.iter().map(|x| t + q * x).collect()
            })
            .collect();
        let o = object(frames.clone(), Some(body.clone()));
        let f = o.framed();
        for (k, frame) in frames.iter().enumerate() {
            let q = UnitQuaternion::from_scaled_axis(V3::new(0.3, -2.0, 1.0) * (k as f64 * 0.2));
            assert!(f.rotation[k].angle_to(&q) < 1e-9, "frame {k}");
            assert!((f.origin[k] - V3::new(1.0, 2.0, -0.5 * k as f64)).norm() < 1e-12);
            for (a, b) in f.local_at(k).iter().zip(&body.rest) {
                assert!((a - b).norm() < 1e-9);
            }
            if k > 0 {
                assert!(f.rotation[k].coords.dot(&f.rotation[k - 1].coords) > 0.0);
            }
            // The split is exact: origin + R · local is the input.
            for (x, l) in frame.iter().zip(f.local_at(k)) {
                assert!((x - (f.origin[k] + f.rotation[k] * l)).norm() < 1e-14);
            }
        }
    }

    #[test]
    fn a_rope_does_not_turn_its_frame() {
        let line =
            |s: f64| -> Vec<V3> { (0..4).map(|i| V3::new(i as f64 * s, 0.0, 1.0)).collect() };
        let mut o = object(vec![line(0.1), line(0.12)], None);
        o.triangles.clear();
        let f = o.framed();
        assert_eq!(f.rotation[1], UnitQuaternion::identity());
        assert!((f.local_at(1)[3].x - 0.18).abs() < 1e-12);
    }
}
