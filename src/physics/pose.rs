//! The pose of a deforming leaf: centre of mass and the rotation that best
//! maps the rest shape onto the current particles (mass-weighted least
//! squares), so a mass-spring leaf can be read like a rigid body.

use crate::physics::model::Model;
use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};

/// Iterations of the rotation fit per call; Newton's method warm-started
/// from the previous frame converges in two or three.
const MAX_ITERATIONS: usize = 30;
/// Stop after a correction smaller than this angle, rad: the error left is
/// of order its square, below 1e-13 rad.
const FINAL_CORRECTION: f64 = 3e-7;

/// Tracks the best-fit rotation of a model's particles frame by frame.
#[derive(Clone, Debug)]
pub struct PoseTracker {
    /// Rest positions relative to the rest centre of mass, times mass.
    weighted_rest: Vec<Vector3<f64>>,
    rotation: UnitQuaternion<f64>,
    /// The turn from the frame before the last to the last, to predict the
    /// next rotation (a constant-rate guess saves a Newton iteration).
    last_turn: UnitQuaternion<f64>,
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
            last_turn: UnitQuaternion::identity(),
        }
    }

    /// Centre of mass and best-fit rotation (body to world) of `position`.
    ///
    /// The rotation R maximises Σ mᵢ (R rᵢ)·(pᵢ − c), found by Newton's method
    /// on the rotation group, warm-started from the previous frame. The
    /// quaternion keeps continuity (no sign jumps).
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
        // The fit depends on A's direction only. Scaled by the power of two
        // that brings its largest entry near 1, every product of the fit is
        // the same bits times a power of two (ordinary leaves get the same
        // rotation to the last bit), and masses far from 1 kg (1e200 kg, or
        // a heavy particle beside light ones) no longer overflow or
        // underflow the Hessian's cofactors (≈ |A|²).
        let largest = a.amax();
        if largest.is_finite() && largest > 0.0 {
            a *= 2f64.powi(-(largest.log2().round() as i32));
        }
        let guess = self.last_turn * self.rotation;
        let mut q = best_rotation(&a, guess);
        // Keep the hemisphere of the previous frame so the CSV has no sign
        // flips (the guess may have crossed it).
        if q.coords.dot(&self.rotation.coords) < 0.0 {
            q = UnitQuaternion::new_unchecked(-q.into_inner());
        }
        self.last_turn = q * self.rotation.inverse();
        self.rotation = q;
        (com, q)
    }
}

/// The rotation R (body to world) that maximises tr(Rᵀ A) for
/// A = Σ mᵢ (pᵢ − c) rᵢᵀ, i.e. best maps rest offsets rᵢ onto current
/// offsets pᵢ − c in the mass-weighted least-squares sense; Newton's method on
/// the rotation group, warm-started at `start`. The result lies in the
/// quaternion hemisphere of `start`, so successive frames have no sign flips.
pub fn best_rotation(a: &Matrix3<f64>, start: UnitQuaternion<f64>) -> UnitQuaternion<f64> {
    let mut q = start;
    for _ in 0..MAX_ITERATIONS {
        // Maximise f(R) = tr(Rᵀ A) over rotations R ← exp(δ̂) R. With
        // M = A Rᵀ: gradient g = Σₖ rₖ × aₖ (the vector part of M − Mᵀ) and
        // Hessian −(tr M · I − sym M). Newton's step δ = (tr M · I − sym M)⁻¹ g
        // converges quadratically, also for a flat leaf whose A has rank 2
        // (a plain gradient step would crawl there).
        let r = q.to_rotation_matrix();
        let m = a * r.matrix().transpose();
        let g = Vector3::new(
            m[(2, 1)] - m[(1, 2)],
            m[(0, 2)] - m[(2, 0)],
            m[(1, 0)] - m[(0, 1)],
        );
        let trace = m.trace();
        let h = Matrix3::identity() * trace - (m + m.transpose()) * 0.5;
        // A 3×3 inverse by cofactors (no square roots); far from the
        // optimum the Hessian may be indefinite, and then the Newton step is
        // no ascent direction: take a scaled gradient step instead.
        let delta = match h.try_inverse().map(|inv| inv * g) {
            Some(d) if d.dot(&g) > 0.0 => d,
            _ => g / (trace.abs() + 1e-300),
        };
        let angle = delta.norm();
        // A Newton step through a nearly singular Hessian can overflow: keep
        // the last (finite) rotation rather than turn by infinity into NaN.
        if !angle.is_finite() {
            break;
        }
        // Turn by δ with the first-order quaternion (1, δ/2), normalised: a
        // rotation by 2 atan(|δ|/2) = |δ| − O(|δ|³) about δ̂, which keeps
        // Newton's quadratic convergence without a sine or cosine.
        let turn = Quaternion::new(1.0, 0.5 * delta.x, 0.5 * delta.y, 0.5 * delta.z);
        q = UnitQuaternion::new_normalize(turn * q.into_inner());
        // Newton converges quadratically: after a correction of |δ| the
        // remaining error is of order |δ|², so stop once that is negligible.
        if angle < FINAL_CORRECTION {
            break;
        }
    }
    let q = UnitQuaternion::new_normalize(*q.quaternion());
    // Keep the hemisphere of the previous frame so the CSV has no sign flips.
    if q.coords.dot(&start.coords) < 0.0 {
        UnitQuaternion::new_unchecked(-q.into_inner())
    } else {
        q
    }
}
