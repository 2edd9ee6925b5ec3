//! Rigid bodies made of particles, moved as the paper does after Hahn (1988):
//! the net force F = Σ fᵢ and net torque τ = Σ rᵢ × fᵢ of all a body's
//! particles drive its linear and angular momentum.
//!
//! A body is a set of model particles; it has no state of its own. Its
//! centre of mass c, velocity V and angular momentum L are read from the
//! particles, so everything else in the simulator (forces, springs to other
//! objects, output) keeps working on particles. Two passes make the particles
//! move as one body with every integrator:
//!
//! 1. **Accelerations** ([`accelerations`], inside the force path): each
//!    member gets the exact rigid-body acceleration under the summed load,
//!
//!    aᵢ = F/M + α × rᵢ + ω × (ω × rᵢ),   α = I⁻¹ (τ − ω × L),   ω = I⁻¹ L,
//!
//!    with rᵢ = xᵢ − c and I the world inertia tensor about c (Euler's
//!    equations in the world frame: dL/dt = τ with L = I ω and
//!    dI/dt ω = ω × L). Internal forces (springs between members) cancel in
//!    F and τ, so they change nothing.
//! 2. **Projection** ([`RigidProjector::project`], after each step): the
//!    integrator moved the members along straight lines, which leaves the
//!    rigid shape by O(h^(p+1)) per step for an order-p scheme. The rotation
//!    R that best maps the body-frame offsets onto the members (the same
//!    Newton fit as [`crate::physics::pose`]) puts them back exactly, and velocities are
//!    reset to V + ω × rᵢ with ω = (R I_b Rᵀ)⁻¹ L. This keeps the centre of
//!    mass, the momentum M V and the angular momentum L unchanged, and never
//!    adds energy (for a given L the rigid velocity field has the least
//!    kinetic energy).
//!
//! The orientation is therefore always an exact rotation, and it follows the
//! rigid-body equations to the integrator's order.

use crate::physics::model::RigidBody;
use crate::physics::pose;
use crate::physics::state::State;
use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};

type V3 = Vector3<f64>;

/// Replaces the force on every member of every body by mᵢ aᵢ, with aᵢ the
/// rigid-body acceleration under the body's summed force and torque (see
/// the module documentation). Called with forces in `force`, before the
/// division by mass, so that the caller's aᵢ = fᵢ/mᵢ gives the rigid value.
///
/// With added mass (`added` holds each particle's tensor Mᵢ; empty: none),
/// each member's inertia is Kᵢ = mᵢ I + Mᵢ and the body's acceleration
/// (A, α) solves the 6 × 6 Newton–Euler system
/// Σ Kᵢ aᵢ = Σ fᵢ, Σ rᵢ × Kᵢ aᵢ = Σ rᵢ × fᵢ with
/// aᵢ = A + α × rᵢ + ω × (ω × rᵢ) — which reduces to the equations above
/// when every Mᵢ is 0 (Σ mᵢ rᵢ = 0 about the centre of mass). The member's
/// force is then replaced by Kᵢ aᵢ, so the caller's per-particle solve
/// Kᵢ⁻¹ (Kᵢ aᵢ) gives the rigid value.
pub fn accelerations(
    bodies: &[RigidBody],
    x: &[V3],
    v: &[V3],
    force: &mut [V3],
    added: &[Matrix3<f64>],
) {
    if !added.is_empty() {
        return accelerations_with_added_mass(bodies, x, v, force, added);
    }
    for body in bodies {
        let (c, vc) = body.centre(x, v);
        let mut f = V3::zeros();
        let mut tau = V3::zeros();
        let mut l = V3::zeros();
        let mut inertia = Matrix3::zeros();
        for (&i, &m) in body.members.iter().zip(&body.member_mass) {
            let r = x[i] - c;
            f += force[i];
            tau += r.cross(&force[i]);
            l += r.cross(&(v[i] - vc)) * m;
            inertia += (Matrix3::identity() * r.norm_squared() - r * r.transpose()) * m;
        }
        // Members stay within round-off of the rigid shape, whose inertia was
        // checked invertible at validation; a failure here means the state
        // is already non-finite, which the divergence check reports.
        let inv = inertia.try_inverse().unwrap_or_else(Matrix3::zeros);
        let omega = inv * l;
        let alpha = inv * (tau - omega.cross(&l));
        let lin = f / body.mass;
        for (&i, &m) in body.members.iter().zip(&body.member_mass) {
            let r = x[i] - c;
            force[i] = (lin + alpha.cross(&r) + omega.cross(&omega.cross(&r))) * m;
        }
    }
}

fn skew(r: &V3) -> Matrix3<f64> {
    Matrix3::new(0.0, -r.z, r.y, r.z, 0.0, -r.x, -r.y, r.x, 0.0)
}

