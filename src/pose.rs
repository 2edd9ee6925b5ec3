//! The pose of a deforming leaf: centre of mass and the rotation that best
//! maps the rest shape onto the current particles (mass-weighted least
//! squares), so a mass-spring leaf can be read like a rigid body.

use crate::model::Model;
use nalgebra::{Matrix3, Unit, UnitQuaternion, Vector3};

/// Iterations of the rotation fit per call; warm-started from the previous
/// frame it converges in two or three, a cold start needs more.
const MAX_ITERATIONS: usize = 50;
/// Stop when the correcting rotation is below this angle, rad.
const ANGLE_TOLERANCE: f64 = 1e-13;

/// Tracks the best-fit rotation of a model's particles frame by frame.
#[derive(Clone, Debug)]
pub struct PoseTracker {
    /// Rest positions relative to the rest centre of mass, times mass.
    weighted_rest: Vec<Vector3<f64>>,
    rotation: UnitQuaternion<f64>,
}

impl PoseTracker {
    /// A tracker for `model`, starting its search at `initial` (the release
    /// rotation, or identity).
    pub fn new(model: &Model, initial: UnitQuaternion<f64>) -> PoseTracker {
        let com = model.centre_of_mass(&model.rest_position);
        let weighted_rest = model
            .rest_position
            .iter()
            .zip(&model.mass)
            .map(|(x, m)| (x - com) * *m)
            .collect();
        PoseTracker {
            weighted_rest,
            rotation: initial,
        }
    }

    /// Centre of mass and best-fit rotation (body to world) of `position`.
    ///
    /// The rotation R maximises Σ mᵢ (R rᵢ)·pᵢ, found by repeatedly turning R
    /// about the axis Σ (R aₖ) × bₖ of the columns of the cross-covariance
    /// (a fixed-point iteration on the polar decomposition, warm-started from
    /// the previous frame). The quaternion keeps continuity (no sign jumps).
    pub fn pose(
        &mut self,
        model: &Model,
        position: &[Vector3<f64>],
    ) -> (Vector3<f64>, UnitQuaternion<f64>) {
        let com = model.centre_of_mass(position);
        // A = Σ (pᵢ − c) (mᵢ rᵢ)ᵀ: R should align the columns of R with those of A.
        let mut a = Matrix3::zeros();
        for (p, r) in position.iter().zip(&self.weighted_rest) {
            a += (p - com) * r.transpose();
        }
        let mut q = self.rotation;
        for _ in 0..MAX_ITERATIONS {
            let r = q.to_rotation_matrix();
            let r = r.matrix();
            let mut torque = Vector3::zeros();
            let mut alignment = 0.0;
            for k in 0..3 {
                torque += r.column(k).cross(&a.column(k));
                alignment += r.column(k).dot(&a.column(k));
            }
            let scale = alignment.abs() + 1e-300;
            let omega = torque / scale;
            let angle = omega.norm();
            if angle < ANGLE_TOLERANCE {
                break;
            }
            q = UnitQuaternion::from_axis_angle(&Unit::new_unchecked(omega / angle), angle) * q;
        }
        let q = UnitQuaternion::new_normalize(*q.quaternion());
        // Keep the hemisphere of the previous frame so the CSV has no sign flips.
        let q = if q.coords.dot(&self.rotation.coords) < 0.0 {
            UnitQuaternion::new_unchecked(-q.into_inner())
        } else {
            q
        };
        self.rotation = q;
        (com, q)
    }
}