fn accelerations_with_added_mass(
    bodies: &[RigidBody],
    x: &[V3],
    v: &[V3],
    force: &mut [V3],
    added: &[Matrix3<f64>],
) {
    for body in bodies {
        let (c, vc) = body.centre(x, v);
        let mut l = V3::zeros();
        let mut inertia = Matrix3::zeros();
        for (&i, &m) in body.members.iter().zip(&body.member_mass) {
            let r = x[i] - c;
            l += r.cross(&(v[i] - vc)) * m;
            inertia += (Matrix3::identity() * r.norm_squared() - r * r.transpose()) * m;
        }
        let omega = inertia.try_inverse().unwrap_or_else(Matrix3::zeros) * l;
        // Blocks of [ΣK, −ΣK[r]×; Σ[r]×K, −Σ[r]×K[r]×] (A, α) = rhs.
        let mut system = nalgebra::Matrix6::<f64>::zeros();
        let mut rhs = nalgebra::Vector6::<f64>::zeros();
        for (&i, &m) in body.members.iter().zip(&body.member_mass) {
            let r = x[i] - c;
            let k = Matrix3::identity() * m + added[i];
            let rx = skew(&r);
            let centripetal = omega.cross(&omega.cross(&r));
            let kc = k * centripetal;
            let blocks = [k, -(k * rx), rx * k, -(rx * k * rx)];
            for (b, blk) in blocks.iter().enumerate() {
                let (row, col) = (3 * (b / 2), 3 * (b % 2));
                for p in 0..3 {
                    for q in 0..3 {
                        system[(row + p, col + q)] += blk[(p, q)];
                    }
                }
            }
            let (f, tau) = (force[i] - kc, r.cross(&force[i]) - r.cross(&kc));
            for p in 0..3 {
                rhs[p] += f[p];
                rhs[3 + p] += tau[p];
            }
        }
        // Members off the rigid shape only by round-off keep the system
        // invertible; a singular one means a non-finite state, which the
        // divergence check reports.
        let solution = system
            .lu()
            .solve(&rhs)
            .unwrap_or_else(nalgebra::Vector6::zeros);
        let lin = V3::new(solution[0], solution[1], solution[2]);
        let alpha = V3::new(solution[3], solution[4], solution[5]);
        for (&i, &m) in body.members.iter().zip(&body.member_mass) {
            let r = x[i] - c;
            let a = lin + alpha.cross(&r) + omega.cross(&omega.cross(&r));
            force[i] = (Matrix3::identity() * m + added[i]) * a;
        }
    }
}

/// The after-step pass that puts every body's members back on its rigid
/// shape; holds each body's last rotation to warm-start the fit.
#[derive(Clone, Debug)]
pub struct RigidProjector {
    rotation: Vec<UnitQuaternion<f64>>,
    /// Whether a projection has run (the first one finds its own start).
    started: bool,
}

/// Of the 24 rotations of a cube (as products of quarter turns about x, y
/// and z), the one that maximises tr(Rᵀ A), identity on a tie: within 63°
/// of any rotation, where the Newton fit of [`pose::best_rotation`]
/// converges. A body released turned far from its rest layout (a plate
/// dropped on edge at a random yaw) would otherwise be fitted from the
/// identity, half a turn away, and could land on the wrong extremum.
fn cube_start(a: &Matrix3<f64>) -> UnitQuaternion<f64> {
    let quarter = std::f64::consts::FRAC_PI_2;
    let mut best = (a.trace(), UnitQuaternion::identity());
    for i in 0..4 {
        for j in 0..4 {
            for k in 0..4 {
                let q = UnitQuaternion::from_euler_angles(
                    i as f64 * quarter,
                    j as f64 * quarter,
                    k as f64 * quarter,
                );
                let f = (q.to_rotation_matrix().matrix().transpose() * a).trace();
                if f > best.0 * (1.0 + 1e-12) + 1e-300 {
                    best = (f, q);
                }
            }
        }
    }
    best.1
}

impl RigidProjector {
    /// A projector for `bodies`; its first projection finds each body's
    /// orientation from the nearest of the 24 rotations of a cube,
    /// later ones start from the last.
    pub fn new(bodies: &[RigidBody]) -> RigidProjector {
        RigidProjector {
            rotation: vec![UnitQuaternion::identity(); bodies.len()],
            started: false,
        }
    }

    /// The rotation (body frame → world) found for body `b` by the last
    /// projection.
    pub fn rotation(&self, b: usize) -> UnitQuaternion<f64> {
        self.rotation[b]
    }

    /// Makes every body exactly rigid again, keeping its centre of mass,
    /// momentum and angular momentum (see the module documentation).
    pub fn project(&mut self, bodies: &[RigidBody], state: &mut State) {
        let first = !self.started;
        self.started = true;
        for (body, rotation) in bodies.iter().zip(&mut self.rotation) {
            let (x, v) = (&mut state.position, &mut state.velocity);
            let (c, vc) = body.centre(x, v);
            let l = body.angular_momentum(x, v, &c, &vc);
            // A = Σ mᵢ (xᵢ − c) bᵢᵀ; the best rotation maximises tr(Rᵀ A).
            let mut a = Matrix3::zeros();
            for ((&i, &m), b) in body
                .members
                .iter()
                .zip(&body.member_mass)
                .zip(&body.offsets)
            {
                a += (x[i] - c) * (b * m).transpose();
            }
            if first {
                *rotation = cube_start(&a);
            }
            let q = pose::best_rotation(&a, *rotation);
            *rotation = q;
            let r: Rotation3<f64> = q.to_rotation_matrix();
            let world_inv = r.matrix() * body.inertia_inv * r.matrix().transpose();
            let omega = world_inv * l;
            for (&i, b) in body.members.iter().zip(&body.offsets) {
                let arm = r * b;
                x[i] = c + arm;
                v[i] = vc + omega.cross(&arm);
            }
        }
    }
}
